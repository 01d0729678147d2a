"""An NLP solver for closed-loop use: generated C when possible, a wall-clock cap on request.

:class:`NLPSolver` takes any CasADi NLP (``{"x", "f", "g", "p"}``), a solver plugin and its
options, and gives one call, :meth:`NLPSolver.solve`, that

* runs the solver as **generated, compiled C** (:mod:`acid.control.codegen.build`) when the plugin
can
  be generated (fatrop, sqpmethod, ...) and a C compiler is found, else **inside CasADi**
  (the same algorithm: answers are bit-identical), with one :class:`CodegenWarning` notice
  per process and reason when it has to fall back;
* enforces, **only when asked** (``timeout_s``, for an ECU-like real-time run), a
  wall-clock cap per solve: the solve runs in a worker thread (CasADi and the compiled
  library release the GIL) and a solve that has not returned after ``timeout_s`` is
  abandoned and reported as failed (``status = "timeout"``); the solver is rebuilt for the
  next call, so a runaway solve never hangs the caller. Without a cap (the default) the
  solve runs in the caller's thread: results never depend on the machine's load;
* returns a plain :class:`NLPResult`.

The paper's NMPC (:class:`acid.control.nmpc.NMPC`) and any other NMPC built on CasADi use it the
same way: build the NLP once, then ``solve`` every sample.
"""

from __future__ import annotations

import queue
import shutil
import tempfile
import threading
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from acid.control.codegen.build import CodegenError, CompiledFunction, compile_function
from acid.errors import CodegenWarning

#: NLP solver function inputs and outputs, in CasADi's order
NLP_INPUTS = ("x0", "p", "lbx", "ubx", "lbg", "ubg", "lam_x0", "lam_g0")
NLP_OUTPUTS = ("x", "f", "g", "lam_x", "lam_g", "lam_p")

#: plugins whose generated C compiles against what the casadi wheel ships (IPOPT's
#: generated C would need the IPOPT headers, which the wheel does not carry)
CODEGEN_PLUGINS = ("fatrop", "sqpmethod")

_NOTICES: set[str] = set()


def _notice_once(key: str, message: str) -> None:
    """Emit ``message`` as a CodegenWarning once per process for ``key``."""
    if key not in _NOTICES:
        _NOTICES.add(key)
        warnings.warn(message, CodegenWarning, stacklevel=3)


@dataclass(frozen=True)
class NLPResult:
    """One NLP solve.

    Attributes
    ----------
    x : primal solution (NaN where the solver produced none).
    f : objective at ``x`` (as the NLP defines it, e.g. scaled).
    lam_x, lam_g : multipliers of the bounds and constraints.
    success : the solver converged and ``x`` is finite.
    status : the solver's return status ("Solve_Succeeded", "timeout", ...).
    iterations : solver iterations (-1 when the backend does not report them).
    solve_time_s : wall time of the solve, s.
    """

    x: np.ndarray
    f: float
    lam_x: np.ndarray
    lam_g: np.ndarray
    success: bool
    status: str
    iterations: int
    solve_time_s: float


def kkt_function(name: str, nlp: dict) -> ca.Function:
    """``(x, p, lam_x, lam_g, lbx, ubx, lbg, ubg) -> (pr_inf, du_inf)`` of an NLP: the
    largest violation of its bounds and constraints, and the largest entry of the gradient
    of its Lagrangian ``f + lam_g' g + lam_x' x`` (CasADi's sign convention for the
    multipliers)."""
    x = nlp["x"]
    sym = type(x).sym
    p = nlp.get("p", sym("p", 0, 1))
    g = nlp.get("g", sym("g", 0, 1))
    lam_x, lbx, ubx = (sym(n, x.numel()) for n in ("lam_x", "lbx", "ubx"))
    lam_g, lbg, ubg = (sym(n, g.numel()) for n in ("lam_g", "lbg", "ubg"))
    grad = ca.gradient(nlp["f"], x) + lam_x
    if g.numel():
        grad += ca.jtimes(g, x, lam_g, True)
    viol = ca.vertcat(ca.fmax(lbx - x, x - ubx), ca.fmax(lbg - g, g - ubg), 0)
    return ca.Function(name, [x, p, lam_x, lam_g, lbx, ubx, lbg, ubg],
                       [ca.mmax(viol), ca.mmax(ca.fabs(grad))],
                       ["x", "p", "lam_x", "lam_g", "lbx", "ubx", "lbg", "ubg"],
                       ["pr_inf", "du_inf"])


