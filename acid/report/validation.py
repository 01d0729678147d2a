"""Figures of the multi-start validation (paper Figs. 5 and 6) from a ``ValidationResult``.

Both functions build a ``matplotlib.figure.Figure`` directly (no pyplot state, no display
backend needed); save them with ``acid._io.save_figure``. Temperatures are drawn in degC,
errors in K, time in s of prediction.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from acid.units import K2C
from acid.validate import ValidationResult

_LABELS = {
    "T_cab": "cabin air $T_{cab}$",
    "T_evap": "evaporator wall $T_{evap}$",
    "T_ain": "inlet air $T_{ain}$",
}
_TRUTH_COLOR = "black"
_PRED_COLOR = "tab:red"
#: Lighter lines of the yardsticks (``ValidationResult.yardsticks``).
_YARDSTICK_COLOR = {"persistence": "tab:purple", "arx": "tab:green", "subspace": "tab:blue"}


def representative_start(result: ValidationResult, channel: str = "T_cab") -> int:
    """Position (0 .. S-1) of the start whose RMSE on ``channel`` is the median one."""
    r = result.per_start[channel]["rmse"]
    return int(np.argsort(r)[(r.size - 1) // 2])


def prediction_figure(result: ValidationResult, start: int | None = None) -> Figure:
    """Paper Fig. 5: one open-loop prediction against the measurements.

    Parameters
    ----------
    result : the validation study.
    start : position of the start in ``result`` (0 .. S-1); by default the start with the
        median T_cab RMSE (a representative, not a best-case, prediction).

    Returns
    -------
    Figure with T_cab, T_evap, T_ain (degC, measured vs predicted) and, below, the inputs
    W_bl (kg/s) and T_evap_set (degC) over the prediction time (s).
    """
    s = representative_start(result) if start is None else int(start)
    if not 0 <= s < result.n_starts:
        raise IndexError(f"start {s} is not in 0..{result.n_starts - 1}")
    t = result.horizon_s
    fig = Figure(figsize=(8.0, 9.0), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    meas, pred = K2C(result.measured[s]), K2C(result.predicted[s])
    for c, name in enumerate(result.channels):
        ax = axes[c]
        ax.plot(t, meas[:, c], color=_TRUTH_COLOR, lw=1.4, label="measured (plant)")
        ax.plot(t, pred[:, c], color=_PRED_COLOR, lw=1.4, ls="--", label="model prediction")
        ax.set_ylabel(f"{_LABELS[name]}\n(°C)")
        rmse = result.per_start[name]["rmse"][s]
        ax.text(0.99, 0.04, f"RMSE {rmse:.2f} K", transform=ax.transAxes, ha="right",
                va="bottom", fontsize=9, color="0.3")
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize=9)

    ax_w = axes[3]
    ax_w.step(t, result.inputs[s, :, 0], where="post", color="tab:blue", lw=1.2)
    ax_w.set_ylabel("blower flow $W_{bl}$\n(kg/s)", color="tab:blue")
    ax_w.tick_params(axis="y", colors="tab:blue")
    ax_set = ax_w.twinx()
    ax_set.step(t, K2C(result.inputs[s, :, 1]), where="post", color="tab:green", lw=1.2)
    ax_set.set_ylabel("set-point $T_{evap,set}$\n(°C)", color="tab:green")
    ax_set.tick_params(axis="y", colors="tab:green")
    ax_w.grid(True, alpha=0.3)
    ax_w.set_xlabel("prediction time (s)")
    ax_w.set_xlim(t[0], t[-1])

    mode = result.settings.get("exogenous", "hold")
    fig.suptitle(f"Open-loop prediction from t = {result.start_time[s]:g} s "
                 f"({result.horizon} steps, T_int/T_shell {mode}; "
                 f"parameters {result.settings.get('params_name', '?')!r})", fontsize=11)
    return fig


def error_figure(result: ValidationResult) -> Figure:
    """Paper Fig. 6: prediction errors (predicted - measured, K) of all starts vs time.

    Each channel's panel shows every start's error trajectory (thin lines), the band
    between the 5th and 95th percentiles over the starts and their mean, against the
    prediction time (s).
    """
    t = result.horizon_s
    fig = Figure(figsize=(8.0, 8.0), layout="constrained")
    axes = fig.subplots(len(result.channels), 1, sharex=True)
    for c, name in enumerate(result.channels):
        ax = axes[c]
        env = result.envelope[name]
        ax.plot(t, result.errors[:, :, c].T, color="0.55", lw=0.5, alpha=0.45)
        ax.fill_between(t, env["p5"], env["p95"], color="tab:orange", alpha=0.3,
                        label="5th-95th percentile")
        ax.plot(t, env["mean"], color="tab:red", lw=1.6, label="mean")
        ax.axhline(0.0, color="black", lw=0.8)
        ax.set_ylabel(f"{_LABELS[name]} error\n(K)")
        m = result.metrics[name]
        ax.text(0.99, 0.04, f"RMSE {m['rmse']:.2f} K, p95 |e| {m['p95_abs']:.2f} K, "
                f"max |e| {m['max_abs']:.2f} K", transform=ax.transAxes, ha="right",
                va="bottom", fontsize=9, color="0.3")
        ax.grid(True, alpha=0.3)
    axes[0].plot([], [], color="0.55", lw=0.8, label=f"each of {result.n_starts} starts")
    axes[0].legend(loc="upper left", fontsize=9)
    axes[-1].set_xlabel("prediction time (s)")
    axes[-1].set_xlim(t[0], t[-1])
    mode = result.settings.get("exogenous", "hold")
    fig.suptitle(f"Prediction errors from {result.n_starts} start instants "
                 f"(T_int/T_shell {mode})", fontsize=11)
    return fig


def yardstick_figure(result: ValidationResult) -> Figure:
    """The model beside its yardsticks: RMSE over the starts vs prediction time (s, K, log
    scale), the model in bold, persistence, ARX and subspace in lighter dashed lines, on the
    same windows. Requires ``validate(..., yardsticks=True)``."""
    if not result.yardsticks:
        raise ValueError("no yardsticks in this validation (validate(..., yardsticks=True))")
    t = result.horizon_s[1:]
    fig = Figure(figsize=(8.0, 8.0), layout="constrained")
    axes = fig.subplots(len(result.channels), 1, sharex=True)
    floor = 1e-3  # K: an RMSE below this is drawn at it (log axis)

    def rmse(pred: np.ndarray, c: int) -> np.ndarray:
        e = pred[:, 1:, c] - result.measured[:, 1:, c]
        return np.maximum(np.sqrt(np.mean(e**2, axis=0)), floor)

    for c, name in enumerate(result.channels):
        ax = axes[c]
        ax.plot(t, rmse(result.predicted, c), color=_PRED_COLOR, lw=1.8,
                label=f"model {result.settings.get('params_name', '')!r}")
        for mark, y in result.yardsticks.items():
            ax.plot(t, rmse(y.predicted, c), color=_YARDSTICK_COLOR.get(mark, "0.4"), lw=1.2,
                    ls="--", alpha=0.65, label=f"{mark} (yardstick)")
        ax.set_yscale("log")
        ax.set_ylabel(f"{_LABELS[name]}\nRMSE over starts (K)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(loc="lower right", fontsize=9)
    axes[-1].set_xlabel("prediction time (s)")
    axes[-1].set_xlim(t[0], t[-1])
    d = result.window_design
    fig.suptitle(f"Model and yardsticks on the same {d['starts']} windows "
                 f"({100 * d['overlap_fraction']:.0f} % overlap of consecutive windows)",
                 fontsize=11)
    return fig
