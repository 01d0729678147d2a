"""Excitation signals and speed profiles, sampled at the model's sample time.

Every random generator takes a ``numpy.random.Generator`` (never global state) and returns
``(signal, spec)``: the (n,) array and a JSON-serialisable dict describing how it was made,
which travels into the dataset's metadata. Dwell times are counted in **samples** here; the
caller (``acid.excite``) converts seconds to samples. Amplitudes are in whatever unit the
caller gives ``low``/``high`` in (kg/s for W_bl, K for temperatures inside the library).

Generators
----------
aprbs : amplitude-modulated PRBS (multi-level random steps with a minimum dwell time).
prbs : maximum-length shift-register sequence (two levels) with a clock period.
multisine : sum of sines on the record's frequency grid, Schroeder or random phases.
slow_exogenous : a slowly wandering temperature (long-dwell APRBS through a first-order lag),
    used to excite T_int / T_shell on the model plant.
constant_speed, drive_cycle : vehicle speed profiles (m/s, mean over each sample period).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from acid.errors import ConfigError, DataError

__all__ = ["aprbs", "prbs", "multisine", "slow_exogenous", "constant_speed", "drive_cycle",
           "available_drive_cycles", "datasets_dir"]


def _check_common(n: int, low: float, high: float) -> None:
    if int(n) < 1:
        raise ConfigError(f"signal length must be at least 1 sample, got {n}")
    if not (math.isfinite(low) and math.isfinite(high)) or not low < high:
        raise ConfigError(f"signal bounds must satisfy low < high, got [{low}, {high}]")


# ------------------------------------------------------------------------------ APRBS
def aprbs(rng: np.random.Generator, n: int, low: float, high: float, min_dwell: int,
          max_dwell: int | None = None, levels: int | None = None) -> tuple[np.ndarray, dict]:
    """Amplitude-modulated PRBS: random levels held for random dwell times.

    Parameters
    ----------
    rng : random generator.
    n : number of samples.
    low, high : amplitude bounds (the signal stays in ``[low, high]``).
    min_dwell, max_dwell : dwell time bounds in samples (uniform integers, inclusive);
        ``max_dwell`` defaults to ``min_dwell`` (constant clock). Only the last segment may
        be shorter than ``min_dwell`` (it is cut by the end of the record).
    levels : ``None`` for levels drawn uniformly in ``[low, high]``; an integer ``L >= 2`` for
        ``L`` equally spaced levels including both bounds (consecutive levels then differ).

    Returns
    -------
    u : (n,) signal.
    spec : generator settings and the realised number of steps.
    """
    _check_common(n, low, high)
    max_dwell = min_dwell if max_dwell is None else max_dwell
    if int(min_dwell) < 1 or int(max_dwell) < int(min_dwell):
        raise ConfigError(f"APRBS dwell must satisfy 1 <= min_dwell <= max_dwell samples, "
                          f"got {min_dwell} .. {max_dwell}")
    if levels is not None and int(levels) < 2:
        raise ConfigError(f"APRBS needs at least 2 levels, got {levels}")
    min_dwell, max_dwell = int(min_dwell), int(max_dwell)
    m = -(-int(n) // min_dwell)  # enough segments to cover n even with the shortest dwell
    dwell = rng.integers(min_dwell, max_dwell + 1, size=m)
    if levels is None:
        values = rng.uniform(low, high, size=m)
    else:
        grid = np.linspace(low, high, int(levels))
        # a random walk on the level indices that never stays put: offsets 1..L-1 modulo L
        steps = rng.integers(1, int(levels), size=m)
        idx = (rng.integers(int(levels)) + np.cumsum(steps) - steps[0]) % int(levels)
        values = grid[idx]
    ends = np.cumsum(dwell)
    n_steps = int(np.count_nonzero(ends < n)) + 1  # segments that reach into the record
    u = np.repeat(values[:n_steps], np.minimum(dwell[:n_steps], n))[:n]
    spec = {"type": "aprbs", "n": int(n), "low": float(low), "high": float(high),
            "min_dwell_samples": min_dwell, "max_dwell_samples": max_dwell,
            "levels": None if levels is None else int(levels), "n_steps": n_steps}
    return u, spec


# ------------------------------------------------------------------------------- PRBS
def prbs(rng: np.random.Generator, n: int, low: float, high: float, dwell: int,
         order: int | None = None) -> tuple[np.ndarray, dict]:
    """Maximum-length binary sequence (MLS) from a linear-feedback shift register.

    Like MATLAB's ``idinput(..., 'prbs', [0 B])``: each register bit is held for ``dwell``
    samples (the clock period, which sets the upper band edge at about ``1/(dwell*Ts)``).

    Parameters
    ----------
    rng : random generator; picks the register's non-zero initial state (the phase).
    n : number of samples.
    low, high : the two levels.
    dwell : clock period in samples (>= 1).
    order : register length m (period 2**m - 1 bits). Default: the smallest m in 3..32
        whose period covers the record (``2**m - 1 >= ceil(n / dwell)``). The sequence
        repeats when the record is longer than one period.

    Returns
    -------
    u : (n,) signal taking only the values ``low`` and ``high``.
    spec : generator settings (order, period in samples, initial state).
    """
    _check_common(n, low, high)
    if int(dwell) < 1:
        raise ConfigError(f"PRBS clock period must be at least 1 sample, got {dwell}")
    dwell = int(dwell)
    n_bits = -(-int(n) // dwell)
    if order is None:
        order = max(3, int(math.ceil(math.log2(n_bits + 1))))
    if not 2 <= int(order) <= 32:
        raise ConfigError(f"PRBS register order must be in 2..32, got {order}")
    order = int(order)
    state = rng.integers(0, 2, size=order).astype(np.int8)
    if not state.any():
        state[rng.integers(order)] = 1
    from scipy.signal import max_len_seq  # lazy: scipy.signal takes ~1 s to import

    bits, _ = max_len_seq(order, state=state.copy(), length=n_bits)
    u = np.where(np.repeat(bits, dwell)[:n] > 0, high, low).astype(float)
    spec = {"type": "prbs", "n": int(n), "low": float(low), "high": float(high),
            "dwell_samples": dwell, "order": order, "period_samples": (2**order - 1) * dwell,
            "initial_state": state.tolist()}
    return u, spec


# --------------------------------------------------------------------------- multisine
def multisine(rng: np.random.Generator, n: int, Ts: float, low: float, high: float,
              band: tuple[float, float] = (1 / 1800, 1 / 50), n_sines: int | None = 24,
              phases: str = "schroeder", period: int | None = None) -> tuple[np.ndarray, dict]:
    """Sum of sines with frequencies on the period's grid, scaled to ``[low, high]``.

    Parameters
    ----------
    rng : random generator (random phases, and the choice of harmonics when thinned).
    n : number of samples.
    Ts : sample time, s.
    low, high : the signal is scaled affinely so that its minimum is ``low`` and maximum
        ``high``.
    band : (f_lo, f_hi) excited band, Hz; must lie below the Nyquist frequency ``1/(2 Ts)``.
    n_sines : number of sines; the harmonics of the period inside the band are thinned to
        this many, evenly spread (``None``: all of them).
    phases : ``"schroeder"`` (low crest factor, deterministic) or ``"random"`` (uniform).
    period : period in samples (default: the whole record), so the frequency grid is
        ``k / (period * Ts)`` and the signal is exactly periodic with that period.

    Returns
    -------
    u : (n,) signal.
    spec : generator settings and the realised frequencies (Hz).
    """
    _check_common(n, low, high)
    period = int(n) if period is None else int(period)
    f_lo, f_hi = float(band[0]), float(band[1])
    nyquist = 0.5 / Ts
    if not 0.0 < f_lo < f_hi <= nyquist:
        raise ConfigError(f"multisine band must satisfy 0 < f_lo < f_hi <= {nyquist:g} Hz "
                          f"(Nyquist at Ts = {Ts:g} s), got ({f_lo:g}, {f_hi:g})")
    if period < 2:
        raise ConfigError(f"multisine period must be at least 2 samples, got {period}")
    df = 1.0 / (period * Ts)
    harmonics = np.arange(int(math.ceil(f_lo / df - 1e-9)), int(math.floor(f_hi / df + 1e-9)) + 1)
    harmonics = harmonics[harmonics >= 1]
    if harmonics.size == 0:
        raise ConfigError(f"multisine band ({f_lo:g}, {f_hi:g}) Hz holds no harmonic of the "
                          f"{period * Ts:g} s period; widen the band or lengthen the period")
    if n_sines is not None and n_sines < harmonics.size:
        if n_sines < 1:
            raise ConfigError(f"multisine needs at least one sine, got n_sines = {n_sines}")
        pick = np.unique(np.round(np.linspace(0, harmonics.size - 1, int(n_sines))).astype(int))
        harmonics = harmonics[pick]
    K = harmonics.size
    if phases == "schroeder":
        k = np.arange(1, K + 1)
        phi = -np.pi * k * (k - 1) / K
    elif phases == "random":
        phi = rng.uniform(-np.pi, np.pi, size=K)
    else:
        raise ConfigError(f"multisine phases must be 'schroeder' or 'random', got {phases!r}")
    t = np.arange(int(n)) * Ts
    freqs = harmonics * df
    x = np.cos(2 * np.pi * np.outer(t, freqs) + phi).sum(axis=1)
    span = x.max() - x.min()
    if span > 0:
        u = low + (high - low) * (x - x.min()) / span
    else:
        u = np.full(int(n), 0.5 * (low + high))
    spec = {"type": "multisine", "n": int(n), "Ts": float(Ts), "low": float(low),
            "high": float(high), "band_hz": [f_lo, f_hi], "period_samples": period,
            "phases": phases, "frequencies_hz": freqs.tolist()}
    return u, spec


# ------------------------------------------------------------------- slow exogenous
def slow_exogenous(rng: np.random.Generator, n: int, Ts: float, low: float, high: float,
                   dwell_s: tuple[float, float] = (600.0, 1800.0),
                   time_constant_s: float = 600.0) -> tuple[np.ndarray, dict]:
    """A slowly wandering temperature: long-dwell APRBS through a first-order lag.

    Stands in for T_int / T_shell on the model plant (where they are exogenous), so that
    eq. 1's gamma1 and gamma2 are excited. The lag starts at the first level, so the signal
    is a running convex combination of levels and stays inside ``[low, high]``.

    Parameters
    ----------
    rng : random generator.
    n : number of samples.
    Ts : sample time, s.
    low, high : bounds, in the caller's temperature unit (K inside the library).
    dwell_s : (min, max) dwell of the underlying steps, s.
    time_constant_s : first-order lag time constant, s (0 gives the raw steps).

    Returns
    -------
    T : (n,) signal.
    spec : generator settings.
    """
    if time_constant_s < 0:
        raise ConfigError(f"time constant must be >= 0 s, got {time_constant_s}")
    lo_d = max(1, int(round(dwell_s[0] / Ts)))
    hi_d = max(lo_d, int(round(dwell_s[1] / Ts)))
    steps, _ = aprbs(rng, n, low, high, lo_d, hi_d)
    a = math.exp(-Ts / time_constant_s) if time_constant_s > 0 else 0.0
    # y[k+1] = a y[k] + (1 - a) u[k], y[0] = u[0]  (exact for steps held over each Ts)
    from scipy.signal import lfilter  # lazy: scipy.signal takes ~1 s to import

    y, _ = lfilter([0.0, 1.0 - a], [1.0, -a], steps, zi=[steps[0]])
    spec = {"type": "slow_exogenous", "n": int(n), "Ts": float(Ts), "low": float(low),
            "high": float(high), "dwell_s": [float(dwell_s[0]), float(dwell_s[1])],
            "time_constant_s": float(time_constant_s)}
    return np.clip(y, low, high), spec


# ---------------------------------------------------------------------- speed profiles
def datasets_dir() -> Path:
    """The shipped data: ``datasets/`` of the repository, installed as the package
    ``acid.datasets`` and found with ``importlib.resources`` (from any directory)."""
    from importlib.resources import files

    return Path(str(files("acid.datasets")))


def available_drive_cycles() -> list[str]:
    """Names of the drive cycles in ``datasets/drive_cycles/`` (file stems, sorted)."""
    folder = datasets_dir() / "drive_cycles"
    return sorted(p.stem for p in folder.glob("*.csv")) if folder.is_dir() else []


def constant_speed(n: int, Ts: float, v: float) -> tuple[np.ndarray, dict]:
    """A constant vehicle speed ``v`` (m/s) for ``n`` samples of ``Ts`` s."""
    if not math.isfinite(v) or v < 0:
        raise ConfigError(f"vehicle speed must be a finite value >= 0 m/s, got {v}")
    return np.full(int(n), float(v)), {"type": "constant", "v_mps": float(v), "Ts": float(Ts)}


def _read_cycle(name: str) -> tuple[np.ndarray, np.ndarray, Path]:
    path = datasets_dir() / "drive_cycles" / f"{name}.csv"
    if not path.is_file():
        names = available_drive_cycles()
        raise DataError(f"unknown drive cycle {name!r} (available: "
                        f"{', '.join(names) if names else 'none in ' + str(path.parent)})")
    try:
        raw = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise DataError(f"{path}: cannot parse drive cycle ({exc})") from None
    if raw.shape[1] < 2 or raw.shape[0] < 2:
        raise DataError(f"{path}: a drive cycle needs columns time_s,speed_mps and 2+ rows")
    t, v = raw[:, 0], raw[:, 1]
    dt = np.diff(t)
    if not np.all(np.isfinite(raw)) or np.any(dt <= 0) or not np.allclose(dt, dt[0]):
        raise DataError(f"{path}: drive cycle time must be finite, increasing and uniform")
    if np.any(v < 0):
        raise DataError(f"{path}: drive cycle has negative speeds")
    return t, v, path


def drive_cycle(name: str, n: int | None = None, Ts: float = 5.0,
                repeat: bool = True) -> tuple[np.ndarray, dict]:
    """A standard drive cycle as the mean speed over each sample period.

    The cycle file (``datasets/drive_cycles/<name>.csv``, columns ``time_s,speed_mps``, 1 Hz)
    is read as a zero-order hold: row i holds over ``[t_i, t_i + dt)``, so one pass lasts
    ``rows * dt`` seconds. Sample k is the mean speed over ``[k Ts, (k+1) Ts)``, computed
    exactly from the travelled distance (so distance is preserved for any Ts).

    Parameters
    ----------
    name : cycle name (file stem), e.g. ``"udds"``; see ``available_drive_cycles()``.
    n : number of samples (default: as many whole periods as one pass of the cycle holds).
    Ts : sample time, s.
    repeat : repeat the cycle back to back to fill ``n`` samples; otherwise the vehicle
        stands still (0 m/s) after the cycle ends.

    Returns
    -------
    v : (n,) mean speed over each sample, m/s.
    spec : cycle name, file, one-pass duration and distance, repetitions.
    """
    t, v, path = _read_cycle(name)
    dt = float(t[1] - t[0])
    one_pass = v.size * dt
    if n is None:
        n = int(one_pass // Ts)
    n = int(n)
    if n < 1:
        raise ConfigError(f"drive cycle {name!r}: need at least one sample of {Ts:g} s")
    horizon = n * Ts
    reps = max(1, int(math.ceil(horizon / one_pass - 1e-12))) if repeat else 1
    speed = np.tile(v, reps)
    distance = np.concatenate(([0.0], np.cumsum(speed) * dt))  # at the row edges
    edges = np.arange(speed.size + 1) * dt
    t_k = np.arange(n + 1) * Ts
    # beyond the data (repeat=False): the distance stays constant, i.e. the vehicle stands
    d_k = np.interp(t_k, edges, distance)
    v_mean = np.diff(d_k) / Ts
    spec = {"type": "drive_cycle", "name": name, "file": path.name, "Ts": float(Ts),
            "cycle_duration_s": one_pass, "cycle_distance_m": float(v.sum() * dt),
            "repeat": bool(repeat), "passes": horizon / one_pass}
    return v_mean, spec
