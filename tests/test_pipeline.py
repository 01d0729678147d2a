"""The cached stage runner behind ``acid reproduce``: order, caching, atomic outputs, jobs."""

from __future__ import annotations

import json

import pytest

from acid.errors import AcidError
from acid.pipeline import Stage, run_pipeline


def make_number(workdir, inputs, config, progress):
    progress(1, 1)
    (workdir / "number.json").write_text(json.dumps({"value": config["value"]}))
    return {"value": config["value"]}


def add_numbers(workdir, inputs, config, progress):
    total = sum(json.loads((p / "number.json").read_text())["value"] for p in inputs.values())
    (workdir / "sum.txt").write_text(str(total))
    return {"sum": total}


def explode(workdir, inputs, config, progress):
    (workdir / "half-written.txt").write_text("partial")
    raise RuntimeError("stage failed")


def _stages(a=1, b=2):
    return [
        Stage("a", "A", make_number, {"value": a}),
        Stage("b", "B", make_number, {"value": b}),
        Stage("sum", "A + B", add_numbers, {}, depends=("a", "b")),
    ]


def test_runs_in_dependency_order_and_caches(tmp_path):
    out = run_pipeline(_stages(), tmp_path)
    assert out["sum"].summary == {"sum": 3}
    assert not any(o.cached for o in out.values())
    again = run_pipeline(_stages(), tmp_path)
    assert all(o.cached for o in again.values())


def test_changed_config_reruns_only_what_depends_on_it(tmp_path):
    run_pipeline(_stages(), tmp_path)
    out = run_pipeline(_stages(b=5), tmp_path)
    assert out["a"].cached and not out["b"].cached and not out["sum"].cached
    assert out["sum"].summary == {"sum": 6}


def test_failed_stage_leaves_no_partial_output(tmp_path):
    with pytest.raises(RuntimeError):
        run_pipeline([Stage("x", "X", explode)], tmp_path)
    assert not (tmp_path / "stages" / "x").exists()
    assert not list((tmp_path / "stages").glob(".x.*"))


def test_unknown_dependency_is_refused(tmp_path):
    with pytest.raises(AcidError, match="unknown stage"):
        run_pipeline([Stage("s", "S", add_numbers, depends=("nope",))], tmp_path)


def test_parallel_jobs_give_the_same_result(tmp_path):
    seen = []
    out = run_pipeline(_stages(), tmp_path, jobs=2, on_progress=lambda n, d, t: seen.append(n))
    assert out["sum"].summary == {"sum": 3}
    assert {"a", "b"} <= set(seen)


def test_next_run_removes_what_a_killed_run_left(tmp_path):
    stale = tmp_path / "stages" / ".a.k1ll3d.tmp"
    stale.mkdir(parents=True)
    (stale / "number.json").write_text('{"value": 99}')
    from _procs import dead_pid

    (tmp_path / f".summary.json.{dead_pid()}.x9.part").write_text("{")
    out = run_pipeline(_stages(), tmp_path)
    assert out["sum"].summary == {"sum": 3}
    assert not list(tmp_path.rglob(".*.tmp")) and not list(tmp_path.rglob(".*.part"))


