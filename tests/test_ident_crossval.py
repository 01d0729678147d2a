"""acid.ident.crossval: bootstrap intervals, paired verdicts against the yardsticks, start
designs, leave-experiments-out cross-validation; ``acid validate --cv experiments`` and the
per-experiment values of a two-record fit."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_ident_validate import _cabin3_record
from typer.testing import CliRunner

from acid.data import Dataset
from acid.ident.crossval import (
    CrossValidation,
    ValidationIntervals,
    cross_validate,
    interval_tables,
)
from acid.ident.fit import fit_model
from acid.models import load
from acid_cli.main import app

NAMES = [f"trip{i}" for i in range(8)]


def _errors(rng, sigma=1.0, experiments=8, per=30, H=3):
    exp = np.repeat(np.arange(experiments), per)
    return rng.normal(0.0, sigma, (exp.size, H)), exp


def _tables(errors, exp, **kw):
    return interval_tables(errors, exp, NAMES, 5.0, (5.0, 10.0, 15.0), n_resamples=300,
                           **kw)


def test_the_interval_covers_the_known_rmse_and_p90():
    # iid N(0, 1) errors: RMSE 1, p90 |e| 1.645; the 95 % interval holds them in most draws
    hits = []
    for seed in range(10):
        e, exp = _errors(np.random.default_rng(seed))
        figs, _ = _tables({"model": e}, exp, seed=seed, per_experiment=False)
        f = figs[0]
        hits.append(f.rmse_lo <= 1.0 <= f.rmse_hi and f.p90_lo <= 1.6449 <= f.p90_hi)
        assert f.n_starts == 240 and f.n_experiments == 8 and f.resolved
        assert f.rmse_hi - f.rmse_lo < 0.4
    assert sum(hits) >= 8
    # a biased sample (RMSE 2) is outside the interval of the first
    e, exp = _errors(np.random.default_rng(0))
    f = _tables({"model": e}, exp, per_experiment=False)[0][0]
    assert not f.rmse_lo <= 2.0 <= f.rmse_hi


def test_a_model_against_itself_is_no_resolvable_difference():
    e, exp = _errors(np.random.default_rng(1))
    _, verdicts = _tables({"model": e, "itself": e.copy()}, exp)
    pooled = [v for v in verdicts if v.scope == "pooled"]
    assert len(pooled) == 3
    assert all(v.verdict == "no resolvable difference" and v.difference == 0 for v in pooled)


def test_a_clearly_better_model_beats_and_the_worse_loses():
    e, exp = _errors(np.random.default_rng(2))
    _, verdicts = _tables({"model": 0.5 * e, "yardstick": e}, exp)
    assert {v.verdict for v in verdicts if v.scope == "pooled"} == {"beats"}
    # per experiment: 30 starts each, still resolved
    assert {v.verdict for v in verdicts if v.scope == "trip3"} == {"beats"}
    _, verdicts = _tables({"model": 2.0 * e, "yardstick": e}, exp)
    assert {v.verdict for v in verdicts if v.scope == "pooled"} == {"loses"}


def test_fewer_than_20_starts_or_3_experiments_is_not_resolved():
    e, exp = _errors(np.random.default_rng(3), experiments=8, per=2)    # 16 starts
    figs, verdicts = _tables({"model": 0.1 * e, "yardstick": e}, exp)
    assert not any(f.resolved for f in figs)
    assert {v.verdict for v in verdicts} == {"not resolved"}
    e, exp = _errors(np.random.default_rng(3), experiments=2, per=50)   # 2 experiments
    figs, verdicts = _tables({"model": 0.1 * e, "yardstick": e}, exp)
    assert not any(f.resolved for f in figs if f.scope == "pooled")
    assert all(f.resolved for f in figs if f.scope != "pooled")        # 50 starts each
    assert {v.verdict for v in verdicts if v.scope == "pooled"} == {"not resolved"}
    e[:40, 1] = np.nan      # a start that does not reach 10 s is not counted there
    figs, _ = _tables({"model": e}, exp)
    assert [f.n_starts for f in figs if f.scope == "pooled"] == [100, 60, 100]


def _three_trips():
    m = load("cabin3")
    rng = np.random.default_rng(5)
    parts = []
    for i in range(3):
        p = m.values.copy()
        parts.append(_cabin3_record(p, rng, n=160, T_int0=312.0 + 3 * i, noise=0.02))
        parts[-1].channels["T_amb"] = parts[-1].channels["T_amb"] + 0.0   # same plant
        parts[-1].channels["T_cab"] = parts[-1].channels["T_cab"] + 1e-6 * (i + 1)  # tag
    ds = Dataset.concatenate(parts)
    ds.source = "three trips"
    return m, ds, parts


def test_cross_validation_folds_never_see_their_held_out_experiment():
    m, ds, parts = _three_trips()
    seen = []

    def spy(model, train, **kw):
        seen.append(train)
        return fit_model(model, train, **kw)

    cv = cross_validate(m, ds, fit_options={"method": "ls"}, starts=6, horizon=30, warmup=50.0,
                        n_resamples=50, fit=spy)
    assert len(seen) == 3 and [f["held_out"] for f in cv.folds] == [["0"], ["1"], ["2"]]
    for i, train in enumerate(seen):
        assert len(train) == sum(len(p) for j, p in enumerate(parts) if j != i)
        held = parts[i].channels["T_cab"]
        assert not np.isin(train.channels["T_cab"], held).any()
        kept = np.concatenate([parts[j].channels["T_cab"] for j in range(3) if j != i])
        np.testing.assert_array_equal(train.channels["T_cab"], kept)
    iv = cv.intervals[0]
    assert {f.scope for f in iv.figures} == {"pooled", "0", "1", "2"}
    assert iv.figure(30 * 5.0).n_starts == 18 and iv.figure(150.0).n_experiments == 3
    assert {v.yardstick for v in iv.verdicts} >= {"persistence", "arx"}
    # results as objects: JSON round trip, a table, a frame, a repr
    back = CrossValidation.from_dict(json.loads(json.dumps(cv.to_dict())))
    assert back.to_dict() == cv.to_dict()
    rows = cv.parameters()     # every estimated shared parameter, its value in each fold
    assert rows and all(len(r["values"]) == 3 and r["spread"] >= 0 for r in rows)
    assert all(r["spread"] == max(r["values"]) - min(r["values"]) for r in rows)
    assert isinstance(back.intervals[0], ValidationIntervals)
    assert "not resolved" in cv.summary() or "*" in cv.summary()
    assert set(cv.to_frame().columns) >= {"scope", "predictor", "time_s", "rmse_lo", "design"}
    assert repr(cv).startswith("CrossValidation(model='cabin3'")


def test_the_cli_cross_validates_experiments(tmp_path):
    _, ds, _ = _three_trips()
    data = ds.to_hdf5(tmp_path / "trips.h5")
    out = tmp_path / "cv.json"
    res = CliRunner().invoke(app, ["validate", str(data), "--model", "cabin3", "--cv",
                                   "experiments", "--method", "ls", "--starts", "6",
                                   "--horizon", "30", "--warmup", "50", "--resamples", "50",
                                   "--starts-design", "even,random", "--json", str(out)])
    assert res.exit_code == 0, res.output
    assert "3 folds" in res.output and "across start designs" in res.output
    d = json.loads(out.read_text())["cross_validation"]
    assert [iv["design"] for iv in d["intervals"]] == ["even", "random"]
    assert d["fit_options"]["method"] == "ls"
    bad = CliRunner().invoke(app, ["validate", str(data), "--model", "cabin3", "--cv", "x"])
    assert bad.exit_code == 2 and "--cv" in bad.output


def test_a_two_record_fit_validates_each_record_with_its_own_values(tmp_path):
    # two records with very different solar loads Q_sol (a per-experiment parameter)
    m = load("cabin3")
    rng = np.random.default_rng(7)
    recs = []
    for i, q in enumerate((0.0, 2000.0)):
        p = m.values.copy()
        p[m.parameter_names.index("Q_sol")] = q
        recs.append(_cabin3_record(p, rng, n=240).to_hdf5(tmp_path / f"r{i}.h5"))
    params = tmp_path / "p.json"
    runner = CliRunner()
    fit = runner.invoke(app, ["fit", str(recs[0]), "--model", "cabin3", "--add-record",
                              str(recs[1]), "--out", str(params), "--method", "oe"])
    assert fit.exit_code == 0, fit.output
    out = tmp_path / "v.json"
    res = runner.invoke(app, ["validate", str(recs[1]), "--model", "cabin3", "--params",
                              str(params), "--starts", "5", "--horizon", "40", "--warmup",
                              "100", "--json", str(out), "--out", str(tmp_path / "f")])
    assert res.exit_code == 0, res.output
    assert "this record's own values" in res.output
    assert "their mean is used" not in res.output
    d = json.loads(out.read_text())
    assert d["channels"]["T_cab"]["max_abs"] < 0.05          # the mean (1000 W) is far off


def test_the_json_carries_every_step_of_the_model_and_the_yardsticks():
    from acid.ident.validate import validate_model

    m, ds, _ = _three_trips()
    res = validate_model(m, ds, starts=6, horizon=37, warmup=50.0, yardsticks=True,
                         estimation=(0, 320))
    d = json.loads(json.dumps(res.to_json_dict()))
    assert set(d["by_step"]) == {"model", *res.yardsticks}
    for k, chans in d["by_step"].items():
        for c, s in chans.items():
            assert len(s["rmse"]) == len(s["p90_abs"]) == len(s["n"]) == 37, (k, c)
    e = res.errors["T_cab"][:, 36]
    assert d["by_step"]["model"]["T_cab"]["rmse"][36] == pytest.approx(np.sqrt(np.mean(e ** 2)))
    assert "errors" not in d["yardsticks"]["arx"]
