"""Generated C: compiled once per structure, cached, verified, loaded; clean fallbacks."""

from __future__ import annotations

import multiprocessing as mp
import warnings

import casadi as ca
import numpy as np
import pytest

from acid.errors import CodegenWarning
from acid.mpc import codegen, solver
from acid.mpc.codegen import CodegenError, compile_function, compiled_library, find_compiler
from acid.mpc.nmpc import NMPC, NMPCConfig
from acid.params import paper
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
    compiled = NMPC(paper())
    assert compiled.backend == "compiled"
    a = fallback.solve(x, ub, C2K(30.0), C2K(33.0))
    b = compiled.solve(x, ub, C2K(30.0), C2K(33.0))
    np.testing.assert_array_equal(a.u, b.u)  # the same algorithm: bit-identical


def test_compiled_and_casadi_fatrop_are_bit_identical_in_closed_loop():
    a, b = NMPC(paper()), NMPC(paper(), NMPCConfig(compiled=False))
    assert a.backend == "compiled" and b.backend == "casadi"
    x = np.array([C2K(30.0), C2K(9.0)])
    for k in range(5):
        ua = a.make_step(x, C2K(25.0 + 0.3 * k), C2K(30.0), C2K(33.0))
        ub = b.make_step(x, C2K(25.0 + 0.3 * k), C2K(30.0), C2K(33.0))
        np.testing.assert_array_equal(ua, ub)
        x = a.log.solutions[-1].T_cab[1], a.log.solutions[-1].T_evap[1]


def _build_in_child(directory, queue):
    cf, info = compile_function(_fn("acid_test_race"), directory=directory)
    queue.put((info["key"], float(cf(np.ones(3))[0][0])))


def test_concurrent_first_uses_build_one_entry_and_both_load(tmp_path):
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    procs = [ctx.Process(target=_build_in_child, args=(tmp_path, q)) for _ in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(120)
    results = [q.get(timeout=5) for _ in procs]
    assert all(p.exitcode == 0 for p in procs)
    assert results[0] == results[1]
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
