"""Figures of the high-fidelity plant studies (paper Fig. 3 and Table I) from result objects.

Builds ``matplotlib.figure.Figure`` objects directly (no pyplot state, Agg-safe); save them
with ``acid._io.save_figure``. Temperatures in degC, powers in W, energy in MJ, time in s.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from acid.paper import TABLE_I
from acid.plant.sweep import SweepResult
from acid.units import K2C


def sweep_figure(result: SweepResult, beside: SweepResult | None = None,
                 labels: tuple[str, str] = ("paper vehicle", "acid's default vehicle")
                 ) -> Figure:
    """Paper Fig. 3 and Table I: responses and energy at constant vehicle speeds.

    Panels: cabin air temperature T_cab (degC), compressor power P_comp (W), condensing
    temperature T_c (degC) and blower power P_bl (W) against time (s), one line per speed,
    of ``result``; bars of the compressor + blower energy (MJ) per speed of ``result``
    (``labels[0]``), of ``beside`` (``labels[1]``, another vehicle at the same speeds, when
    given) and the paper's Table I values.
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
        for s, same in _distinct_traces(result.traces[name]):
            y = result.traces[name][s]
            speeds = ", ".join(f"{result.speeds_mps[k]:g}" for k in same)
            ax.plot(t, K2C(y) if is_temp else y, color=colors[s], lw=1.0 + 0.2 * (S - 1 - s),
                    ls=_LINESTYLES[s % len(_LINESTYLES)], label=f"{speeds} m/s")
        ax.set_ylabel(label)
        ax.set_xlabel("time (s)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(title="vehicle speed", fontsize=8, ncols=2)
    axes[0].set_title(f"traces: {labels[0]}", fontsize=9, loc="left")

    x = np.arange(S)
    series = [(result.energy_MJ, f"{labels[0]} (compressor + blower)", "tab:blue")]
    if beside is not None:
        if not np.array_equal(beside.speeds_mps, result.speeds_mps):
            raise ValueError("sweep_figure: the vehicle beside was run at other speeds")
        series.append((beside.energy_MJ, labels[1], "tab:orange"))
    # the paper's bars only beside a run of the paper's length (a shorter run uses less)
    p_vals = [TABLE_I.energy_at(v) if abs(result.duration_s - TABLE_I.duration_s) < 1e-9
              else None for v in result.speeds_mps]
    p_vals = np.array([math.nan if p is None else p for p in p_vals])
    if np.any(np.isfinite(p_vals)):
        series.append((p_vals, "paper Table I (CoolSim)", "0.6"))
    w = 0.8 / len(series)
    for k, (vals, label, color) in enumerate(series):
        xs = x + (k - (len(series) - 1) / 2) * w
        ax_bar.bar(xs, vals, width=w, color=color, label=label)
        if k < len(series) - (1 if np.any(np.isfinite(p_vals)) else 0):
            for xi, e in zip(xs, vals, strict=True):
                ax_bar.text(xi, e, f"{e:.2f}", ha="center", va="bottom", fontsize=7)
    ax_bar.set_xticks(x, [f"{v:g}" for v in result.speeds_mps])
    ax_bar.set_xlabel("vehicle speed (m/s)")
    ax_bar.set_ylabel(f"A/C energy over {result.duration_s:g} s (MJ)")
    ax_bar.legend(fontsize=8, loc="lower left")
    ax_bar.grid(True, axis="y", alpha=0.3)
    ratio = f"E({result.speeds_mps[-1]:g} m/s) / E({result.speeds_mps[0]:g} m/s) = " \
            f"{result.ratio_last_first:.3f} ({labels[0]})"
    if beside is not None:
        ratio += f", {beside.ratio_last_first:.3f} ({labels[1]})"
    fig.suptitle(f"Speed sensitivity, nominal controller: {ratio}; paper "
                 f"{TABLE_I.energy_MJ[-1] / TABLE_I.energy_MJ[0]:.2f}")
    return fig


def _distinct_traces(traces) -> list[tuple[int, list[int]]]:
    """[(row, rows with the same trace)] for the rows of ``traces``: speeds whose traces are
    equal (a blower at its maximum at every speed) are drawn once, labelled with all of them,
    instead of as lines hidden under each other."""
    out: list[tuple[int, list[int]]] = []
    for s, y in enumerate(traces):
        for first, same in out:
            ref = traces[first]
            if np.allclose(y, ref, rtol=1e-9, atol=1e-9 * max(1.0, float(np.nanmax(np.abs(ref))))):
                same.append(s)
                break
        else:
            out.append((s, [s]))
    return out


#: one dash pattern per speed as well as a colour, and earlier (lower) lines wider: close or
#: equal curves (T_cab tracks the same set-point at every speed, the blower saturates) stay
#: distinguishable (checked by ``acid.report.audit``)
_LINESTYLES = ("-", (0, (5, 1.5)), (0, (3, 1.5, 1, 1.5)), (0, (1, 1.2)), (0, (7, 2, 1, 2)),
               (0, (2, 2)))


def _colormap():
    from matplotlib import colormaps

    return colormaps["viridis"]


def plant_check_figures(result) -> dict[str, Figure]:
    """Figures of ``acid plant-check`` from a ``PlantCheckResult`` (nothing computed here).

    ``"plant_check_energy"``: Table I beside the paper (with and without the condenser fan)
    and the steady COP map; ``"plant_check_service"``: idle pressures against the service
    chart's bands, and the pull-down traces against the JAF user test.
    """
    figs = {}
    fig = Figure(figsize=(11.0, 4.5), layout="constrained")
    ax1, ax2 = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    t = result.table_i
    if t:
        x = np.arange(len(t["speeds_mps"]))
        ax1.bar(x - 0.27, t["energy_MJ"], width=0.27, color="tab:blue",
                label="plant: compressor + blower")
        ax1.bar(x, t["energy_with_fan_MJ"], width=0.27, color="tab:cyan",
                label="plant: + condenser fan")
        ax1.bar(x + 0.27, t["paper_MJ"], width=0.27, color="0.6", label="paper Table I")
        ax1.set_xticks(x, [f"{v:g}" for v in t["speeds_mps"]])
        ax1.legend(fontsize=8, loc="lower left")
    ax1.set_xlabel("vehicle speed (m/s)")
    ax1.set_ylabel("A/C energy over 600 s (MJ)")
    ax1.set_title("(a) Table I")
    ax1.grid(True, axis="y", alpha=0.3)
    cm = result.cop_map
    if cm:
        N = cm["grid"]["N_rpm"]
        for key, vals in cm["cop"].items():
            Ta, v = key.split("_")
            ax2.plot(N, vals, marker="o", ls="-" if v == "0mps" else "--",
                     label=f"{Ta[:-1]} °C, {v[:-3]} m/s")
        ax2.legend(fontsize=7, ncols=2)
    ax2.set_xlabel("compressor speed (rpm)")
    ax2.set_ylabel("steady COP Q_e / P_comp (1)")
    ax2.set_title("(f) steady COP, evaporator wall 5 °C")
    ax2.grid(True, alpha=0.3)
    figs["plant_check_energy"] = fig

    fig = Figure(figsize=(11.0, 4.5), layout="constrained")
    ax1, ax2 = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    s = result.service
    if s:
        for T, (hlo, hhi, llo, lhi) in s["chart"].items():
            T = float(T)
            ax1.plot([T, T], [hlo, hhi], color="0.6", lw=8, alpha=0.6)
            ax1.plot([T, T], [llo, lhi], color="0.6", lw=8, alpha=0.6)
        ax1.plot(s["ambient_C"], s["high_kPa"], "o-", color="tab:red", label="plant high side")
        ax1.plot(s["ambient_C"], s["low_kPa"], "o-", color="tab:blue", label="plant low side")
        ax1.plot([], [], color="0.6", lw=8, alpha=0.6, label="service chart band")
        ax1.set_yscale("log")
        ax1.legend(fontsize=8)
    ax1.set_xlabel("ambient temperature (°C)")
    ax1.set_ylabel("idle pressure (kPa gauge)")
    ax1.set_title("(d) idle service chart")
    ax1.grid(True, alpha=0.3)
    p = result.pulldown
    if p:
        for label, name in (("jaf", "55 °C soak (JAF conditions)"),
                            ("hot43", "60 °C soak, 43 °C, 1000 W/m²")):
            d = p.get(label)
            if not d:
                continue
            tt = np.asarray(d["time_s"]) / 60.0
            ax2.plot(tt, d["T_cab_C"], label=f"T_cab, {name}")
        ax2.errorbar([10.0], [28.5], yerr=[[1.0], [1.0]], fmt="s", color="k", capsize=4,
                     label="JAF 2016: 27.5-29.5 °C at 10 min")
        ax2.axhline(25.0, color="0.5", ls=":", lw=1)
        from acid.studies.credentials.plant import HOT_PULLDOWN_MIN as lo_hi

        ax2.axvspan(*lo_hi, color="0.85", alpha=0.5,
                    label=f"design target: 25 °C after {lo_hi[0]:g}-{lo_hi[1]:g} min")
        ax2.legend(fontsize=8)
    ax2.set_xlabel("time (min)")
    ax2.set_ylabel("cabin air temperature (°C)")
    ax2.set_title("(e) pull-down at standstill")
    ax2.grid(True, alpha=0.3)
    figs["plant_check_service"] = fig
    return figs
