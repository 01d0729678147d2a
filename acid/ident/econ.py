"""The econ model's identification (``acid fit --model econ``): acid.ident's staged fit of the
declaration :mod:`acid.models.econ` (its ``FIT_STAGES``) into :class:`EconParams`; nothing is
read from a plant's configuration."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acid.errors import DataError
from acid.ident.envelope import envelope_ranges
from acid.ident.fit import DeclaredFitResult
from acid.models import econ
from acid.models.econ import MAP_INPUTS, PowerMap
from acid.models.econ_params import NAMES, EconParams

# ------------------------------------------------------------------ identification
#: Channels ``acid fit --model econ`` needs (P_bl optional: eq. 5 then keeps its start).
REQUIRED = econ.STATES + ("W_bl", "T_evap_set", "v_veh", "T_amb", "T_ain", "P_comp")
#: |dT_cab/dt| and |dT_evap/dt| below this count as near-steady (the map's steady error), K/s
_STEADY_RATE = 0.02


@dataclass(frozen=True)
class EconFit:
    """The econ model identified by :func:`identify`: ``params`` (with the power map's
    domain and quality) and ``fit``, acid.ident's report of the staged fit."""

    params: EconParams
    fit: DeclaredFitResult

    @property
    def power_map_quality(self) -> dict:
        return self.params.power_map.quality

    @property
    def warnings(self) -> tuple[str, ...]:
        return self.fit.warnings

    def to_json_dict(self) -> dict:
        return {**self.fit.to_json_dict(), "power_map_quality": self.power_map_quality}


def identify(ds, covariance: str = "hac", hac_bandwidth="auto",
             skip_s: float = econ.FIT_SKIP_S) -> EconFit:
    """Identify the econ model from ``ds`` (channels ``REQUIRED``) with acid.ident's staged
    fit of the declaration (``acid.models.econ.FIT_STAGES``); warnings (``warnings.warn``,
    ``IdentifiabilityWarning``) where the excitation leaves a part unidentified. ``skip_s``:
    seconds left out at each experiment's start (``acid.models.econ.FIT_SKIP_S``)."""
    import warnings

    from acid.errors import IdentifiabilityWarning
    from acid.ident.fit import provenance
    from acid.ident.stages import Stage, fit_stages

    ds.validate(require=REQUIRED, min_samples=20)
    for name, unit, need in (("v_veh", "m/s", 5.0), ("T_amb", "K", 2.0)):
        if float(np.ptp(ds.get(name, unit))) < need:
            warnings.warn(f"{name} varies by only {np.ptp(ds.get(name, unit)):.3g} {unit} in "
                          f"the data: the power map and the shell balance are not identified "
                          f"in {name} (use `acid excite --model econ`)", IdentifiabilityWarning,
                          stacklevel=2)
    for name, unit, need, part in (("W_bl", "kg/s", 0.02, "air side"),
                                   ("T_evap_set", "K", 1.0, "evaporator")):
        if float(np.ptp(ds.get(name, unit))) < need:
            raise DataError(f"{ds.source}: {name} is (nearly) constant: the {part} is not "
                            "identifiable; excite it")
    fit = fit_stages(econ.model, ds, [Stage(*s) for s in econ.FIT_STAGES],
                     covariance=covariance, hac_bandwidth=hac_bandwidth,
                     skip_s=skip_s)
    # the map's domain and quality on the rows it was fitted on, as fitted: the model's coil
    # load from the measured state, the wall's storage from the measured end state
    x = np.column_stack([ds.get(n, u) for n, u in zip(econ.STATES, econ.STATE_UNITS,
                                                      strict=True)])
    keep = np.zeros(len(ds), dtype=bool)
    for a, b in ds.segments():
        keep[a + int(round(skip_s / ds.Ts)): b - 1] = True
    k = np.flatnonzero(keep)
    u = np.column_stack([ds.get("W_bl", "kg/s"), ds.get("T_evap_set", "K")])[k]
    d = np.column_stack([ds.get("v_veh", "m/s"), ds.get("T_amb", "K")])[k]
    out = econ.casadi_interval(ds.Ts).map(k.size)(x[k].T, u.T, d.T,
                                                  np.tile(fit.values, (k.size, 1)).T,
                                                  np.zeros((len(econ.STATES), k.size)))
    Q_coil, T_ev = (np.asarray(out[j]).ravel() for j in (5, 6))
    s = econ.parameters(fit.values)
    Q_e = econ.refrigerant_heat(s, Q_coil, x[k, 3], x[k + 1, 3], ds.Ts)
    P_hat = econ.compressor_power(s, Q_e, T_ev, d[:, 0], d[:, 1])
    P = ds.get("P_comp", "W")[k]
    e = P - P_hat
    steady = (np.abs(x[k + 1, 0] - x[k, 0]) / ds.Ts < _STEADY_RATE) & \
        (np.abs(x[k + 1, 3] - x[k, 3]) / ds.Ts < _STEADY_RATE) & (P > 0.05 * P.max())
    rms = float(np.sqrt(np.mean(e**2)))
    quality = {"n": int(P.size), "rms_W": rms, "rms_pct": 100.0 * rms / float(np.mean(P)),
               "max_abs_W": float(np.max(np.abs(e))),
               "r2": 1.0 - float(e @ e) / float(np.sum((P - P.mean()) ** 2)),
               "mean_P_W": float(np.mean(P)), "n_steady": int(steady.sum())}
    if steady.sum() >= 10:
        quality.update(steady_rms_pct=100.0 * float(np.sqrt(np.mean((e / P)[steady] ** 2))),
                       steady_max_pct=100.0 * float(np.max(np.abs(e / P)[steady])))
    domain = {n: (float(v.min()), float(v.max())) for (n, _), v in
              zip(MAP_INPUTS, (Q_e, T_ev, d[:, 0], d[:, 1]), strict=True)}
    envelope = envelope_ranges(Q_e=Q_e, T_evap=T_ev, T_cab=x[k, 0], W_bl=u[:, 0],
                               T_amb=d[:, 1])
    se = {e.name: e.stderr for e in fit.estimates}
    prov = {**provenance(ds, "acid.ident staged fit (acid.models.econ.FIT_STAGES)"),
            "skip_s": skip_s, **({"data_seed": ds.metadata["seed"]}
                                          if "seed" in ds.metadata else {})}
    params = EconParams.from_vector(
        fit.values, power_map=PowerMap(coef=fit.values[len(NAMES) + 1:len(NAMES) + 16],
                                       stderr=tuple(se[n] for n in econ.MAP_NAMES),
                                       domain=domain, quality=quality, envelope=envelope),
        stderr={n: se[n] for n in NAMES + ("C_ew",)}, Ts=float(ds.Ts), name="econ-fit",
        provenance=prov)
    return EconFit(params=params, fit=fit)
