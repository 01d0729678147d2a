"""Figure of the drive-cycle CAV study (:mod:`acid.mpc.cav_study`) from its result object.

Builds a ``matplotlib.figure.Figure`` directly (no pyplot state); save with
``acid._io.save_figure``. Speeds in m/s, temperatures in °C, powers in W, energies in kJ,
time in s.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from acid.mpc.cav_study import CASES, CavStudyResult
from acid.units import K2C

_COLORS = {"A": "tab:blue", "B": "tab:orange", "C": "tab:green"}
_STYLE = {"A": "-", "B": "-", "C": "--"}  # C dashed: it coincides with A where it never
#                                           pre-cools
_WIDTH = {"A": 2.6, "B": 1.4, "C": 1.2}   # A wide under C: both stay visible
_BAND = {"color": "tab:red", "linestyle": ":", "linewidth": 1.4}


def cav_study_figure(result: CavStudyResult) -> Figure:
    """Speed, T_cab with the comfort band, A/C power and cumulative energy of A/B/C.

    Parameters
    ----------
    result : the study; the high-fidelity plant runs (``result.main``) are drawn.

    Returns
    -------
    Figure with four stacked panels sharing the time axis.
    """
    study = result.main
    cfg = result.config
    fig = Figure(figsize=(10, 10))
    axs = fig.subplots(4, 1, sharex=True)
    run0 = study.cases["A"].run
    t_step = run0.time[:-1]
    Ts = run0.Ts
    axs[0].step(np.append(t_step, run0.time[-1]), np.append(result.v_step, result.v_step[-1]),
                where="post", color="k", linewidth=1.0)
    axs[0].set_ylabel("vehicle speed (m/s)")
    axs[0].set_title(f"{cfg.cycle.upper()}: A/C energy at equal mean cabin temperature "
                     f"(N = {cfg.horizon}, high-fidelity plant)")
    for key in CASES:
        c = study.cases[key]
        run = c.run
        col = _COLORS[key]
        ls = _STYLE[key]
        lw = _WIDTH[key]
        axs[1].plot(run.time, K2C(run.T_cab), color=col, linestyle=ls, lw=lw, label=c.label)
        P = run.P_comp + run.P_bl
        axs[2].step(np.append(run.time[:-1], run.time[-1]), np.append(P, P[-1]), where="post",
                    color=col, linestyle=ls, linewidth=0.8 * lw, label=c.label)
        E = np.concatenate(([0.0], np.cumsum(P) * Ts)) / 1e3
        axs[3].plot(run.time, E, color=col, linestyle=ls, lw=lw,
                    label=f"{c.label}: {c.energy_J / 1e6:.4f} MJ "
                          f"(end-corrected {c.corrected_energy_J / 1e6:.4f} MJ)")
    b = study.cases["B"].run
    axs[1].plot(b.time, K2C(b.T_cab_max), color=_COLORS["B"], linestyle="--", linewidth=0.9,
                label="ICM bound (B)")
    for T in (cfg.T_low, cfg.T_high):
        axs[1].axhline(K2C(T), **_BAND)
    axs[1].axhline(K2C(study.target_mean_K), color="black", linewidth=0.7, linestyle=(0, (1, 3)),
                   label=f"mean T_cab target {K2C(study.target_mean_K):.2f} °C")
    axs[1].set_ylabel("cabin temperature $T_{cab}$ (°C)")
    axs[2].set_ylabel("P_comp + P_bl (W)")
    axs[3].set_ylabel("cumulative energy (kJ)")
    axs[3].set_xlabel("time (s)")
    for ax in axs[1:]:
        ax.legend(fontsize=7, loc="best")
    for ax in axs:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig
