"""The controller of any declared model as a standalone C package (``acid export-c --model``).

The controller is the tracking configuration of the one optimal-control builder
(:class:`acid.control.ocp.OCP`) over the declaration: over ``N`` samples,

    min  sum_{i<N} sum_n (n(i) - ref_n(i))^2 / scale_n^2      s.t. the model, u_min <= u <= u_max

for the tracked names ``n`` (states, inputs or outputs; by default the measured states), with
the disturbances previewed per stage. ``scale_n`` is 1 in the declared unit (1 K for a
temperature). The parameters (the table of ``acid fit --model``'s parameter file, a
per-experiment one at the mean of its experiments) are constants in the C.

Like the paper's package (:mod:`acid.control.codegen.export_paper`): one call

    int acid_ocp_step(const double *x, const double *d, const double *ref, double *u);

``x[NX]`` the state, ``d[N*ND]`` the disturbance preview (stage-major), ``ref[N*NT]`` the
references (stage-major), ``u[NU]`` the first move. It checks that every input is finite,
solves with the SQP method and the active-set QP solver qrqp (generated as plain C, cold
start: the model simulated with mid-range inputs), and returns a distinct status for a
refused input or a failed solve, with the mid-range input. No text of the model file reaches
the C raw: names and labels go through :func:`acid.control.codegen.export_paper.c_text` (a
whitelist of
characters), numbers through :func:`acid.control.codegen.export_paper.c_number`.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from pathlib import Path

import casadi as ca
import numpy as np

from acid import __version__
from acid._io import write_text
from acid.control.codegen.build import generate_source
from acid.control.codegen.export_paper import build_c, c_number, c_text, run_lines
from acid.control.nmpc import sqp_options
from acid.control.ocp import OCP, OCPSpec, tracking_cost
from acid.errors import ConfigError
from acid.models.declaration import Model

NAME = "acid_ocp_solve"
FILES = ("acid_ocp_solver.c", "acid_ocp.h", "acid_ocp.c", "main.c", "Makefile",
         "problem.json")
STATUS = {"ok": 0, "not_finite": 1, "solver_failed": 2}


@dataclasses.dataclass(frozen=True)
class TrackingController:
    """What is exported: the declaration, its parameter values, the tracked names, the input
    bounds (declared units) and the horizon."""

    model: Model
    theta: np.ndarray
    track: tuple[str, ...]
    input_bounds: Mapping[str, tuple[float, float]]
    N: int = 10
    params_label: str = "declared values"

    def __post_init__(self):
        m = self.model
        known = m.state_names + tuple(i.name for i in m.inputs) + m.output_names
        for n in self.track:
            if n not in known:
                raise ConfigError(f"--track {n}: not a state, input or output of model "
                                  f"{m.name!r} (known: {', '.join(known)})")
        if not self.track:
            raise ConfigError("--track: name at least one state, input or output to track")
        if not 1 <= int(self.N) <= 200:
            raise ConfigError(f"--horizon must be between 1 and 200, got {self.N}")

    def ocp(self) -> OCP:
        cost, refs = tracking_cost({n: 1.0 for n in self.track})
        return OCP(self.model, OCPSpec(N=int(self.N), stage_cost=cost, stage_parameters=refs,
                                       input_bounds=dict(self.input_bounds)))

    @property
    def u_mid(self) -> np.ndarray:
        return np.array([0.5 * sum(self.input_bounds[i.name]) for i in self.model.inputs])


def step_function(ctrl: TrackingController) -> ca.Function:
    """``(x[nx], d[N*nd], ref[N*nt]) -> u[nu]``: cold guess, SQP solve, first move clipped
    to its bounds, as one CasADi function (the exported step)."""
    ocp = ctrl.ocp()
    m, N, nt = ctrl.model, int(ctrl.N), len(ctrl.track)
    x = ca.MX.sym("x", m.nx)
    d = ca.MX.sym("d", N * m.nd)
    ref = ca.MX.sym("ref", N * nt)
    D = ca.reshape(d, m.nd, N)
    R = ca.reshape(ref, nt, N)
    p = [ca.MX(0.0)] * ocp.par.size

    def put(block, values):
        for i, v in zip(ocp.par.index(block).ravel(), values, strict=True):
            p[i] = v

    put("x0", ca.vertsplit(x))
    put("theta", [ca.MX(v) for v in ctrl.theta])
    if m.nd:
        put("d", [D[k, i] for i in range(N) for k in range(m.nd)])
    put("q", [R[k, i] for i in range(N) for k in range(nt)])
    p = ca.vertcat(*p)
    # cold guess: mid-range inputs, the model simulated from x
    u_mid = ctrl.u_mid
    X = ocp.trajectory(x, ca.repmat(ca.DM(u_mid), 1, N), D, R, ca.DM(ctrl.theta),
                       ca.DM.zeros(ocp.ntarget))[0]
    w0 = [ca.MX(0.0)] * ocp.w.size
    for i in range(N + 1):
        for k, j in enumerate(ocp.w.at("x", i)):
            w0[j] = (X[k, i] - ocp.x_offset[k]) / ocp.x_scale[k]
        if i < N:
            for k, j in enumerate(ocp.w.at("u", i)):
                w0[j] = ca.MX(ocp.u_nlp(u_mid)[k])
    solver = ca.nlpsol("acid_ocp_sqp", "sqpmethod", ocp.nlp,
                       dict(sqp_options(max_iter=100), error_on_fail=True))
    res = solver(x0=ca.vertcat(*w0), p=p, lbx=ocp.lbx, ubx=ocp.ubx, lbg=ocp.lbg,
                 ubg=ocp.ubg)
    iu0 = ocp.w.at("u", 0)
    u0 = ca.vertcat(*(ocp.u_offset[k] + res["x"][int(j)] / ocp.u_scale[k]
                      for k, j in enumerate(iu0)))
    u0 = ca.fmin(ca.fmax(u0, ocp.u_min), ocp.u_max)
    return ca.Function(NAME, [x, d, ref], [u0], ["x", "d", "ref"], ["u"])


def python_reference(ctrl: TrackingController, x, d, ref, solver: str = "sqp") -> np.ndarray:
    """The first move from the same NLP solved inside CasADi (``"sqp"``: the exported
    algorithm and guess; ``"ipopt"``: an independent interior-point solve)."""
    fn = step_function(ctrl) if solver == "sqp" else None
    if fn is not None:
        return np.asarray(fn(x, d, ref)).ravel()
    ocp = ctrl.ocp()
    m, N, nt = ctrl.model, int(ctrl.N), len(ctrl.track)
    D, R = np.reshape(d, (N, m.nd)), np.reshape(ref, (N, nt))
    pv = ocp.parameters(np.zeros(ocp.par.size), x0=x, theta=ctrl.theta, d=D, q=R)
    X = np.asarray(ocp.trajectory(x, np.tile(ctrl.u_mid[:, None], N), D.T, R.T, ctrl.theta,
                                  np.zeros(ocp.ntarget))[0]).T
    w0 = np.zeros(ocp.w.size)
    w0[ocp.w.index("x")] = (X - ocp.x_offset) / ocp.x_scale
    w0[ocp.w.index("u")] = ocp.u_nlp(ctrl.u_mid)
    S = ca.nlpsol("acid_ocp_ipopt", "ipopt", ocp.nlp, {
        "print_time": False, "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-12,
                                       "bound_relax_factor": 0.0}})
    w = np.asarray(S(x0=w0, p=pv, lbx=ocp.lbx, ubx=ocp.ubx, lbg=ocp.lbg,
                     ubg=ocp.ubg)["x"]).ravel()
    return np.clip(ocp.plan(w)[0], ocp.u_min, ocp.u_max)


_HEADER = """\
/* acid_ocp.h -- tracking NMPC of the declared model "{model}" as plain C.
 * Generated by acid {version} (acid export-c --model) for the parameters "{params}".
 * Declared units (kelvin inside). Horizon N = {N} steps of Ts = {Ts} s. */