def test_a_second_run_into_a_held_folder_is_refused(tmp_path):
    import subprocess
    import sys

    hold = ("import sys\nfrom acid.outdir import claim\nwith claim(sys.argv[1], 'acid reproduce'):"
            "\n    print('held', flush=True)\n    sys.stdin.readline()\n")
    p = subprocess.Popen([sys.executable, "-c", hold, str(tmp_path)], text=True,
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert p.stdout.readline().strip() == "held"
        with pytest.raises(AcidError, match=f"in use by acid reproduce \\(pid {p.pid}"):
            run_pipeline(_stages(), tmp_path)
    finally:
        p.communicate("\n", timeout=30)
    assert not (tmp_path / "stages").exists()


def test_without_dask_parallel_jobs_run_here_with_a_notice(tmp_path, monkeypatch):
    import acid.executor

    monkeypatch.setattr(acid.executor, "dask_available", lambda: False)
    notes = []
    out = run_pipeline(_stages(), tmp_path, jobs=2, notice=notes.append)
    assert out["sum"].summary == {"sum": 3}
    assert len(notes) == 1 and "pip install 'acid[distributed]'" in notes[0]


# ------------------------------------------------ stage records validated on reuse (issue 24)
def _record(root, name):
    return root / "stages" / name / "stage.json"


def test_a_record_carries_its_content_hash_and_its_files_hashes(tmp_path):
    from acid._io import file_sha256

    run_pipeline(_stages(), tmp_path)
    d = json.loads(_record(tmp_path, "a").read_text())
    assert d["file_sha256"] == {"number.json": file_sha256(tmp_path / "stages/a/number.json")}
    assert len(d["content_sha256"]) == 64 and d["key"]


@pytest.mark.parametrize("tamper", ["summary", "file", "missing file", "hash", "not json"])
def test_a_tampered_record_is_recomputed_with_one_notice(tmp_path, tamper):
    run_pipeline(_stages(), tmp_path)
    rec = _record(tmp_path, "a")
    d = json.loads(rec.read_text())
    if tamper == "summary":        # the cached result edited: the sum would be wrong
        d["summary"]["value"] = 100
        rec.write_text(json.dumps(d))
    elif tamper == "file":         # an output file a later stage reads
        (tmp_path / "stages/a/number.json").write_text('{"value": 100}')
    elif tamper == "missing file":
        (tmp_path / "stages/a/number.json").unlink()
    elif tamper == "hash":
        d["content_sha256"] = "0" * 64
        rec.write_text(json.dumps(d))
    else:
        rec.write_text("{ not json")
    notes = []
    out = run_pipeline(_stages(), tmp_path, notice=notes.append)
    assert not out["a"].cached and out["b"].cached
    assert out["a"].summary == {"value": 1} and out["sum"].summary == {"sum": 3}
    (line,) = notes
    assert line.startswith("stage a: the cached record") and "recomputing it" in line
    assert "\n" not in line
    # recomputed: the next run reuses it without a word
    notes.clear()
    again = run_pipeline(_stages(), tmp_path, notice=notes.append)
    assert all(o.cached for o in again.values()) and notes == []


def test_a_record_for_other_inputs_is_recomputed_silently(tmp_path):
    run_pipeline(_stages(), tmp_path)
    notes = []
    out = run_pipeline(_stages(a=7), tmp_path, notice=notes.append)
    assert not out["a"].cached and out["sum"].summary == {"sum": 9} and notes == []


def test_a_record_of_another_acid_version_is_not_reused(tmp_path, monkeypatch):
    import acid.pipeline

    monkeypatch.setattr(acid.pipeline, "source_fingerprint", lambda: "same code")
    run_pipeline(_stages(), tmp_path)
    assert all(o.cached for o in run_pipeline(_stages(), tmp_path).values())
    monkeypatch.setattr(acid.pipeline, "__version__", "0.0.0-other")
    out = run_pipeline(_stages(), tmp_path)
    assert not any(o.cached for o in out.values())


def test_acid_reproduce_again_into_the_same_folder_reuses_and_says_so(tmp_path, monkeypatch):
    """The README's promise (issue 24): a later run into the same folder reuses the cached
    stages, names them in one line and writes the report again; a tampered record is
    recomputed with one line."""
    from typer.testing import CliRunner

    import acid_cli.reproduce as cli_reproduce
    from acid_cli.main import app

    monkeypatch.setattr(cli_reproduce, "build_stages", lambda opts: _stages())
    args = ["reproduce", "--out", str(tmp_path), "--jobs", "1"]
    first = CliRunner().invoke(app, args)
    assert first.exit_code == 0, first.output
    assert "reused" not in first.output
    report = tmp_path / "report.html"
    report.unlink()
    second = CliRunner().invoke(app, args)
    assert second.exit_code == 0, second.output
    (line,) = [ln for ln in second.output.splitlines() if ln.startswith("note: reused")]
    assert "reused 3 of 3 stages" in line and "a, b, sum" in line
    assert report.is_file()
    d = json.loads(_record(tmp_path, "b").read_text())
    d["summary"]["value"] = 40
    _record(tmp_path, "b").write_text(json.dumps(d))
    third = CliRunner().invoke(app, args)
    assert third.exit_code == 0, third.output
    (line,) = [ln for ln in third.output.splitlines() if ln.startswith("stage b:")]
    assert "the cached record" in line and "recomputing it" in line
    assert "reused 2 of 3 stages" in third.output and "(a, sum:" in third.output
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["stages"]["sum"]["summary"] == {"sum": 3}