class _Call:
    """One job handed to a :class:`_Worker`: the worker either starts it or finds it
    cancelled (never both), decided under ``lock``."""

    __slots__ = ("job", "lock", "done", "started", "cancelled", "out")

    def __init__(self, job):
        self.job = job
        self.lock = threading.Lock()
        self.done = threading.Event()
        self.started = self.cancelled = False
        self.out = None


class _Worker:
    """A daemon thread that runs one job at a time; the caller waits with a timeout.

    Jobs travel through a queue and each carries its own completion event, so a caller
    that gives up (a timeout) never touches a lock the thread holds or has not yet taken:
    a job that times out before the thread picks it up is cancelled and never runs, one
    that times out while running is abandoned. :meth:`stop` queues a sentinel, so it is
    safe at any moment (before the thread first runs, during a job, twice).

    The thread holds no reference to a job between jobs, so the solver that owns it can be
    garbage-collected (and stop it) as usual.
    """

    def __init__(self, name: str):
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self.thread.start()

    def _loop(self):
        while True:
            call = self._queue.get()
            if call is None:
                return
            with call.lock:
                if call.cancelled:
                    continue
                call.started = True
            try:
                call.out = (call.job(), None)
            except BaseException as exc:  # handed to the caller
                call.out = (None, exc)
            call.job = None
            call.done.set()
            del call

    def run(self, job, timeout_s: float) -> tuple[bool, bool, object, BaseException | None]:
        """(finished, started, result, exception) of ``job()`` run within ``timeout_s``
        seconds. Not finished and not started: the job was cancelled before it began (it
        never runs); not finished but started: it is still running, abandoned."""
        call = _Call(job)
        self._queue.put(call)
        if not call.done.wait(timeout_s):
            with call.lock:
                if not call.started:
                    call.cancelled = True
                    call.job = None
                    return False, False, None, None
            if not call.done.is_set():
                return False, True, None, None
        out, exc = call.out
        return True, True, out, exc

    def stop(self):
        """Let the thread end (after the job it may still be running)."""
        self._queue.put(None)


