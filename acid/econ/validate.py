"""Multi-start open-loop predictions of the econ model, for :func:`acid.validate.validate`.

The same study as the paper's model (60 starts x 300 steps by default): from each start
``k0`` the five states are predicted from their measurements at ``k0``, driven by the
measured inputs ``W_bl`` and ``T_evap_set``; the vehicle speed and ambient are held at their
values at ``k0`` (``exogenous="hold"``, the conservative choice, like the paper's held
T_int/T_shell) or follow their measurements (``"measured"``: the preview a connected vehicle
has). Unlike the paper's model, the interior and shell are *predicted*, not measured inputs.

The validated channels are the paper's three (T_cab, T_evap, T_ain: directly comparable);
the extra channels (T_int, T_shell, w_cab in g/kg, P_comp in W) and the energy over each
window are reported beside them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acid.data import Dataset
from acid.econ.params import REQUIRED, EconParams
from acid.models import econ

#: Extra channels: (name, unit, factor from model units).
EXTRA_CHANNELS = (("T_int", "K", 1.0), ("T_shell", "K", 1.0), ("w_cab", "g/kg", 1e3),
                  ("P_comp", "W", 1.0))


@dataclass(frozen=True)
class EconWindows:
    """Predictions over the windows (S starts, H + 1 steps).

    Attributes
    ----------
    predicted, measured : (S, H + 1, 3) T_cab, T_evap, T_ain, K.
    inputs : (S, H + 1, 2) measured W_bl (kg/s), T_evap_set (K).
    exogenous : (S, H + 1, 2) the predicted T_int, T_shell, K.
    extra : {name: (predicted, measured, unit)} of ``EXTRA_CHANNELS``, (S, H + 1) each.
    energy : (predicted, measured) compressor energy of each window, (S,) J.
    """

    predicted: np.ndarray
    measured: np.ndarray
    inputs: np.ndarray
    exogenous: np.ndarray
    extra: dict
    energy: tuple


def predict_windows(ds: Dataset, idx: np.ndarray, p: EconParams,
                    exogenous: str = "hold") -> EconWindows:
    """Open-loop predictions of the econ model over the windows ``idx`` (S, H + 1).

    The model runs H + 1 intervals so that the interval means T_ain and P_comp exist at every
    step 0 .. H (step i of the dataset is the mean over [t_i, t_i + Ts)).
    """
    ds.validate(require=REQUIRED)
    K = {n: ds.get(n, "K") for n in ("T_cab", "T_int", "T_shell", "T_evap", "T_evap_set",
                                     "T_amb", "T_ain")}
    w = ds.get("w_cab", "kg/kg")
    W = ds.get("W_bl", "kg/s")[idx]
    Tset = K["T_evap_set"][idx]
    v, Ta = ds.get("v_veh", "m/s")[idx], K["T_amb"][idx]
    if exogenous == "hold":
        v = np.broadcast_to(v[:, :1], v.shape)
        Ta = np.broadcast_to(Ta[:, :1], Ta.shape)
    k0 = idx[:, 0]
    x0 = np.stack([K["T_cab"][k0], K["T_int"][k0], K["T_shell"][k0], K["T_evap"][k0], w[k0]],
                  axis=-1)
    X, Y = econ.model.simulate(x0, np.stack([W, Tset], axis=-1), np.stack([v, Ta], axis=-1),
                               p.theta_all)
    y = dict(zip(econ.model.output_names, np.moveaxis(Y, -1, 0), strict=True))
    P_comp = np.maximum(y["P_comp"], 0.0)      # the map clipped at zero, as a plant does
    xs = X[:, :-1, :]                          # states at steps 0 .. H
    predicted = np.stack([xs[..., 0], xs[..., 3], y["T_ain"]], axis=-1)
    measured = np.stack([K["T_cab"][idx], K["T_evap"][idx], K["T_ain"][idx]], axis=-1)
    P_meas = ds.get("P_comp", "W")[idx]
    extra = {}
    for (name, unit, f), pred, meas in zip(
            EXTRA_CHANNELS, (xs[..., 1], xs[..., 2], xs[..., 4], P_comp),
            (K["T_int"][idx], K["T_shell"][idx], w[idx], P_meas), strict=True):
        extra[name] = (f * pred, f * meas, unit)
    Ts = float(ds.Ts)
    return EconWindows(predicted=predicted, measured=measured,
                       inputs=np.stack([W, Tset], axis=-1),
                       exogenous=np.stack([xs[..., 1], xs[..., 2]], axis=-1), extra=extra,
                       energy=(P_comp.sum(axis=1) * Ts, P_meas.sum(axis=1) * Ts))


def extra_metrics(win: EconWindows) -> dict:
    """Pooled |error| statistics of the extra channels and the window energies."""
    out = {}
    for name, (pred, meas, unit) in win.extra.items():
        e = np.abs(pred - meas).ravel()
        out[name] = {"unit": unit, "rmse": float(np.sqrt(np.mean(e**2))),
                     "median_abs": float(np.median(e)),
                     "p90_abs": float(np.percentile(e, 90)), "max_abs": float(e.max())}
    pred_E, meas_E = win.energy
    rel = 100.0 * np.abs(pred_E - meas_E) / np.maximum(meas_E, 1.0)
    out["compressor_energy"] = {
        "unit": "% per window", "rmse": float(np.sqrt(np.mean(rel**2))),
        "median_abs": float(np.median(rel)), "p90_abs": float(np.percentile(rel, 90)),
        "max_abs": float(rel.max()),
        "bias_pct": float(100.0 * (pred_E.sum() - meas_E.sum()) / meas_E.sum())}
    return out
