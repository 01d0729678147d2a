"""acid._io: atomic writes refuse bad targets in one line and clean up after killed writers."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from acid._io import atomic_path, clean_stale_parts, write_json, write_text
from acid.errors import OutputError

WRITER = """
import sys, time
from acid._io import atomic_path
with atomic_path(sys.argv[1]) as tmp:
    tmp.write_bytes(b"half of a file")
    print("ready", flush=True)
    time.sleep(60)
"""


def _killed_writer(target) -> None:
    """A process writing ``target`` through ``atomic_path``, killed with SIGKILL mid-write."""
    p = subprocess.Popen([sys.executable, "-c", WRITER, str(target)], stdout=subprocess.PIPE,
                         text=True)
    try:
        assert p.stdout.readline().strip() == "ready"
    finally:
        p.send_signal(signal.SIGKILL)
        p.wait()


def _parts(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".part"))


def test_a_killed_writer_leaves_only_a_part_file_and_the_next_write_removes_it(tmp_path):
    target = tmp_path / "out.json"
    write_text(target, "earlier\n")
    _killed_writer(target)
    assert target.read_text() == "earlier\n"  # the earlier output is intact
    assert len(_parts(tmp_path)) == 1
    write_json(tmp_path / "other.json", {"a": 1})  # any later write into the folder
    assert _parts(tmp_path) == []
    assert target.read_text() == "earlier\n"


def test_part_files_of_live_writers_are_kept(tmp_path):
    live = tmp_path / f".x.json.{os.getpid()}.abcd1234.part"
    live.write_text("being written by this very process")
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        theirs = tmp_path / f".y.json.{other.pid}.abcd1234.part"
        theirs.write_text("being written by a live process")
        assert clean_stale_parts(tmp_path) == []
    finally:
        other.kill()
        other.wait()
    assert clean_stale_parts(tmp_path) == [theirs]
    assert live.exists()


def test_old_part_files_without_a_process_id_are_removed(tmp_path):
    legacy = tmp_path / ".x.h5.k3j2h1g0.part"
    legacy.write_text("from an older acid")
    assert clean_stale_parts(tmp_path) == []  # young: maybe somebody is writing it
    old = time.time() - 7200
    os.utime(legacy, (old, old))
    assert clean_stale_parts(tmp_path) == [legacy]


@pytest.mark.parametrize("make,target,fragment", [
    (lambda d: (d / "adir").mkdir(), "adir", "is a folder"),
    (lambda d: (d / "afile").write_text("x"), "afile/out.json", "is a file, not a folder"),
    (lambda d: (d / "afile").write_text("x"), "afile/a/b/out.json", "is a file, not a folder"),
])
def test_bad_targets_are_one_line_output_errors(tmp_path, make, target, fragment):
    make(tmp_path)
    with pytest.raises(OutputError, match=fragment) as info:
        write_json(tmp_path / target, {})
    assert "\n" not in str(info.value) and str(tmp_path / target) in str(info.value)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_folder_is_an_output_error(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(OutputError, match="not writable"):
            write_text(ro / "x.txt", "x")
    finally:
        ro.chmod(0o700)


def test_an_error_inside_the_write_keeps_the_old_file_and_no_part(tmp_path):
    target = tmp_path / "x.txt"
    write_text(target, "old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("new, half")
        raise RuntimeError("boom")
    assert target.read_text() == "old" and _parts(tmp_path) == []


def _file_size_limit(nbytes: int):
    """``preexec_fn``: files of this process may not grow beyond ``nbytes`` (writes past it
    fail with EFBIG instead of killing the process with SIGXFSZ)."""
    import resource

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))
    return limit


@pytest.mark.slow
@pytest.mark.parametrize("args, culprit", [
    (["export-c", "--no-check", "--out", "OUT/c"], "OUT/c/acid_nmpc_solver.c"),
    (["export-fmu", "--out", "OUT/p.fmu"], "OUT/p.fmu"),
    (["claims", "--json", "OUT/c.json"], "OUT/c.json"),
    (["excite", "--duration", "600", "--out", "OUT/x.h5"], "OUT/x.h5"),  # an HDF5 dataset
])
def test_a_file_size_limit_is_one_line_naming_the_output(tmp_path, args, culprit):
    """EFBIG (a quota or ``ulimit -f``): one line naming the output, exit 2, no temporary
    file and no temporary folder left."""
    exe = os.path.join(os.path.dirname(sys.executable), "acid")
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    out = tmp_path / "out"
    r = subprocess.run([exe, *[a.replace("OUT", str(out)) for a in args]], text=True,
                       capture_output=True, preexec_fn=_file_size_limit(2048), timeout=600,
                       env={**os.environ, "TMPDIR": str(tmp)})
    lines = [ln for ln in (r.stdout + r.stderr).splitlines() if ln.strip()]
    assert r.returncode == 2, lines
    assert lines[-1].startswith("error: ") and culprit.replace("OUT", str(out)) in lines[-1]
    assert "File too large" in lines[-1] and "internal error" not in lines[-1]
    assert "Traceback" not in r.stderr
    assert [p for p in out.rglob(".*")] == [] and list(tmp.iterdir()) == []
