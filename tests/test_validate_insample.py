"""In-sample windows found by position, not by value: ``validate_model(..., estimation=est)``
places each experiment of the estimation ``Dataset`` as one contiguous block of the
validated record and marks only that block's samples. A sensor holding its value across the
split (samples after it equal to samples before it) is not taken for the estimation data;
with two records fitted on the first half of each, exactly those halves are marked."""

from __future__ import annotations

import numpy as np
import pytest

import acid
from acid.ident.data import ModelData
from acid.ident.validate import estimation_samples
from acid.models import Model, Parameter, Signal, State

TS, N = 60.0, 400


def _room() -> Model:
    return Model(
        "room", states=[State("T", "K")], inputs=[Signal("u", "W", "heater")],
        disturbances=[Signal("T_out", "K", "outdoor")],
        parameters=[Parameter("C", "J/K", 6e5, 1e4, 1e7),
                    Parameter("UA", "W/K", 45.0, 1.0, 500.0)],
        Ts=TS, ode=lambda s: {"T": (s.UA * (s.T_out - s.T) + s.u) / s.C})


def _record(seed: int, held: tuple[int, int] | None = None) -> acid.Dataset:
    """The room simulated (0.05 K noise); ``held`` (a, b): heater off, outdoor constant and
    the air sensor holding its value from sample a to b (every channel repeats)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 1500.0, N // 40), 40)
    t_out = 278.15 + 4.0 * np.sin(np.arange(N) * TS / 86400.0 * 2 * np.pi)
    m = _room()
    X, _ = m.simulate(np.array([290.0]), u[:-1, None], t_out[:-1, None], m.values)
    T = X[:, 0] + rng.normal(0, 0.05, N)
    if held is not None:
        a, b = held
        u[a:b], t_out[a:b], T[a:b] = 0.0, t_out[a], T[a]
    return acid.Dataset(time=np.arange(N) * TS, Ts=TS,
                        channels={"T": T, "u": u, "T_out": t_out},
                        units={"T": "K", "u": "W", "T_out": "K"})


def test_a_value_held_across_the_split_is_not_in_sample():
    model = _room()
    ds = _record(1, held=(170, 240))            # held over the split at sample 200
    est, _ = ds.split(0.5)
    data, e = ModelData.of(model, ds), ModelData.of(model, est)
    mark, notes = estimation_samples(data, e, ds.time, est.time)
    assert mark[:200].all() and not mark[200:].any() and notes == []
    # by value, samples 200..239 equal sample 170 of the estimation part: 40 more marked
    # (the old rule); by position none is. Every window after the split is kept:
    res = acid.validate_model(model, ds, None, starts=N, horizon=20, warmup=0,
                              start_range=(200, N), estimation=est, yardsticks=False)
    assert res.starts.min() == 200 and res.starts.size == N - 200 - 20
    assert not any("left out" in n for n in res.notes)
    # windows that do reach into the estimation half are left out, counted by position
    res = acid.validate_model(model, ds, None, starts=N, horizon=20, warmup=0,
                              estimation=est, yardsticks=False)
    assert res.starts.min() == 200
    assert any(n.startswith("200 of 400 samples are the estimation data's (placed by "
                            "position): 200 of 380 candidate starts") for n in res.notes)


def test_two_records_fitted_on_their_first_halves():
    model = _room()
    recs = [_record(2), _record(3, held=(150, 260))]
    est = acid.Dataset.concatenate([r.window(0, N // 2) for r in recs])
    whole = acid.Dataset.concatenate(recs)
    mark, notes = estimation_samples(ModelData.of(model, whole), ModelData.of(model, est),
                                     whole.time, est.time)
    want = np.zeros(2 * N, dtype=bool)
    want[:N // 2] = want[N:N + N // 2] = True
    assert np.array_equal(mark, want) and notes == []
    res = acid.validate_model(model, whole, None, starts=2 * N, horizon=20, warmup=0,
                              estimation=est, yardsticks=False)
    kept = set(res.starts.tolist())
    assert kept == set(range(N // 2, N - 20)) | set(range(N + N // 2, 2 * N - 20))


def test_a_copy_that_is_not_a_stretch_of_the_record_is_said_not_guessed():
    model = _room()
    ds = _record(4)
    est, _ = ds.split(0.5)
    est.channels["T"] = est["T"] + 1e-6                   # e.g. a filtered copy
    mark, notes = estimation_samples(ModelData.of(model, ds), ModelData.of(model, est))
    assert not mark.any()
    assert notes and "experiment(s) 0 (200 samples) are not a stretch of this record" \
        in notes[0]


def test_estimation_ranges_that_overlap_the_windows_are_marked():
    model = _room()
    ds = _record(5)
    res = acid.validate_model(model, ds, None, starts=5, horizon=20, warmup=0,
                              start_range=(100, N), estimation=(0, 200), yardsticks=False)
    inside = [k for k in res.starts.tolist() if k < 200]       # a window k .. k + 20
    assert res.settings["in_sample_starts"] == inside and inside
    assert any(f"{len(inside)} of 5 windows score samples of the estimation ranges" in n
               for n in res.notes)


@pytest.mark.parametrize("shift", [0.0, 7.0])
def test_a_stretch_repeated_exactly_takes_its_own_time_else_every_place(shift):
    model = _room()
    one = _record(6)
    ds = acid.Dataset.concatenate([one.window(0, 100), one.window(0, 100)])
    ds = acid.Dataset(time=np.arange(200) * TS, Ts=TS, channels=dict(ds.channels),
                      units=dict(ds.units))                   # one experiment, twice the same
    est = ds.window(0, 100)
    est.time = est.time + shift
    mark, notes = estimation_samples(ModelData.of(model, ds), ModelData.of(model, est),
                                     ds.time, est.time)
    if shift == 0.0:
        assert mark[:100].all() and not mark[100:].any() and notes == []
    else:
        assert mark.all() and "repeat exactly" in notes[0]
