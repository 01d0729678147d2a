"""Figures of the multi-start validation (paper Figs. 5 and 6) from the one validation
result, ``acid.ident.validate.DeclaredValidation`` (any declared model).

Each function builds a ``matplotlib.figure.Figure`` directly (no pyplot state, no display
backend needed); save them with ``acid._io.save_figure``. The temperature channels (K in
the model) are drawn, temperatures in degC, errors in K, time in s of prediction.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from acid.ident.validate import DeclaredValidation
from acid.units import K2C

_LABELS = {
    "T_cab": "cabin air $T_{cab}$",
    "T_evap": "evaporator wall $T_{evap}$",
    "T_ain": "inlet air $T_{ain}$",
}
_TRUTH_COLOR = "black"
_PRED_COLOR = "tab:red"
#: Lighter lines of the yardsticks (``DeclaredValidation.yardsticks``).
_YARDSTICK_COLOR = {"persistence": "tab:purple", "arx": "tab:green", "subspace": "tab:blue"}


def _temperatures(result: DeclaredValidation) -> list[tuple[int, str]]:
    """(position, name) of the channels in K, the paper's three first when present."""
    return [(c, n) for c, (n, u) in enumerate(zip(result.channels, result.units, strict=True))
            if u == "K"]


def _label(name: str) -> str:
    return _LABELS.get(name, name)


def _held(result: DeclaredValidation) -> str:
    held = result.settings.get("hold", ())
    return f"{'/'.join(held)} held" if held else "disturbances measured"


def representative_start(result: DeclaredValidation, channel: str = "T_cab") -> int:
    """Position (0 .. S-1) of the start whose RMSE on ``channel`` (default T_cab, else the
    first temperature channel) is the median one."""
    if channel not in result.errors:
        channel = (_temperatures(result) or [(0, result.channels[0])])[0][1]
    r = np.sqrt(np.nanmean(result.errors[channel] ** 2, axis=1))
    return int(np.argsort(r)[(r.size - 1) // 2])


def prediction_figure(result: DeclaredValidation, start: int | None = None) -> Figure:
    """Paper Fig. 5: one open-loop prediction against the measurements.

    ``start``: position of the start in ``result`` (0 .. S-1); by default the start with
    the median T_cab RMSE (a representative, not a best-case, prediction). The temperature
    channels (degC, measured vs predicted) and, below, the first two inputs (W_bl in kg/s
    and T_evap_set in degC for the paper's model) over the prediction time (s).
    """
    s = representative_start(result) if start is None else int(start)
    if not 0 <= s < result.n_starts:
        raise IndexError(f"start {s} is not in 0..{result.n_starts - 1}")
    t = result.horizon_s
    temps = _temperatures(result)
    fig = Figure(figsize=(8.0, 2.25 * (len(temps) + 1)), layout="constrained")
    axes = fig.subplots(len(temps) + 1, 1, sharex=True)
    meas, pred = K2C(result.measured[s]), K2C(result.predicted[s])
    for ax, (c, name) in zip(axes, temps, strict=False):
        ax.plot(t, meas[:, c], color=_TRUTH_COLOR, lw=1.4, label="measured (plant)")
        ax.plot(t, pred[:, c], color=_PRED_COLOR, lw=1.4, ls="--", label="model prediction")
        ax.set_ylabel(f"{_label(name)}\n(°C)")
        rmse = float(np.sqrt(np.nanmean(result.errors[name][s] ** 2)))
        ax.text(0.99, 0.04, f"RMSE {rmse:.2f} K", transform=ax.transAxes, ha="right",
                va="bottom", fontsize=9, color="0.3")
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize=9)

    ax_u = axes[-1]
    for i, (ax, color) in enumerate(zip((ax_u, ax_u.twinx()), ("tab:blue", "tab:green"),
                                        strict=False)):
        if i >= len(result.input_names):
            break
        name, unit = result.input_names[i], result.input_units[i]
        v = result.inputs[s, :, i]
        ax.step(t, K2C(v) if unit == "K" else v, where="post", color=color, lw=1.2)
        ax.set_ylabel(f"{name}\n({'°C' if unit == 'K' else unit})", color=color)
        ax.tick_params(axis="y", colors=color)
    ax_u.grid(True, alpha=0.3)
    ax_u.set_xlabel("prediction time (s)")
    ax_u.set_xlim(t[0], t[-1])
    fig.suptitle(f"Open-loop prediction from t = {result.start_time[s]:g} s "
                 f"({result.horizon} steps, {_held(result)}; "
                 f"parameters {result.settings.get('params', '?')!r})", fontsize=11)
    return fig


def error_figure(result: DeclaredValidation) -> Figure:
    """Paper Fig. 6: prediction errors (predicted - measured, K) of all starts vs time.

    Each temperature channel's panel shows every start's error trajectory (thin lines), the
    band between the 5th and 95th percentiles over the starts and their mean, against the
    prediction time (s, steps 1 .. horizon).
    """
    t = result.horizon_s[1:]
    temps = _temperatures(result)
    fig = Figure(figsize=(8.0, 2.7 * len(temps)), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(temps), 1, sharex=True))
    for ax, (_, name) in zip(axes, temps, strict=True):
        e = result.errors[name]
        ax.plot(t, e.T, color="0.55", lw=0.5, alpha=0.45)
        p5, p95 = np.nanpercentile(e, [5.0, 95.0], axis=0)
        ax.fill_between(t, p5, p95, color="tab:orange", alpha=0.3,
                        label="5th-95th percentile")
        ax.plot(t, np.nanmean(e, axis=0), color="tab:red", lw=1.6, label="mean")
        ax.axhline(0.0, color="black", lw=0.8)
        ax.set_ylabel(f"{_label(name)} error\n(K)")
        m = result.metrics[name]
        ax.text(0.99, 0.04, f"RMSE {m['rmse']:.2f} K, p95 |e| {m['p95_abs']:.2f} K, "
                f"max |e| {m['max_abs']:.2f} K", transform=ax.transAxes, ha="right",
                va="bottom", fontsize=9, color="0.3")
        ax.grid(True, alpha=0.3)
    axes[0].plot([], [], color="0.55", lw=0.8, label=f"each of {result.n_starts} starts")
    axes[0].legend(loc="upper left", fontsize=9)
    axes[-1].set_xlabel("prediction time (s)")
    axes[-1].set_xlim(0.0, t[-1])
    fig.suptitle(f"Prediction errors from {result.n_starts} start instants "
                 f"({_held(result)})", fontsize=11)
    return fig


