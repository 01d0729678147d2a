"""Figures of the closed-loop NMPC scenarios (paper Figs. 7-10) from ``ScenarioResult``.

Every function builds a ``matplotlib.figure.Figure`` directly (no pyplot state, no display
backend); save with ``acid._io.save_figure``. Temperatures are drawn in degC, flows in kg/s,
powers in W, speeds in m/s, energies in kJ, time in s. Constraints are red dotted lines, as
in the paper.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from acid.numbers import format_number
from acid.paper import STUDIES
from acid.studies.mpc_check.scenarios import ScenarioResult
from acid.units import K2C

_BOUND = {"color": "tab:red", "linestyle": ":", "linewidth": 1.4}
#: one style per run; runs often coincide (both at an input bound), so every later run is
#: thinner and dashed and its markers differ: the earlier run stays visible around it
#: (checked by ``acid.report.audit``)
_RUN_STYLES = (
    {"color": "tab:blue", "linestyle": "-", "linewidth": 2.6, "marker": "o"},
    {"color": "tab:orange", "linestyle": (0, (4, 2)), "linewidth": 1.3, "marker": "x"},
    {"color": "tab:green", "linestyle": (0, (1, 1.5)), "linewidth": 1.1, "marker": "+"},
    {"color": "tab:purple", "linestyle": "-.", "linewidth": 0.9, "marker": "."},
)


def _run_style(j: int, markers: bool) -> dict:
    """Line style of run ``j`` (with markers on sampled states, without on stairs)."""
    st = dict(_RUN_STYLES[j % len(_RUN_STYLES)])
    if markers:
        st["ms"] = 4
    else:
        st.pop("marker")
    return st


def _check(result: ScenarioResult) -> None:
    if result.skipped is not None or not result.runs:
        raise ValueError(f"scenario {result.name!r} has no runs to draw ({result.skipped})")


def _stairs(ax, run, values, **kw):
    """Draw per-step values (held over [t_k, t_k + Ts)) as steps."""
    t = np.append(run.time[:-1], run.time[-1])
    ax.step(t, np.append(values, values[-1]), where="post", **kw)


def closed_loop_figure(result: ScenarioResult, with_power: bool | None = None) -> Figure:
    """Paper Figs. 7 (model) and 8 (high-fidelity plant): states, bounds and inputs.

    Parameters
    ----------
    result : scenario ``"model"`` or ``"plant"`` with one run per initial condition.
    with_power : add the compressor and blower power panels (default: for the plant).

    Returns
    -------
    Figure with T_cab (degC) and its bounds, T_evap (degC) and its bounds, W_bl (kg/s),
    T_evap_set (degC) [and P_comp, P_bl (W)] against time (s).
    """
    _check(result)
    if with_power is None:
        with_power = result.name != "model"
    n_ax = 6 if with_power else 4
    fig = Figure(figsize=(8.0, 2.0 * n_ax), layout="constrained")
    axes = fig.subplots(n_ax, 1, sharex=True)
    r0 = result.runs[0]
    for j, run in enumerate(result.runs):
        pts, st = _run_style(j, True), _run_style(j, False)
        axes[0].plot(run.time, K2C(run.T_cab), label=run.label, **pts)
        axes[1].plot(run.time, K2C(run.T_evap), label=run.label, **pts)
        _stairs(axes[2], run, run.W_bl, label=run.label, **st)
        _stairs(axes[3], run, K2C(run.T_evap_set), label=run.label, **st)
        if with_power:
            _stairs(axes[4], run, run.P_comp, label=run.label, **st)
            _stairs(axes[5], run, run.P_bl, label=run.label, **st)
    axes[0].step(r0.time, K2C(r0.T_cab_max), where="post", label="bounds", **_BOUND)
    axes[0].plot(r0.time, K2C(r0.T_cab_min), **_BOUND)
    axes[1].axhline(K2C(r0.T_evap_max), label="bounds", **_BOUND)
    axes[1].axhline(K2C(r0.T_evap_min), **_BOUND)
    labels = ["cabin air $T_{cab}$ (°C)", "evaporator wall $T_{evap}$ (°C)",
              "blower flow $W_{bl}$ (kg/s)", "set-point $T_{evap,set}$ (°C)",
              "compressor $P_{comp}$ (W)", "blower $P_{bl}$ (W)"]
    for ax, lab in zip(axes, labels, strict=False):
        ax.set_ylabel(lab)
        ax.grid(True, alpha=0.3)
    for ax in axes:
        ax.legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(result.title)
    return fig


def cav_profile_figure(result: ScenarioResult) -> Figure:
    """Paper Fig. 9: the previewed speed profile and the ICM upper bound on T_cab.

    Returns a figure with v_veh (m/s) above the Case 1 (ICM) and Case 2 (constant) bounds
    (degC) against time (s); the comparison window is shaded.
    """
    _check(result)
    case1, case2 = result.runs[:2]
    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax_v, ax_t = fig.subplots(2, 1, sharex=True)
    _stairs(ax_v, case1, case1.v_veh, color="black")
    ax_v.set_ylabel("vehicle speed $v_{veh}$ (m/s)")
    ax_t.step(case1.time, K2C(case1.T_cab_max), where="post", color="tab:red",
              label="Case 1: ICM bound")
    ax_t.step(case2.time, K2C(case2.T_cab_max), where="post", color="tab:gray",
              linestyle="--", label="Case 2: constant bound")
    ax_t.set_ylabel(r"upper bound $\overline{T}_{cab}$ (°C)")
    ax_t.set_xlabel("time (s)")
    ax_t.legend(loc="best", fontsize="small")
    for ax in (ax_v, ax_t):
        _shade(ax, result)
        ax.grid(True, alpha=0.3)
    fig.suptitle("Previewed speed and coordinated upper bound on $T_{cab}$ (paper Fig. 9)")
    return fig


def _shade(ax, result: ScenarioResult) -> None:
    w = result.metrics.get("window_s")
    if w:
        ax.axvspan(w[0], w[1], color="tab:green", alpha=0.08, label="comparison window")
    s = result.metrics.get("shutoff_s")
    if s:
        ax.axvspan(s[0], s[1], color="tab:gray", alpha=0.15, label="compressor off (Case 1)")


def cav_comparison_figure(result: ScenarioResult) -> Figure:
    """Paper Fig. 10: Case 1 (ICM) vs Case 2 (constant bound) on the high-fidelity plant.

    Returns a figure with T_cab and bounds (degC), T_evap (degC), A/C power P_comp + P_bl
    (W) and the cumulative A/C energy over the comparison window (kJ) against time (s).
    """
    _check(result)
    case1, case2 = result.runs[:2]
    w = result.metrics.get("window_s", [case1.time[0], case1.time[-1]])
    fig = Figure(figsize=(8.0, 9.0), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    for j, run in enumerate((case1, case2)):
        pts, st = _run_style(j, True), _run_style(j, False)
        axes[0].plot(run.time, K2C(run.T_cab), label=run.label, **pts)
        axes[0].step(run.time, K2C(run.T_cab_max), where="post", color=st["color"],
                     linestyle=":", linewidth=1.2)
        axes[1].plot(run.time, K2C(run.T_evap), label=run.label, **pts)
        _stairs(axes[2], run, run.P_comp + run.P_bl, label=run.label, **st)
        m = run.step_mask(tuple(w))
        e = np.cumsum(np.where(m, (run.P_comp + run.P_bl) * run.Ts, 0.0)) / 1e3
        axes[3].plot(run.time[1:], e, label=f"{run.label}: {e[-1]:.1f} kJ", **st)
    axes[0].set_ylabel("cabin air $T_{cab}$ (°C)")
    axes[1].set_ylabel("evaporator wall $T_{evap}$ (°C)")
    axes[2].set_ylabel("A/C power $P_{comp} + P_{bl}$ (W)")
    axes[3].set_ylabel("energy in window (kJ)")
    axes[3].set_xlabel("time (s)")
    for ax in axes:
        _shade(ax, result)
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize="small")
    axes[3].legend(loc="upper left", fontsize="small")
    saving = result.metrics.get("saving_pct")
    txt = (f", saving {format_number(saving, '.1f')} % (paper: "
           f"{format_number(STUDIES.cav_saving_pct, 'g')} %)" if saving is not None else "")
    fig.suptitle(f"Case 1 (ICM) vs Case 2 (constant bound){txt} (paper Fig. 10)")
    return fig


def mpc_figures(scenarios: dict) -> dict[str, Figure]:
    """All figures for the scenarios that ran: {file stem: Figure}."""
    figs = {}
    model = scenarios.get("model")
    if model is not None and model.skipped is None and model.runs:
        figs["fig7_model"] = closed_loop_figure(model)
    plant = scenarios.get("plant")
    if plant is not None and plant.skipped is None and plant.runs:
        figs["fig8_plant"] = closed_loop_figure(plant)
    cav = scenarios.get("cav")
    if cav is not None and cav.skipped is None and cav.runs:
        figs["fig9_cav_bound"] = cav_profile_figure(cav)
        figs["fig10_cav_comparison"] = cav_comparison_figure(cav)
    return figs
