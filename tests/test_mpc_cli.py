"""``acid mpc-check`` through Typer's CliRunner."""

from __future__ import annotations

import json

from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid_cli.main import app

runner = CliRunner()


def test_skip_plant_writes_the_summary_with_the_documented_keys(tmp_path):
    out, js = tmp_path / "figs", tmp_path / "check.json"
    res = runner.invoke(app, ["mpc-check", "--skip-plant", "--out", str(out), "--json", str(js)])
    assert res.exit_code == 0, res.output  # the paper's timing budget (Ts/8) is generous
    d = json.loads(js.read_text())
    assert set(d["scenarios"]) == {"model", "plant", "cav"}
    model = d["scenarios"]["model"]
    for key in ("energy_MJ", "max_violation_K", "first_step_violation_K", "solve_ms",
                "fallbacks", "passed", "criterion"):
        assert key in model, key
    assert set(model["solve_ms"]) >= {"median", "p95", "max", "mean"}
    assert d["timing"]["passed"] is True and d["timing"]["budget_ms"] == 625.0
    assert model["passed"] is True and model["max_violation_K"] <= 0.01
    assert d["scenarios"]["plant"]["skipped"] and d["scenarios"]["cav"]["skipped"]
    assert d["scenarios"]["cav"]["passed"] is None
    assert isinstance(d["passed"], bool) and (d["passed"] == (res.exit_code == 0))
    assert (out / "fig7_model.png").stat().st_size > 1000


def test_bad_params_file_is_a_one_line_error(tmp_path):
    bad = tmp_path / "params.json"
    bad.write_text("{not json")
    res = runner.invoke(app, ["mpc-check", "--skip-plant", "--params", str(bad)])
    assert res.exit_code == 2
    assert_one_line_error(res, "not valid JSON", str(bad))


def test_bad_backoff_prior_is_rejected():
    res = runner.invoke(app, ["mpc-check", "--skip-plant", "--backoff-prior", "-1"])
    assert res.exit_code == 2
    assert_one_line_error(res, "--backoff-prior")


def test_unknown_solver_is_rejected():
    res = runner.invoke(app, ["mpc-check", "--skip-plant", "--solver", "snopt"])
    assert res.exit_code == 2
    assert_one_line_error(res, "--solver", "snopt")


def test_export_c_writes_the_package_and_reports_its_check(tmp_path):
    out, js = tmp_path / "pkg", tmp_path / "export.json"
    res = runner.invoke(app, ["export-c", "--out", str(out), "--check-states", "2",
                              "--json", str(js)])
    assert res.exit_code == 0, res.output
    d = json.loads(js.read_text())
    assert (out / "acid_nmpc.h").is_file() and d["N"] == 6
    if d["check"] is not None:  # a C compiler exists
        assert d["check"]["max_rel_diff_vs_sqp"] <= 1e-9


def test_export_c_bad_inputs_are_one_line_errors(tmp_path):
    res = runner.invoke(app, ["export-c", "--params", str(tmp_path / "nope.json"),
                              "--out", str(tmp_path / "pkg")])
    assert res.exit_code == 2
    assert_one_line_error(res, "nope.json")
    res = runner.invoke(app, ["export-c", "--horizon", "1", "--out", str(tmp_path / "pkg")])
    assert res.exit_code == 2
    assert_one_line_error(res, "--horizon")
    assert not (tmp_path / "pkg").exists()  # nothing written
