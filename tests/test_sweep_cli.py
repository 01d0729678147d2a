"""``acid sweep`` on the command line: one-line errors before any worker starts, the dry run,
option conflicts, and Ctrl-C (exit 130, finished scenarios kept, the rerun resumes)."""

from __future__ import annotations

import json

import pytest
from _cli import assert_one_line_error
from _procs import (
    alive,
    descendants,
    group_left,
    hidden,
    interrupt,
    output_until_exit,
    start,
    wait_for,
)
from typer.testing import CliRunner

import acid.executor
from acid_cli.main import app

runner = CliRunner()


@pytest.fixture
def no_workers(monkeypatch):
    """Fail the test if a Dask cluster is started."""

    def refuse(*args, **kwargs):
        raise AssertionError("a Dask cluster was started for a bad specification")

    monkeypatch.setattr(acid.executor, "DaskExecutor", refuse)


@pytest.mark.parametrize("text, fragments", [
    ('[grid]\nambient_C = [30.0]\n[controllers.turbo]\n', ["controllers.turbo",
                                                          "unknown controller 'turbo'"]),
    ('[grid]\nhumidity_pct = [-5.0]\n', ["grid", "humidity_pct = -5"]),
    ('[grid]\nambient_C = []\n', ["grid", "ambient_C is empty"]),
    ('[grid\n', ["not valid TOML"]),
    # hostile inputs (issue 24): nested overrides, deep nesting, physical ranges, step counts
    ('[defaults]\nplant = { V_disp = { x = 1.0 } }\n[grid]\nambient_C = [30.0]\n',
     ["defaults", "plant.V_disp must be a value"]),
    ('[[scenarios]]\nplant = { a = [[1.0]] }\n', ["scenarios #1", "plant.a must be a value"]),
    ("x = " + "[" * 5000 + "]" * 5000 + "\n", ["nests 5000 levels", "at most 32"]),
    ("a" + ".a" * 60 + " = 1\n", ["nests deeper than 32"]),
    ('[defaults]\nplant = { V_disp = 1.0 }\n[grid]\nambient_C = [30.0]\n',
     ["V_disp = 1 m^3", "5e-06..0.0005"]),
    ('[defaults]\nplant = { dt_int = 1e-6, Ts = 5.0 }\n[grid]\nambient_C = [30.0]\n',
     ["dt_int"]),
])
def test_bad_spec_is_one_line_before_any_worker_starts(tmp_path, no_workers, text, fragments):
    spec = tmp_path / "s.toml"
    spec.write_text(text)
    res = runner.invoke(app, ["sweep", str(spec), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2
    assert_one_line_error(res, str(spec), *fragments)
    assert not (tmp_path / "out").exists()


def test_dry_run_lists_scenarios_and_runs_nothing(tmp_path, no_workers):
    spec = tmp_path / "climates.toml"
    spec.write_text('[grid]\nambient_C = [25.0, 35.0]\ncycle = ["udds", "nycc", 15.0]\n')
    res = runner.invoke(app, ["sweep", str(spec), "--dry-run", "--out", str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())  # a long temporary path may wrap the line
    assert "6 scenarios x 2 controllers" in text and "specification OK" in text
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args, fragment", [
    (["--jobs", "2", "--scheduler", "tcp://127.0.0.1:1"], "--jobs and --scheduler"),
    (["--jobs", "0"], "--jobs 0"),
    (["--json", "SPEC"], "--json"),
])
def test_conflicting_options(tmp_path, no_workers, args, fragment):
    spec = tmp_path / "s.toml"
    spec.write_text('[grid]\nambient_C = [30.0]\n')
    args = [str(spec) if a == "SPEC" else a for a in args]
    res = runner.invoke(app, ["sweep", str(spec), *args])
    assert_one_line_error(res, fragment)


@pytest.mark.slow
def test_ctrl_c_keeps_finished_scenarios_and_the_rerun_resumes(tmp_path):
    """Ctrl-C (SIGINT to the whole process group) once a scenario has finished while the
    other worker computes: exit 130, nothing of the run's process group left (re-parented
    children included), the finished scenarios kept and reused by the rerun."""
    spec = tmp_path / "six.toml"
    spec.write_text('[defaults]\ncycle = 15.0\nduration_s = 300.0\nwarmup_s = 300.0\n'
                    '[grid]\nambient_C = [26.0, 32.0, 38.0]\n'
                    'humidity_pct = [30.0, 60.0]\n')
    out = tmp_path / "out"
    p = start("sweep", str(spec), "--out", str(out), "--jobs", "2")

    def finished():
        return len(list((out / "scenarios").glob("*.json"))) if (out / "scenarios").is_dir() \
            else 0

    assert wait_for(lambda: finished() >= 1), p.communicate()[0]
    kids = descendants(p)
    interrupt(p)
    text = output_until_exit(p, 120)
    assert p.returncode == 130, text
    assert "interrupted" in text and "Traceback" not in text
    assert wait_for(lambda: not alive(kids), 30), alive(kids)
    assert wait_for(lambda: not group_left(p.pid), 30), group_left(p.pid)
    assert not (out / "results.parquet").exists() and hidden(out) == []
    kept = finished()
    assert 1 <= kept < 6
    for f in (out / "scenarios").glob("*.json"):
        assert json.loads(f.read_text())["status"] == "ok"
    res = runner.invoke(app, ["sweep", str(spec), "--out", str(out), "--jobs", "1",
                              "--no-figures", "--json", str(tmp_path / "s.json")])
    assert res.exit_code == 0, res.output
    s = json.loads((tmp_path / "s.json").read_text())
    assert (s["computed"], s["reused"], s["failed"]) == (6 - kept, kept, 0)


# ------------------------------------------------------------- hostile inputs (issue 24)
TINY = ('[defaults]\ncycle = 10.0\nduration_s = 60.0\nwarmup_s = 0.0\n'
        '[grid]\nambient_C = [30.0]\n[controllers.nominal]\n')


def _files(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def test_a_folder_of_another_specs_results_is_refused_and_the_same_spec_resumes(
        tmp_path, no_workers):
    from acid.executor import InlineExecutor
    from acid.studies.sweep import load_spec, run_sweep

    first = tmp_path / "first.toml"
    first.write_text(TINY)
    out = tmp_path / "out"
    run_sweep(load_spec(first), out, executor=InlineExecutor(), figures=False)
    before = _files(out)
    assert {"spec.toml", "summary.json", "results.csv"} <= set(before)
    other = tmp_path / "other.toml"
    other.write_text(TINY.replace("30.0", "35.0"))
    res = runner.invoke(app, ["sweep", str(other), "--out", str(out)])
    assert res.exit_code == 2
    assert_one_line_error(res, "--out", str(out), "another specification")
    assert _files(out) == before  # nothing overwritten
    # the same specification (another file, other comments) resumes: nothing to run
    again = tmp_path / "again.toml"
    again.write_text("# the same sweep\n" + TINY)
    res = runner.invoke(app, ["sweep", str(again), "--out", str(out), "--no-figures"])
    assert res.exit_code == 0, res.output
    assert "1 scenario finished earlier: nothing to run" in res.output
    # results without a spec.toml are another (unknown) specification's too
    (out / "spec.toml").unlink()
    res = runner.invoke(app, ["sweep", str(first), "--out", str(out)])
    assert_one_line_error(res, "--out", "unknown specification")


def test_unstable_parameters_are_refused_before_any_worker_unless_allowed(tmp_path,
                                                                          no_workers):
    from acid.models.params import paper

    paper().replace(gamma=(0.9, 0.9, 0.2, 0.5, 0.6, 0.3, 10.0), name="bad").to_json(
        tmp_path / "b.json")
    spec = tmp_path / "s.toml"
    spec.write_text('[defaults]\nparams = "b.json"\n[grid]\nambient_C = [30.0]\n')
    res = runner.invoke(app, ["sweep", str(spec), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert_one_line_error(res, "s.toml", "params", "b.json", "unstable", "--allow-unstable")
    assert not (tmp_path / "o").exists()
    res = runner.invoke(app, ["sweep", str(spec), "--out", str(tmp_path / "o"), "--dry-run",
                              "--allow-unstable"])
    assert res.exit_code == 0, res.output


def test_a_spec_named_only_by_dots_is_refused(tmp_path, no_workers, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in ("..toml", "...toml"):
        (tmp_path / name).write_text(TINY)
        res = runner.invoke(app, ["sweep", name])
        assert res.exit_code == 2
        assert_one_line_error(res, "SPEC.toml", name, "only of dots", "--out")
    assert not (tmp_path / "reports").exists()


@pytest.mark.parametrize("address, fragment", [
    ("tcp://[::", "not a scheduler address"), ("foo://h:1", "unknown scheme"),
    ("tcp://h:99999", "port 99999"), ("tcp://h:port", "not a scheduler address"),
])
def test_a_malformed_scheduler_address_is_one_line(tmp_path, no_workers, address, fragment):
    spec = tmp_path / "s.toml"
    spec.write_text(TINY)
    res = runner.invoke(app, ["sweep", str(spec), "--out", str(tmp_path / "o"),
                              "--scheduler", address])
    assert res.exit_code == 2
    assert_one_line_error(res, "--scheduler", fragment)
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_a_worker_that_dies_while_the_cluster_starts_is_one_line(tmp_path):
    """Every worker process exits in its preload (as a worker killed by the OOM killer or a
    broken environment would): one line, exit 2, nothing left running."""
    import os
    import subprocess
    import sys

    die = tmp_path / "die.py"
    die.write_text("import os\nos._exit(3)\n")
    spec = tmp_path / "s.toml"
    spec.write_text(TINY)
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__PRELOAD": json.dumps([str(die)])}
    exe = os.path.join(os.path.dirname(sys.executable), "acid")
    r = subprocess.run([exe, "sweep", str(spec), "--out", str(tmp_path / "o"), "--jobs",
                        "2"], capture_output=True, text=True, env=env, timeout=600)
    text = r.stdout + r.stderr
    assert r.returncode == 2, text
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: the local Dask cluster"), text
    assert "did not start" in lines[0] and "--jobs 1" in lines[0]
    assert not (tmp_path / "o" / "results.csv").exists()


def test_each_progress_line_names_the_scenario_that_finished(tmp_path, monkeypatch):
    """Into a log, one line per finished scenario: how many of how many, and which one as
    the spec gives it (user text, printed literally: a ``[red]`` in a file name stays), and
    whether it failed."""
    import contextlib
    import re

    import acid.studies.sweep.runner
    from acid.executor import InlineExecutor
    from acid.models.params import paper

    monkeypatch.setattr(acid.studies.sweep.runner, "open_executor",
                        lambda *a, **k: contextlib.nullcontext(InlineExecutor()))
    paper().to_json(tmp_path / "p[red]x.json")
    spec = tmp_path / "s.toml"
    spec.write_text('title = "lines"\nplugins = ["_sweep_plugin"]\n'
                    '[defaults]\ncycle = 10.0\nduration_s = 60.0\nwarmup_s = 0.0\n'
                    '[grid]\nambient_C = [30.0]\nparams = ["paper", "p[red]x.json"]\n'
                    '[[scenarios]]\nambient_C = 41.0\n'
                    '[controllers.nominal]\n[controllers.fragile]\nabove_C = 40.0\n')
    res = runner.invoke(app, ["sweep", str(spec), "--out", str(tmp_path / "o"),
                              "--no-figures"])
    assert res.exit_code == 0, res.output
    lines = [m.groups() for m in re.finditer(
        r"^sweep lines: (\d)/(\d) \(\d+ %\), \d+ s: (.+)$", res.output, re.M)]
    assert lines == [
        ("1", "3", "grid scenario #1 (ambient_C = 30, params = 'paper')"),
        ("2", "3", "grid scenario #2 (ambient_C = 30, params = 'p[red]x.json')"),
        ("3", "3", "scenarios #1: failed")], res.output
