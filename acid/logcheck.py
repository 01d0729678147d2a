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


# ------------------------------------------------------------- gaps, spikes, ranges
#: The fastest a channel can physically change, in its stored unit per second:
#: (channel names or a name prefix, limit, what it is, why). A step beyond
#: ``limit * dt + tolerance`` between two samples is impossible.
#:
#: Cabin air: the BMW i3's cabin holds about 3 m^3 of air, 3.6 kg x 1005 J/(kg K) = 3.6 kJ/K.
#: Even the largest heat flow the car can put into it, the 5.5 kW high-voltage heater or a
#: cooling capacity of the same order from the 4-5 kW compressor, plus 1 kW of sun, would
#: change that air alone by at most 6.5 kW / 3.6 kJ/K = 1.8 K/s; the seats, dashboard and
#: trim it is bound to (tens of kJ/K) slow it by an order of magnitude. 2 K/s is a bound no
#: real cabin reaches: the 48 BMW i3 trips change by at most 0.2 K/s over 0.1 s steps.
#: Ambient air (a sensor behind the bumper): 1 K/s (the trips: at most 0.5 K/s, a sensor
#: quantised at 0.5 K). Air leaving the evaporator or heater core follows the coil within
#: seconds: 5 K/s (the trips: at most 1.5 K/s outside one corrupted stretch).
RATE_LIMITS = (
    (("T_cab",), 2.0, "cabin air"),
    (("T_amb",), 1.0, "ambient air"),
    (("T_evap", "T_ain"), 5.0, "air after the evaporator or heater core"),
)

#: Values a channel cannot take, in its stored unit: (names or a name prefix, low, high,
#: what it is). Electric powers from the BMW i3's data: the high-voltage coolant heater is
#: rated 5.5 kW, and its LIN reading sits at 7.0 kW in 20 of the 22 winter trips (the rating
#: at nominal voltage; its draw rises with the battery's): above 8 kW is a fault (TripB02
#: logs 36-39 kW for 158 s). The electric compressor draws 4-5 kW at most (the summer trips:
#: 3.3 kW at most): above 6 kW is a fault. A small negative reading (an offset) is tolerated,
#: -100 W. Air temperatures: outside -45 .. 95 degC (the automotive sensors' -40 .. 85 degC
#: with margin) is no air in a car.
RANGE_LIMITS = (
    (("P_heater", "P_heat", "P_hvh", "P_ptc"), -100.0, 8000.0, "the heater's electric power"),
    (("P_comp", "P_ac"), -100.0, 6000.0, "the A/C compressor's electric power"),
    (("T_cab", "T_amb", "T_evap", "T_ain"), -45.0, 95.0, "an air temperature"),
)

#: The units ``RATE_LIMITS`` and ``RANGE_LIMITS`` are written in, by base unit.
LIMIT_UNITS = {"K": "degC", "W": "W"}

#: A glitch is an impossible jump away and one back within this time (longer: a jump).
GLITCH_MAX_S = 60.0

#: Smallest step (stored unit) a sensor's noise or quantisation may add to the rate bound.
RATE_TOLERANCE = 0.5

#: A channel with impossible steps at more than this share of its samples is not judged by
#: its rate (a noisy sensor or another kind of signal than the limit is for).
MAX_JUMP_SHARE = 0.01


def _match(name: str, names: tuple[str, ...]) -> bool:
    return name in names or name.startswith(tuple(n + "_" for n in names))


def rate_limit(name: str) -> tuple[float, str] | None:
    """(limit in the stored unit per s, what) of a channel, or None."""
    for names, limit, what in RATE_LIMITS:
        if _match(name, names):
            return limit, what
    return None


def range_limit(name: str) -> tuple[float, float, str] | None:
    """(low, high, what) of a channel in its stored unit, or None."""
    for names, lo, hi, what in RANGE_LIMITS:
        if _match(name, names):
            return lo, hi, what
    return None


def _step(time: np.ndarray) -> float:
    return float(np.median(np.diff(time))) if time.size > 1 else 1.0


def _times(time: np.ndarray, starts: np.ndarray, most: int = 3) -> str:
    shown = ", ".join(f"{time[s]:.6g}" for s in starts[:most])
    return f"t = {shown}" + (", ..." if starts.size > most else "") + " s"


