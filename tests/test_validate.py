"""acid's one validator (``acid.ident.validate``: ``validate`` for parameter objects that name
their model) on the paper's model, and its figures (acid/report/validation.py).

Data come from the control-oriented model itself (``ModelPlant``, noise-free), so the true
parameters are known: the preset must predict its own data exactly, and a deliberately
changed parameter set must not. Errors are k-step errors, k = 1 .. horizon.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import ConfigError, DataError
from acid.ident.validate import held_out_part, validate
from acid.models.params import paper
from acid.plant import InputSchedule, ModelPlant
from acid.signals import aprbs
from acid.units import C2K

PAPER_CHANNELS = ("T_cab", "T_evap", "T_ain")


def model_data(n: int = 1500, seed: int = 0, vary_exogenous: bool = True,
               params=None) -> Dataset:
    """Noise-free data of the model plant under APRBS inputs (Table II bounds)."""
    rng = np.random.default_rng(seed)
    W_bl, _ = aprbs(rng, n, 0.05, 0.15, min_dwell=6, max_dwell=30)
    T_set, _ = aprbs(rng, n, C2K(3.0), C2K(10.0), min_dwell=6, max_dwell=30)
    k = np.arange(n)
    if vary_exogenous:
        T_int = C2K(35.0 + 3.0 * np.sin(2 * np.pi * k / 700.0))
        T_shell = C2K(38.0 + 4.0 * np.cos(2 * np.pi * k / 900.0))
    else:
        T_int, T_shell = np.full(n, C2K(35.0)), np.full(n, C2K(38.0))
    schedule = InputSchedule(W_bl, T_set, 0.0, T_int=T_int, T_shell=T_shell,
                             spec={"seed": seed})
    return ModelPlant(params or paper()).simulate(schedule)


@pytest.fixture(scope="module")
def varying():
    return model_data(vary_exogenous=True)


@pytest.fixture(scope="module")
def constant():
    return model_data(vary_exogenous=False)


def _max_error(r) -> float:
    return max(float(np.nanmax(np.abs(r.errors[c]))) for c in r.channels)


def _validate(ds, params, **kw):
    """``validate`` without the yardsticks: their ARX and subspace fits are 90 % of a call's
    CPU and leave the model's numbers unchanged (checked below, where the yardstick tests
    call ``validate`` itself)."""
    return validate(ds, params, **{"yardsticks": False, **kw})


def test_preset_predicts_its_own_data_to_numerical_noise(varying, constant):
    for ds, mode in ((varying, "measured"), (constant, "hold"), (constant, "measured")):
        r = _validate(ds, paper(), starts=60, horizon=300, exogenous=mode)
        assert r.predicted.shape == (60, 301, 4) == r.measured.shape
        assert r.errors["T_cab"].shape == (60, 300)
        assert _max_error(r) <= 1e-9, mode
        for name in PAPER_CHANNELS:
            assert r.metrics[name]["max_abs"] <= 1e-9
            assert r.metrics[name]["rmse"] <= 1e-9
            assert r.metrics[name]["fit_percent"] == pytest.approx(100.0, abs=1e-6)


def test_perturbed_model_errors_grow_with_horizon(constant):
    p = paper()
    truth = p.replace(gamma=(p.gamma[0] * 1.2,) + p.gamma[1:4] + (p.gamma[4] * 1.05,)
                      + p.gamma[5:], tau=(p.tau[0] + 0.05,) + p.tau[1:], name="truth")
    ds = model_data(vary_exogenous=False, params=truth)
    r = _validate(ds, p, starts=60, horizon=300)
    # eqs. 1-2 are contractive (time constants of a few steps): the error rises from the
    # measured initial state and settles at the mismatch's steady-state offset
    e = np.abs(r.errors["T_cab"]).mean(axis=0)        # step 1 .. 300
    early, late = e[:2].mean(), e[49:].mean()
    assert late > 1.5 * early > 0, (early, late)
    assert np.all(np.diff(e[:5]) > 0)
    for name in ("T_evap", "T_ain"):
        assert np.abs(r.errors[name]).mean(axis=0)[99:].mean() > 1e-3
        assert r.metrics[name]["rmse"] > 1e-3
    assert np.all(r.predicted[:, 0, :2] == r.measured[:, 0, :2])   # the measured start


def test_hold_and_measured_exogenous_differ_when_T_int_varies(varying, constant):
    held = _validate(varying, paper(), starts=20, horizon=200, exogenous="hold")
    meas = _validate(varying, paper(), starts=20, horizon=200, exogenous="measured")
    assert held.metrics["T_cab"]["max_abs"] > 0.1
    assert meas.metrics["T_cab"]["max_abs"] <= 1e-9
    e = np.abs(held.errors["T_cab"]).mean(axis=0)  # holding a drifting T_int: error grows
    assert e[149:].mean() > 2 * e[:19].mean()
    # the evaporator does not see T_int: identical either way
    np.testing.assert_array_equal(held.predicted[..., 1], meas.predicted[..., 1])
    assert held.settings["hold"] == ("T_int", "T_shell") and meas.settings["hold"] == ()
    # with constant disturbances both modes are the same
    a = _validate(constant, paper(), starts=10, horizon=100, exogenous="hold")
    b = _validate(constant, paper(), starts=10, horizon=100, exogenous="measured")
    np.testing.assert_array_equal(a.predicted, b.predicted)


def test_windows_never_cross_an_experiment_boundary():
    parts = [model_data(n, seed=s) for s, n in enumerate((400, 150, 520, 320))]
    ds = Dataset.concatenate(parts)
    r = _validate(ds, paper(), starts=60, horizon=300, exogenous="measured")
    idx = r.starts[:, None] + np.arange(301)[None, :]
    assert np.all(ds.experiment[idx] == ds.experiment[r.starts][:, None])
    assert 1 not in set(ds.experiment[r.starts])  # 150 samples: no window fits
    assert _max_error(r) <= 1e-9  # each window is one consistent trajectory
    assert r.starts.size == 60 and np.all(np.diff(r.starts) > 0)


def test_start_placement_even_random_and_held_out(varying):
    n = len(varying)
    even = _validate(varying, paper(), starts=60, horizon=300)
    assert even.starts[0] == 0 and even.starts[-1] == n - 301
    np.testing.assert_array_equal(even.starts, _validate(varying, paper()).starts)
    np.testing.assert_allclose(even.start_time, varying.time[even.starts])
    r1 = _validate(varying, paper(), placement="random", seed=3)
    r2 = _validate(varying, paper(), placement="random", seed=3)
    r3 = _validate(varying, paper(), placement="random", seed=4)
    np.testing.assert_array_equal(r1.starts, r2.starts)
    assert not np.array_equal(r1.starts, r3.starts)
    held = _validate(varying, paper(), starts=30, horizon=200, held_out_fraction=0.5)
    assert held.starts.min() >= n // 2
    assert held.settings["sample_range"] == [n // 2, n]
    ranged = _validate(varying, paper(), starts=5, horizon=100, start_range=(100, 400))
    assert ranged.starts.min() >= 100 and ranged.starts.max() + 100 < 400


def test_few_admissible_starts_are_used_once_with_a_warning(varying):
    short = varying.window(0, 310)  # 10 admissible starts for 300 steps
    with pytest.warns(UserWarning, match="only 10 distinct start"):
        r = _validate(short, paper(), starts=60, horizon=300)
    assert r.n_starts == 10 and r.settings["starts_requested"] == 60
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        overlapping = _validate(varying.window(0, 1000), paper(), starts=60, horizon=300)
    assert overlapping.n_starts == 60


def test_record_too_short_and_bad_options_are_one_line_errors(varying):
    ds = varying.window(0, 200)
    ds.source = "short.h5"
    with pytest.raises(DataError, match=r"short\.h5: record too short: no experiment") as exc:
        validate(ds, paper(), starts=60, horizon=300)
    assert "\n" not in str(exc.value)
    with pytest.raises(DataError, match="no experiment"):
        validate(varying, paper(), horizon=300, held_out_fraction=0.1)
    with pytest.raises(ConfigError, match="exogenous"):
        validate(varying, paper(), exogenous="forecast")
    with pytest.raises(ConfigError, match="starts"):
        validate(varying, paper(), starts=0)
    with pytest.raises(ConfigError, match="held-out-fraction"):
        validate(varying, paper(), held_out_fraction=1.5)
    with pytest.raises(DataError, match="T_int"):
        validate(varying.select(["T_cab", "T_evap", "T_ain", "W_bl", "T_evap_set",
                                 "T_shell"]), paper())
    with pytest.raises(DataError, match="expected model parameters"):
        validate(varying, 3.5)


def test_metrics_and_json(varying):
    r = _validate(varying, paper().replace(tau=(0.05, 0.0, 0.0)), starts=12, horizon=60)
    np.testing.assert_allclose(r.horizon_s, np.arange(61) * 5.0)
    e = r.predicted[:, 1:, 0] - r.measured[:, 1:, 0]
    np.testing.assert_allclose(r.errors["T_cab"], e)
    m = r.metrics["T_cab"]   # steps 1 .. 60 of every start, by hand
    assert m["rmse"] == pytest.approx(np.sqrt(np.mean(e ** 2)))
    assert m["median_abs"] == pytest.approx(np.median(np.abs(e)))
    assert m["p95_abs"] == pytest.approx(np.percentile(np.abs(e), 95))
    y, yh = r.measured[:, 1:, 0], r.predicted[:, 1:, 0]
    fits = 100 * (1 - np.linalg.norm(y - yh, axis=1)
                  / np.linalg.norm(y - y.mean(axis=1, keepdims=True), axis=1))
    assert m["fit_percent"] == pytest.approx(np.median(fits))
    d = json.loads(json.dumps(r.to_json_dict(), allow_nan=False))
    for name in PAPER_CHANNELS:
        for key in ("rmse", "max_abs", "p95_abs", "median_abs", "p90_abs", "mean_abs",
                    "fit_percent", "fit_percent_pooled"):
            assert key in d["channels"][name]
    assert d["n_starts"] == 12 and d["settings"]["hold"] == ["T_int", "T_shell"]
    assert d["by_time"]["T_cab"]["60"]["rmse_K"] == pytest.approx(
        np.sqrt(np.mean(r.errors["T_cab"][:, 11] ** 2)))


def test_constant_truth_gives_null_fit_not_nan():
    n = 400
    p = paper()
    T_set = np.full(n, C2K(5.0))
    x_evap = float(p.tau[1] - p.gamma[4] * T_set[0]) / (1 - p.gamma[3] - p.gamma[4])
    sched = InputSchedule(np.full(n, 0.1), T_set, 0.0)
    ds = ModelPlant(p).simulate(sched, initial={"T_evap": x_evap})
    d = _validate(ds, p, starts=5, horizon=100).to_json_dict()
    json.dumps(d, allow_nan=False)
    assert d["channels"]["T_evap"]["fit_percent"] is None


def test_figures_have_the_papers_panels_and_units(varying):
    from acid.report.validation import error_figure, prediction_figure

    r = _validate(varying, paper(), starts=8, horizon=100)
    fig5 = prediction_figure(r)
    labels = [ax.get_ylabel() for ax in fig5.axes]
    assert sum("(°C)" in lab for lab in labels) == 4 and any("(kg/s)" in lab for lab in labels)
    assert fig5.axes[3].get_xlabel() == "prediction time (s)"
    fig6 = error_figure(r)
    assert len(fig6.axes) == 3 and all("(K)" in ax.get_ylabel() for ax in fig6.axes)
    assert len(fig6.axes[0].lines) >= r.n_starts + 2  # every start, mean, zero line
    with pytest.raises(IndexError):
        prediction_figure(r, start=8)


def test_shared_fixtures_noise_free_and_noisy(model_dataset, noisy_model_dataset):
    exact = _validate(model_dataset, paper(), exogenous="measured")
    assert _max_error(exact) <= 1e-9
    noisy = _validate(noisy_model_dataset, paper(), exogenous="measured")
    for name in PAPER_CHANNELS:  # 0.05 K measurement noise, a contractive model
        assert 0.03 < noisy.metrics[name]["rmse"] < 0.08, name


# ------------------------------------------------------------- held-out, in-sample
SHA = "a" * 64


@pytest.mark.parametrize("prov,requested,fraction,source,in_sample", [
    ({"data_sha256": SHA, "estimation_fraction": 0.5}, None, 0.5, "params provenance", False),
    ({"data_sha256": SHA, "estimation_fraction": 1.0}, None, None, "whole record", True),
    ({"data_sha256": SHA}, None, None, "whole record", True),
    ({"data_sha256": "b" * 64, "estimation_fraction": 0.5}, None, None, "whole record", False),
    ({"estimation_fraction": 0.5}, None, 0.5, "params provenance", False),  # no record: ours
    ({}, None, None, "whole record", False),                                  # e.g. paper
    ({"data_sha256": SHA, "estimation_fraction": 0.5}, 0.5, 0.5, "--held-out-fraction", False),
    ({"data_sha256": SHA, "estimation_fraction": 0.5}, 0.8, 0.8, "--held-out-fraction", True),
])
def test_held_out_part_and_in_sample_warning(prov, requested, fraction, source, in_sample):
    part = held_out_part(prov, "d.h5", SHA, requested)
    assert (part.fraction, part.source) == (fraction, source)
    assert (part.warning is not None) == in_sample
    if in_sample:
        assert "in-sample" in part.warning and "d.h5" in part.warning


def test_diverging_predictions_are_an_error_not_nan(varying):
    g = list(paper().gamma)
    g[0] = 1e300  # cabin pole -1e300: overflows within a few steps
    with pytest.raises(DataError, match="diverge"):
        _validate(varying, paper().replace(gamma=tuple(g)), starts=3, horizon=50)


def test_more_starts_than_admissible_allocates_nothing_large(varying):
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        res = _validate(varying, paper(), starts=10**9, horizon=50)
    assert res.n_starts <= len(varying)


# --------------------------------------------------------- yardsticks and window design
def test_yardsticks_leave_the_models_numbers_unchanged_and_join_the_json(varying):
    plain = validate(varying, paper(), starts=12, horizon=300, held_out_fraction=0.5,
                     yardsticks=False)
    marked = validate(varying, paper(), starts=12, horizon=300, held_out_fraction=0.5)
    np.testing.assert_array_equal(plain.starts, marked.starts)
    np.testing.assert_array_equal(plain.predicted, marked.predicted)
    assert plain.metrics == marked.metrics
    assert plain.to_json_dict()["yardsticks"] == {}
    d = json.loads(json.dumps(marked.to_json_dict(), allow_nan=False))
    assert set(d["yardsticks"]) == {"persistence", "arx", "subspace"}
    for name, table in d["yardsticks_by_time"].items():
        for c in PAPER_CHANNELS:
            for t in ("60", "300", "1500"):
                assert set(table[c][t]) == {"rmse_K", "p90_K", "n"}, (name, c, t)
    assert marked.settings["yardsticks_fitted_on"] == [0, len(varying) // 2]


def test_window_design_of_the_default_study_says_the_windows_overlap(varying):
    r = _validate(varying, paper(), starts=60, horizon=300, held_out_fraction=0.5)
    w = r.to_json_dict()["window_design"]
    assert w["starts"] == 60 and w["horizon_s"] == 1500.0 and not w["non_overlapping"]
    gaps = np.diff(r.starts) * 5.0
    assert w["start_spacing_s"] == {"min": gaps.min(), "median": float(np.median(gaps)),
                                    "max": gaps.max()}
    assert w["overlap_fraction"] == pytest.approx(np.mean(1 - np.diff(r.starts) / 301))
    assert w["overlap_fraction"] > 0.9 and w["max_windows_per_sample"] > 30
    assert "held at their value at each start" in w["held_disturbances"]
    measured = _validate(varying, paper(), starts=5, horizon=100, exogenous="measured")
    assert "follows its measurement" in measured.window_design["held_disturbances"]


def test_non_overlapping_starts_share_no_sample(varying):
    n = len(varying)
    with pytest.warns(UserWarning, match=r"windows of 100 steps .* fit without overlap"):
        r = _validate(varying, paper(), starts=60, horizon=100, non_overlapping=True)
    k0 = r.starts
    assert k0.size == (n - 101) // 101 + 1  # as many as fit
    assert np.all(np.diff(k0) >= 101)
    covered = np.concatenate([np.arange(k, k + 101) for k in k0])
    assert np.unique(covered).size == covered.size  # no sample in two windows
    w = r.window_design
    assert w["overlap_fraction"] == 0.0 and w["max_windows_per_sample"] == 1
    assert w["non_overlapping"] and r.settings["non_overlapping"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # enough room: no warning, spread evenly
        few = _validate(varying, paper(), starts=3, horizon=100, non_overlapping=True)
    assert few.starts[0] == 0 and few.starts[-1] == n - 101
    with pytest.raises(ConfigError, match="--non-overlapping"):
        _validate(varying, paper(), non_overlapping=True, placement="random")


def test_non_overlapping_starts_respect_experiment_boundaries(varying):
    ds = Dataset.concatenate([varying.window(0, 700), varying.window(700, 1500)])
    with pytest.warns(UserWarning):
        r = _validate(ds, paper(), starts=100, horizon=100, non_overlapping=True)
    exp = ds.experiment
    for k in r.starts:
        assert exp[k] == exp[k + 100]
    assert np.all(np.diff(r.starts) >= 101)
    assert r.n_starts == 600 // 101 + 1 + 700 // 101 + 1


def test_reproduce_stage_result_and_report_section_carry_design_and_yardsticks(varying):
    from acid.claims.results import ValidationStage
    from acid.report.sections import SECTION_BUILDERS

    r = validate(varying, paper(), starts=12, horizon=300, held_out_fraction=0.5,
                 yardsticks=True)
    stage = ValidationStage.from_json_dict(
        json.loads(json.dumps(ValidationStage.of(r).to_json_dict())))
    assert stage.channels["T_cab"].p90_abs == r.metrics["T_cab"]["p90_abs"]
    assert stage.window_design.startswith("window design: 12 starts")
    assert stage.overlap_fraction == r.window_design["overlap_fraction"]
    assert set(stage.by_horizon) == {"model", "persistence", "arx", "subspace"}
    assert stage.yardsticks_fitted_on == (0, len(varying) // 2)
    sec = SECTION_BUILDERS[ValidationStage](stage)
    assert "12 starts" in sec.paragraphs[0] and "never used for control" in sec.paragraphs[1]
    assert sec.header[2].startswith("60 s")
    assert sec.rows[1][:2] == ("T_cab", "persistence (yardstick)")
    # a stage record written before the yardsticks still reads (no design, no table)
    old = ValidationStage.from_json_dict({k: v for k, v in stage.to_json_dict().items()
                                          if k in ("starts", "horizon", "horizon_s",
                                                   "channels")})
    assert SECTION_BUILDERS[ValidationStage](old).rows == ()
