"""acid.control.codegen.export: the controller of any declared model as a standalone C package."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from acid.control.codegen.build import find_compiler
from acid.control.codegen.export import (
    STATUS,
    TrackingController,
    check_model_export,
    export_model_c,
    sample_problems,
)
from acid.control.codegen.export_paper import build_c, run_lines
from acid.errors import ConfigError
from acid.models.loader import load

needs_cc = pytest.mark.skipif(find_compiler() is None, reason="no C compiler")

HOSTILE = '''
from acid.models import Model, Parameter, Signal, State

def step(s):
    return {"T_cab": s.T_cab + s.k * (s.T_in - s.T_cab)}

model = Model('evil */ #include "x" \\\\ name', states=[State("T_cab", "K")],
              inputs=[Signal("T_in", "K", description='*/ int pwned; /*')],
              parameters=[Parameter("k", "1", 0.3, 0.0, 1.0, description='"); system("')],
              Ts=5.0, step=step)
'''


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    m = load("car_cabin")
    ctrl = TrackingController(m, m.values, ("T_cab",), {"T_evap": (276.15, 313.15)}, N=8)
    out = tmp_path_factory.mktemp("car")
    export_model_c(ctrl, out)
    return ctrl, out


def test_the_package_of_a_declared_model_is_plain_c_and_says_what_it_is(car):
    ctrl, out = car
    solver = (out / "acid_ocp_solver.c").read_text()
    includes = {ln.split()[1] for ln in solver.splitlines() if ln.startswith("#include")}
    assert includes <= {"<math.h>", "<stdarg.h>", "<stdio.h>", "<string.h>"}
    meta = json.loads((out / "problem.json").read_text())
    assert meta["model"] == "car_cabin" and meta["ref_per_stage"] == ["T_cab"]
    assert meta["parameters"] == dict(zip(ctrl.model.parameter_names, ctrl.model.values,
                                          strict=True))
    assert f"#define ACID_OCP_NX {ctrl.model.nx}" in (out / "acid_ocp.h").read_text()


@pytest.fixture(scope="module")
def exe(car, tmp_path_factory):
    """The package's example compiled once (the C compiler is most of these tests' time)."""
    _, out = car
    return build_c(out, tmp_path_factory.mktemp("build"),
                   ("main.c", "acid_ocp.c", "acid_ocp_solver.c"))


@needs_cc
def test_the_exported_move_is_the_nlps_optimum(car, exe, monkeypatch):
    import acid.control.codegen.export as export

    ctrl, out = car
    built = []

    def the_module_build(package, build_dir, sources):   # the same package, compiled above
        built.append((Path(package), tuple(sources)))
        return exe

    monkeypatch.setattr(export, "build_c", the_module_build)
    res = check_model_export(out, ctrl, n_states=6, seed=2)
    assert built == [(out, ("main.c", "acid_ocp.c", "acid_ocp_solver.c"))]
    assert res["c_status_ok"] == 6
    assert res["interior_moves"] >= 2          # moves inside the bounds test the optimum
    assert res["max_diff_vs_sqp"] <= 1e-9      # the same algorithm inside CasADi
    assert res["max_diff_vs_ipopt"] <= 1e-6    # an independent interior-point solve


@needs_cc
def test_a_non_finite_input_gives_its_status_and_the_mid_range_input(car, exe):
    ctrl, _ = car
    (x, d, r), = sample_problems(ctrl, 1)
    bad = x.copy()
    bad[0] = np.nan
    rows = run_lines(exe, [np.r_[x, d, r], np.r_[bad, d, r]], 2)
    assert rows[0, 0] == STATUS["ok"] and rows[1, 0] == STATUS["not_finite"]
    assert rows[1, 1] == pytest.approx(ctrl.u_mid[0])


def test_user_text_never_reaches_the_c_raw(tmp_path):
    f = tmp_path / "evil.py"
    f.write_text(HOSTILE)
    m = load(str(f))
    ctrl = TrackingController(m, m.values, ("T_cab",), {"T_in": (280.0, 320.0)}, N=3)
    export_model_c(ctrl, tmp_path / "c")
    for name in ("acid_ocp.h", "acid_ocp.c", "acid_ocp_solver.c", "main.c"):
        text = (tmp_path / "c" / name).read_text()
        for bad in ('#include "x"', "pwned", "system(", "\\\\"):
            assert bad not in text, (name, bad)
    assert "evil __ _include _x_ _ name" in (tmp_path / "c" / "acid_ocp.h").read_text()


def test_a_name_the_model_lacks_is_one_line():
    m = load("car_cabin")
    with pytest.raises(ConfigError, match="T_dash"):
        TrackingController(m, m.values, ("T_dash",), {"T_evap": (276.15, 313.15)})
