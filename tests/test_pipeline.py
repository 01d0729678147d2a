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
