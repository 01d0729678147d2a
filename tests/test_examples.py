"""Bundled examples addressable from anywhere (issue 23): ``acid examples`` lists and copies
them, ``example:NAME`` is accepted wherever a command reads a file, and the wheel ships
every one of them."""

from __future__ import annotations

import fnmatch
from pathlib import Path

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid import examples
from acid.data import Dataset
from acid.errors import ConfigError
from acid_cli._common import resolve_examples
from acid_cli.main import app

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
runner = CliRunner()


def test_every_bundled_file_is_listed_with_a_description():
    found = examples.available()
    on_disk = {p.name for folder in ("examples", "plant")
               for p in (ROOT / "datasets" / folder).iterdir()
               if p.is_file() and p.suffix in (".toml", ".gz")}
    assert on_disk <= set(found)
    assert {"sample_log.csv.gz", "sample_log_map.toml", "bmw_i3_map.toml",
            "sweep_econ.toml", "table_i_20cc.toml"} <= set(found)
    for name in found:
        kind, what = examples.describe(name)
        assert kind and what, name


def test_the_wheel_ships_every_example():
    """pyproject's package data covers every bundled file (the wheel has them)."""
    conf = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    for name, path in examples.available().items():
        package = "acid.datasets." + path.parent.name
        assert package in conf["packages"], package
        globs = conf["package-data"].get(package, [])
        assert any(fnmatch.fnmatch(name, g) for g in globs), (name, globs)


def test_references_resolve_keeping_their_type():
    path = resolve_examples(Path("example:sweep_econ.toml"))
    assert isinstance(path, Path) and path.is_file() and path.name == "sweep_econ.toml"
    assert resolve_examples("example:sweep_econ.toml") == str(path)
    assert resolve_examples([Path("a.csv"), Path("example:sample_log.csv.gz")])[1].is_file()
    assert resolve_examples("paper") == "paper" and resolve_examples(None) is None
    with pytest.raises(ConfigError, match="sample_log_map.toml"):
        examples.resolve("example:sample_log_mapp.toml")


def test_examples_lists_and_copies(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, ["examples"])
    assert r.exit_code == 0, r.output
    for name in examples.available():
        assert name in r.output
    r = runner.invoke(app, ["examples", "copy", "sweep_econ.toml"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "sweep_econ.toml").read_bytes() == \
        examples.resolve("sweep_econ.toml").read_bytes()
    r = runner.invoke(app, ["examples", "copy", "example:sweep_econ.toml"])
    assert_one_line_error(r, "sweep_econ.toml", "--force")
    assert runner.invoke(app, ["examples", "copy", "sweep_econ.toml", "--force"]).exit_code == 0
    (tmp_path / "maps").mkdir()
    r = runner.invoke(app, ["examples", "copy", "bmw_i3_map.toml", "maps"])
    assert r.exit_code == 0 and (tmp_path / "maps" / "bmw_i3_map.toml").is_file()
    r = runner.invoke(app, ["examples", "path", "sample_log.csv.gz"])
    assert r.exit_code == 0 and Path(r.output.strip()) == examples.resolve("sample_log.csv.gz")


@pytest.mark.parametrize(("args", "fragments"), [
    (["examples", "frob"], ["ACTION", "frob"]),
    (["examples", "copy"], ["NAME"]),
    (["examples", "copy", "nope.toml"], ["nope.toml", "acid examples"]),
    (["examples", "list", "x"], ["NAME", "x"]),
])
def test_examples_bad_input_is_one_line(args, fragments, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert_one_line_error(runner.invoke(app, args), *fragments)


def test_import_of_the_sample_log_works_from_an_empty_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, ["import", "example:sample_log.csv.gz", "--map",
                            "example:sample_log_map.toml", "--out", "x.h5"])
    assert r.exit_code == 0, r.output
    ds = Dataset.from_hdf5(tmp_path / "x.h5")
    assert len(ds) == 300 and ds.experiment_names() == ["sample_log"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.h5"]


def test_a_bundled_example_is_never_an_output(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    target = examples.resolve("bmw_i3_map.toml")
    before = target.read_bytes()
    r = runner.invoke(app, ["import", "example:sample_log.csv.gz", "--map",
                            "example:sample_log_map.toml", "--out", "example:bmw_i3_map.toml"])
    assert_one_line_error(r, "--out", "bundled")
    assert target.read_bytes() == before
