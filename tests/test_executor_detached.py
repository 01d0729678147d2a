"""``acid reproduce --scheduler ADDRESS`` without a shared disk: the stages run on an existing
cluster whose workers work in their own folder; their inputs travel with the tasks and their
files come back through the client, which writes them under OUT."""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

import pytest

from acid.pipeline import Stage, run_pipeline

pytest.importorskip("distributed")


def produce(workdir, inputs, config, progress):
    """A first stage: one file in a sub-folder."""
    (workdir / "sub").mkdir()
    (workdir / "sub" / "number.json").write_text(json.dumps({"x": config["x"]}))
    progress(1, 1)
    return {"x": config["x"], "workdir": str(workdir), "pid": os.getpid()}


def consume(workdir, inputs, config, progress):
    """A second stage: reads its input's file from wherever the worker was given it."""
    x = json.loads((inputs["a"] / "sub" / "number.json").read_text())["x"]
    (workdir / "double.txt").write_text(str(2 * x))
    return {"double": 2 * x, "workdir": str(workdir), "input": str(inputs["a"]),
            "pid": os.getpid()}


@pytest.fixture
def cluster(tmp_path_factory):
    """A real local Dask cluster of 2 worker processes whose folders are not the run's."""
    from distributed import LocalCluster

    scratch = tmp_path_factory.mktemp("workers-elsewhere")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None, local_directory=str(scratch),
                      silence_logs=logging.ERROR) as c:
        yield c, scratch


def test_stages_run_on_a_scheduler_without_a_shared_disk(tmp_path, cluster):
    c, scratch = cluster
    root = tmp_path / "out"
    stages = [Stage("a", "a", produce, {"x": 21}),
              Stage("b", "b", consume, {}, depends=("a",))]
    outcomes = run_pipeline(stages, root, scheduler=c.scheduler_address)
    a, b = outcomes["a"].summary, outcomes["b"].summary
    assert b["double"] == 42
    # the stages ran on the workers, in the workers' own folder, never under OUT
    assert os.getpid() not in (a["pid"], b["pid"])
    for where in (a["workdir"], b["workdir"], b["input"]):
        assert Path(where).is_relative_to(scratch) and not Path(where).is_relative_to(root)
        assert not Path(where).exists()  # the worker's scratch folder is removed
    # the client wrote what came back, with records that pass the cache's checks
    assert (root / "stages" / "a" / "sub" / "number.json").is_file()
    assert (root / "stages" / "b" / "double.txt").read_text() == "42"
    again = run_pipeline(stages, root, scheduler=c.scheduler_address)
    assert all(o.cached for o in again.values())
    assert not any(p.name.startswith(".") for p in (root / "stages").iterdir())
