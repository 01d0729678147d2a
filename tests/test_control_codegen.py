"""Generated C: compiled once per structure, cached, verified, loaded; clean fallbacks."""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from acid.control.codegen import build as codegen
from acid.control.codegen import solver
from acid.control.codegen.build import (
    CodegenError,
    compile_function,
    compiled_library,
    find_compiler,
)
from acid.control.nmpc import NMPC, NMPCConfig
from acid.errors import CodegenWarning
from acid.models.params import paper
from acid.units import C2K

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="no C compiler")


def _fn(name="acid_test_fn", k=3.0):
    x = ca.SX.sym("x", 3)
    return ca.Function(name, [x], [ca.sin(x) * k + ca.sumsqr(x)])


def test_compiled_function_matches_casadi_and_is_cached(tmp_path):
    fn = _fn()
    cf, info = compile_function(fn, directory=tmp_path)
    x = np.array([0.1, -2.0, 3.0])
    np.testing.assert_array_equal(cf(x)[0], np.asarray(fn(x)).ravel())
    assert info["compile_s"] > 0 and info["repaired"] is None
    cf2, info2 = compile_function(fn, directory=tmp_path)
    assert info2["compile_s"] == 0.0 and info2["key"] == info["key"]  # from the cache
    assert len(list(tmp_path.glob("*.so"))) == 1 and len(list(tmp_path.glob("*.json"))) == 1
    # another structure, another entry
    _, info3 = compile_function(_fn(k=4.0), directory=tmp_path)
    assert info3["key"] != info["key"]


