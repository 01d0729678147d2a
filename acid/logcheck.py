"""What a real log's channels look like: units that contradict the values, clipped
(censored) and quantised sensors. Used by the import (``acid.data``) on every file.

Each check returns findings as plain dicts (they go into the dataset's metadata as JSON):
``{"channel", "kind", "message", ...}`` with ``kind`` one of ``"unit"`` (the values look
like another unit of the same quantity), ``"quantised"`` (the sensor holds values on a few
levels) and ``"held"`` (the channel sits at its maximum or minimum for long runs: a clipped
sensor, a controlled limit or a steady value; :func:`censored_across` decides over several
files).
"""

from __future__ import annotations

import numpy as np

from acid.units import UNIT_SCALES, base_unit, from_base, storage_unit

#: Plausible maximum of a channel's magnitude, in its base unit, when it is not all zero:
#: (channel names or a name prefix, base unit, low, high, what it is).
PLAUSIBLE_MAX = (
    (("v_veh",), "m/s", 15.0 / 3.6, 70.0, "a vehicle speed"),
    (("P_comp", "P_ac"), "W", 20.0, 20e3, "an A/C compressor power"),
    (("P_bl", "P_fan"), "W", 2.0, 3e3, "a blower or fan power"),
    (("W_bl",), "kg/s", 0.005, 1.0, "a blower air mass flow"),
)

#: A car's acceleration beyond this (99.9th percentile of |dv/dt| over 1 s), m/s^2: the
#: speed is not in m/s. Measured on 26 BMW i3 trips: at most 4.3 m/s^2 (km/h read as m/s:
#: at least 6.8).
MAX_ACCELERATION = 6.0

#: A channel is reported as held at an extreme when it sits exactly there for at least this
#: share of the record and for one run at least ``HELD_RUN_S`` long.
#: A channel with at most this many distinct values (and at least 3) over 100 samples or
#: more is quantised, however often it changes.
FEW_LEVELS = 16

HELD_FRACTION = 0.02
HELD_RUN_S = 60.0


def _rule(name: str, base: str):
    for names, b, lo, hi, what in PLAUSIBLE_MAX:
        if b == base and (name in names or name.startswith(tuple(n + "_" for n in names))):
            return lo, hi, what
    return None


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def plausibility(name: str, raw: np.ndarray, unit: str, time: np.ndarray) -> list[dict]:
    """Warnings for a measured channel whose values contradict its declared ``unit``.

    ``raw`` is in the declared unit. A speed, A/C or blower power or blower flow whose
    maximum falls outside the range of such a quantity, or a speed whose accelerations no car
    reaches, gets a finding naming the unit(s) of the same quantity that fit the values.
    """
    base = base_unit(unit)
    rule = _rule(name, base)
    if rule is None or raw.size == 0:
        return []
    lo, hi, what = rule
    peak = float(np.nanmax(np.abs(raw))) if np.isfinite(raw).any() else 0.0
    if peak == 0.0:
        return []
    stored = storage_unit(unit)
    peak_base = peak * UNIT_SCALES[unit][1]
    out = []
    if not lo <= peak_base <= hi:
        likely = [u for u, (b, f, o) in UNIT_SCALES.items()
                  if b == base and o == 0.0 and u != unit and lo <= peak * f <= hi]
        hint = (f"; the values look like {' or '.join(repr(u) for u in likely)}"
                if likely else "")
        out.append({"channel": name, "kind": "unit", "declared": unit, "likely": likely,
                    "message": f"channel {name!r}: maximum {_fmt(peak)} {unit} "
                               + (f"({_fmt(peak_base)} {stored}) " if stored != unit else "")
                               + f"is implausible for {what} "
                               f"({_fmt(from_base(lo, unit))}-{_fmt(from_base(hi, unit))} "
                               f"{unit}){hint}"})
    elif base == "m/s" and time.size > 2:
        acc = _acceleration_p999(raw * UNIT_SCALES[unit][1], time)
        if acc > MAX_ACCELERATION:
            likely = [u for u, (b, f, o) in UNIT_SCALES.items() if b == base and u != unit
                      and f < UNIT_SCALES[unit][1]
                      and acc * f / UNIT_SCALES[unit][1] <= MAX_ACCELERATION]
            hint = f"; the values look like {likely[0]!r}" if likely else ""
            out.append({"channel": name, "kind": "unit", "declared": unit, "likely": likely[:1],
                        "message": f"channel {name!r}: accelerations up to {acc:.3g} m/s^2 "
                                   f"(99.9th percentile over 1 s, declared {unit!r}) are "
                                   f"implausible for a car (at most {MAX_ACCELERATION:g})"
                                   f"{hint}"})
    return out


def _acceleration_p999(v: np.ndarray, time: np.ndarray) -> float:
    dt = float(np.median(np.diff(time)))
    if not (np.isfinite(dt) and dt > 0):
        return 0.0
    lag = max(1, int(round(1.0 / dt)))
    if v.size <= lag:
        return 0.0
    span = time[lag:] - time[:-lag]
    ok = span > 0
    a = np.abs(v[lag:] - v[:-lag])[ok] / span[ok]
    a = a[np.isfinite(a)]
    return float(np.percentile(a, 99.9)) if a.size else 0.0


