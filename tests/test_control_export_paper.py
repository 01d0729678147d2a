"""acid export-c: a standalone C package whose first move is acid's NMPC's."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acid.control.codegen.build import find_compiler
from acid.control.codegen.export_paper import (
    MAX_DISTURBANCE_K,
    STATUS,
    build_example,
    c_number,
    c_text,
    check_export,
    export_c,
    run_example,
)
from acid.control.nmpc import NMPCConfig
from acid.errors import ConfigError
from acid.models.params import paper
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
    assert out[1, 0] == STATUS["not_finite"] and out[2, 0] == STATUS["implausible_temperature"]
    for row in out[1:]:
        np.testing.assert_array_equal(row[1:], safe)


def _ctypes_step(package, tmp_path):
    """``acid_nmpc_step`` of the package compiled into a shared library with the system cc,
    called through ctypes: (x, d, b) -> (status, u)."""
    import ctypes
    import subprocess

    lib = tmp_path / "libacid_nmpc.so"
    subprocess.run([*find_compiler(), "-O1", "-std=c99", "-shared", "-fPIC", "-o", str(lib),
                    str(package / "acid_nmpc.c"), str(package / "acid_nmpc_solver.c"), "-lm"],
                   check=True, capture_output=True, timeout=900)
    fn = ctypes.CDLL(str(lib)).acid_nmpc_step
    dp = ctypes.POINTER(ctypes.c_double)
    fn.argtypes, fn.restype = [dp, dp, dp, dp], ctypes.c_int

    def step(x, d, b):
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (x, d, b)]
        u = np.full(2, -1.0)
        status = fn(*(a.ctypes.data_as(dp) for a in arrays), u.ctypes.data_as(dp))
        return status, u

    return step


@needs_cc
def test_the_exported_step_returns_a_distinct_status_per_bad_input(package, tmp_path):
    step = _ctypes_step(package, tmp_path)
    x = np.array([C2K(25.5), C2K(6.0)])
    d = np.array([C2K(30.0), C2K(33.0), C2K(30.0), 0.0, 0.0])
    b = np.r_[np.full(6, C2K(26.0)), np.full(6, C2K(20.0))]
    safe = np.asarray(NMPCConfig().u_safe)
    status, u = step(x, d, b)
    assert status == STATUS["ok"] and not np.allclose(u, safe)
    crossed = b.copy()
    crossed[6 + 3] = C2K(27.0)  # lower bound of step 4 above its upper bound (26 degC)
    cases = {
        "not_finite": (x, np.r_[d[:3], np.inf, 0.0], b),
        "implausible_temperature": (x, np.r_[d[:2], 30.0, d[3:]], b),  # T_amb in degC
        "crossed_bounds": (x, d, crossed),
        "absurd_disturbance": (x, np.r_[d[:3], 0.0, MAX_DISTURBANCE_K + 0.5], b),
    }
    for name, (xx, dd, bb) in cases.items():
        status, u = step(xx, dd, bb)
        assert status == STATUS[name], name
        np.testing.assert_array_equal(u, safe)
    # within the stated range a disturbance estimate is solved, not refused
    status, _ = step(x, np.r_[d[:3], 0.0, MAX_DISTURBANCE_K - 0.5], b)
    assert status in (STATUS["ok"], STATUS["solver_failed"])
    header = (package / "acid_nmpc.h").read_text()
    for name, code in STATUS.items():
        assert f"#define ACID_NMPC_{name.upper().replace('_TEMPERATURE', '')} {code}" in header


def test_text_of_a_parameter_file_cannot_reach_the_generated_c_as_code(tmp_path):
    evil = 'x" */ int injected = 1; /* \n#include "/etc/passwd"\n'
    out = tmp_path / "pkg"
    export_c(paper().replace(name=evil), out, NMPCConfig(N=2))
    for name in ("acid_nmpc.h", "acid_nmpc.c", "main.c", "Makefile"):
        text = (out / name).read_text()
        assert "*/ int injected" not in text and "/etc/passwd" not in text, name
    header = (out / "acid_nmpc.h").read_text()
    assert f'parameters "{c_text(evil)}".' in header
    assert set(c_text(evil)) <= set("x_ intjectd=1cluds.ahpw")
    assert c_text('a*/b\n"c') == "a__b__c" and c_text("x" * 200).endswith("...")
    assert c_number(0.1, "v") == "0.1" and c_number(5, "v") == "5.0"
    with pytest.raises(ConfigError, match="Ts"):
        c_number(float("nan"), "Ts")


@needs_cc
def test_export_c_cli_with_a_hostile_parameter_name_builds_and_checks(tmp_path):
    """A params.json whose name closes a C comment and adds code: the package still builds,
    --check passes, and the name reaches the C only as whitelisted text."""
    from typer.testing import CliRunner

    from acid_cli.main import app

    p = tmp_path / "evil.json"
    paper().replace(name='*/ int evil(void) { return 1; } /*\n#error "x"').to_json(p)
    out = tmp_path / "pkg"
    res = CliRunner().invoke(app, ["export-c", "--params", str(p), "--out", str(out),
                                   "--horizon", "2", "--check-states", "2"])
    assert res.exit_code == 0, res.output
    assert "C solves OK" in res.output
    text = "".join((out / n).read_text() for n in ("acid_nmpc.h", "acid_nmpc.c"))
    assert "evil(void)" not in text and "#error" not in text and "*/ int" not in text
    assert "__ int evil_void_ _ return 1_ _ ____error _x_" in text
