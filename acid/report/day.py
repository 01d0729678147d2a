"""The figure of ``acid day`` from the traces of ``acid.studies.day.day_trace``: one column per
season; top, the ambient and the cabin under each controller (degC) with the comfort band's
edge; bottom, the climate's electric power (kW) and the hourly price (right axis). Builds a
``matplotlib.figure.Figure`` directly; save it with ``acid._io.save_figure``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

_STYLES = {"none": ("C3", "-"), "timer": ("C0", "--"), "planner": ("C2", ":"),
           "plant-search": ("C1", "-.")}


def day_figure(traces: Mapping[str, Mapping[str, Mapping[str, np.ndarray]]],
               band_C: Mapping[str, float], hourly_price: tuple[float, ...],
               labels: Mapping[str, str]) -> Figure:
    """``traces[season][controller]``: arrays ``t_h``, ``T_amb_C``, ``T_cab_C``,
    ``P_climate_kW``, ``phase``; ``labels[season]`` the panel title."""
    seasons = list(traces)
    fig = Figure(figsize=(6.0 * len(seasons), 7.0), layout="constrained")
    axes = fig.subplots(2, len(seasons), squeeze=False, sharex=True)
    for j, season in enumerate(seasons):
        ax_t, ax_p = axes[0][j], axes[1][j]
        first = next(iter(traces[season].values()))
        ax_t.plot(first["t_h"], first["T_amb_C"], color="0.5", lw=1.2, label="ambient")
        for name, tr in traces[season].items():
            color, ls = _STYLES.get(name, ("C4", "-."))
            ax_t.plot(tr["t_h"], tr["T_cab_C"], color=color, ls=ls, lw=1.3,
                      label=f"cabin, {name}")
            ax_p.plot(tr["t_h"], tr["P_climate_kW"], color=color, ls=ls, lw=1.1,
                      label=f"climate power, {name}")
        ax_t.axhline(band_C[season], color="k", lw=0.8, ls="-.", label="comfort band edge")
        ax_t.set_ylabel("temperature, degC")
        ax_t.set_title(labels.get(season, season), fontsize=10)
        ax_t.legend(fontsize=7, loc="best")
        ax_p.set_ylabel("climate power, kW")
        ax_p.set_xlabel("clock time, h")
        ax_p.legend(fontsize=7, loc="upper left")
        ax_pr = ax_p.twinx()
        hours = np.arange(25)
        ax_pr.step(hours, list(hourly_price) + [hourly_price[-1]], where="post", color="0.6",
                   lw=1.0)
        ax_pr.set_ylabel("price, USD/kWh", color="0.4")
        ax_p.set_xlim(first["t_h"][0], first["t_h"][-1] + 0.2)
    return fig


__all__ = ["day_figure"]