def test_a_corrupted_cache_entry_is_rebuilt_not_loaded(tmp_path):
    fn = _fn("acid_test_corrupt")
    lib, info = compiled_library(fn, directory=tmp_path)
    data = lib.read_bytes()
    lib.write_bytes(data[: len(data) // 2])  # truncated, as after a crash of the disk
    cf, info2 = compile_function(fn, directory=tmp_path)
    assert info2["repaired"] and "corrupted" in info2["repaired"]
    np.testing.assert_array_equal(cf(np.ones(3))[0], np.asarray(fn(np.ones(3))).ravel())
    assert lib.read_bytes() == data  # rebuilt identically


def test_a_missing_manifest_counts_as_corrupted(tmp_path):
    fn = _fn("acid_test_manifest")
    lib, _ = compiled_library(fn, directory=tmp_path)
    lib.with_suffix(".json").unlink()
    _, info = compiled_library(fn, directory=tmp_path)
    assert "manifest" in info["repaired"]


def test_a_bogus_compiler_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    with pytest.raises(CodegenError, match="no-such-cc"):
        compile_function(_fn("acid_test_bogus"), directory=tmp_path)


def test_a_failing_compiler_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "false")  # runs, fails every compilation
    monkeypatch.setattr(codegen, "_compiler_identity", lambda cc: "false: 0")
    with pytest.raises(CodegenError, match="failed"):
        compile_function(_fn("acid_test_false"), directory=tmp_path)
    assert not list(tmp_path.glob("*.so"))  # nothing half-written is left


def test_nmpc_falls_back_to_casadi_with_one_notice_and_the_same_answer(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("CC", str(tmp_path / "bogus-cc"))
    monkeypatch.setattr(solver, "_NOTICES", set())
    x, ub = [C2K(27.0), C2K(6.0)], C2K(25.0)
    with pytest.warns(CodegenWarning, match="bogus-cc"):
        fallback = NMPC(paper())
    with warnings.catch_warnings():
        warnings.simplefilter("error", CodegenWarning)  # one notice per process and reason
        NMPC(paper())
    assert fallback.backend == "casadi"
    monkeypatch.delenv("CC")
    monkeypatch.delenv("ACID_CACHE_DIR")  # the per-user cache: built once, like every NMPC's
    compiled = NMPC(paper())
    assert compiled.backend == "compiled"
    a = fallback.solve(x, ub, C2K(30.0), C2K(33.0))
    b = compiled.solve(x, ub, C2K(30.0), C2K(33.0))
    np.testing.assert_array_equal(a.u, b.u)  # the same algorithm: bit-identical


@pytest.mark.parametrize("solver_name", ["sqp", "fatrop"])
def test_compiled_and_casadi_solvers_are_bit_identical_in_closed_loop(solver_name):
    a = NMPC(paper(), NMPCConfig(solver=solver_name))
    b = NMPC(paper(), NMPCConfig(solver=solver_name, compiled=False))
    assert a.backend == "compiled" and b.backend == "casadi"
    x = np.array([C2K(30.0), C2K(9.0)])
    for k in range(5):
        ua = a.make_step(x, C2K(25.0 + 0.3 * k), C2K(30.0), C2K(33.0))
        ub = b.make_step(x, C2K(25.0 + 0.3 * k), C2K(30.0), C2K(33.0))
        np.testing.assert_array_equal(ua, ub)
        x = a.log.solutions[-1].T_cab[1], a.log.solutions[-1].T_evap[1]


def _build_in_child(directory, queue):
    cf, info = compile_function(_fn("acid_test_race"), directory=directory)
    queue.put((info["key"], float(cf(np.ones(3))[0][0]), info["compile_s"] > 0))


def test_concurrent_first_uses_build_one_entry_and_both_load(tmp_path):
    """The second process waits on the first one's lock and loads its build: one compile."""
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    procs = [ctx.Process(target=_build_in_child, args=(tmp_path, q)) for _ in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(600)
    results = [q.get(timeout=5) for _ in procs]
    assert all(p.exitcode == 0 for p in procs)
    assert results[0][:2] == results[1][:2]
    assert sorted(r[2] for r in results) == [False, True]  # exactly one of them compiled
    assert len(list(tmp_path.glob("*.so"))) == 1
    assert not list(tmp_path.glob("*.part"))


def test_a_reused_memory_slot_starts_afresh():
    """A released slot of the compiled solver is re-initialised for its next owner, so an
    instance's answers do not depend on what ran before it in the process."""
    x, ub = [C2K(26.3), C2K(7.0)], np.r_[C2K(25.5), np.full(6, C2K(25.2))]

    def first_move():
        return NMPC(paper()).solve(x, ub, C2K(30.0), C2K(33.0)).u

    before = first_move()
    other = NMPC(paper(), NMPCConfig(first_move="pinned"))  # another active-set structure
    other.solve([C2K(27.0), C2K(6.0)], C2K(25.0), C2K(30.0), C2K(33.0), u_prev=[0.1, C2K(5.0)])
    del other
    import gc

    gc.collect()
    np.testing.assert_array_equal(first_move(), before)


# ------------------------------------------------------ a cache key free of install paths
def test_the_cache_key_holds_no_install_path(tmp_path, monkeypatch):
    """One build serves every virtualenv and clone: neither where casadi is installed nor
    the compiler's path enters the key, and the library carries no rpath."""
    source = '#include <fatrop/ocp/OCPAbstract.hpp>\nint f(void) { return 0; }\n'
    libs = codegen.runtime_libraries(source)
    assert libs == ["blasfeo", "fatrop"]
    cc = find_compiler()
    key = codegen.build_key(source, cc, libs)
    alias = tmp_path / "bin" / "cc"  # the same compiler under another path
    alias.parent.mkdir()
    alias.symlink_to(Path(cc[0]) if os.path.isabs(cc[0]) else Path(
        __import__("shutil").which(cc[0])))
    monkeypatch.setattr(codegen, "casadi_dir", lambda: tmp_path / "other-venv" / "casadi")
    assert codegen.build_key(source, [str(alias), *cc[1:]], libs) == key
    assert str(tmp_path) in " ".join(codegen.link_flags(libs))  # used to compile, not keyed
    assert codegen.build_key(source + " ", cc, libs) != key
    monkeypatch.setattr(codegen, "OPT_FLAG", "-O0")
    assert codegen.build_key(source, cc, libs) != key


def test_large_sources_are_compiled_at_the_large_level(monkeypatch):
    monkeypatch.setattr(codegen, "LARGE_SOURCE", 100)
    assert codegen.cflags("x" * 99)[0] == codegen.OPT_FLAG
    assert codegen.cflags("x" * 100)[0] == codegen.LARGE_OPT_FLAG == "-O1"
    # a function called on every control step is built at the small sources' level, and
    # that build has a key of its own
    assert codegen.cflags("x" * 100, hot=True)[0] == codegen.OPT_FLAG
    cc = find_compiler()
    assert codegen.build_key("x" * 100, cc, [], hot=True) != codegen.build_key("x" * 100, cc, [])


def test_a_build_for_the_host_cpu_is_keyed_by_that_cpu(monkeypatch):
    """-march=native code must not be served to another CPU from a shared cache: the CPU
    the compiler resolves enters the key; a compiler that resolves none builds generic."""
    cc = find_compiler()
    source = "int f(void) { return 0; }\n"
    cpu = codegen.host_cpu(tuple(cc))
    if not cpu:
        pytest.skip(f"{cc[0]} does not resolve -march=native here")
    assert cpu.startswith("-march=") and "-march=native" not in cpu.split()
    assert "-march=native" in codegen.cflags(source, cc)
    key = codegen.build_key(source, cc, [])
    monkeypatch.setattr(codegen, "host_cpu", lambda cc: "-march=othercpu -mavx2")
    assert codegen.build_key(source, cc, []) != key
    monkeypatch.setattr(codegen, "host_cpu", lambda cc: "")
    assert "-march=native" not in codegen.cflags(source, cc)
    assert codegen.build_key(source, cc, []) != key


def test_a_fatrop_solver_library_names_no_install_path():
    mpc = NMPC(paper(), NMPCConfig(solver="fatrop"))
    assert mpc.backend == "compiled"
    info = mpc._nlp.build_info
    assert info["libraries"] == ["blasfeo", "fatrop"]
    lib = Path(info["path"]).read_bytes()
    assert str(codegen.casadi_dir()).encode() not in lib  # no rpath, no include path
    manifest = Path(info["path"]).with_suffix(".json").read_text()
    assert str(codegen.casadi_dir()) not in manifest


# ------------------------------------------------------------ a compile that finishes
def _script(tmp_path, body: str) -> Path:
    path = tmp_path / "fake-cc"
    path.write_text("#!/bin/sh\n" + body)
    path.chmod(0o755)
    return path


def _gone(pid: int) -> bool:
    """The process has ended (gone, or a zombie waiting for its reaper)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")


def _wait_gone(pid: int) -> bool:
    for _ in range(600):  # the verdict is "it ends", whatever the load (up to a minute)
        if _gone(pid):
            return True
        __import__("time").sleep(0.1)
    return False


def test_what_the_compiler_leaves_running_is_killed_with_it(tmp_path):
    pidfile = tmp_path / "pid"
    cc = _script(tmp_path, f"sleep 600 &\necho $! > {pidfile}\nexit 3\n")
    code, _, _ = codegen.run_compiler([str(cc)])
    assert code == 3
    assert _wait_gone(int(pidfile.read_text()))


def test_a_compiler_past_its_wall_backstop_is_stopped_with_its_whole_group(tmp_path):
    pidfile = tmp_path / "pid"
    cc = _script(tmp_path, f"sleep 600 &\necho $! > {pidfile}\nwait\n")
    with pytest.raises(CodegenError, match="did not finish"):
        codegen.run_compiler([str(cc)], wall_s=2.0)  # the script never ends by itself
    # (on a machine so loaded that the script had not yet started its child, there is
    # nothing left to kill; the test above checks the group kill without a race)
    if pidfile.exists() and pidfile.read_text().strip():
        assert _wait_gone(int(pidfile.read_text()))


def test_an_interrupt_during_a_compile_kills_the_whole_group(tmp_path, monkeypatch):
    pidfile = tmp_path / "pid"
    cc = _script(tmp_path, f"sleep 600 &\necho $! > {pidfile}\nwait\n")
    real_wait = subprocess.Popen.wait

    def interrupted(self, timeout=None):
        if timeout is None:  # the reaping wait after the kill
            return real_wait(self)
        while not (pidfile.exists() and pidfile.read_text().strip()):
            real_wait_or_none(self)
        raise KeyboardInterrupt  # Ctrl-C while the compiler runs

    def real_wait_or_none(proc):
        with contextlib.suppress(subprocess.TimeoutExpired):
            real_wait(proc, timeout=0.05)

    monkeypatch.setattr(subprocess.Popen, "wait", interrupted)
    with pytest.raises(KeyboardInterrupt):
        codegen.run_compiler([str(cc)])
    monkeypatch.undo()
    assert _wait_gone(int(pidfile.read_text()))


def test_the_compiler_is_bounded_by_cpu_time(tmp_path, monkeypatch):
    monkeypatch.setattr(codegen, "COMPILE_CPU_S", 1)
    spin = [sys.executable, "-c", "while True: pass"]  # a compiler that never finishes
    code, _, cpu = codegen.run_compiler(spin)
    assert code == -signal.SIGXCPU
    assert cpu > 0.5  # its CPU seconds are counted (about the 1 s limit)


def test_a_compile_killed_for_cpu_time_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setattr(codegen, "COMPILE_CPU_S", 1)
    monkeypatch.setattr(codegen, "_compiler_identity", lambda cc: "spin: 0")
    monkeypatch.setattr(codegen, "host_cpu", lambda cc: "")  # its probe would spin for 60 s
    cc = _script(tmp_path, f'exec {sys.executable} -c "while True: pass"\n')
    with pytest.raises(CodegenError, match="CPU seconds"):
        compile_function(_fn("acid_test_spin"), cc=[str(cc)], directory=tmp_path)
    assert not list(tmp_path.glob("*.so"))


# ------------------------------------------------------------------- the compile lock
def _entry(fn, directory: Path) -> tuple[Path, Path, Path]:
    source = codegen.generate_source(fn)
    key = codegen.build_key(source, find_compiler(), codegen.runtime_libraries(source))
    stem = f"{fn.name()}-{key}"
    return directory / f"{stem}.so", directory / f"{stem}.json", directory / f".{stem}.lock"


def test_a_lock_held_too_long_is_a_fallback_not_a_second_compile(tmp_path, monkeypatch):
    fn = _fn("acid_test_lockwait")
    lib, _, lock = _entry(fn, tmp_path)
    monkeypatch.setattr(codegen, "LOCK_WAIT_S", 0.3)
    fd = os.open(lock, os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)  # another process is building this entry
        with pytest.raises(CodegenError, match="another process"):
            compile_function(fn, directory=tmp_path)
        assert not lib.exists()
    finally:
        os.close(fd)
    cf, info = compile_function(fn, directory=tmp_path)  # lock free again: it builds
    assert info["compile_s"] > 0


# ------------------------------------------------- cache faults fall back (issue 24)
def _sqp_nlp():
    x = ca.SX.sym("x", 2)
    return {"x": x, "f": (x[0] - 1) ** 2 + (x[1] + 2) ** 2, "g": x[0] + x[1]}


SQP = {"qpsol": "qrqp", "print_time": False, "print_header": False, "print_iteration": False,
       "print_status": False, "qpsol_options": {"print_iter": False, "print_header": False,
                                                "print_info": False}}


def _solver_falls_back(monkeypatch, match: str):
    monkeypatch.setattr(solver, "_NOTICES", set())
    with pytest.warns(CodegenWarning, match=match) as rec:
        s = solver.NLPSolver("acid_test_fault", _sqp_nlp(), "sqpmethod", SQP)
    assert len([w for w in rec if w.category is CodegenWarning]) == 1
    assert s.backend == "casadi"
    res = s.solve(np.zeros(2), [], -np.inf, np.inf, -10.0, 10.0)
    assert res.success
    np.testing.assert_allclose(res.x, [1.0, -2.0], atol=1e-8)


def test_a_file_where_the_cache_folder_goes_falls_back(tmp_path, monkeypatch):
    (tmp_path / "nmpc").write_text("not a folder")
    monkeypatch.setenv("ACID_CACHE_DIR", str(tmp_path))
    with pytest.raises(CodegenError, match="cannot be used"):
        compile_function(_fn(), directory=tmp_path / "nmpc")
    _solver_falls_back(monkeypatch, "cannot be used")


def test_a_folder_where_the_lock_goes_falls_back(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_CACHE_DIR", str(tmp_path))
    folder = tmp_path / "nmpc"
    gen = ca.nlpsol("acid_test_fault", "sqpmethod", _sqp_nlp(), dict(SQP, error_on_fail=True))
    _, _, lock = _entry(gen, folder)
    lock.mkdir(parents=True)
    _solver_falls_back(monkeypatch, "cannot be used")
    assert not list(folder.glob("*.so"))


def test_a_read_only_cache_loads_what_it_holds_and_builds_nothing(tmp_path, monkeypatch):
    fn = _fn("acid_test_ro")
    lib, _, lock = _entry(fn, tmp_path)
    compiled_library(fn, directory=tmp_path)  # a valid entry
    lock.unlink()
    empty = tmp_path / "empty"
    empty.mkdir()
    for d in (tmp_path, empty):
        d.chmod(0o555)
    try:
        if os.access(tmp_path, os.W_OK):  # root ignores the mode: read-only as EROFS does
            def ro(path):
                raise OSError(errno.EROFS, "Read-only file system", str(path))
            monkeypatch.setattr(codegen, "_open_lock", ro)
        cf, info = compile_function(fn, directory=tmp_path)
        assert info["compile_s"] == 0.0
        np.testing.assert_array_equal(cf(np.ones(3))[0], np.asarray(fn(np.ones(3))).ravel())
        with pytest.raises(CodegenError, match="read-only"):
            compile_function(fn, directory=empty)
    finally:
        for d in (tmp_path, empty):
            d.chmod(0o755)


def _forge_manifest(lib: Path, verified: bool) -> None:
    """Rewrite the manifest so that it agrees with whatever ``lib`` now holds."""
    manifest = lib.with_suffix(".json")
    meta = json.loads(manifest.read_text())
    meta["sha256"] = hashlib.sha256(lib.read_bytes()).hexdigest()
    if verified:
        meta["verified"] = meta["sha256"]
    else:
        meta.pop("verified", None)
    manifest.write_text(json.dumps(meta))


def _load_in_child(directory, name, queue):
    fn = _fn(name)
    cf, info = compile_function(fn, directory=directory)
    ok = bool(np.array_equal(cf(np.ones(3))[0], np.asarray(fn(np.ones(3))).ravel()))
    queue.put((ok, info["repaired"]))


def _in_child(directory, name):
    """compile_function in a spawned process: a crash there fails the test, not the run."""
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    p = ctx.Process(target=_load_in_child, args=(directory, name, q))
    p.start()
    p.join(600)
    assert p.exitcode == 0, f"the process died (exit code {p.exitcode})"
    return q.get(timeout=5)


@pytest.mark.parametrize("verified", [False, True])
def test_a_truncated_library_with_a_consistent_manifest_is_rebuilt_not_loaded(
        tmp_path, verified):
    name = f"acid_test_trunc{int(verified)}"
    lib, _ = compiled_library(_fn(name), directory=tmp_path)
    data = lib.read_bytes()
    lib.write_bytes(data[: len(data) * 2 // 3])  # used to kill the process with SIGBUS
    _forge_manifest(lib, verified)
    assert codegen.elf_problem(lib.read_bytes())
    ok, repaired = _in_child(tmp_path, name)
    assert ok and "damaged" in repaired
    assert lib.read_bytes() == data


def test_a_library_that_crashes_when_loaded_is_caught_in_a_child_and_rebuilt(tmp_path):
    name = "acid_test_crash"
    lib, _ = compiled_library(_fn(name), directory=tmp_path)
    evil = tmp_path / "evil.c"
    evil.write_text("#include <signal.h>\n"
                    "__attribute__((constructor)) static void boom(void) { raise(SIGBUS); }\n"
                    f"long long {name}_n_in(void) {{ return 1; }}\n")
    code, out, _ = codegen.run_compiler([*find_compiler(), "-shared", "-fPIC", str(evil),
                                         "-o", str(lib)])
    assert code == 0, out
    assert codegen.elf_problem(lib.read_bytes()) is None  # a well-formed library
    _forge_manifest(lib, verified=False)
    assert "SIGBUS" in codegen.load_in_child(lib, name, [], 1)
    ok, repaired = _in_child(tmp_path, name)
    assert ok and "trial load" in repaired


def test_a_verified_entry_is_not_loaded_in_a_child_again(tmp_path, monkeypatch):
    fn = _fn("acid_test_once")
    lib, _ = compiled_library(fn, directory=tmp_path)
    meta = json.loads(lib.with_suffix(".json").read_text())
    assert meta["verified"] == meta["sha256"]
    calls = []
    monkeypatch.setattr(codegen, "load_in_child", lambda *a: calls.append(a))
    compile_function(fn, directory=tmp_path)
    assert calls == []


def test_elf_check_refuses_what_is_not_a_whole_shared_object(tmp_path):
    lib, _ = compiled_library(_fn("acid_test_elf"), directory=tmp_path)
    data = lib.read_bytes()
    assert codegen.elf_problem(data) is None
    assert codegen.elf_problem(b"") == "not an ELF file"
    assert codegen.elf_problem(b"#!/bin/sh\n" * 10) == "not an ELF file"
    for cut in (63, 200, len(data) // 2, len(data) - 1):
        assert codegen.elf_problem(data[:cut]), cut