#ifndef ACID_OCP_H
#define ACID_OCP_H

#ifdef __cplusplus
extern "C" {{
#endif

#define ACID_OCP_N {N}
#define ACID_OCP_NX {nx}   /* states: {states} */
#define ACID_OCP_ND {nd}   /* disturbances per stage: {disturbances} */
#define ACID_OCP_NT {nt}   /* references per stage: {track} */
#define ACID_OCP_NU {nu}   /* inputs: {inputs} */

#define ACID_OCP_OK 0
#define ACID_OCP_NOT_FINITE 1    /* an input is NaN or infinite */
#define ACID_OCP_SOLVER_FAILED 2 /* the solver did not converge */

/* One update: x[NX], d[N*ND] and ref[N*NT] stage by stage; u[NU] the move to apply.
 * Returns ACID_OCP_OK, or a non-zero code with u = the mid-range input. Not re-entrant. */
int acid_ocp_step(const double *x, const double *d, const double *ref, double *u);

#ifdef __cplusplus
}} /* extern "C" */
#endif
#endif /* ACID_OCP_H */
"""

_WRAPPER = """\
/* acid_ocp.c -- input checks, workspace and fallback around the generated solver. */
#include <math.h>
#include "acid_ocp.h"

typedef long long int casadi_int;
int {name}(const double **arg, double **res, casadi_int *iw, double *w, int mem);
void {name}_incref(void);
int {name}_checkout(void);

