"""The stage runner's order of work: the longest remaining chain of estimated costs starts
first, never more stages in flight than workers, CPU seconds recorded."""

from __future__ import annotations

import math

from acid.executor import InlineExecutor
from acid.pipeline import Stage, chain_costs, run_pipeline


def busy(workdir, inputs, config, progress):
    x = 0
    for i in range(config.get("loops", 1000)):
        x += i * i
    (workdir / "x.txt").write_text(str(x))
    progress(1, 1)
    return {"x": x}


def _graph():
    # a cheap stage at the head of a long chain, a long lone stage, a short lone stage
    return [Stage("head", "head", busy, {}, cost=1.0),
            Stage("tail", "tail", busy, {}, depends=("head",), cost=100.0),
            Stage("lone_long", "lone long", busy, {}, cost=50.0),
            Stage("lone_short", "lone short", busy, {}, cost=2.0)]


def test_chain_costs_are_bottom_levels():
    rank = chain_costs(_graph())
    assert rank == {"head": 101.0, "tail": 100.0, "lone_long": 50.0, "lone_short": 2.0}


class _TwoSlots(InlineExecutor):
    """Runs inline but says it has two workers; records how many tasks were in flight."""

    def __init__(self):
        super().__init__()
        self.workers = 2
        self.most = 0

    def submit(self, fn, *args):
        task = super().submit(fn, *args)
        self.most = max(self.most, len(self._pending))
        return task


def test_longest_chain_first_and_no_more_in_flight_than_workers(tmp_path):
    started: list[str] = []
    ex = _TwoSlots()
    out = run_pipeline(_graph(), tmp_path, executor=ex, on_start=started.append)
    # the chain's head first (101), then the long lone stage; the short one waits for a free
    # worker and the tail (100) overtakes it as soon as its head is done
    assert started == ["head", "lone_long", "tail", "lone_short"]
    assert ex.most == 2
    assert all(o.cpu_seconds >= 0.0 and not math.isnan(o.cpu_seconds) for o in out.values())
    again = run_pipeline(_graph(), tmp_path, executor=_TwoSlots())
    assert all(o.cached for o in again.values())
    assert again["tail"].cpu_seconds == out["tail"].cpu_seconds   # read back from the record


def test_one_worker_keeps_the_declared_order(tmp_path):
    started: list[str] = []
    run_pipeline(_graph(), tmp_path, on_start=started.append)
    assert started == ["head", "lone_long", "lone_short", "tail"]
