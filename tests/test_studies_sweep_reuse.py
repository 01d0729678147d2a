"""A sweep's paper NMPCs are built once per thread and reused (the warm-up, the controllers,
the tails and the scenarios of one climate): the same numbers as fresh builds, fewer builds."""

from __future__ import annotations

import math

import pytest

from acid.studies.sweep import context, spec_from_dict
from acid.studies.sweep.scenario import run_scenario, scenario_tasks

#: short scenarios (60 s at 15 m/s after a 60 s warm-up, a 30 s tail); the second and third
#: share the climate options of the NMPC (ambient), not the humidity
SPEC = {"title": "reuse", "defaults": {"cycle": 15.0, "duration_s": 60.0, "warmup_s": 60.0,
                                       "tail_s": 30.0},
        "scenarios": [{"ambient_C": 30.0}, {"ambient_C": 36.0, "humidity_pct": 40.0},
                      {"ambient_C": 36.0, "humidity_pct": 60.0}],
        "controllers": {"nmpc": {}, "icm": {}}}


def _numbers(record: dict) -> list:
    """Every number of the record's rows but the timings and the provenance."""
    out = []
    for row in record["rows"]:
        for k, v in sorted(row.items()):
            if isinstance(v, float) and "_ms" not in k and not k.endswith("_s") \
                    and "time" not in k:
                out.append((row["controller"], k, v))
    return out


def _run(monkeypatch, keep: int) -> tuple[list, int]:
    built = []

    class Counted(context.NMPC):
        def __init__(self, *a, **kw):
            built.append(1)
            super().__init__(*a, **kw)

    monkeypatch.setattr(context, "NMPC", Counted)
    monkeypatch.setattr(context, "BUILT_KEEP", keep)
    monkeypatch.setattr(context, "_BUILT", type(context._BUILT)())   # an empty cache
    tasks = scenario_tasks(spec_from_dict(SPEC, "reuse"))
    records = [run_scenario(t) for t in tasks]
    assert all(r["status"] == "ok" for r in records), [r["error"] for r in records]
    return [_numbers(r) for r in records], len(built)


def test_reused_nmpcs_give_the_numbers_of_fresh_builds(monkeypatch):
    fresh, n_fresh = _run(monkeypatch, keep=0)
    reused, n_reused = _run(monkeypatch, keep=4)
    # per scenario: warm-up, nmpc, icm and two tails; one build per climate when reused
    assert n_fresh == 3 * 5 and n_reused == 2
    assert len(fresh[0]) > 10
    for a, b in zip(fresh, reused, strict=True):
        assert [k for *k, _ in a] == [k for *k, _ in b]
        for (c, k, x), (_, _, y) in zip(a, b, strict=True):
            assert x == y or (math.isnan(x) and math.isnan(y)), (c, k, x, y)
    if any(x != 0 for rec in fresh for *_, x in rec):
        return
    pytest.fail("every number is zero: nothing was compared")