static casadi_int iw[{sz_iw} > 0 ? {sz_iw} : 1];
static double work[{sz_w} > 0 ? {sz_w} : 1];
static int mem = -1;
static const double u_safe[ACID_OCP_NU] = {{{u_safe}}};

int acid_ocp_step(const double *x, const double *d, const double *ref, double *u) {{
  const double *arg[{sz_arg} > 3 ? {sz_arg} : 3];
  double *res[{sz_res} > 1 ? {sz_res} : 1];
  int i;
  for (i = 0; i < ACID_OCP_NU; ++i) u[i] = u_safe[i];
  for (i = 0; i < ACID_OCP_NX; ++i) if (!isfinite(x[i])) return ACID_OCP_NOT_FINITE;
  for (i = 0; i < ACID_OCP_N * ACID_OCP_ND; ++i) if (!isfinite(d[i])) return ACID_OCP_NOT_FINITE;
  for (i = 0; i < ACID_OCP_N * ACID_OCP_NT; ++i) if (!isfinite(ref[i])) return ACID_OCP_NOT_FINITE;
  if (mem < 0) {{
    {name}_incref();
    mem = {name}_checkout();
    if (mem < 0) return ACID_OCP_SOLVER_FAILED;
  }}
  arg[0] = x;
  arg[1] = d;
  arg[2] = ref;
  res[0] = u;
  if ({name}(arg, res, iw, work, mem)) {{
    for (i = 0; i < ACID_OCP_NU; ++i) u[i] = u_safe[i];
    return ACID_OCP_SOLVER_FAILED;
  }}
  for (i = 0; i < ACID_OCP_NU; ++i) if (!isfinite(u[i])) {{
    for (i = 0; i < ACID_OCP_NU; ++i) u[i] = u_safe[i];
    return ACID_OCP_SOLVER_FAILED;
  }}
  return ACID_OCP_OK;
}}
"""

_MAIN = """\
/* main.c -- example: one problem per line on stdin, x[NX] d[N*ND] ref[N*NT];
 * prints "status u[0] .. u[NU-1]" per line. */
#include <stdio.h>
#include "acid_ocp.h"

