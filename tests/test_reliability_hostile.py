"""The generated hostile scan (``tests/_hostile.py``), a sample of every class run here:
bad files in every file slot (empty, truncated HDF5/CSV, a folder, missing, a plain file),
outputs that cannot be written, an earlier ``--json`` a refused run must keep, and every
command's numeric option given twice. Each is one ``error:`` line naming the culprit, exit 2,
nothing changed in the workspace. (The full scan, with NaN/inf/1e300/-1/0/below absolute
zero for every numeric option: ``python tests/_hostile.py``.)"""

from __future__ import annotations

import pytest
from _catalogue import build_workspace
from _hostile import BAD_FILES, probes, run_probe


def _sample():
    """Every bad kind in the first file slot and one (rotating) in each other slot; per
    command one output probe of each kind, one kept --json, one option given twice."""
    chosen, seen = [], set()
    for p in probes():
        if p.group.startswith("file"):
            k = int(p.group[4:])
            if k and p.value != BAD_FILES[(k + 1) % len(BAD_FILES)]:
                continue
            key = (p.group, p.value)
        elif p.group in ("out", "twice", "kept"):
            key = (p.group, p.command, p.value if p.group == "out" else "")
        else:
            continue
        if key not in seen:
            seen.add(key)
            chosen.append(p)
    return chosen


SAMPLE = _sample()


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    return build_workspace(tmp_path_factory.mktemp("hostile") / "template")


def test_the_sample_covers_every_class():
    kinds = {p.value for p in SAMPLE}
    assert set(BAD_FILES) | {"twice", "nan+json"} <= kinds, kinds
    assert {p.group for p in SAMPLE} >= {"out", "kept", "twice", "file0", "file18"}
    assert len({p.command for p in SAMPLE if p.value == "twice"}) >= 12


@pytest.mark.parametrize("probe", SAMPLE, ids=[p.id for p in SAMPLE])
def test_hostile_input_is_one_line_naming_the_culprit(probe, template, tmp_path):
    verdict, out, took = run_probe(probe, template, tmp_path / "w", seconds=60.0)
    assert verdict == "clean", f"{verdict} after {took:.1f} s: {out}"
