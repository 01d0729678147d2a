"""What a validation of a declared model returns: :class:`DeclaredValidation` (the errors
per channel, prediction step and start, the yardsticks on the same windows, the settings;
``summary()``, ``to_frame()``, ``plot_horizon()`` and a JSON round trip). Written by
:func:`acid.ident.validate.validate_model`; printing lives in the CLI, figures in
``acid.report.validation``."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acid._io import json_safe
from acid.errors import DataError


@dataclass(frozen=True)
class DeclaredValidation:
    """Open-loop errors of a declared model (frozen; printing lives in the CLI, figures in
    ``acid.report.validation``).

    ``errors[channel]`` is (n_starts, horizon): prediction minus measurement at 1..horizon
    steps ahead (NaN where the channel is not recorded or the experiment has ended);
    ``predicted`` and ``measured`` are (n_starts, horizon + 1, channels), step 0 the start
    (model units: K, kg/s, W...). ``metrics[channel]``: ``rmse``, ``mean_abs``,
    ``median_abs``, ``p90_abs``, ``p95_abs``, ``max_abs``, ``fit_percent`` (median over
    the starts of each window's fit, %) and ``fit_percent_pooled``, over steps 1..horizon.
    ``energy[channel]`` (outputs in W): |error| of each window's energy, % of the measured.
    ``horizon`` is in steps of ``Ts`` s (``horizon_s`` the times), ``warmup`` in samples
    (``warmup_s`` in s, as the ``warmup`` given to ``validate_model``).
    """

    model: str
    channels: tuple[str, ...]
    units: tuple[str, ...]
    starts: np.ndarray
    horizon: int
    warmup: int
    Ts: float
    errors: dict
    metrics: dict
    by_horizon: tuple
    notes: tuple[str, ...]
    yardsticks: dict = field(default_factory=dict)
    #: {channel: {"<t>": {"rmse_K", "p90_K", "n"}}} at ``REPORT_TIMES_S`` (the starts that
    #: reach each time); each yardstick has its own under ``yardsticks[name]["by_time"]``.
    by_time: dict = field(default_factory=dict)
    predicted: np.ndarray | None = None
    measured: np.ndarray | None = None
    start_time: np.ndarray | None = None
    energy: dict = field(default_factory=dict)
    #: (n_starts, horizon + 1, inputs) the measured inputs over each window
    inputs: np.ndarray | None = None
    input_names: tuple[str, ...] = ()
    input_units: tuple[str, ...] = ()
    #: how the study was run: parameters' label and provenance, held disturbances, sample
    #: range, placement, estimation samples of the yardsticks
    settings: dict = field(default_factory=dict)
    #: ``by_step()`` as read back from JSON (``from_json_dict``), when the per-start errors
    #: it is computed from are not held; None otherwise
    step_stats: dict | None = field(default=None, repr=False, compare=False)

    @property
    def n_starts(self) -> int:
        return int(self.starts.size)

    @property
    def warmup_s(self) -> float:
        """The warm-up stretch before each start, s (``warmup`` is in samples)."""
        return self.warmup * self.Ts

    @property
    def horizon_s(self) -> np.ndarray:
        """Prediction time of steps 0 .. horizon, s."""
        return np.arange(self.horizon + 1) * self.Ts

    @property
    def window_design(self) -> dict:
        """How the windows lie: start spacing (s), horizon (s), overlap, what is held.

        ``overlap_fraction``: the mean share of a window's ``horizon + 1`` samples that the
        next window also holds; ``max_windows_per_sample``: the most windows one sample
        lies in (one event enters that many starts' errors)."""
        k0, H = np.sort(self.starts), self.horizon
        gaps = np.diff(k0)
        shared = np.clip(H + 1 - gaps, 0, None) / (H + 1)
        cover = np.zeros(int(k0.max()) + H + 2 if k0.size else 1, dtype=int)
        np.add.at(cover, k0, 1)
        np.add.at(cover, k0 + H + 1, -1)
        held = self.settings.get("hold", ())
        return {"starts": self.n_starts,
                "non_overlapping": bool(self.settings.get("non_overlapping", False)),
                "horizon_s": H * self.Ts,
                "start_spacing_s": ({"min": float(gaps.min() * self.Ts),
                                     "median": float(np.median(gaps) * self.Ts),
                                     "max": float(gaps.max() * self.Ts)}
                                    if gaps.size else None),
                "overlap_fraction": float(shared.mean()) if shared.size else 0.0,
                "max_windows_per_sample": int(np.cumsum(cover).max()) if k0.size else 0,
                "held_disturbances": (
                    f"{' and '.join(held)} held at their value at each start over its window"
                    if held else "every disturbance follows its measurement (a preview)")}

    def by_horizon_table(self) -> dict:
        """{"model" | yardstick: {channel: {"<t>": {"rmse_K", "p90_K", "n"}}}} at
        ``REPORT_TIMES_S`` and the horizon; at the scored steps (``by_horizon``) when the
        horizon is shorter than every report time (a fast system sampled in ms)."""
        if any(self.by_time.get(c) for c in self.channels):
            return {"model": self.by_time,
                    **{k: y["by_time"] for k, y in self.yardsticks.items()}}
        # a horizon shorter than every report time: the scored steps instead
        return {"model": _steps_as_times(self.by_horizon, self.channels, self.Ts),
                **{k: _steps_as_times(y.get("by_horizon", []), self.channels, self.Ts)
                   for k, y in self.yardsticks.items()}}

    def to_frame(self):
        """The errors by prediction time as a pandas DataFrame, a row per predictor (the
        model, then each yardstick), channel and time: predictor, channel, time_s, rmse,
        p90_abs, n (the starts scored there)."""
        import pandas as pd

        return pd.DataFrame([{"predictor": who, "channel": c, "time_s": float(t),
                              "rmse": v.get("rmse_K"), "p90_abs": v.get("p90_K"),
                              "n": v.get("n")}
                             for who, chans in self.by_horizon_table().items()
                             for c, times in chans.items() for t, v in times.items()])

    def summary(self) -> str:
        """The validation as text: the windows, one table of RMSE by prediction time (the
        model and each yardstick), the model's metrics over the whole horizon, notes."""
        lines = [f"{self.model}: {self.n_starts} windows of {self.horizon} steps "
                 f"({self.horizon * self.Ts:g} s)"]
        for c, u in zip(self.channels, self.units, strict=True):
            m = self.metrics.get(c, {})
            lines.append(f"  {c} [{u}]: RMSE {m.get('rmse', math.nan):.4g}, fit "
                         f"{m.get('fit_percent', math.nan):.1f} % over steps 1..horizon")
            table = {who: chans.get(c, {}) for who, chans in self.by_horizon_table().items()}
            times = list(table.get("model", {}))
            if times:
                width = max(len(w) for w in table)
                heads = [f"{float(t):.4g} s" for t in times]
                cw = max(9, *(len(h) for h in heads))
                lines.append(f"    {'RMSE at':<{width}} " + " ".join(
                    f"{h:>{cw}}" for h in heads))
                for who, row in table.items():
                    lines.append(f"    {who:<{width}} " + " ".join(
                        f"{row.get(t, {}).get('rmse_K', math.nan):>{cw}.4g}" for t in times))
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def plot_horizon(self):
        """A matplotlib figure: the RMSE at every prediction step 1 .. horizon against the
        prediction time, a panel per channel, the model and each yardstick."""
        import matplotlib.pyplot as plt

        steps = self.by_step()
        fig, axes = plt.subplots(len(self.channels), 1, squeeze=False, sharex=True,
                                 figsize=(6.0, 2.2 * len(self.channels)))
        t = self.horizon_s[1:]
        for ax, c, u in zip(axes[:, 0], self.channels, self.units, strict=True):
            for who, chans in steps.items():
                if c in chans:
                    ax.plot(t[:len(chans[c]["rmse"])], np.array(chans[c]["rmse"], float),
                            label=who, lw=2.0 if who == "model" else 1.0)
            ax.set_ylabel(f"{c} RMSE [{u}]")
        axes[-1, 0].set_xlabel("prediction time [s]")
        axes[0, 0].legend(fontsize="small")
        fig.tight_layout()
        return fig

    def __repr__(self) -> str:
        return f"DeclaredValidation(\n{self.summary()}\n)"

    def to_json_dict(self) -> dict:
        """The validation as strict JSON: every metric, each prediction step 1 .. horizon of
        the model and the yardsticks (``by_step``), the chosen horizons, the settings and
        notes; the per-start arrays behind the figures (errors, predictions, measurements,
        inputs) are left out. ``from_json_dict`` reads it back."""
        return json_safe({
            "model": self.model, "horizon": self.horizon, "warmup": self.warmup,
            "warmup_s": self.warmup_s,
            "Ts": self.Ts, "n_starts": int(self.starts.size),
            "starts": self.starts.tolist(),
            "start_time_s": None if self.start_time is None else self.start_time.tolist(),
            "inputs_of_windows": {"names": list(self.input_names),
                                  "units": list(self.input_units)},
            "metrics_over": "all starts, prediction steps 1 .. horizon",
            "channels": {c: {"unit": u, **self.metrics[c]}
                         for c, u in zip(self.channels, self.units, strict=True)},
            "energy": self.energy, "window_design": self.window_design,
            "settings": self.settings,
            "by_horizon": list(self.by_horizon), "notes": list(self.notes),
            "yardsticks": {k: {n: v for n, v in y.items() if n not in ("rmse_by_step", "errors")}
                           for k, y in self.yardsticks.items()},
            "by_time": self.by_time,
            "yardsticks_by_time": {k: y["by_time"] for k, y in self.yardsticks.items()},
            "by_step": self.by_step()})

    @classmethod
    def from_json_dict(cls, d: dict) -> DeclaredValidation:
        """The validation ``to_json_dict`` (or ``acid validate --json``, which writes the
        same keys beside its own) wrote: ``from_json_dict(v.to_json_dict()) == v``. Its
        summary, frame, horizon figure and JSON are the original's; the per-start arrays
        behind Figs. 5-6 are not in the JSON (``errors`` empty, ``predicted`` None).
        Non-finite numbers, stored as null, come back as NaN."""
        try:
            chans = d["channels"]
            names = tuple(chans)
            ys = {k: {**y, "channels": {c: _nan_floats(m) for c, m in y["channels"].items()},
                      "by_horizon": [_nan_floats(r) for r in y["by_horizon"]],
                      "by_time": _nan_floats(d["yardsticks_by_time"][k])}
                  for k, y in d["yardsticks"].items()}
            settings = dict(d["settings"])
            if "hold" in settings:
                settings["hold"] = tuple(settings["hold"])
            io = d.get("inputs_of_windows", {})
            t0 = d.get("start_time_s")
            return cls(
                model=d["model"], channels=names,
                units=tuple(chans[c]["unit"] for c in names),
                starts=np.asarray(d["starts"], dtype=int), horizon=int(d["horizon"]),
                warmup=int(d["warmup"]), Ts=float(d["Ts"]), errors={},
                metrics={c: _nan_floats({k: v for k, v in chans[c].items() if k != "unit"})
                         for c in names},
                by_horizon=tuple(_nan_floats(r) for r in d["by_horizon"]),
                notes=tuple(d["notes"]), yardsticks=ys, by_time=_nan_floats(d["by_time"]),
                start_time=None if t0 is None else np.asarray(t0, dtype=float),
                energy=_nan_floats(d["energy"]), input_names=tuple(io.get("names", ())),
                input_units=tuple(io.get("units", ())), settings=settings,
                step_stats=_nan_floats(d["by_step"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise DataError(f"not a validation summary (acid validate --json): missing or "
                            f"malformed {exc}") from None

    @classmethod
    def from_json(cls, path: str | Path) -> DeclaredValidation:
        """``from_json_dict`` of the JSON file ``path`` (``acid validate --json``)."""
        import json

        try:
            d = json.loads(Path(path).read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise DataError(f"{path}: cannot read a validation summary: {exc}") from None
        return cls.from_json_dict(d)

    def __eq__(self, other) -> bool:
        """Equal when their JSON is (arrays by value, NaN equal to NaN)."""
        if not isinstance(other, DeclaredValidation):
            return NotImplemented
        return self.to_json_dict() == other.to_json_dict()

    __hash__ = None

    def by_step(self) -> dict:
        """{"model" | yardstick: {channel: {"rmse", "p90_abs", "n"}}}: lists over every
        prediction step 1 .. horizon (the starts scored at each step), none left out."""
        if self.step_stats is not None and not self.errors:
            return self.step_stats
        out = {"model": self.errors, **{k: y.get("errors", {})
                                        for k, y in self.yardsticks.items()}}
        return {k: {c: _step_stats(e) for c, e in errs.items()} for k, errs in out.items()}


def _nan_floats(obj):
    """JSON's null (a non-finite number) as NaN, recursively through dicts and lists."""
    if isinstance(obj, dict):
        return {k: _nan_floats(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_nan_floats(v) for v in obj]
    return math.nan if obj is None else obj


def _step_stats(e: np.ndarray) -> dict:
    """RMSE, p90 |e| and count of the finite errors at each step (column) of ``e``."""
    ok = np.isfinite(e)
    n = ok.sum(axis=0)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        r = np.sqrt(np.nanmean(np.where(ok, e, np.nan) ** 2, axis=0))
        p = np.nanpercentile(np.abs(np.where(ok, e, np.nan)), 90, axis=0)
    return {"rmse": r.tolist(), "p90_abs": p.tolist(),
            "n": n.astype(int).tolist()}


def _steps_as_times(rows, channels, Ts) -> dict:
    """``by_horizon`` rows ({"step", channel: {"rmse", "p90_abs", "n"}}) in the shape of
    ``by_time``: {channel: {"<t>": {"rmse_K", "p90_K", "n"}}}, t = step * Ts in s."""
    out: dict = {c: {} for c in channels}
    for r in rows:
        for c in channels:
            if c in r:
                out[c][f"{r['step'] * Ts:g}"] = {"rmse_K": r[c].get("rmse"),
                                                  "p90_K": r[c].get("p90_abs"),
                                                  "n": r[c].get("n")}
    return out