int main(void) {
  double x[ACID_OCP_NX], d[ACID_OCP_N * ACID_OCP_ND + 1], r[ACID_OCP_N * ACID_OCP_NT + 1];
  double u[ACID_OCP_NU];
  int i, k;
  for (;;) {
    for (i = 0; i < ACID_OCP_NX; ++i) if (scanf("%lf", &x[i]) != 1) return 0;
    for (i = 0; i < ACID_OCP_N * ACID_OCP_ND; ++i) if (scanf("%lf", &d[i]) != 1) return 2;
    for (i = 0; i < ACID_OCP_N * ACID_OCP_NT; ++i) if (scanf("%lf", &r[i]) != 1) return 2;
    k = acid_ocp_step(x, d, r, u);
    printf("%d", k);
    for (i = 0; i < ACID_OCP_NU; ++i) printf(" %.17g", u[i]);
    printf("\\n");
  }
}
"""

_MAKEFILE = """\
# Builds the controller library and the example with a C compiler alone.
CC ?= cc
CFLAGS ?= -O2
AR ?= ar

all: libacid_ocp.a example

libacid_ocp.a: acid_ocp.o acid_ocp_solver.o
\t$(AR) rcs $@ $^

%.o: %.c acid_ocp.h
\t$(CC) $(CFLAGS) -c -o $@ $<

example: main.c acid_ocp.h libacid_ocp.a
\t$(CC) $(CFLAGS) -o $@ main.c libacid_ocp.a -lm

clean:
\trm -f *.o libacid_ocp.a example

.PHONY: all clean
"""


def _names(rows) -> str:
    return c_text(", ".join(getattr(r, "name", r) for r in rows) or "none", 120)


def export_model_c(ctrl: TrackingController, out: str | Path) -> tuple[str, ...]:
    """Write the C package of ``ctrl`` into ``out`` (atomic writes; files of the same names
    replaced, nothing else touched). Returns the file names."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a folder")
    m = ctrl.model
    fn = step_function(ctrl)
    sz = [int(n) for n in (fn.sz_arg(), fn.sz_res(), fn.sz_iw(), fn.sz_w())]
    fmt = {"model": c_text(m.name), "version": c_text(__version__),
           "params": c_text(ctrl.params_label), "N": int(ctrl.N), "Ts": c_number(m.Ts, "Ts"),
           "nx": m.nx, "nd": m.nd, "nt": len(ctrl.track), "nu": m.nu,
           "states": _names(m.states), "disturbances": _names(m.disturbances),
           "track": _names(ctrl.track), "inputs": _names(m.inputs)}
    files = {
        "acid_ocp_solver.c": generate_source(fn),
        "acid_ocp.h": _HEADER.format(**fmt),
        "acid_ocp.c": _WRAPPER.format(
            name=NAME, sz_arg=sz[0], sz_res=sz[1], sz_iw=sz[2], sz_w=sz[3],
            u_safe=", ".join(c_number(v, "input midpoint") for v in ctrl.u_mid)),
        "main.c": _MAIN,
        "Makefile": _MAKEFILE,
        "problem.json": json.dumps({
            "acid_version": __version__, "casadi_version": ca.__version__,
            "model": m.name, "model_source": Path(m.source).name, "N": int(ctrl.N),
            "Ts_s": m.Ts, "solver": "sqpmethod + qrqp",
            "parameters": dict(zip(m.parameter_names, map(float, ctrl.theta), strict=True)),
            "params": ctrl.params_label,
            "x": [f"{s.name} [{s.unit}]" for s in m.states],
            "d_per_stage": [f"{s.name} [{s.unit}]" for s in m.disturbances],
            "ref_per_stage": list(ctrl.track),
            "u": [f"{s.name} [{s.unit}]" for s in m.inputs],
            "input_bounds": {k: list(map(float, v)) for k, v in ctrl.input_bounds.items()},
            "status": STATUS}, indent=2) + "\n",
    }
    out.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        write_text(out / name, text)
    return tuple(files)


def _sample(unit: str, rng: np.random.Generator, name: str) -> float:
    """A plausible value of a signal for the check: 15-35 degC in K, 0-30 m/s for a speed,
    else 0 (a seeded summer cabin)."""
    if unit == "K":
        return 273.15 + rng.uniform(15.0, 35.0)
    if unit == "m/s":
        return rng.uniform(0.0, 30.0)
    return 0.0


