"""Summary figures of a scenario sweep (``acid sweep``) from its results table.

Builds ``matplotlib.figure.Figure`` objects directly (no pyplot state, Agg-safe); save them
with ``acid._io.save_figure``. Temperatures in degC, energy in MJ, savings and energy
differences in %.
"""

from __future__ import annotations

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


def _colors(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    return [cmap(i % 10) for i in range(max(n, 1))]


__all__ = ["saving_figure", "energy_figure"]
