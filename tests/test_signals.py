"""acid.signals: bounds, dwell times, reproducibility, PRBS and multisine properties, cycles."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from acid import signals
from acid.errors import ConfigError, DataError


def _runs(u: np.ndarray) -> np.ndarray:
    """Lengths of the runs of equal consecutive values."""
    edges = np.flatnonzero(np.diff(u) != 0) + 1
    return np.diff(np.concatenate(([0], edges, [u.size])))


# ----------------------------------------------------------------------- APRBS
@pytest.mark.parametrize("levels", [None, 2, 5])
def test_aprbs_bounds_and_dwell(rng, levels):
    u, spec = signals.aprbs(rng, 1440, 0.05, 0.15, min_dwell=4, max_dwell=60, levels=levels)
    assert u.shape == (1440,)
    assert u.min() >= 0.05 and u.max() <= 0.15
    runs = _runs(u)
    assert runs[:-1].min() >= 4  # only the last run may be cut by the end of the record
    assert runs.max() <= 60  # consecutive levels differ, so each run is one dwell
    if levels is not None:
        np.testing.assert_allclose(np.unique(u), np.linspace(0.05, 0.15, levels))
    assert spec["type"] == "aprbs" and spec["min_dwell_samples"] == 4
    assert spec["n_steps"] == runs.size


def test_aprbs_spreads_over_the_range(rng):
    u, _ = signals.aprbs(rng, 20000, 3.0, 10.0, 4, 60)
    assert u.min() < 3.5 and u.max() > 9.5


def test_aprbs_same_seed_same_signal():
    a, sa = signals.aprbs(np.random.default_rng(7), 500, 0, 1, 3, 9)
    b, sb = signals.aprbs(np.random.default_rng(7), 500, 0, 1, 3, 9)
    c, _ = signals.aprbs(np.random.default_rng(8), 500, 0, 1, 3, 9)
    np.testing.assert_array_equal(a, b)
    assert sa == sb
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("kw", [{"min_dwell": 0}, {"min_dwell": 5, "max_dwell": 2},
                                {"min_dwell": 2, "levels": 1}, {"min_dwell": 2, "low": 1}])
def test_aprbs_rejects_bad_settings(rng, kw):
    args = {"n": 100, "low": 0.0, "high": 1.0, "max_dwell": None}
    args.update(kw)
    with pytest.raises(ConfigError):
        signals.aprbs(rng, **args)


# ------------------------------------------------------------------------ PRBS
def test_prbs_is_a_maximum_length_sequence(rng):
    order = 7
    period = 2**order - 1
    u, spec = signals.prbs(rng, period, -1.0, 1.0, dwell=1, order=order)
    assert set(np.unique(u)) == {-1.0, 1.0}
    assert np.sum(u > 0) == 2 ** (order - 1)  # one more 1 than 0 per period
    # circular autocorrelation: N at lag 0, -1 at every other lag
    r = np.real(np.fft.ifft(np.abs(np.fft.fft(u)) ** 2))
    assert r[0] == pytest.approx(period)
    np.testing.assert_allclose(r[1:], -1.0, atol=1e-9)
    assert spec["period_samples"] == period


def test_prbs_clock_period_and_default_order(rng):
    u, spec = signals.prbs(rng, 1440, 0.05, 0.15, dwell=6)
    assert set(np.unique(u)) == {0.05, 0.15}
    runs = _runs(u)
    assert np.all(runs[:-1] % 6 == 0)
    assert spec["order"] == 8 and spec["period_samples"] >= 1440  # one period covers it


def test_prbs_repeats_with_its_period(rng):
    u, spec = signals.prbs(rng, 100, 0.0, 1.0, dwell=2, order=4)
    p = spec["period_samples"]
    assert p == 30
    np.testing.assert_array_equal(u[:p], u[p:2 * p])


def test_prbs_seed_sets_the_phase():
    a, sa = signals.prbs(np.random.default_rng(1), 200, 0, 1, 1, order=7)
    b, sb = signals.prbs(np.random.default_rng(1), 200, 0, 1, 1, order=7)
    np.testing.assert_array_equal(a, b)
    assert sa["initial_state"] == sb["initial_state"] and any(sa["initial_state"])


# ------------------------------------------------------------------- multisine
@pytest.mark.parametrize("phases", ["schroeder", "random"])
def test_multisine_bounds_and_band(rng, phases):
    n, Ts, band = 1440, 5.0, (1 / 1800, 1 / 50)
    u, spec = signals.multisine(rng, n, Ts, 3.0, 10.0, band=band, n_sines=12, phases=phases)
    assert u.min() == pytest.approx(3.0) and u.max() == pytest.approx(10.0)
    f = np.fft.rfftfreq(n, Ts)
    power = np.abs(np.fft.rfft(u - u.mean())) ** 2
    in_band = (f >= band[0] - 1e-12) & (f <= band[1] + 1e-12)
    assert power[~in_band].sum() < 1e-9 * power.sum()  # all energy on the chosen lines
    lines = f[power > 1e-6 * power.max()]
    np.testing.assert_allclose(lines, spec["frequencies_hz"])
    assert len(spec["frequencies_hz"]) == 12


def test_multisine_schroeder_has_lower_crest_factor_than_zero_phases(rng):
    u, spec = signals.multisine(rng, 2000, 5.0, -1, 1, band=(0.001, 0.05), n_sines=None)
    t = np.arange(2000) * 5.0
    flat = np.cos(2 * np.pi * np.outer(t, spec["frequencies_hz"])).sum(axis=1)

    def crest(x):
        x = x - x.mean()
        return np.abs(x).max() / np.sqrt(np.mean(x**2))

    assert crest(u) < 0.5 * crest(flat)


def test_multisine_periodic_and_rejects_bad_band(rng):
    u, _ = signals.multisine(rng, 400, 5.0, 0, 1, band=(0.005, 0.05), period=100)
    np.testing.assert_allclose(u[:100], u[300:], atol=1e-12)
    with pytest.raises(ConfigError, match="Nyquist"):
        signals.multisine(rng, 400, 5.0, 0, 1, band=(0.01, 0.2))
    with pytest.raises(ConfigError, match="no harmonic"):
        signals.multisine(rng, 100, 5.0, 0, 1, band=(1e-4, 1.5e-3))


# -------------------------------------------------------------- slow exogenous
def test_slow_exogenous_stays_in_range_and_is_slow(rng):
    y, spec = signals.slow_exogenous(rng, 1440, 5.0, 298.15, 318.15)
    assert y.min() >= 298.15 and y.max() <= 318.15
    assert np.abs(np.diff(y)).max() < 20.0 * 5.0 / 600.0 + 1e-9  # lag limits the rate
    assert y.max() - y.min() > 3.0  # but it does move
    assert spec["time_constant_s"] == 600.0


# ---------------------------------------------------------------- speed profiles
def test_constant_speed():
    v, spec = signals.constant_speed(10, 5.0, 12.5)
    np.testing.assert_array_equal(v, 12.5)
    assert spec == {"type": "constant", "v_mps": 12.5, "Ts": 5.0}
    with pytest.raises(ConfigError):
        signals.constant_speed(10, 5.0, -1.0)


def test_available_drive_cycles_lists_shipped_files():
    names = signals.available_drive_cycles()
    assert {"udds", "hwfet", "us06", "sc03", "nycc", "wltc3"} <= set(names)


def test_drive_cycle_averages_each_window_and_keeps_distance():
    raw = np.loadtxt(signals.datasets_dir() / "drive_cycles" / "udds.csv", delimiter=",",
                     skiprows=1)[:, 1]
    v, spec = signals.drive_cycle("udds", Ts=5.0)
    n = raw.size // 5
    assert v.shape == (n,)
    np.testing.assert_allclose(v, raw[:5 * n].reshape(n, 5).mean(axis=1))
    assert spec["cycle_distance_m"] == pytest.approx(raw.sum())


def test_drive_cycle_repeats_to_fill_and_stops_without_repeat():
    raw = np.loadtxt(signals.datasets_dir() / "drive_cycles" / "us06.csv", delimiter=",",
                     skiprows=1)[:, 1]
    n = 3 * raw.size  # three passes at Ts = 1 s
    v, spec = signals.drive_cycle("us06", n=n, Ts=1.0)
    np.testing.assert_allclose(v, np.tile(raw, 3))
    assert spec["passes"] == pytest.approx(3.0)
    v1, _ = signals.drive_cycle("us06", n=n, Ts=1.0, repeat=False)
    np.testing.assert_allclose(v1[:raw.size], raw)
    assert np.all(v1[raw.size:] == 0.0)


def test_drive_cycle_non_integer_window_preserves_distance():
    v, spec = signals.drive_cycle("hwfet", n=100, Ts=7.3)
    raw = np.loadtxt(signals.datasets_dir() / "drive_cycles" / "hwfet.csv", delimiter=",",
                     skiprows=1)[:, 1]
    assert v.sum() * 7.3 == pytest.approx(raw[:730].sum())


def test_unknown_drive_cycle_lists_available():
    with pytest.raises(DataError) as e:
        signals.drive_cycle("autobahn")
    msg = str(e.value)
    assert "'autobahn'" in msg and "udds" in msg and "wltc3" in msg and "\n" not in msg


def test_datasets_dir_is_the_acid_datasets_package_resource():
    from importlib.resources import files

    folder = signals.datasets_dir()
    assert folder == Path(str(files("acid.datasets")))
    assert (folder / "drive_cycles" / "udds.csv").is_file()
    assert "nycc" in signals.available_drive_cycles()


def test_drive_cycles_are_read_from_datasets_dir(tmp_path, monkeypatch):
    (tmp_path / "drive_cycles").mkdir()
    (tmp_path / "drive_cycles" / "ramp.csv").write_text(
        "time_s,speed_mps\n" + "\n".join(f"{i},{i}" for i in range(10)) + "\n")
    monkeypatch.setattr(signals, "datasets_dir", lambda: tmp_path)
    assert signals.available_drive_cycles() == ["ramp"]
    v, _ = signals.drive_cycle("ramp", Ts=5.0)
    np.testing.assert_allclose(v, [2.0, 7.0])
