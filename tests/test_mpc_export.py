"""acid export-c: a standalone C package whose first move is acid's NMPC's."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acid.mpc.codegen import find_compiler
from acid.mpc.export import build_example, check_export, export_c, run_example
from acid.mpc.nmpc import NMPCConfig
from acid.params import paper
from acid.units import C2K

needs_cc = pytest.mark.skipif(find_compiler() is None, reason="no C compiler")


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    out = tmp_path_factory.mktemp("export")
    export_c(paper(), out)
    return out


def test_the_package_holds_plain_c_and_says_what_it_is(package):
    names = {p.name for p in package.iterdir()}
    assert names == {"acid_nmpc_solver.c", "acid_nmpc.h", "acid_nmpc.c", "main.c", "Makefile",
                     "problem.json"}
    solver = (package / "acid_nmpc_solver.c").read_text()
    includes = {ln.split()[1] for ln in solver.splitlines() if ln.startswith("#include")}
    assert includes <= {"<math.h>", "<stdarg.h>", "<stdio.h>", "<string.h>"}  # libc only
    header = (package / "acid_nmpc.h").read_text()
    assert "int acid_nmpc_step(const double *x, const double *disturbances" in header
    meta = json.loads((package / "problem.json").read_text())
    assert meta["N"] == 6 and meta["solver"] == "sqpmethod + qrqp"
    assert meta["params"]["gamma"] == list(paper().gamma)


@needs_cc
def test_exported_first_move_matches_the_python_nmpc_on_20_states(package):
    res = check_export(package, paper(), n_states=24, seed=3)
    assert res["states"] == 24 and res["c_status_ok"] == 24
    assert res["max_rel_diff_vs_sqp"] <= 1e-9  # the same algorithm in Python
    assert res["max_rel_diff_vs_fatrop"] <= 1e-6  # the default (interior-point) solver


@needs_cc
def test_the_exported_step_refuses_bad_inputs_with_the_safe_move(package, tmp_path):
    exe = build_example(package, tmp_path)
    ok = (np.array([C2K(25.5), C2K(6.0)]),
          np.array([C2K(30.0), C2K(33.0), C2K(30.0), 0.0, 0.0]),
          np.r_[np.full(6, C2K(26.0)), np.full(6, C2K(20.0))])
    nan_state = (np.array([np.nan, C2K(6.0)]), ok[1], ok[2])
    celsius = (np.array([27.0, 6.0]), ok[1], ok[2])
    out = run_example(exe, [ok, nan_state, celsius])
    safe = NMPCConfig().u_safe
    assert out[0, 0] == 0 and not np.allclose(out[0, 1:], safe)
    for row in out[1:]:
        assert row[0] == 1  # ACID_NMPC_BAD_INPUT
        np.testing.assert_array_equal(row[1:], safe)