class NLPSolver:
    """A CasADi NLP solved by ``plugin``, as compiled C when possible, optionally capped.

    Parameters
    ----------
    name : function name (also the compiled library's name and symbol).
    nlp : ``{"x": w, "f": cost, "g": constraints, "p": parameters}`` of CasADi SX/MX.
    plugin : CasADi ``nlpsol`` plugin (``"fatrop"``, ``"ipopt"``, ``"sqpmethod"``, ...).
    options : the plugin's options (as for ``casadi.nlpsol``).
    compiled : ``"auto"`` (generated C when the plugin supports code generation and a
        compiler works, else CasADi with one notice), ``True`` (the same, and a notice
        whenever it falls back) or ``False`` (always CasADi).
    verify : ``(tol_pr, tol_du)``: accept a solve only when its primal infeasibility (bounds
        and constraints) and the largest entry of the gradient of its Lagrangian are at
        most these (checked by a generated function of the NLP, compiled alongside). For
        solvers whose own success flag cannot be trusted: CasADi's generated ``sqpmethod``
        returns 0 when it stops at its iteration limit or on a short step. None: trust the
        solver.
    kkt_name : name of the convergence check's function (default ``NAME_kkt``): solvers of
        one NLP that give the same name share its compiled library (one build).
    timeout_s : wall-clock cap per solve, s (default None: no cap, the solve runs in the
        caller's thread). Only for a run that must keep a real-time budget (an ECU-like
        run): a cap makes results depend on the machine's load, so offline studies, tests
        and sweeps never set one.
    hot : the solver runs on every control step: its C is built at the optimisation level
        of small sources whatever its size (:func:`acid.control.codegen.build.cflags`); a rescue
        that runs on a few steps keeps the cheaper build.

    Attributes
    ----------
    backend : ``"compiled"`` or ``"casadi"``.
    build_info : what the compiled path did (cache key, compile time, repairs) or why it
        is not used.
    """

    def __init__(self, name: str, nlp: dict, plugin: str, options: dict,
                 compiled: bool | str = "auto", verify: tuple[float, float] | None = None,
                 timeout_s: float | None = None, kkt_name: str | None = None,
                 hot: bool = False):
        self.name = name
        self.hot = hot
        self.kkt_name = kkt_name or f"{name}_kkt"
        self.verify = verify
        self.plugin = plugin
        self.timeout_s = timeout_s
        self._nlp = nlp
        self._options = dict(options)
        self._want_compiled = compiled
        self._worker: _Worker | None = None
        self.timeouts = 0
        self._build()

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        self.backend = "casadi"
        self.build_info: dict = {}
        self._compiled = None
        self._fn = ca.nlpsol(self.name, self.plugin, self._nlp, self._options)
        self.n_x, self.n_g = self._fn.nnz_in(0), self._fn.nnz_in(4)
        self._kkt = kkt_function(self.kkt_name, self._nlp) if self.verify else None
        self._kkt_c = None
        if self._want_compiled is False:
            self.build_info = {"reason": "compiled=False"}
            return
        if self.plugin not in CODEGEN_PLUGINS:
            self.build_info = {"reason": f"{self.plugin} is not generated as C by acid"}
            return
        try:
            # the generated solver reports failure through its return code
            gen = ca.nlpsol(self.name, self.plugin, self._nlp,
                            dict(self._options, error_on_fail=True))
            self._compiled, info = compile_function(gen, hot=self.hot)
        except CodegenError as exc:
            self.build_info = {"reason": str(exc)}
            _notice_once(f"{self.plugin}:{exc}",
                         f"{exc}; solving {self.name!r} with {self.plugin} inside CasADi "
                         "(same answers, slower)")
            return
        self.backend = "compiled"
        self.build_info = info
        if info.get("repaired"):
            warnings.warn(info["repaired"], CodegenWarning, stacklevel=3)
        if self._kkt is not None:
            try:
                self._kkt_c, _ = compile_function(self._kkt)
            except CodegenError:  # the check runs inside CasADi (same numbers)
                self._kkt_c = None

    def close(self) -> None:
        """Stop the worker thread and release the compiled memory slot."""
        if self._worker is not None:
            self._worker.stop()
            self._worker = None
        if self._compiled is not None:
            self._compiled.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: S110 - interpreter shutdown
            pass

    # ------------------------------------------------------------------ solve
    def _unpack_compiled(self, flag: int) -> tuple:
        out = self._compiled.outputs
        return (out[0].copy(), float(out[1][0]), out[3].copy(), out[4].copy(),
                flag == 0, "Solve_Succeeded" if flag == 0 else f"failed (code {flag})", -1)

    def _solve_casadi(self, args: list) -> tuple:
        res = self._fn(*args)
        st = self._fn.stats()
        return (np.asarray(res[0]).ravel(), float(res[1]), np.asarray(res[3]).ravel(),
                np.asarray(res[4]).ravel(), bool(st.get("success", False)),
                str(st.get("return_status", "")), int(st.get("iter_count", -1)))

    def solve(self, x0, p, lbx, ubx, lbg, ubg, lam_x0=None, lam_g0=None) -> NLPResult:
        """Solve once (arguments as for a CasADi ``nlpsol`` function, numpy arrays).

        Never raises for a solver failure or a timeout (``success`` is False); a CasADi
        evaluation error propagates as RuntimeError.
        """
        args = [x0, p, lbx, ubx, lbg, ubg,
                0.0 if lam_x0 is None else lam_x0, 0.0 if lam_g0 is None else lam_g0]
        t0 = time.perf_counter()
        cf = self._compiled
        if cf is not None:  # the worker only makes the C call; buffers are filled here
            for buf, a in zip(cf.inputs, args, strict=True):
                buf[:] = a
            job = cf.call
        else:
            def job():
                return self._solve_casadi(args)
        if self.timeout_s is None:
            out = job()
        else:
            if self._worker is None:
                self._worker = _Worker(f"{self.name}-solver")
            finished, started, out, exc = self._worker.run(job, self.timeout_s)
            if not finished:
                return self._timed_out(time.perf_counter() - t0, started)
            if exc is not None:
                raise exc
        if cf is not None:
            out = self._unpack_compiled(out)
        x, f, lam_x, lam_g, success, status, iters = out
        success = success and bool(np.isfinite(x.sum()))  # NaN or inf anywhere
        if success and self.verify:
            pr, du = self._residuals(x, p, lam_x, lam_g, lbx, ubx, lbg, ubg)
            if not (pr <= self.verify[0] and du <= self.verify[1]):  # False for NaN too
                success = False
                status = f"not converged (primal {pr:.1e}, dual {du:.1e}; {status})"
        dt = time.perf_counter() - t0
        return NLPResult(x=x, f=f, lam_x=lam_x, lam_g=lam_g, success=success,
                         status=status, iterations=iters, solve_time_s=dt)

    def _residuals(self, x, p, lam_x, lam_g, lbx, ubx, lbg, ubg) -> tuple[float, float]:
        """(primal infeasibility, largest entry of the Lagrangian's gradient) at a result."""
        args = (x, p, lam_x, lam_g, lbx, ubx, lbg, ubg)
        if self._kkt_c is not None:
            out = self._kkt_c(*args)
            return float(out[0][0]), float(out[1][0])
        pr, du = self._kkt(*args)
        return float(pr), float(du)

    def _timed_out(self, dt: float, started: bool) -> NLPResult:
        """A solve past its cap. One that never started was cancelled (nothing to undo);
        a running one is abandoned (its thread and memory stay busy) and the solver
        rebuilt."""
        self.timeouts += 1
        if started:
            self._worker.stop()  # the thread ends if the solve ever returns; it is a daemon
            self._worker = None
            if self._compiled is not None:
                self._compiled.abandon()
            self._build()
        nan = np.full(self.n_x, np.nan)
        return NLPResult(x=nan, f=float("nan"), lam_x=nan, lam_g=np.full(self.n_g, np.nan),
                         success=False, status="timeout", iterations=-1, solve_time_s=dt)


