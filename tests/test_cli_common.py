"""What every command shares (``acid_cli._common``): literal printing of user text, one-line
usage errors, the output-path check, in-sample and resampling notices, --allow-unstable."""

from __future__ import annotations

import os

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.errors import DataError, OutputError
from acid.models.params import paper
from acid_cli._common import check_paths
from acid_cli.main import app

runner = CliRunner()


def _acid(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture
def data_file(model_dataset, tmp_path):
    return model_dataset.to_hdf5(tmp_path / "d.h5")


def test_paths_with_square_brackets_are_printed_literally(tmp_path):
    out = tmp_path / "[/x]" / "[bold]d.h5"
    res = _acid("excite", "--plant", "model", "--duration", "600", "--out", out,
                "--json", tmp_path / "[red]s.json")
    assert res.exit_code == 0, res.output
    flat = "".join(res.output.split())
    assert "[bold]d.h5" in flat and "[red]s.json" in flat
    assert out.is_file()


def test_bracketed_text_in_messages_survives(tmp_path):
    res = _acid("fit", tmp_path / "[dim]missing[/dim].h5", "--out", tmp_path / "p.json")
    assert_one_line_error(res, "[dim]missing[/dim].h5", "not found")


@pytest.mark.parametrize("args,fragment", [
    (["excite", "--seed", "x", "--out", "x.h5"], "--seed"),
    (["excite", "--out", "x.h5", "--frobnicate"], "--frobnicate"),
    (["excite"], "--out"),
    (["reproduce", "--jobs", "0"], "--jobs"),
])
def test_usage_errors_are_one_line(args, fragment):
    res = _acid(*args)
    assert res.exit_code == 2
    assert_one_line_error(res, fragment)


def test_outputs_are_compared_by_file_not_by_spelling(tmp_path):
    a = tmp_path / "a.h5"
    a.write_text("data")
    os.link(a, tmp_path / "hard.h5")
    with pytest.raises(OutputError, match="is also the input DATA"):
        check_paths(inputs={"DATA": a}, outputs={"--out": tmp_path / "hard.h5"})
    with pytest.raises(OutputError, match="also by --out"):
        check_paths(outputs={"--out": tmp_path / "x.json", "--json": tmp_path / "." / "x.json"})
    with pytest.raises(OutputError, match="would be written also by --json"):
        check_paths(outputs={"--json": tmp_path / "figs" / "fig5.png"},
                    folders={"--out": (tmp_path / "figs", ("fig5.png",))})
    with pytest.raises(DataError, match="--params .* is a folder"):
        check_paths(inputs={"--params": tmp_path})
    check_paths(inputs={"DATA": a}, outputs={"--out": tmp_path / "new" / "p.json"},
                folders={"--fig": (tmp_path / "figs", ("a.png",))})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.h5", "hard.h5"]  # nothing made


def test_validating_on_the_fitted_record_warns_in_sample(data_file, tmp_path):
    params = tmp_path / "p.json"
    assert _acid("fit", data_file, "--out", params).exit_code == 0
    res = _acid("validate", data_file, "--params", params, "--starts", 5, "--horizon", 50,
                "--out", tmp_path / "figs", "--no-figures")
    assert res.exit_code == 0, res.output
    assert "warning:" in res.output and "in-sample" in res.output


def test_allow_unstable_lets_a_user_validate_unstable_parameters(data_file, tmp_path):
    g = list(paper().gamma)
    g[3] = 2.0  # |gamma4 + gamma5| = 1.48: the evaporator wall diverges
    params = paper().replace(gamma=tuple(g)).to_json(tmp_path / "u.json")
    args = ["validate", data_file, "--params", params, "--starts", 3, "--horizon", 20,
            "--out", tmp_path / "figs", "--no-figures"]
    assert_one_line_error(_acid(*args), "u.json", "gamma4 + gamma5")
    res = _acid(*args, "--allow-unstable")
    assert res.exit_code == 0, res.output


def test_import_notes_data_already_at_Ts(model_dataset, tmp_path):
    src = tmp_path / "run.csv"
    ds = model_dataset.window(0, 50)
    cols = ["t", "Tcab", "Wbl"]
    rows = [f"{t:g},{c:.6g},{w:.6g}" for t, c, w in zip(ds.time, ds["T_cab"], ds["W_bl"],
                                                         strict=True)]
    src.write_text(",".join(cols) + "\n" + "\n".join(rows) + "\n")
    cmap = tmp_path / "map.toml"
    cmap.write_text('time = "t"\nTs = 5.0\n[channels]\nT_cab = "Tcab"\nW_bl = "Wbl"\n')
    res = _acid("import", src, "--map", cmap, "--out", tmp_path / "run.h5")
    assert res.exit_code == 0, res.output
    assert "note:" in res.output and "not resampled" in " ".join(res.output.split())


def test_a_table_into_a_log_keeps_every_cell(capsys, monkeypatch):
    """Into a log (no terminal, COLUMNS unset) tables are ``LOG_COLUMNS`` wide: rich's 80
    cut every cell of cav-study's 14-column table to '0.…'."""
    from acid_cli._common import LOG_COLUMNS, print_table

    monkeypatch.delenv("COLUMNS", raising=False)
    print_table("energies", [f"column {i}" for i in range(9)], [["0.123456"] * 9])
    out = capsys.readouterr().out
    assert "…" not in out and out.count("0.123456") == 9   # 100 columns: cut at 80
    assert max(len(line) for line in out.splitlines()) <= LOG_COLUMNS
    monkeypatch.setenv("COLUMNS", "60")                # the user's width wins
    print_table("energies", ["a", "b"], [["1", "2"]])
    assert max(len(line) for line in capsys.readouterr().out.splitlines()) <= 60
