"""Figures of the high-fidelity plant studies (paper Fig. 3 and Table I) from result objects.

Builds ``matplotlib.figure.Figure`` objects directly (no pyplot state, Agg-safe); save them
with ``acid._io.save_figure``. Temperatures in degC, powers in W, energy in MJ, time in s.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from acid.claims import TABLE_I
from acid.plant.sweep import SweepResult
from acid.units import K2C


def sweep_figure(result: SweepResult) -> Figure:
    """Paper Fig. 3 and Table I: responses and energy at constant vehicle speeds.

    Panels: cabin air temperature T_cab (degC), compressor power P_comp (W), condensing
    temperature T_c (degC) and blower power P_bl (W) against time (s), one line per speed;
    bars of the compressor + blower energy (MJ) per speed beside the paper's Table I values.
    """
    fig = Figure(figsize=(11.0, 8.5), layout="constrained")
    gs = fig.add_gridspec(3, 2)
    axes = [fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[0, 1]),
            fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[1, 1])]
    ax_bar = fig.add_subplot(gs[2, :])
    cmap = _colormap()
    S = result.speeds_mps.size
    colors = [cmap(0.1 + 0.8 * s / max(S - 1, 1)) for s in range(S)]
    t = result.time
    panels = (("T_cab", "cabin air $T_{cab}$ (°C)", True),
              ("P_comp", "compressor power $P_{comp}$ (W)", False),
              ("T_c", "condensing temperature $T_c$ (°C)", True),
              ("P_bl", "blower power $P_{bl}$ (W)", False))
    for ax, (name, label, is_temp) in zip(axes, panels, strict=True):
        for s in range(S):
            y = result.traces[name][s]
            ax.plot(t, K2C(y) if is_temp else y, color=colors[s], lw=1.0,
                    ls=_LINESTYLES[s % len(_LINESTYLES)],
                    label=f"{result.speeds_mps[s]:g} m/s")
        ax.set_ylabel(label)
        ax.set_xlabel("time (s)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(title="vehicle speed", fontsize=8, ncols=2)

    x = np.arange(S)
    ax_bar.bar(x - 0.2, result.energy_MJ, width=0.4, color="tab:blue",
               label="acid high-fidelity plant (compressor + blower)")
    # the paper's bars only beside a run of the paper's length (a shorter run uses less)
    p_vals = [TABLE_I.energy_at(v) if abs(result.duration_s - TABLE_I.duration_s) < 1e-9
              else None for v in result.speeds_mps]
    p_vals = [math.nan if p is None else p for p in p_vals]
    if any(math.isfinite(p) for p in p_vals):
        ax_bar.bar(x + 0.2, p_vals, width=0.4, color="0.6", label="paper Table I (CoolSim)")
    for xi, e in zip(x, result.energy_MJ, strict=True):
        ax_bar.text(xi - 0.2, e, f"{e:.2f}", ha="center", va="bottom", fontsize=8)
    ax_bar.set_xticks(x, [f"{v:g}" for v in result.speeds_mps])
    ax_bar.set_xlabel("vehicle speed (m/s)")
    ax_bar.set_ylabel(f"A/C energy over {result.duration_s:g} s (MJ)")
    ax_bar.legend(fontsize=8, loc="lower left")
    ax_bar.grid(True, axis="y", alpha=0.3)
    fig.suptitle(f"Speed sensitivity, nominal controller: E({result.speeds_mps[-1]:g} m/s) / "
                 f"E({result.speeds_mps[0]:g} m/s) = {result.ratio_last_first:.3f} "
                 f"(paper {TABLE_I.energy_MJ[-1] / TABLE_I.energy_MJ[0]:.2f})")
    return fig


#: one dash pattern per speed as well as a colour: close curves (T_cab tracks the same
#: set-point at every speed) stay distinguishable (checked by ``acid.report.audit``)
_LINESTYLES = ("-", (0, (5, 1.5)), (0, (3, 1.5, 1, 1.5)), (0, (1, 1.2)), (0, (7, 2, 1, 2)),
               (0, (2, 2)))


def _colormap():
    from matplotlib import colormaps

    return colormaps["viridis"]