def nonfinite_stretches(values: np.ndarray, time: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of NaN/inf: (starts, lengths in samples, durations in s = samples x the median
    step)."""
    starts, lengths = _runs(~np.isfinite(values))
    return starts, lengths, lengths * _step(time)


def bridge(values: np.ndarray, bad: np.ndarray, time: np.ndarray, hold: bool) -> np.ndarray:
    """``values`` with the ``bad`` samples replaced from the good ones around them: linear
    interpolation in time (a continuous signal), or the last good value held (a set-point or
    command, held between its changes by design; the next good one before the first). Ends
    take the nearest good value."""
    out = np.array(values, dtype=float)
    good = ~bad
    if not bad.any() or not good.any():
        return out
    if hold:
        idx = np.where(good, np.arange(out.size), -1)
        idx = np.maximum.accumulate(idx)
        first = int(np.argmax(good))
        idx[idx < 0] = first
        return out[idx]
    out[bad] = np.interp(time[bad], time[good], out[good])
    return out


def _tolerance(values: np.ndarray) -> float:
    d = np.diff(values)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return RATE_TOLERANCE
    mad = float(np.median(np.abs(d - np.median(d))))
    return RATE_TOLERANCE + 3 * 1.4826 * mad


def flag_samples(name: str, values: np.ndarray, unit: str, time: np.ndarray
                 ) -> tuple[np.ndarray, list[dict]]:
    """Samples of a measured channel that no sensor working properly gives, and findings.

    ``values`` are finite, in the stored ``unit`` (degC, W). Three kinds of flag:

    * ``"range"``: outside the channel kind's physical range (``RANGE_LIMITS``);
    * ``"glitch"``: a step faster than the channel's physical rate (``RATE_LIMITS``) and a
      step back, the other way, to the level before within ``GLITCH_MAX_S``, the median of
      the samples between off that level by more than the tolerance: those samples (a sensor
      reading 0.0 degC for 10 s in a 25 degC cabin, or a single spike);
    * ``"jump"``: such a step that does not come back: the first sample after it.

    Returns the (N,) bool mask of flagged samples and one finding per kind found
    (``{"channel", "kind", "count", "samples", "first_at_s", "message"}``).
    """
    flagged = np.zeros(values.shape, dtype=bool)
    out: list[dict] = []
    if values.size < 2 or unit != LIMIT_UNITS.get(base_unit(unit)):
        return flagged, out
    rng = range_limit(name)
    if rng is not None:
        lo, hi, what = rng
        bad = (values < lo) | (values > hi)
        if bad.mean() > 0.5:  # most of the record: a wrong unit (``plausibility``), not faults
            bad[:] = False
        if bad.any():
            starts, lengths = _runs(bad)
            flagged |= bad
            peak = float(values[bad][np.argmax(np.abs(values[bad]))])
            out.append(_finding(name, "range", starts, lengths, time,
                                f"outside {what}'s range "
                                f"{_fmt(lo)} .. {_fmt(hi)} {unit} (up to {_fmt(peak)} {unit})"))
    rate = rate_limit(name)
    if rate is not None:
        limit, what = rate
        v = np.where(flagged, np.nan, values)
        ok = np.flatnonzero(np.isfinite(v))
        tv, vv = time[ok], v[ok]
        tol = _tolerance(vv)
        jumps = np.flatnonzero(np.abs(np.diff(vv)) > limit * np.diff(tv) + tol)
        if jumps.size > MAX_JUMP_SHARE * vv.size + 10:  # noise beyond the tolerance, or the
            jumps = jumps[:0]                           # wrong channel kind: not judged
        glitch_starts, glitch_lengths, lone = [], [], []
        p = 0
        while p < jumps.size:
            j = jumps[p]
            back = None
            for q in range(p + 1, jumps.size):
                k = jumps[q]
                if tv[k + 1] - tv[j + 1] > GLITCH_MAX_S:
                    break
                if np.sign(vv[k + 1] - vv[k]) == -np.sign(vv[j + 1] - vv[j]) and \
                        abs(vv[k + 1] - vv[j]) <= limit * (tv[k + 1] - tv[j]) + tol and \
                        abs(np.median(vv[j + 1:k + 1]) - (vv[j] + vv[k + 1]) / 2) > tol:
                    back = q      # back to the level before, from a level of its own
                    break
            if back is not None:
                k = jumps[back]
                flagged[ok[j + 1]:ok[k] + 1] = True
                glitch_starts.append(ok[j + 1])
                glitch_lengths.append(ok[k] + 1 - ok[j + 1])
                p = back + 1
            else:
                flagged[ok[j + 1]] = True
                lone.append(ok[j + 1])
                p += 1
        if glitch_starts:
            starts, lengths = np.array(glitch_starts), np.array(glitch_lengths)
            out.append(_finding(name, "glitch", starts, lengths, time,
                                f"{starts.size} glitch{'es' if starts.size > 1 else ''} far "
                                f"from both neighbours (a step faster than {what} can change, "
                                f"{limit:g} {unit}/s, and back)"))
        if lone:
            starts = np.array(lone)
            out.append(_finding(name, "jump", starts, np.ones(starts.size, int), time,
                                f"{starts.size} step{'s' if starts.size > 1 else ''} faster "
                                f"than {what} can change ({limit:g} {unit}/s) that "
                                f"do{'es' if starts.size == 1 else ''} not "
                                f"come back "
                                f"within {GLITCH_MAX_S:g} s (the sample after it flagged)"))
    return flagged, out


def _finding(name: str, kind: str, starts: np.ndarray, lengths: np.ndarray,
             time: np.ndarray, what: str,
             tail: str = "values bridged from the good samples around") -> dict:
    dt = _step(time)
    samples = int(lengths.sum())
    return {"channel": name, "kind": kind, "count": int(starts.size), "samples": samples,
            "longest_s": float(lengths.max()) * dt, "first_at_s": float(time[starts[0]]),
            "at_s": [float(time[s]) for s in starts[:20]],
            "message": f"channel {name!r}: {what}: {samples} sample"
                       f"{'s' if samples > 1 else ''} (longest "
                       f"{float(lengths.max()) * dt:.3g} s) at {_times(time, starts)}: masked "
                       f"in {name}_censored, {tail}"}


def bridged_finding(name: str, starts: np.ndarray, lengths: np.ndarray, time: np.ndarray,
                    hold: bool, limit: float) -> dict:
    """The finding for a channel's NaN/inf stretches bridged at import."""
    how = "the last value held (a set-point or command)" if hold else "linear interpolation"
    n = starts.size
    f = _finding(name, "bridged", starts, lengths, time,
                 f"{n} NaN/inf stretch{'es' if n > 1 else ''} (empty cells) bridged by {how} "
                 f"(max_gap_s = {limit:g} s)", tail="not scored or fitted")
    f["method"] = "hold" if hold else "linear"
    return f
