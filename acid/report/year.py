"""The whole-year figure from ``acid.plant.year.YearResult``: the share of range the
climate costs, and the climate energy, against ambient (degC).

One colour per drive cycle, one marker per vehicle (the first filled, the others hollow);
solid: with the heat pump (and the A/C above the switch-over), dashed: the coolant heater
alone (below the switch-over only; above it both systems share the cooling point). Builds a
``matplotlib.figure.Figure`` directly; save it with ``acid._io.save_figure``.
"""

from __future__ import annotations

from matplotlib.figure import Figure

from acid.plant.year import HEAT_PUMP, HEATER_ONLY, YearResult
from acid.units import K2C

_MARKERS = ("o", "s", "^", "D", "v", "P")


def year_figure(result: YearResult) -> Figure:
    """Two panels against ambient: share of range (%), climate energy per km (Wh/km)."""
    fig = Figure(figsize=(11.0, 5.6), layout="constrained")
    ax_share, ax_energy = fig.subplots(1, 2)
    colors = {c: f"C{i}" for i, c in enumerate(result.cycles)}
    for iv, vehicle in enumerate(result.vehicles):
        for cycle in result.cycles:
            for heating, style in ((HEAT_PUMP, "-"), (HEATER_ONLY, "--")):
                pts = result.select(cycle, vehicle, heating)
                if heating == HEATER_ONLY:
                    pts = [p for p in pts if p.mode == "heating"]
                if not pts:
                    continue
                x = [K2C(p.T_amb_K) for p in pts]
                # the first vehicle filled, the others hollow and larger: lines that coincide
                # (the heater alone heats the same cabin in both vehicles) stay visible
                kw = {"color": colors[cycle], "linestyle": style,
                      "marker": _MARKERS[iv % len(_MARKERS)], "markersize": 5.0 + 3.0 * iv,
                      "markerfacecolor": colors[cycle] if iv == 0 else "none",
                      "label": f"{cycle}, {vehicle}, {heating}"}
                ax_share.plot(x, [100.0 * p.share for p in pts], **kw)
                ax_energy.plot(x, [1000.0 * p.E_climate_kWh / p.distance_km for p in pts],
                               **kw)
    for ax in (ax_share, ax_energy):
        ax.axvline(result.switch_C, color="0.6", linewidth=0.8)
        ax.set_xlabel("ambient (°C)")
        ax.grid(alpha=0.3)
    ax_share.set_ylabel("share of range the climate costs (%)")
    ax_energy.set_ylabel("climate energy (Wh/km)")
    ax_share.set_title(f"heating below {result.switch_C:g} °C, cooling above")
    ax_energy.set_title("compressor + heater + blower + front fan")
    handles, labels = ax_share.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=min(4, max(1, len(labels))),
               fontsize=7)
    return fig


__all__ = ["year_figure"]
