"""``acid sweep`` on a real Dask LocalCluster: 4 scenarios on 2 worker processes, a failing
scenario recorded while the others complete, a rerun that resumes, results equal to an
in-process run bit for bit."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from acid.executor import DaskExecutor, InlineExecutor
from acid.studies.sweep import run_sweep, spec_from_dict

pytestmark = pytest.mark.slow

#: short scenarios: 60 s at 15 m/s after a 60 s warm-up, charged back over 30 s
SPEC = {
    "title": "test",
    "plugins": ["_sweep_plugin"],
    "defaults": {"cycle": 15.0, "duration_s": 60.0, "warmup_s": 60.0, "tail_s": 30.0},
    "grid": {"ambient_C": [28.0, 32.0, 36.0]},
    "scenarios": [{"ambient_C": 41.0, "humidity_pct": 70.0}],
    "controllers": {"nmpc": {}, "icm": {}, "fragile": {"above_C": 40.0}},
}


@pytest.fixture(scope="module")
def dask_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    spec = spec_from_dict(SPEC, "test spec")
    seen = []
    with DaskExecutor(workers=2) as ex:
        assert ex.kind == "local" and ex.workers == 2
        first = run_sweep(spec, out, executor=ex, figures=True,
                          on_progress=lambda done, total, label: seen.append((done, total,
                                                                             label)))
        second = run_sweep(spec, out, workers=2)  # nothing to run: no cluster is started
        yield spec, out, first, second, seen, ex.address


def test_four_scenarios_run_on_two_workers_and_stream_to_disk(dask_sweep):
    spec, out, first, _, seen, _ = dask_sweep
    assert first.computed == 4 and first.reused == 0
    assert [s[:2] for s in seen] == [(i, 4) for i in range(1, 5)]
    assert sorted(s[2] for s in seen) == [  # each line names its scenario as the spec does
        "grid scenario #1 (ambient_C = 28)", "grid scenario #2 (ambient_C = 32)",
        "grid scenario #3 (ambient_C = 36)", "scenarios #1: failed"]
    assert len(list((out / "scenarios").glob("*.json"))) == 4
    df = first.table
    assert len(df) == 4 * 3 and set(df["controller"]) == {"nmpc", "icm", "fragile"}
    workers = set(df.loc[df["status"] == "ok", "worker"])
    assert len(workers) >= 1 and all(":" in w for w in workers)
    assert "2 worker processes (local cluster)" == first.executor


def test_failing_scenario_is_recorded_and_the_others_complete(dask_sweep):
    _, out, first, _, _, _ = dask_sweep
    df = first.table
    bad = df[df["status"] != "ok"]
    assert list(bad["controller"]) == ["fragile"] and list(bad["ambient_C"]) == [41.0]
    assert "too hot for this controller" in bad["error"].iloc[0]
    assert first.failed == 1
    ok = df[df["status"] == "ok"]
    assert len(ok) == 11  # the hot scenario's other controllers ran too
    # physics: hotter is costlier; savings are against the baseline (the first controller)
    nm = ok[ok["controller"] == "nmpc"].sort_values("ambient_C")
    assert np.all(np.diff(nm["energy_MJ"]) > 0)
    assert np.all(nm["saving_pct"] == 0.0)
    assert np.all(np.isfinite(ok["mean_T_cab_C"])) and np.all(ok["solve_ms_median"] > 0)
    rec = json.loads(next(p for p in (out / "scenarios").glob("*.json")
                          if json.loads(p.read_text())["status"] == "error").read_text())
    assert "RuntimeError" in rec["tracebacks"]["fragile"]


def test_second_run_resumes_and_does_nothing_new(dask_sweep):
    _, _, first, second, _, _ = dask_sweep
    assert second.computed == 0 and second.reused == 4
    assert second.executor == "nothing to run"
    pd.testing.assert_frame_equal(first.table, second.table)


def test_outputs_are_a_tidy_table_and_figures(dask_sweep):
    _, out, first, _, _, _ = dask_sweep
    df = pd.read_parquet(out / "results.parquet")
    assert len(df) == 12 and {"energy_MJ", "saving_pct", "comfort_violation_Ks",
                              "solve_ms_p95", "scenario_key", "acid_version"} <= set(df.columns)
    csv = pd.read_csv(out / "results.csv")
    assert np.allclose(csv["energy_MJ"], df["energy_MJ"], equal_nan=True)
    for name in ("saving_vs_ambient.png", "energy_per_cycle.png"):
        assert (out / name).stat().st_size > 10_000
    s = json.loads((out / "summary.json").read_text())
    assert s["scenarios"] == 4 and s["per_controller"]["fragile"]["scenarios_failed"] == 1
    assert not list(out.rglob(".*.part"))


def test_worker_results_equal_an_in_process_run_bit_for_bit(dask_sweep, tmp_path):
    spec, _, first, _, _, _ = dask_sweep
    one = spec_from_dict({**SPEC, "grid": {"ambient_C": [32.0]}, "scenarios": []}, "one")
    inline = run_sweep(one, tmp_path, executor=InlineExecutor(), figures=False).table
    dask = first.table[first.table["ambient_C"] == 32.0].reset_index(drop=True)
    for col in ("energy_MJ", "mean_T_cab_C", "max_T_cab_C", "tail_energy_MJ", "saving_pct"):
        assert np.array_equal(inline[col].to_numpy(), dask[col].to_numpy()), col
    # every other column too, but where and how long it ran (and its index in its spec)
    timing = {"solve_ms_median", "solve_ms_p95", "solve_ms_max", "scenario_elapsed_s",
              "worker", "scenario", "scenario_key"}
    assert list(inline.columns) == list(dask.columns)
    def cells(col):  # a missing value reads None whatever the column's dtype
        return [[None if pd.isna(v) else v for v in t[col].tolist()] for t in (inline, dask)]

    for col in inline.columns.difference(sorted(timing)):
        mine, theirs = cells(col)
        assert mine == theirs, col


def test_an_existing_cluster_is_used_by_its_scheduler_address(dask_sweep, tmp_path):
    address = dask_sweep[-1]
    one = spec_from_dict({**SPEC, "grid": {"ambient_C": [30.0]}, "scenarios": [],
                          "controllers": {"nmpc": {}}}, "one")
    res = run_sweep(one, tmp_path, scheduler=address, figures=False)
    assert res.computed == 1 and res.failed == 0
    assert res.executor == f"2 worker processes (cluster {address})"


def test_identification_runs_once_per_plant_configuration(tmp_path, monkeypatch):
    d = {"defaults": {"cycle": 15.0, "duration_s": 60.0, "warmup_s": 60.0,
                      "params": "identify"},
         "grid": {"cycle": [15.0, 5.0]}, "identify": {"duration_s": 1800.0, "method": "ls"},
         "controllers": {"nmpc": {}}}
    import acid.studies.sweep.runner as runner

    calls, real = [], runner.identify_params

    def counted(cfg, settings, *rest):
        calls.append(settings)
        return real(cfg, settings, *rest)

    monkeypatch.setattr(runner, "identify_params", counted)
    res = run_sweep(spec_from_dict(d, "ident"), tmp_path, executor=InlineExecutor(),
                    figures=False)
    assert len(calls) == 1 and res.failed == 0
    recs = [json.loads(p.read_text()) for p in (tmp_path / "scenarios").glob("*.json")]
    assert len(recs) == 2 and recs[0]["params"] == recs[1]["params"]
    assert recs[0]["params"]["name"] == "identified-ls"
    assert set(res.table["params"]) == {"identified-ls"}


def test_tampered_records_are_reported_and_run_again(tmp_path):
    """A record that is not what acid wrote (another key, a text where a number goes, not
    JSON, too deep) neither stops the sweep nor enters its table: it is run again."""
    from acid.studies.sweep.results import record_problem

    d = {"defaults": {"cycle": 10.0, "duration_s": 60.0, "warmup_s": 0.0},
         "grid": {"ambient_C": [30.0, 35.0, 40.0, 25.0]}, "controllers": {"nominal": {}}}
    first = run_sweep(spec_from_dict(d, "t"), tmp_path, executor=InlineExecutor(),
                      figures=False)
    assert first.computed == 4
    files = sorted((tmp_path / "scenarios").glob("*.json"))
    good = json.loads(files[1].read_text())
    files[0].write_text(json.dumps({**good, "key": "0" * 16}))
    bad = json.loads(files[1].read_text())
    bad["rows"][0]["energy_MJ"] = "lots"
    files[1].write_text(json.dumps(bad))
    files[2].write_text("[" * 100_000 + "]" * 100_000)
    files[3].write_text(json.dumps({**good, "key": files[3].stem, "rows": "x"}))
    again = run_sweep(spec_from_dict(d, "t"), tmp_path, executor=InlineExecutor(),
                      figures=False)
    assert (again.computed, again.reused) == (4, 0)
    why = again.tampered
    assert set(why) == {f.stem for f in files}
    assert "does not match its file name" in why[files[0].stem]
    assert why[files[1].stem] == 'rows[0].energy_MJ = "lots" is not a number'
    assert "nests 100000 levels" in why[files[2].stem]
    assert "rows must be a non-empty list" in why[files[3].stem]
    timing = [c for c in first.table.columns if "elapsed" in c or c == "worker"]
    pd.testing.assert_frame_equal(again.table.drop(columns=timing),
                                  first.table.drop(columns=timing))
    assert json.loads((tmp_path / "summary.json").read_text())["tampered_records"] == why
    assert record_problem(good, good["key"], ("nominal",)) == ""
    assert "controllers" in record_problem(good, good["key"], ("nmpc", "icm"))


def test_unstable_identified_parameters_fail_their_scenarios_unless_allowed(tmp_path,
                                                                            monkeypatch):
    """What the spec check cannot see before the run (params = "identify") is checked where
    the parameters appear: the scenarios that need them are errors naming the flag."""
    from acid.models.params import ModelParams

    d = {"defaults": {"cycle": 15.0, "duration_s": 60.0, "warmup_s": 0.0,
                      "params": "identify"},
         "grid": {"ambient_C": [30.0]}, "identify": {"duration_s": 1800.0, "method": "ls"},
         "controllers": {"nominal": {}}}
    # the identified model is made to look unstable: the check, not the fit, is under test
    monkeypatch.setattr(ModelParams, "stability_problems",
                        lambda self: ["eq. 2 is unstable: gamma4 + gamma5 = 1.2"])
    res = run_sweep(spec_from_dict(d, "ident"), tmp_path / "a", executor=InlineExecutor(),
                    figures=False)
    assert res.failed == 1
    [f] = res.failures()
    assert "eq. 2 is unstable" in f["error"] and "--allow-unstable" in f["error"]
    ok = run_sweep(spec_from_dict(d, "ident", allow_unstable=True), tmp_path / "b",
                   executor=InlineExecutor(), figures=False)
    assert ok.failed == 0 and set(ok.table["status"]) == {"ok"}
