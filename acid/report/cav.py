"""Figures of the drive-cycle energy study (:mod:`acid.studies.cav_study`) from its result objects.

Builds ``matplotlib.figure.Figure`` objects directly (no pyplot state); save with
``acid._io.save_figure``. Speeds in m/s, temperatures in °C, humidity in g/kg, powers in W,
energies in MJ, time in s.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from acid.studies.cav_study import CONTROLLERS, CavStudyResult, CycleStudy
from acid.units import K2C

CONTROLLER_COLORS = {"A": "tab:blue", "B": "tab:orange", "D": "tab:purple", "E": "tab:green",
           "P": "tab:brown", "F": "tab:red", "plan": "black"}
_STYLE = {"A": "-", "B": "-", "D": ":", "E": "-", "P": "-.", "F": "-.", "plan": "--"}
#: A drawn wide under E, F and the plan: where they coincide all stay visible (the report
#: audits every figure for hidden lines)
_WIDTH = {"A": 2.6, "B": 1.6, "D": 1.4, "E": 1.2, "P": 1.4, "F": 1.8, "plan": 1.2}
_Z = {"A": 2, "B": 2, "D": 3, "E": 4, "P": 3, "F": 3, "plan": 3}   # E on top
_BAND = {"color": "tab:red", "linestyle": ":", "linewidth": 1.2}


def energy_figure(result: CavStudyResult) -> Figure:
    """Tail-corrected energy per controller and cycle (grouped bars), savings vs A on top;
    a controller outside the RH band is hatched and labelled "RH"."""
    cycles = list(result.cycles)
    keys = [k for k in CONTROLLERS if any(k in c.results for c in result.cycles.values())]
    fig = Figure(figsize=(max(6.0, 1.6 * len(cycles) + 2.0), 4.8), layout="constrained")
    ax = fig.subplots()
    width = 0.8 / len(keys)
    x = np.arange(len(cycles))
    for j, key in enumerate(keys):
        vals = [c.results[key].tail_corrected_J / 1e6 if key in c.results else np.nan
                for c in result.cycles.values()]
        bars = ax.bar(x + (j - (len(keys) - 1) / 2) * width, vals, width,
                      color=CONTROLLER_COLORS[key], label=key, alpha=0.85)
        if key == "plan":   # the plan's spread over its independent optima
            for b, c in zip(bars, result.cycles.values(), strict=True):
                var = c.results["plan"].extra.get("variants", {}) if "plan" in c.results else {}
                e = [v["tail_corrected_energy_MJ"] for v in var.values() if v["matched"]]
                if len(e) > 1:
                    xc = b.get_x() + b.get_width() / 2
                    ax.vlines(xc, min(e), max(e), color="tab:gray", lw=2.0, zorder=5,
                              label="_spread")
        for b, c in zip(bars, result.cycles.values(), strict=True):
            s = c.saving_pct(key) if key in c.results and key != "A" else None
            out = key in c.results and not c.in_rh_band(key)
            if out:
                b.set_hatch("//")
            if s is not None or out:
                text = ("" if s is None else f"{s:.1f}%") + (" RH" if out else "")
                ax.annotate(text.strip(), (b.get_x() + b.get_width() / 2, b.get_height()),
                            ha="center", va="bottom", fontsize=6, rotation=90)
    ax.set_xticks(x, [c.upper() for c in cycles])
    ax.set_ylabel("energy, end state charged back (MJ)")
    ax.set_title("A/C energy (compressor + blower) at equal mean cabin temperature; "
                 "labels: saving vs A (RH: outside the RH band);\nplan: best known plan, "
                 "perfect information (grey: spread of its independent optima)", fontsize=9)
    ax.legend(fontsize=8, ncols=len(keys), loc="upper center", bbox_to_anchor=(0.5, -0.08))
    ax.grid(True, axis="y", alpha=0.3)
    return fig


def trajectory_figure(study: CycleStudy, keys=("A", "E", "F", "plan")) -> Figure:
    """Speed, T_cab with the band, T_evap_set, W_bl, humidity and power: A, E, the best
    fixed-coil PI F and the best known plan."""
    keys = [k for k in keys if k in study.results]
    fig = Figure(figsize=(10, 12), layout="constrained")
    axs = fig.subplots(6, 1, sharex=True)
    sc = study.scenario
    t = np.arange(sc.n + 1) * sc.Ts
    axs[0].step(t, np.append(sc.v, sc.v[-1]), where="post", color="k", lw=1.0)
    axs[0].set_ylabel("speed (m/s)")
    axs[0].set_title(f"{sc.name.upper()}: paper NMPC (A), economic NMPC with preview (E), "
                     "best fixed-coil PI (F) and the best known plan (perfect information) "
                     "replayed on the plant", fontsize=9)
    for key in keys:
        r = study.results[key]
        run, col, ls = r.run, CONTROLLER_COLORS[key], _STYLE[key]
        lab = f"{key}: {r.tail_corrected_J / 1e6:.4f} MJ (end state charged back)"
        kw = {"color": col, "ls": ls, "lw": _WIDTH[key], "zorder": _Z[key], "label": key}
        axs[1].plot(t, K2C(run.T_cab), **{**kw, "label": lab})
        axs[2].step(t[:-1], K2C(run.T_evap_set), where="post", **kw)
        axs[3].step(t[:-1], run.W_bl, where="post", **kw)
        axs[4].plot(t, 1e3 * run.w_cab, **kw)
        axs[5].step(t[:-1], run.P_comp + run.P_bl, where="post", **{**kw, "lw": 0.8 * kw["lw"]})
    for T in (study.T_low, study.T_high):
        axs[1].axhline(K2C(T), zorder=1, **_BAND)
    axs[1].axhline(K2C(study.target_mean_K), color="grey", lw=0.8, zorder=1,
                   label="_target")   # a reference, often covered by the runs riding it
    axs[1].set_title(f"every run's mean: {K2C(study.target_mean_K):.2f} °C (grey line); "
                     "dotted: the comfort band", fontsize=9)
    axs[1].set_ylabel("$T_{cab}$ (°C)")
    axs[1].legend(fontsize=7, loc="best")
    axs[2].set_ylabel("$T_{evap,set}$ (°C)")
    axs[3].set_ylabel("$W_{bl}$ (kg/s)")
    axs[4].set_ylabel("cabin humidity\n$w_{cab}$ (g/kg)")
    axs[5].set_ylabel("$P_{comp} + P_{bl}$ (W)")
    axs[5].set_xlabel("time (s)")
    for ax in axs:
        ax.grid(True, alpha=0.3)
    return fig
