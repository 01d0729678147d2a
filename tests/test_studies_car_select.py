"""acid.studies.car.select: structures chosen by leave-trips-out cross-validation.

Synthetic trips from a known structure (a cabin air fed by the supply air and losing to the
ambient); three candidates: one too small (no ambient path), the true one, one too big (an
extra path to an input the truth ignores). The rule must pick the true one: the too small is
resolvably worse, the too big no better."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import DataError
from acid.models import Model, Parameter, Signal, State
from acid.studies.car import select as sel

TS = 5.0
STATES = [State("T_cab", "K", description="cabin air")]
INPUTS = [Signal("T_evap", "K", "supply air")]
DIST = [Signal("T_amb", "K", "ambient"), Signal("T_x", "K", "a signal the truth ignores")]


def _declared(name, uses_amb, uses_x):
    def ode(s):
        q = s.G * (s.T_evap - s.T_cab)
        if uses_amb:
            q = q + s.UA * (s.T_amb - s.T_cab)
        if uses_x:
            q = q + s.UX * (s.T_x - s.T_cab)
        return {"T_cab": q / (1e3 * s.C)}
    pars = [Parameter("C", "kJ/K", 20.0, 1.0, 200.0), Parameter("G", "W/K", 50.0, 1.0, 500.0)]
    if uses_amb:
        pars.append(Parameter("UA", "W/K", 20.0, 0.0, 500.0))
    if uses_x:
        pars.append(Parameter("UX", "W/K", 5.0, 0.0, 500.0))
    return Model(name, states=STATES, inputs=INPUTS, disturbances=DIST, parameters=pars,
                 Ts=TS, ode=ode)


SMALL = _declared("small", False, False)
TRUE = _declared("true", True, False)
BIG = _declared("big", True, True)


def _trips(n_trips=4, n=150, seed=0):
    rng = np.random.default_rng(seed)
    truth = TRUE.values.copy()
    truth[TRUE.parameter_names.index("UA")] = 60.0
    parts = []
    for _ in range(n_trips):
        evap = np.repeat(rng.uniform(278.0, 300.0, n // 24 + 1), 24)[:n]
        amb = np.full(n, rng.uniform(290.0, 310.0)) + np.linspace(0.0, 3.0, n)
        tx = np.repeat(rng.uniform(280.0, 320.0, n // 30 + 1), 30)[:n]
        X, _ = TRUE.simulate(np.array([amb[0]]), evap[:, None], np.c_[amb, tx], truth)
        ch = {"T_cab": X[:-1, 0] - 273.15 + 0.02 * rng.standard_normal(n),
              "T_evap": evap - 273.15, "T_amb": amb - 273.15, "T_x": tx - 273.15}
        ds = Dataset(np.arange(n) * TS, ch, dict.fromkeys(ch, "degC"), TS)
        parts.append(ds)
    return Dataset.concatenate(parts)


@pytest.fixture(scope="module")
def selection():
    return sel.select_structure(_trips(), [BIG, TRUE, SMALL], fit_options={"method": "ls"},
                                folds=2, rule_time_s=150.0, starts=12, horizon=30, warmup=0,
                                to_end=False, n_resamples=100)


def test_the_rule_picks_the_true_structure(selection):
    s = selection
    assert s.chosen == "true"
    # the too small one is resolvably worse; the too big one is not resolvably better
    small, true, big = (s.candidate(n).figure(150.0) for n in ("small", "true", "big"))
    assert small.rmse > max(true.rmse_hi, big.rmse_hi)
    assert true.rmse <= s.candidate(s.best).figure(150.0).rmse_hi
    assert s.candidate("small").n_free < s.candidate("true").n_free < s.candidate("big").n_free
    # the same folds for every candidate, the yardsticks on them
    assert s.folds == (("0", "2"), ("1", "3"))
    assert all(c.cv.folds[0]["held_out"] == ["0", "2"] for c in s.candidates)
    assert set(s.yardsticks) >= {"persistence", "arx"}


def test_the_reversed_rule_would_not(selection):
    # choose() with the candidates' sizes reversed (the biggest ranked smallest) picks "big"
    flipped = [sel.CandidateScore(c.name, -c.n_free, c.n_states, c.figures, c.verdicts,
                                  c.parameters, c.seconds, c.cv) for c in selection.candidates]
    assert sel.choose(flipped, 150.0)[1] == "big"
    assert sel.choose(selection.candidates, 150.0)[1] == "true"


def test_table_summary_and_json(selection, tmp_path):
    text = selection.summary()
    assert "true (chosen)" in text and "Rule: the fewest free parameters" in text
    d = json.loads(json.dumps(selection.to_dict(), allow_nan=False))
    assert d["chosen"] == "true" and len(d["candidates"]) == 3
    assert {c["name"] for c in d["candidates"]} == {"big", "true", "small"}
    assert d["candidates"][0]["parameters"][0]["name"] == "C"


def test_one_candidate_or_an_unreached_time_is_one_error(selection):
    with pytest.raises(DataError, match="at least 2 candidate"):
        sel.select_structure(_trips(3, 60), [TRUE], fit_options={"method": "ls"})
    with pytest.raises(DataError, match="no candidate has a resolved"):
        sel.choose(selection.candidates, 9999.0)


def test_cli_refuses_a_bad_season_or_one_candidate(tmp_path):
    from typer.testing import CliRunner

    from acid_cli.main import app

    runner = CliRunner()
    r = runner.invoke(app, ["car", "select", str(tmp_path), "--season", "spring"])
    assert r.exit_code == 2 and "--season" in r.output and "summer" in r.output
    r = runner.invoke(app, ["car", "select", str(tmp_path), "--candidates", "car_cabin"])
    assert r.exit_code == 2 and "--candidates" in r.output


def test_cross_validations_run_apart_assemble_to_the_same_choice(selection):
    from acid.ident.crossval import CrossValidation

    runs = [({"big": BIG, "true": TRUE, "small": SMALL}[c.name],
             CrossValidation.from_dict(json.loads(json.dumps(c.cv.to_dict()))), c.seconds)
            for c in selection.candidates]
    again = sel.assemble(runs, 150.0)
    assert (again.best, again.chosen) == (selection.best, selection.chosen)
    other = CrossValidation(runs[1][1].model, runs[1][1].channel, {}, runs[1][1].folds[::-1],
                            runs[1][1].intervals)
    with pytest.raises(DataError, match="same folds"):
        sel.assemble([runs[0], (TRUE, other, 0.0)], 150.0)


@pytest.mark.parametrize("name, season", [("bmw_i3_summer_cabin.json", "summer"),
                                          ("bmw_i3_winter_heating.json", "winter")])
def test_the_shipped_structures_load_as_their_candidates(name, season):
    from acid.examples import resolve
    from acid.models import load
    from acid.models.values import ParameterValues

    ps = ParameterValues.from_json(resolve(f"example:{name}"))
    assert ps.declaration.name in sel.CANDIDATES[season]
    m = load(ps.declaration.name)
    for p, v in zip(m.parameters, ps.theta, strict=True):
        assert p.min <= v <= p.max, p.name
    assert ps.provenance.get("chosen") == m.name


def test_the_cabin_air_is_scored_not_the_first_channel_in_kelvin(monkeypatch):
    # the heating structures list the coolant first: the selection must score T_cab
    import acid.ident.crossval as cv

    seen = []

    def fake(model, ds, **kw):
        seen.append(kw.get("channel"))
        raise DataError("stop")

    monkeypatch.setattr(cv, "cross_validate", fake)
    with pytest.raises(DataError, match="stop"):
        sel.select_structure(_trips(3, 60), [TRUE, SMALL], fit_options={"method": "ls"})
    assert seen == ["T_cab"]
