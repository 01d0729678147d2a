"""Output folders owned by one run: the lock, its message, stale temporaries removed."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest
from _procs import dead_pid

from acid.errors import AcidError
from acid.outdir import LOCK_NAME, FolderBusyError, claim, clean_stale

HOLD = textwrap.dedent("""
    import sys, time
    from acid.outdir import claim
    with claim(sys.argv[1], "acid test-holder"):
        print("held", flush=True)
        sys.stdin.readline()
""")


def test_a_second_process_is_refused_with_the_holder_named(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(tmp_path)], text=True,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(FolderBusyError, match=rf"in use by acid test-holder \(pid "
                                                   rf"{holder.pid}"):
            with claim(tmp_path, "acid test"):
                pass
    finally:
        holder.communicate("\n", timeout=30)
    with claim(tmp_path, "acid test"):  # released when the holder ended
        pass


def test_lock_of_a_killed_process_does_not_block(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(tmp_path)], text=True,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    assert holder.stdout.readline().strip() == "held"
    holder.kill()
    holder.wait(timeout=30)
    assert (tmp_path / LOCK_NAME).exists()
    with claim(tmp_path, "acid test"):
        pass


def test_claims_are_reentrant_in_one_process(tmp_path):
    with claim(tmp_path, "outer"), claim(tmp_path / ".", "inner"):
        pass
    with claim(tmp_path, "again"):
        pass


def test_stale_temporaries_are_removed_and_results_kept(tmp_path):
    (tmp_path / "stages" / ".fit.ab12.tmp").mkdir(parents=True)
    (tmp_path / "stages" / ".fit.ab12.tmp" / "params.json").write_text("{}")
    (tmp_path / "stages" / "sweep").mkdir()
    (tmp_path / "stages" / "sweep" / "sweep.json").write_text("{}")
    pid = dead_pid()
    (tmp_path / f".report.html.{pid}.x1y2.part").write_text("<html")
    (tmp_path / "scenarios").mkdir()
    (tmp_path / "scenarios" / f".0123.json.{pid}.zz.part").write_text("{")
    (tmp_path / "keep.txt").write_text("mine")
    with claim(tmp_path, "acid test"):
        left = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    assert left == [LOCK_NAME, "keep.txt", "scenarios", "stages", "stages/sweep",
                    "stages/sweep/sweep.json"]
    assert clean_stale(tmp_path / "missing") == []


def test_a_file_is_not_an_output_folder(tmp_path):
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(AcidError, match="is a file"):
        with claim(f, "acid test"):
            pass