# --------------------------------------------------------------- one C call per step
#: inputs of a fused step function, in order (see :func:`step_function`)
STEP_INPUTS = ("w_prev", "lam_x_prev", "lam_g_prev", "warm", "x0", "p", "lbx", "ubx",
               "u_guess")
#: its first outputs; the caller's ``post`` outputs follow
STEP_OUTPUTS = ("w", "f", "lam_x", "lam_g", "pr_inf", "du_inf")
#: the pairs (output, input) through which one step hands its solution to the next
_CARRIED = (("w", "w_prev"), ("lam_x", "lam_x_prev"), ("lam_g", "lam_g_prev"))


def step_function(name: str, nlp: dict, plugin: str, options: dict, *, lbg, ubg,
                  shift_w, shift_g, ix0, cold: ca.Function, post: ca.Function) -> ca.Function:
    """A whole NMPC step as ONE CasADi function (an MX graph of calls), to be generated as
    one C function:

    ``(w_prev, lam_x_prev, lam_g_prev, warm, x0, p, lbx, ubx, u_guess) ->
    (w, f, lam_x, lam_g, pr_inf, du_inf, *post(w, p))``

    * the initial point: with ``warm`` = 1 the previous solution ``w_prev`` and its
      multipliers shifted by one stage (``w_prev[shift_w]``, ``lam_g_prev[shift_g]``), the
      measured state ``x0`` (NLP scaling) written into ``w[ix0]``; with ``warm`` = 0
      ``cold(x0, p, u_guess)`` and zero multipliers (only the branch taken is evaluated);
    * the solve: ``nlpsol(name, plugin, nlp, options)`` with ``lbg``/``ubg`` as constants
      (a solver generated with ``error_on_fail`` makes the whole call return non-zero when
      it fails);
    * the convergence check: :func:`kkt_function`'s primal infeasibility and the largest
      entry of the Lagrangian's gradient at the result;
    * ``post(w, p)``: what the caller reports (e.g. the clipped plan and its trajectory).

    The caller feeds ``w``, ``lam_x``, ``lam_g`` back as the next step's ``*_prev``
    (:class:`StepSolver` swaps buffers, no copy).
    """
    solver = ca.nlpsol(name + "_nlp", plugin, nlp, options)
    nw, ng, npar = solver.nnz_in(0), solver.nnz_in(4), solver.nnz_in(1)
    nx0, nug = len(ix0), cold.nnz_in(2)
    W, LX, LG = ca.MX.sym("w_prev", nw), ca.MX.sym("lam_x_prev", nw), ca.MX.sym("lam_g_prev", ng)
    warm, x0, p = ca.MX.sym("warm"), ca.MX.sym("x0", nx0), ca.MX.sym("p", npar)
    lbx, ubx, ug = ca.MX.sym("lbx", nw), ca.MX.sym("ubx", nw), ca.MX.sym("u_guess", nug)
    ix0 = [int(i) for i in ix0]
    # the warm branch: a permutation, then the measured state
    ws, wc = ca.MX.sym("w_prev", nw), ca.MX.sym("x0", nx0)
    wl, gl = ca.MX.sym("lam_x_prev", nw), ca.MX.sym("lam_g_prev", ng)
    pp, uu = ca.MX.sym("p", npar), ca.MX.sym("u_guess", nug)
    w_warm = ws[[int(i) for i in shift_w]]
    w_warm[ix0] = wc
    warm_fn = ca.Function(name + "_warm", [ws, wl, gl, wc, pp, uu],
                          [w_warm, wl[[int(i) for i in shift_w]],
                           gl[[int(i) for i in shift_g]]])
    cold_fn = ca.Function(name + "_cold", [ws, wl, gl, wc, pp, uu],
                          [cold(wc, pp, uu), ca.DM.zeros(nw), ca.DM.zeros(ng)])
    guess = ca.Function.conditional(name + "_guess", [cold_fn, warm_fn], cold_fn)
    w0, lx0, lg0 = guess(warm, W, LX, LG, x0, p, ug)
    lbg, ubg = ca.DM(np.asarray(lbg, float)), ca.DM(np.asarray(ubg, float))
    sol = solver(x0=w0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, lam_x0=lx0, lam_g0=lg0)
    kkt = kkt_function(name + "_kkt", nlp)
    pr, du = kkt(sol["x"], p, sol["lam_x"], sol["lam_g"], lbx, ubx, lbg, ubg)
    extra = post(sol["x"], p)
    extra = list(extra) if isinstance(extra, (list, tuple)) else [extra]
    return ca.Function(name, [W, LX, LG, warm, x0, p, lbx, ubx, ug],
                       [sol["x"], sol["f"], sol["lam_x"], sol["lam_g"], pr, du, *extra],
                       list(STEP_INPUTS), list(STEP_OUTPUTS) + post.name_out())


