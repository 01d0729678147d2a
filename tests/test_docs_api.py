"""What a new user reads on the documentation site exists and says what the objects do,
checked without building the site: every public name has its entry in the API reference,
`smooth_sign` is the soft sign the EMPS example relies on, and a validation of a system
sampled in milliseconds prints its table of the model beside the yardsticks."""

from __future__ import annotations

import importlib
import inspect
import re
from pathlib import Path

import casadi as ca
import numpy as np

import acid
import acid.models
from acid.models import RK4, Model, Parameter, Signal, State, smooth_sign

ROOT = Path(__file__).resolve().parents[1]


def _documented() -> set[str]:
    text = (ROOT / "docs" / "reference.md").read_text()
    paths = set(re.findall(r"^::: ([\w.]+)", text, re.M))
    for mod, members in re.findall(r"^::: ([\w.]+)\n(?:    .*\n)*?\s+members: \[([^\]]*)\]",
                                   text, re.M):
        paths |= {f"{mod}.{m.strip()}" for m in members.split(",")}
    return paths


def test_every_public_class_and_function_has_its_reference_entry():
    documented = _documented()
    missing = []
    for mod, names in (("acid", acid.__all__), ("acid.models", acid.models.__all__)):
        m = importlib.import_module(mod)
        for name in names:
            obj = getattr(m, name, None)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue
            if obj.__module__.startswith("casadi"):
                continue
            if f"{obj.__module__}.{obj.__qualname__}" not in documented:
                missing.append(f"{mod}.{name} ({obj.__module__}.{obj.__qualname__})")
    assert not missing, missing


def test_smooth_sign_is_a_soft_sign_with_a_gradient_at_zero():
    assert smooth_sign(1.0, 0.01) > 0.999 and smooth_sign(-1.0, 0.01) < -0.999
    v = ca.SX.sym("v")
    slope = ca.Function("d", [v], [ca.jacobian(smooth_sign(v, 0.01), v)])
    assert float(slope(0.0)) == 100.0           # 1 / width where the axis rests


def test_a_millisecond_validation_prints_the_model_beside_the_yardsticks():
    """A horizon of 0.3 s is shorter than every report time: the table comes from the scored
    steps (before, it was empty)."""
    model = Model("lag", states=[State("y", "V")], inputs=[Signal("u", "V")],
                  parameters=[Parameter("a", "1/s", 20.0, 0.0, 100.0)],
                  Ts=0.01, ode=lambda s: {"y": s.a * (s.u - s.y)}, integrator=RK4(substeps=2))
    rng = np.random.default_rng(0)
    n = 400
    u = np.repeat(rng.uniform(-1, 1, n // 20), 20)
    y = np.zeros(n)
    for k in range(n - 1):                       # exact discretisation of the first-order lag
        y[k + 1] = u[k] + (y[k] - u[k]) * np.exp(-20.0 * 0.01)
    data = acid.Dataset(time=np.arange(n) * 0.01, channels={"y": y + rng.normal(0, 1e-3, n),
                                                              "u": u},
                        units={"y": "V", "u": "V"}, Ts=0.01)
    res = acid.validate_model(model, data, starts=8, horizon=30, warmup=0.05, yardsticks=True,
                              estimation=(0, 200), start_range=(200, n))
    text = res.summary()
    rows = {line.split()[0] for line in text.splitlines()[2:] if line.startswith("    ")}
    assert {"model", "persistence", "arx", "subspace"} <= rows, text
    frame = res.to_frame()
    assert set(frame.predictor) == {"model", "persistence", "arx", "subspace"}
    assert frame.time_s.max() == 0.3


def test_the_printed_fit_table_keeps_its_columns_aligned():
    """Units of different lengths ("kg", "N*s/m") no longer push the status column about."""
    model = Model("mass", states=[State("v", "m/s")], inputs=[Signal("F", "N")],
                  parameters=[Parameter("M", "kg", 2.0, 0.1, 10.0),
                              Parameter("c", "N*s/m", 1.0, 0.0, 10.0)],
                  Ts=0.1, ode=lambda s: {"v": (s.F - s.c * s.v) / s.M},
                  integrator=RK4(substeps=2))
    rng = np.random.default_rng(1)
    n = 200
    F = np.repeat(rng.uniform(-1, 1, n // 10), 10)
    v = np.zeros(n)
    for k in range(n - 1):
        v[k + 1] = F[k] / 2.0 + (v[k] - F[k] / 2.0) * np.exp(-2.0 / 4.0 * 0.1)
    data = acid.Dataset(time=np.arange(n) * 0.1, channels={"v": v + rng.normal(0, 1e-3, n),
                                                             "F": F},
                        units={"v": "m/s", "F": "N"}, Ts=0.1)
    fit = acid.fit_model(model, data, method="oe")
    rows = [line for line in fit.summary().splitlines()
            if line.split()[:1] in (["name"], ["M"], ["c"])]
    assert len(rows) == 3
    assert len({line.index(word) for line, word in
                zip(rows, ("status", "estimated", "estimated"), strict=True)}) == 1, rows


def test_an_exported_function_stays_callable_after_its_submodule_is_imported():
    # the command line imports acid.excite (the module); the site's first example then
    # calls acid.excite(...) in the same process
    import subprocess
    import sys

    code = ("import acid, importlib; importlib.import_module('acid.excite'); "
            "from acid.excite import excite; assert acid.excite is excite, acid.excite")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