#: A tracked temperature's reference is drawn this close to its sampled state, K: far
#: references only saturate the first move at an input bound, where it checks nothing.
REF_NEAR_K = 0.3


def sample_problems(ctrl: TrackingController, n: int, seed: int = 0) -> list[tuple]:
    """``n`` seeded problems (x, d, ref) for the check (stage-major previews); a tracked
    temperature state's reference within ``REF_NEAR_K`` of its sampled value, so that many
    first moves lie inside their bounds, where the optimum is tested."""
    rng = np.random.default_rng(seed)
    m, N = ctrl.model, int(ctrl.N)
    units = {r.name: r.unit for r in (*m.states, *m.inputs, *m.outputs)}
    near = {t: m.state_names.index(t) for t in ctrl.track
            if t in m.state_names and units[t] == "K"}
    out = []
    for _ in range(n):
        x = np.array([_sample(s.unit, rng, s.name) for s in m.states])
        d = np.array([_sample(s.unit, rng, s.name) for _ in range(N) for s in m.disturbances])
        ref = {t: x[i] + rng.uniform(-REF_NEAR_K, REF_NEAR_K) for t, i in near.items()}
        r = np.array([ref[t] if t in ref else _sample(units[t], rng, t)
                      for _ in range(N) for t in ctrl.track])
        out.append((x, d, r))
    return out


def check_model_export(package: str | Path, ctrl: TrackingController, n_states: int = 10,
                       seed: int = 0) -> dict:
    """Build the package with the C compiler, run its example on seeded problems and compare
    the first moves with the same NLP solved inside CasADi: by the same algorithm (SQP, the
    same guess) and by IPOPT from the same guess. Relative to the input ranges."""
    import tempfile

    problems = sample_problems(ctrl, n_states, seed)
    with tempfile.TemporaryDirectory(prefix="acid-export-check-") as tmp:
        exe = build_c(package, tmp, ("main.c", "acid_ocp.c", "acid_ocp_solver.c"))
        C = run_lines(exe, [np.r_[x, d, r] for x, d, r in problems], 1 + ctrl.model.nu)
    span = np.array([np.diff(ctrl.input_bounds[i.name])[0] for i in ctrl.model.inputs])
    sqp = step_function(ctrl)
    d_sqp, d_ipopt, failed = [], [], {"sqp": 0, "ipopt": 0}

    def solved(name, solve):
        """A reference solve's first move, or None when CasADi reports it failed."""
        try:
            return np.asarray(solve()).ravel()
        except RuntimeError:  # the solver's own failure, counted and reported, not raised
            failed[name] += 1
            return None

    for (x, d, r), c in zip(problems, C, strict=True):
        u_sqp = solved("sqp", lambda x=x, d=d, r=r: sqp(x, d, r))
        u_ip = solved("ipopt", lambda x=x, d=d, r=r: python_reference(ctrl, x, d, r, "ipopt"))
        if u_sqp is not None:
            d_sqp.append(float(np.max(np.abs(c[1:] - u_sqp) / span)))
        if u_ip is not None:
            d_ipopt.append(float(np.max(np.abs(c[1:] - u_ip) / span)))
    lo = np.array([ctrl.input_bounds[i.name][0] for i in ctrl.model.inputs])
    inside = np.all((C[:, 1:] > lo + 0.01 * span) & (C[:, 1:] < lo + 0.99 * span), axis=1)
    return {"states": len(problems), "seed": seed, "c_status_ok": int(np.sum(C[:, 0] == 0)),
            "interior_moves": int(np.sum(inside & (C[:, 0] == 0))),
            "max_diff_vs_sqp": max(d_sqp, default=math.nan),
            "max_diff_vs_ipopt": max(d_ipopt, default=math.nan),
            "reference_failed": failed}
