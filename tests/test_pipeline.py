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