def _runs(flags: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and lengths of the runs of True in ``flags``."""
    d = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    starts = np.flatnonzero(d == 1)
    return starts, np.flatnonzero(d == -1) - starts


def quantisation(name: str, values: np.ndarray, unit: str, time: np.ndarray) -> dict | None:
    """A finding when the sensor holds its values on a few levels (a quantised sensor,
    logged faster than it reports, possibly with interpolation between levels).

    Held samples are those in runs of at least 3 equal values; the channel is quantised
    when most samples (>= 50 %) are held, on at least 3 levels, or when it takes 3 to
    ``FEW_LEVELS`` distinct values only; the step is the lower quartile of the spacing
    between neighbouring levels.
    """
    v = values[np.isfinite(values)]
    if v.size < 30:
        return None
    change = np.flatnonzero(np.diff(v) != 0) + 1
    run_start = np.concatenate(([0], change))
    run_len = np.diff(np.concatenate((run_start, [v.size])))
    long = run_len >= 3
    held = float(run_len[long].sum()) / v.size
    levels = np.unique(v[run_start[long]])
    distinct = np.unique(v)
    if 3 <= distinct.size <= FEW_LEVELS and v.size >= 100:
        levels, held = distinct, max(held, 0.5)   # few distinct values: quantised whatever
    if held < 0.5 or levels.size < 3:             # how long each is held
        return None
    step = float(np.percentile(np.diff(levels), 25))
    dt = float(np.median(np.diff(time))) if time.size > 1 else float("nan")
    typical = float(np.median(run_len[long] if long.any() else run_len)) * dt
    return {"channel": name, "kind": "quantised", "step": step, "levels": int(levels.size),
            "held_fraction": held, "unit": unit,
            "message": f"channel {name!r}: quantised sensor, {held:.0%} of the samples held "
                       f"on {levels.size} levels, step about {_fmt(step)} {unit} (typical "
                       f"hold {typical:.3g} s)"}


def held_extremes(name: str, values: np.ndarray, unit: str, time: np.ndarray) -> list[dict]:
    """The channel's maximum and minimum where it sits there for long runs.

    A run at exactly 0 of a speed, power or flow is a standing car or a switched-off
    device, not a sensor limit, and is not reported.
    """
    out = []
    v = values
    if v.size < 3 or not np.isfinite(v).all():
        return out
    dt = float(np.median(np.diff(time))) if time.size > 1 else 0.0
    for side, level in (("max", float(v.max())), ("min", float(v.min()))):
        if level == 0.0 and unit != "degC":
            continue
        at = np.abs(v - level) <= 1e-9 * max(1.0, abs(level))
        frac = float(at.mean())
        if frac >= 1.0:
            continue
        _, lengths = _runs(at)
        longest = float(lengths.max()) * dt if lengths.size else 0.0
        if frac >= HELD_FRACTION and longest >= HELD_RUN_S:
            what = "maximum" if side == "max" else "minimum"
            out.append({"channel": name, "kind": "held", "side": side, "level": level,
                        "unit": unit, "fraction": frac, "longest_s": longest,
                        "message": f"channel {name!r}: at its {what} {_fmt(level)} {unit} for "
                                   f"{frac:.0%} of the record (longest run {longest:.0f} s): "
                                   "a clipped sensor, a controlled limit or a steady value"})
    return out


def censored_across(experiments: list[dict]) -> list[dict]:
    """Censoring over several files: a level that is a channel's extreme over *all* files and
    where it sits for long runs in at least two of them (a sensor's or a controller's limit:
    a steady value does not repeat as the overall extreme).

    ``experiments``: ``[{"name": ..., "extremes": {channel: (min, max)}, "checks": [...]}]``.
    """
    if len(experiments) < 2:
        return []
    out = []
    channels = sorted({c for e in experiments for c in e.get("extremes", {})})
    for ch in channels:
        ext = [e["extremes"][ch] for e in experiments if ch in e.get("extremes", {})]
        for side, overall in (("max", max(x[1] for x in ext)), ("min", min(x[0] for x in ext))):
            hits = [(e["name"], f) for e in experiments for f in e.get("checks", [])
                    if f["kind"] == "held" and f["channel"] == ch and f["side"] == side
                    and f["level"] == overall]
            if len(hits) < 2:
                continue
            unit = next(f["unit"] for e in experiments for f in e.get("checks", [])
                        if f["kind"] == "held" and f["channel"] == ch)
            key = "censored_above" if side == "max" else "censored_below"
            names = [n for n, _ in hits]
            shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
            out.append({"channel": ch, "kind": "censored", "side": side, "level": overall,
                        "unit": unit, "files": names,
                        "fraction": float(np.mean([f["fraction"] for _, f in hits])),
                        "longest_s": float(max(f["longest_s"] for _, f in hits)),
                        "message": f"channel {ch!r}: sits at {_fmt(overall)} {unit}, its "
                                   f"{'maximum' if side == 'max' else 'minimum'} over all "
                                   f"{len(experiments)} files, for long runs in {len(names)} "
                                   f"of them ({shown}): a sensor or controller limit; if the "
                                   f"sensor clips there, {key} = {_fmt(overall)} in the "
                                   "map masks it"})
    return out


def gaps(time: np.ndarray, Ts: float | None) -> dict | None:
    """A finding when the record's time jumps: steps longer than 5 times its median step
    (and than ``Ts``), where a logger paused. Resampling interpolates across them."""
    if time.size < 3 or not np.isfinite(time).all():
        return None
    dt = np.diff(time)
    step = float(np.median(dt))
    if not step > 0:
        return None
    limit = max(5 * step, Ts or 0.0)
    where = np.flatnonzero(dt > limit)
    if where.size == 0:
        return None
    longest = float(dt[where].max())
    first = float(time[where[0]])
    return {"channel": "time", "kind": "gap", "count": int(where.size), "longest_s": longest,
            "first_at_s": first,
            "message": f"time jumps {where.size} time(s) by more than {limit:.3g} s (longest "
                       f"{longest:.3g} s, first at t = {first:.6g} s): the logger paused; "
                       "resampling interpolates across a jump"}