def yardstick_figure(result: DeclaredValidation) -> Figure:
    """The model beside its yardsticks: RMSE over the starts vs prediction time (s, K, log
    scale), the model in bold, persistence, ARX and subspace in lighter dashed lines, on the
    same windows. Requires ``validate(..., yardsticks=True)``."""
    if not result.yardsticks:
        raise ValueError("no yardsticks in this validation (validate(..., yardsticks=True))")
    t = result.horizon_s[1:]
    temps = _temperatures(result)
    fig = Figure(figsize=(8.0, 2.7 * len(temps)), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(temps), 1, sharex=True))
    floor = 1e-3  # K: an RMSE below this is drawn at it (log axis)
    for ax, (_, name) in zip(axes, temps, strict=True):
        model_rmse = np.sqrt(np.nanmean(result.errors[name] ** 2, axis=0))
        ax.plot(t, np.maximum(model_rmse, floor), color=_PRED_COLOR, lw=1.8,
                label=f"model {result.settings.get('params', '')!r}")
        for mark, y in result.yardsticks.items():
            if name in y["rmse_by_step"]:
                ax.plot(t, np.maximum(y["rmse_by_step"][name], floor),
                        color=_YARDSTICK_COLOR.get(mark, "0.4"), lw=1.2, ls="--", alpha=0.65,
                        label=f"{mark} (yardstick)")
        ax.set_yscale("log")
        ax.set_ylabel(f"{_label(name)}\nRMSE over starts (K)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(loc="lower right", fontsize=9)
    axes[-1].set_xlabel("prediction time (s)")
    axes[-1].set_xlim(t[0], t[-1])
    d = result.window_design
    fig.suptitle(f"Model and yardsticks on the same {d['starts']} windows "
                 f"({100 * d['overlap_fraction']:.0f} % overlap of consecutive windows)",
                 fontsize=11)
    return fig
