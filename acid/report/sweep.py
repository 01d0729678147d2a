"""Summary figures of a scenario sweep (``acid sweep``) from its results table.

Builds ``matplotlib.figure.Figure`` objects directly (no pyplot state, Agg-safe); save them
with ``acid._io.save_figure``. Temperatures in degC, energy in MJ, savings and energy
differences in %.
"""

from __future__ import annotations

import json

import numpy as np
from matplotlib.figure import Figure


def _ok(df):
    return df[df["status"] == "ok"]


def saving_figure(df, baseline: str) -> Figure:
    """Saving against the baseline vs ambient temperature, one series per controller.

    Every successful scenario is a dot (raw saving, %); the line joins the mean at each
    ambient; where the end state was charged back (``tail_s`` > 0) the corrected mean is
    drawn dashed.
    """
    fig = Figure(figsize=(7.5, 4.5), layout="constrained")
    ax = fig.add_subplot()
    ok = _ok(df)
    others = [c for c in dict.fromkeys(ok["controller"]) if c != baseline]
    cmap = _colors(len(others))
    for i, label in enumerate(others):
        g = ok[ok["controller"] == label]
        x = g["ambient_C"].to_numpy(float)
        y = g["saving_pct"].to_numpy(float)
        ax.scatter(x, y, s=14, alpha=0.45, color=cmap[i])
        means = g.groupby("ambient_C")[["saving_pct", "saving_tail_corrected_pct"]].mean()
        ax.plot(means.index, means["saving_pct"], "-o", color=cmap[i], ms=4,
                label=f"{label} (mean)")
        corr = means["saving_tail_corrected_pct"]
        if corr.notna().any():
            ax.plot(means.index, corr, "--", color=cmap[i], label=f"{label}, end state "
                                                                   "charged back")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("ambient temperature (°C)")
    ax.set_ylabel(f"energy saving vs {baseline} (%)")
    ax.set_title("Saving against ambient, per controller (compressor + blower energy)")
    if others:
        ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def energy_figure(df) -> Figure:
    """A/C energy per drive cycle and controller against the sweep's baseline controller
    (the table's ``baseline`` column): the mean over the other conditions as a difference in
    % of the baseline's (``acid.report.energy_bars``), so that a 5 % difference can be read."""
    from acid.report.energy_bars import difference_figure, sweep_energy_bars

    ok = _ok(df)
    baseline = str(ok["baseline"].iloc[0]) if len(ok) and "baseline" in ok else ""
    controllers = [str(c) for c in dict.fromkeys(ok["controller"])]
    cmap = dict(zip(controllers, _colors(len(controllers)), strict=True))
    return difference_figure(sweep_energy_bars(df, baseline), controllers, cmap)


def prediction_figure(df, econ: str, references: list[str], plan: str | None = None
                      ) -> Figure:
    """Where prediction pays: per scenario, the saving of the economic NMPC ``econ`` against
    each PI reference (bars), and the best known plan's against the first reference (black
    marker on that bar, whisker its spread): the distance from the bar's top to the marker
    is the gap to the plan. A hatched bar's reference missed the econ's mean cabin
    temperature (not equal comfort). Savings tail-corrected, %."""
    ok = _ok(df)
    first = ok.drop_duplicates("scenario").set_index("scenario")
    labels = first["label"].map(_short_label)
    if "warmup_s" in first:  # a pull-down from the soak says so
        labels = labels.where(first["warmup_s"] > 0, labels + ", from the soak")
    scen = list(labels.index)
    fig = Figure(figsize=(max(7.5, 1.1 * len(scen) + 2.0), 5.0), layout="constrained")
    ax = fig.add_subplot()
    x = np.arange(len(scen))
    width = 0.8 / max(len(references), 1)
    cmap = _colors(len(references) + 1)
    from acid.studies.sweep.results import corrected_saving, unequal_comfort

    bad = {s: set(unequal_comfort(g, econ, references)) for s, g in ok.groupby("scenario")}
    for i, ref in enumerate(references):
        y = corrected_saving(ok, econ, ref).reindex(scen).to_numpy(float)
        bars = ax.bar(x - 0.4 + width * (i + 0.5), y, width, color=cmap[i],
                      label=f"{econ} vs {ref}")
        for b, s in zip(bars, scen, strict=True):
            if ref in bad.get(s, ()):
                b.set_hatch("//")
                b.set_alpha(0.45)
    if any(bad.values()):
        ax.bar([np.nan], [np.nan], color="white", edgecolor="0.3", hatch="//",
               label="hatched: the reference missed the mean T_cab (not equal comfort)")
    if plan is not None and plan in set(ok["controller"]):
        y = corrected_saving(ok, plan, references[0]).reindex(scen).to_numpy(float)
        g = ok[ok["controller"] == plan].set_index("scenario").reindex(scen)
        spread = [json.loads(s).get("plan_spread_pct") if isinstance(s, str) else None
                  for s in g.get("info", [None] * len(scen))]
        err = np.array([s if s is not None and np.isfinite(s) else 0.0 for s in spread])
        ax.errorbar(x - 0.4 + 0.5 * width, y, yerr=0.5 * err, fmt="D", color="k", ms=5,
                    capsize=3,
                    label=f"best known plan vs {references[0]} (whisker: its spread)")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xticks(x, [labels[s] for s in scen], fontsize=7, rotation=20, ha="right")
    ax.set_ylabel("saving, end state charged back (%)")
    ax.set_title("Where prediction pays beyond a tuned PI (compressor + blower energy)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    return fig


def _short_label(label: str) -> str:
    """A scenario label without its set-point and refrigerant (fits under a bar)."""
    parts = [p.strip() for p in str(label).split(",")]
    return ", ".join(p for p in parts if not p.startswith(("R1", "R7", "set ")))


def _colors(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    return [cmap(i % 10) for i in range(max(n, 1))]


__all__ = ["saving_figure", "energy_figure", "prediction_figure"]
