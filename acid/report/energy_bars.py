"""Energy charts whose differences can be read: each controller's energy as a difference
against the best simple baseline, per group (drive cycle), instead of full bars from zero
that all look equal when they differ by 5 %.

Builds ``matplotlib.figure.Figure`` objects directly (no pyplot state); save with
``acid._io.save_figure`` or ``acid.report.figures.save_report_figure``. Differences in % of
the baseline's energy (negative: less energy than the baseline), energies in MJ.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from matplotlib.figure import Figure


@dataclass(frozen=True)
class EnergyBars:
    """What a difference chart shows, as plain data.

    Attributes
    ----------
    groups : group labels (drive cycles), in order.
    baseline : per group, the name of the controller the others are compared with.
    energy_MJ : ``{group: {controller: energy, MJ}}``; a controller missing from a group is
        not drawn there.
    flagged : ``{group: controllers}`` drawn hatched (e.g. outside the humidity band).
    title, flag_meaning : the chart's title and what a hatched bar means.
    labels : how a group is named under its bars (default: its name).
    """

    groups: tuple[str, ...]
    baseline: Mapping[str, str]
    energy_MJ: Mapping[str, Mapping[str, float]]
    flagged: Mapping[str, tuple[str, ...]]
    title: str
    flag_meaning: str = ""
    labels: Mapping[str, str] = field(default_factory=dict)

    def difference_pct(self, group: str, controller: str) -> float:
        """``100 (E_controller - E_baseline) / E_baseline`` in ``group``, % (NaN if absent)."""
        e = self.energy_MJ[group]
        base = e.get(self.baseline[group], math.nan)
        x = e.get(controller, math.nan)
        if not (math.isfinite(base) and math.isfinite(x)) or base == 0.0:
            return math.nan
        return 100.0 * (x - base) / base


def difference_figure(bars: EnergyBars, controllers: Sequence[str],
                      colors: Mapping[str, str] | None = None) -> Figure:
    """Grouped bars of each controller's energy difference against its group's baseline, %.

    The zero line is the baseline; every bar is labelled with its value (horizontal text);
    the x tick of each group names the baseline and its energy in MJ; the legend sits to the
    right of the axes, clear of the bars. Controllers without a value anywhere are left out.
    """
    shown = [c for c in controllers
             if any(c != bars.baseline[g] and c in bars.energy_MJ[g] for g in bars.groups)]
    fig = Figure(figsize=(max(6.5, 1.3 * len(bars.groups) * max(len(shown), 1) / 3 + 3.0),
                          4.6), layout="constrained")
    ax = fig.subplots()
    width = 0.8 / max(len(shown), 1)
    x = np.arange(len(bars.groups))
    for j, key in enumerate(shown):
        vals = np.array([math.nan if key == bars.baseline[g]
                         else bars.difference_pct(g, key) for g in bars.groups])
        pos = x + (j - (len(shown) - 1) / 2) * width
        drawn = ax.bar(pos, np.nan_to_num(vals, nan=0.0), width,
                       color=(colors or {}).get(key), label=key, alpha=0.9)
        for b, v, g in zip(drawn, vals, bars.groups, strict=True):
            if not math.isfinite(v):
                b.set_visible(False)
                continue
            if key in bars.flagged.get(g, ()):
                b.set_hatch("//")
            ax.annotate(f"{v:+.1f}", (b.get_x() + b.get_width() / 2, v),
                        xytext=(0, 2 if v >= 0 else -2), textcoords="offset points",
                        ha="center", va="bottom" if v >= 0 else "top", fontsize=7)
    ax.axhline(0.0, color="0.25", lw=1.0)
    ax.set_xticks(x, [_group_tick(bars, g) for g in bars.groups])
    ax.set_ylabel("energy vs the baseline (%)\n(below 0: less energy)")
    ax.set_title(bars.title, fontsize=9)
    ax.use_sticky_edges = False   # room beyond the zero line and the longest bar's label
    ax.margins(y=0.15)
    ax.grid(True, axis="y", alpha=0.3)
    if shown:
        handles, labels = ax.get_legend_handles_labels()
        if bars.flag_meaning and any(bars.flagged.values()):
            from matplotlib.patches import Patch

            handles.append(Patch(facecolor="white", edgecolor="0.3", hatch="//"))
            labels.append(bars.flag_meaning)
        ax.legend(handles, labels, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return fig


def _group_tick(bars: EnergyBars, group: str) -> str:
    base = bars.baseline[group]
    e = bars.energy_MJ[group].get(base)
    energy = f"{base} = {e:.3g} MJ" if e is not None else f"no {base}"
    return f"{bars.labels.get(group, group)}\n{energy}"


def cav_energy_bars(result, baselines: Sequence[str] = ("F", "P", "A")) -> EnergyBars:
    """The drive-cycle study (``acid.studies.cav_study.CavStudyResult``) as an ``EnergyBars``:
    tail-corrected energies; the baseline of each cycle is the best (least energy) of the
    simple controllers ``baselines`` present in it (the fixed-coil PI F, the PI with a coil
    reset P, the paper's NMPC A)."""
    groups = tuple(result.cycles)
    energy, base, flagged = {}, {}, {}
    for name, st in result.cycles.items():
        energy[name] = {k: r.tail_corrected_J / 1e6 for k, r in st.results.items()}
        simple = [k for k in baselines if k in energy[name]]
        if not simple:
            raise ValueError(f"cycle {name!r}: none of the baselines {baselines} ran")
        base[name] = min(simple, key=lambda k: energy[name][k])
        flagged[name] = tuple(k for k in st.results if not st.in_rh_band(k))
    return EnergyBars(groups=groups, baseline=base, energy_MJ=energy, flagged=flagged,
                      title="A/C energy (compressor + blower, end state charged back) at equal "
                            "mean cabin temperature,\nagainst the best simple controller of "
                            "each cycle (named under it)",
                      flag_meaning="outside the RH band",
                      labels={g: g.upper() for g in groups})


def sweep_energy_bars(df, baseline: str) -> EnergyBars:
    """A sweep's results table as an ``EnergyBars``: per drive cycle, each controller's mean
    energy over the other conditions against the sweep's ``baseline`` controller."""
    ok = df[df["status"] == "ok"]
    groups = tuple(str(c) for c in dict.fromkeys(ok["cycle"]))
    energy = {str(c): {str(k): float(v) for k, v in g.groupby("controller")["energy_MJ"]
                       .mean().items()}
              for c, g in ok.groupby("cycle", sort=False)}
    return EnergyBars(groups=groups, baseline={g: baseline for g in groups},
                      energy_MJ={g: energy[g] for g in groups}, flagged={},
                      title=f"A/C energy per drive cycle against {baseline} (mean over the "
                            "other conditions)")


__all__ = ["EnergyBars", "cav_energy_bars", "difference_figure", "sweep_energy_bars"]