class StepSolver:
    """A :func:`step_function` as one compiled C call, with the previous solution carried
    from one call to the next by swapping buffers.

    Fill :attr:`inputs` (by name: ``x0``, ``p``, ``lbx``, ``ubx``, ``u_guess``; ``warm`` is
    set by :meth:`step`), call :meth:`step`, read :attr:`outputs` (views valid until the
    next step). After a successful step :meth:`commit` makes its ``w``, ``lam_x``,
    ``lam_g`` the next step's ``*_prev`` (a pointer swap); :meth:`load` copies a solution
    found elsewhere (e.g. by a fallback solver) in instead.

    Raises :class:`CodegenError` when it cannot be generated, compiled or loaded (the
    caller keeps its separate calls then). ``timeout_s``: the call runs in a worker thread
    and is abandoned after that many seconds (as :class:`NLPSolver`).
    """

    def __init__(self, fn: ca.Function, timeout_s: float | None = None, hot: bool = True):
        self.fn = fn
        self.name = fn.name()
        self.timeout_s = timeout_s
        self.hot = hot
        self.timeouts = 0
        self._worker: _Worker | None = None
        self._load()

    def _load(self, private: bool = False) -> None:
        """Load the compiled step; ``private``: from a copy of the library, so that a call
        abandoned in the loaded one (still running in its thread) shares no static memory
        (the inner solver's memory pool) with the calls that follow."""
        cf, self.build_info = compile_function(self.fn, hot=self.hot)
        if private:
            src = Path(self.build_info["path"])
            with tempfile.TemporaryDirectory(prefix="acid-step-") as tmp:
                dst = Path(tmp) / src.name
                shutil.copyfile(src, dst)
                cf.close()
                cf = CompiledFunction(self.fn, dst)   # mapped: the file can go
        self._cf = cf
        names_in, names_out = self.fn.name_in(), self.fn.name_out()
        iin = {n: i for i, n in enumerate(names_in)}
        iout = {n: i for i, n in enumerate(names_out)}
        # the carried blocks: two buffers each (A, B), ping-pong: a step reads A and writes
        # B, the next reads B and writes A; both arrangements are prepared once, a commit
        # only switches pointers
        pairs = [(iout[o], iin[i]) for o, i in _CARRIED]
        views = []
        for flip in (False, True):
            ins, outs = list(cf.inputs), list(cf.outputs)
            ptr_in, ptr_out = [], []
            for ko, ki in pairs:
                a, b = cf.inputs[ki], cf.outputs[ko]
                if flip:
                    a, b = b, a
                ins[ki], outs[ko] = a, b
                ptr_in.append((ki, a.ctypes.data))
                ptr_out.append((ko, b.ctypes.data))
            views.append((dict(zip(names_in, ins, strict=True)),
                          dict(zip(names_out, outs, strict=True)), ptr_in, ptr_out))
        self._views = views
        self._parity = 0
        self.inputs, self.outputs = views[0][0], views[0][1]

    def step(self, warm: bool) -> tuple[bool, int]:
        """One call (warm-started from the carried solution when ``warm``): (finished, C
        return code). Not finished: the call timed out (abandoned, the library reloaded)."""
        self.inputs["warm"][0] = 1.0 if warm else 0.0
        cf = self._cf
        if self.timeout_s is None:
            return True, cf.call()
        if self._worker is None:
            self._worker = _Worker(f"{self.name}-step")
        finished, started, out, exc = self._worker.run(cf.call, self.timeout_s)
        if not finished:
            self.timeouts += 1
            if started:
                self._worker.stop()
                self._worker = None
                prev = {n: b.copy() for n, b in self.inputs.items()}
                cf.abandon()
                self._load(private=True)
                for n, v in prev.items():
                    self.inputs[n][:] = v
            return False, -1
        if exc is not None:
            raise exc
        return True, out

    def commit(self) -> None:
        """Make the last step's solution the next step's warm start (pointers switched, no
        copy)."""
        self._parity ^= 1
        ins, outs, ptr_in, ptr_out = self._views[self._parity]
        arg, res = self._cf._arg, self._cf._res
        for i, ptr in ptr_in:
            arg[i] = ptr
        for i, ptr in ptr_out:
            res[i] = ptr
        # the inputs that are not carried keep their buffers (the same objects)
        self.inputs, self.outputs = ins, outs

    def load(self, w, lam_x, lam_g) -> None:
        """Copy a solution found elsewhere in as the next step's warm start."""
        for (_, n), v in zip(_CARRIED, (w, lam_x, lam_g), strict=True):
            self.inputs[n][:] = v

    def close(self) -> None:
        if self._worker is not None:
            self._worker.stop()
            self._worker = None
        self._cf.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: S110 - interpreter shutdown
            pass
