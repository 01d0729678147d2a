"""``acid sweep`` on the command line: one-line errors before any worker starts, the dry run,
option conflicts, and Ctrl-C (exit 130, finished scenarios kept, the rerun resumes)."""

from __future__ import annotations

import json

import pytest
from _cli import assert_one_line_error
from _procs import alive, descendants, hidden, interrupt, start, wait_for
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
    assert "6 scenarios x 2 controllers" in res.output and "specification OK" in res.output
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args, fragment", [
    (["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "--workers and --scheduler"),
    (["--workers", "0"], "--workers 0"),
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
    spec = tmp_path / "twelve.toml"
    spec.write_text('[defaults]\ncycle = 15.0\nduration_s = 300.0\nwarmup_s = 300.0\n'
                    '[grid]\nambient_C = [26.0, 29.0, 32.0, 35.0, 38.0, 41.0]\n'
                    'humidity_pct = [30.0, 60.0]\n')
    out = tmp_path / "out"
    p = start("sweep", str(spec), "--out", str(out), "--workers", "2")

    def finished():
        return len(list((out / "scenarios").glob("*.json"))) if (out / "scenarios").is_dir() \
            else 0

    assert wait_for(lambda: finished() >= 1), p.communicate()[0]
    kids = descendants(p)
    interrupt(p)
    text, _ = p.communicate(timeout=120)
    assert p.returncode == 130, text
    assert "interrupted" in text and "Traceback" not in text
    assert wait_for(lambda: not alive(kids), 30), alive(kids)
    assert not (out / "results.parquet").exists() and hidden(out) == []
    kept = finished()
    assert 1 <= kept < 12
    for f in (out / "scenarios").glob("*.json"):
        assert json.loads(f.read_text())["status"] == "ok"
    res = runner.invoke(app, ["sweep", str(spec), "--out", str(out), "--workers", "1",
                              "--no-figures", "--json", str(tmp_path / "s.json")])
    assert res.exit_code == 0, res.output
    s = json.loads((tmp_path / "s.json").read_text())
    assert (s["computed"], s["reused"], s["failed"]) == (12 - kept, kept, 0)
