"""Yardsticks for the multi-start validation: persistence, ARX and a subspace model.

A reviewer's first question about a grey-box model is whether it predicts better than
trivial black-box predictors fitted on the same data. Each yardstick here predicts the same
windows (start ``k0``, steps ``i = 0 .. H``) as :func:`acid.ident.validate.validate_model`, from the
same information the model gets: the outputs measured up to ``k0`` and the inputs over the
window (measured, or held at their value at ``k0`` where the model holds them).

* **persistence**: every output held at its value at ``k0``.
* **ARX** (multi-output, with an offset): ``y(k) = c + sum_{l=1..na} A_l y(k - l)
  + sum_{j=0..nb-1} B_j u(k - j)``, fitted by least squares on the estimation part.
  The input enters at lag 0 (``nk = 0``) because outputs are interval means over the
  interval over which the inputs are held (``T_ain`` responds within the sample). Orders
  ``na, nb`` in 1..4: see the order rule below (AIC is reported beside it). Simulated open
  loop over the window (its own past predictions fed back), never one step ahead.
* **subspace** (PO-MOESP, Verhaegen and Verdult 2007, written here: ``nfoursid`` takes a
  full N x N SVD per order, seconds each on a 1,400-sample record):
  ``x(k+1) = A x + B u``, ``y = C x + D u + d0``; ``A``, ``C`` from the extended
  observability matrix (``BLOCK_ROWS`` block rows), ``B``, ``D``, ``d0`` by least squares on
  the estimation stretch (the longest experiment in it). Order ``n`` in 1..8. Before each
  start the state is estimated by least squares on the outputs of the ``PAST_SAMPLES``
  preceding samples and ``y(k0)`` (the deterministic model, no noise model); from there the
  model runs open loop.

**Order rule** (both fitted yardsticks): the stable candidate with the least mean squared
standardised open-loop error over ``ORDER_WINDOWS`` windows of the validation's horizon
placed on the estimation part, with the inputs held there as over the validation windows.
AIC was the first rule: on plant data it chose ARX models that lean on exact relations
between the measured T_int, T_shell and the outputs (coefficients near 1e5, one-step fit
excellent); with those disturbances held over a window they predicted errors of 100-2000 K.
The rule now judges a candidate by the task it is used for.

Signals are standardised by their mean and standard deviation on the estimation part (an
input constant there carries no information and is left out). Near the start of an
experiment, where fewer past samples exist than a yardstick needs, the first sample is
repeated (steady state assumed). Step 0 of every yardstick is the measurement (the
yardsticks are given ``y(k0)``); their predictions start at step 1.

These are yardsticks: they are reported beside the model, labelled as such, and are never
offered to a controller (nothing here returns parameters a controller accepts).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from acid._blas import fixed_blas
from acid.errors import ConfigError

#: The yardsticks, in the order they are reported.
YARDSTICKS = ("persistence", "arx", "subspace")
#: ARX orders tried (na and nb each).
ARX_ORDERS = (1, 2, 3, 4)
#: Subspace orders tried.
SUBSPACE_ORDERS = tuple(range(1, 9))
#: Block rows of the subspace method's Hankel matrices (past and future, samples).
BLOCK_ROWS = 15
#: Samples before each start over which the subspace model's state is estimated.
PAST_SAMPLES = 60
#: Windows placed on the estimation part to choose the subspace order.
ORDER_WINDOWS = 20
#: Fewest estimation samples a fitted yardstick accepts.
MIN_ESTIMATION_SAMPLES = 4 * BLOCK_ROWS + 20
#: Below this standard deviation (in the signal's unit) a signal counts as constant.
CONSTANT_STD = 1e-9


@dataclass(frozen=True)
class YardstickPrediction:
    """One yardstick's predictions over the validation windows.

    Attributes
    ----------
    name : "persistence", "arx" or "subspace".
    predicted : (S, H + 1, ny) predicted outputs, in the unit of the data given.
    description : one line: what it is and how its order was chosen.
    settings : orders, the rule, the estimation samples, inputs used.
    """

    name: str
    predicted: np.ndarray
    description: str
    settings: dict = field(default_factory=dict)


@dataclass(frozen=True)
class _Scaler:
    mean: np.ndarray
    std: np.ndarray

    @classmethod
    def of(cls, x: np.ndarray) -> _Scaler:
        std = x.std(axis=0)
        return cls(x.mean(axis=0), np.where(std > CONSTANT_STD, std, 1.0))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return (x - self.mean) / self.std

    def back(self, z: np.ndarray) -> np.ndarray:
        return z * self.std + self.mean


# ----------------------------------------------------------------------- windows
def segment_first(experiment: np.ndarray) -> np.ndarray:
    """(N,) index of the first sample of each sample's experiment."""
    n = experiment.shape[0]
    new = np.ones(n, dtype=bool)
    new[1:] = experiment[1:] != experiment[:-1]
    return np.maximum.accumulate(np.where(new, np.arange(n), 0))


def windows(x: np.ndarray, k0: np.ndarray, horizon: int, past: int,
            first: np.ndarray, held: np.ndarray | None = None) -> np.ndarray:
    """(S, past + H + 1, nx): samples k0 - past .. k0 + H of ``x`` for each start.

    Samples before the start of ``k0``'s experiment repeat its first sample; columns marked
    in ``held`` keep their value at ``k0`` after ``k0``.
    """
    rel = np.arange(-past, horizon + 1)
    idx = np.maximum(k0[:, None] + rel[None, :], first[k0][:, None])
    out = x[idx]
    if held is not None and np.any(held):
        out[:, past + 1:, held] = out[:, past:past + 1, held]
    return out


def persistence(y: np.ndarray, k0: np.ndarray, horizon: int) -> YardstickPrediction:
    """Every output held at its value at ``k0`` over steps 0 .. H."""
    pred = np.repeat(y[k0][:, None, :], horizon + 1, axis=1)
    return YardstickPrediction("persistence", pred, "persistence: every channel held at "
                               "its value at the start", {"rule": "y(k0 + i) = y(k0)"})


# ----------------------------------------------------------------------- ARX
@dataclass(frozen=True)
class ARX:
    """A fitted multi-output ARX yardstick (standardised variables inside)."""

    na: int
    nb: int
    A: np.ndarray      # (na, ny, ny): A[l - 1] multiplies y(k - l)
    B: np.ndarray      # (nb, ny, nu): B[j] multiplies u(k - j)
    c: np.ndarray      # (ny,)
    aic: float
    stable: bool

    @property
    def lag(self) -> int:
        return max(self.na, self.nb - 1)

    def simulate(self, yw: np.ndarray, uw: np.ndarray, past: int) -> np.ndarray:
        """Open loop from ``past`` on: ``yw`` (S, past + H + 1, ny) holds the measured
        outputs up to index ``past`` (later values ignored), ``uw`` the inputs throughout."""
        y = yw.copy()
        for t in range(past + 1, y.shape[1]):
            acc = np.broadcast_to(self.c, y[:, t].shape).copy()
            for lag in range(1, self.na + 1):
                acc += y[:, t - lag] @ self.A[lag - 1].T
            for j in range(self.nb):
                acc += uw[:, t - j] @ self.B[j].T
            y[:, t] = acc
        return y


def _arx_rows(segments, lag: int) -> np.ndarray:
    """Indices k of estimation rows with ``lag`` past samples in the same experiment."""
    return np.concatenate([np.arange(a + lag, b) for a, b in segments if b - a > lag]
                          or [np.empty(0, dtype=int)])


@fixed_blas
def fit_arx(y: np.ndarray, u: np.ndarray, segments, orders=ARX_ORDERS,
            select: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[ARX, dict]:
    """Least-squares ARX for every ``na, nb`` in ``orders``; among the stable candidates the
    one with least open-loop error over the estimation windows ``select`` = (yw, uw) (see
    :func:`open_loop_score`), or with least AIC when ``select`` is None.

    ``y`` (N, ny), ``u`` (N, nu) standardised; ``segments`` the (start, stop) experiments.
    All candidates use the same rows (those with ``max(orders)`` past samples). Returns the
    model and {"na,nb": score}.
    """
    ny, nu = y.shape[1], u.shape[1]
    k = _arx_rows(segments, max(orders))
    if k.size == 0:
        raise ValueError("no ARX regression rows")
    best, scores = None, {}
    for na in orders:
        for nb in orders:
            cols = [np.ones((k.size, 1))]
            cols += [y[k - lag] for lag in range(1, na + 1)]
            cols += [u[k - j] for j in range(nb)]
            X = np.concatenate(cols, axis=1)
            theta, *_ = np.linalg.lstsq(X, y[k], rcond=None)
            e = y[k] - X @ theta
            sigma = e.T @ e / k.size
            sign, logdet = np.linalg.slogdet(sigma + 1e-300 * np.eye(ny))
            p = theta.size
            aic = k.size * (logdet if sign > 0 else -1e6) + 2 * p
            A = np.stack([theta[1 + (lag - 1) * ny:1 + lag * ny].T for lag in range(1, na + 1)])
            off = 1 + na * ny
            B = np.stack([theta[off + j * nu:off + (j + 1) * nu].T for j in range(nb)])
            stable = _ar_stable(A)
            cand = ARX(na, nb, A, B, theta[0], float(aic), stable)
            score = cand.aic if select is None else open_loop_score(cand, *select)
            scores[f"{na},{nb}"] = score
            key = (not stable, score)
            if best is None or key < best[0]:
                best = (key, cand)
    return best[1], scores


def open_loop_score(model, yw: np.ndarray, uw: np.ndarray, past: int | None = None) -> float:
    """Mean squared (standardised) open-loop error of ``model`` over windows ``yw``, ``uw``
    (S, past + H + 1, .) after their first ``past + 1`` samples; inf if it diverges."""
    past = PAST_SAMPLES if past is None else past
    with np.errstate(all="ignore"):
        err = model.simulate(yw, uw, past)[:, past + 1:] - yw[:, past + 1:]
    return float(np.mean(err**2)) if np.all(np.isfinite(err)) else math.inf


def _ar_stable(A: np.ndarray) -> bool:
    """Whether the autoregressive part (na, ny, ny) has all poles inside the unit circle."""
    na, ny, _ = A.shape
    comp = np.zeros((na * ny, na * ny))
    comp[:ny, :] = np.concatenate(list(A), axis=1)
    if na > 1:
        comp[ny:, :-ny] = np.eye((na - 1) * ny)
    return bool(np.max(np.abs(np.linalg.eigvals(comp))) < 1.0)


# ----------------------------------------------------------------------- subspace
@dataclass(frozen=True)
class Subspace:
    """A fitted state-space yardstick ``x(k+1) = A x + B u``, ``y = C x + D u + d0``
    (standardised variables inside)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    d0: np.ndarray
    stable: bool

    @property
    def order(self) -> int:
        return int(self.A.shape[0])

    def simulate(self, yw: np.ndarray, uw: np.ndarray, past: int) -> np.ndarray:
        """Outputs over (S, past + H + 1, ny): the state at the start of the stretch
        ``0 .. past`` by least squares on its measured outputs, the model run through
        ``past``, open loop after it (``yw`` after ``past`` is ignored)."""
        S, T, ny = yw.shape
        n = self.order
        P = past + 1
        Phi = np.empty((P, ny, n))      # free response to the initial state
        M = np.eye(n)
        for t in range(P):
            Phi[t] = self.C @ M
            M = self.A @ M
        x = np.zeros((S, n))            # forced response from a zero state
        forced = np.empty((S, P, ny))
        for t in range(P):
            forced[:, t] = x @ self.C.T + uw[:, t] @ self.D.T + self.d0
            x = x @ self.A.T + uw[:, t] @ self.B.T
        r = (yw[:, :P] - forced).reshape(S, P * ny)
        xa, *_ = np.linalg.lstsq(Phi.reshape(P * ny, n), r.T, rcond=None)
        x = x + xa.T @ M.T              # M = A^P
        out = yw.copy()
        for t in range(P, T):
            out[:, t] = x @ self.C.T + uw[:, t] @ self.D.T + self.d0
            x = x @ self.A.T + uw[:, t] @ self.B.T
        return out


def _hankel(x: np.ndarray, first: int, rows: int, cols: int) -> np.ndarray:
    """Block Hankel matrix: block row r holds x(first + r + j), j = 0 .. cols - 1."""
    return np.concatenate([x[first + r:first + r + cols].T for r in range(rows)], axis=0)


@fixed_blas
def moesp_observability(y: np.ndarray, u: np.ndarray, s: int = BLOCK_ROWS
                        ) -> tuple[np.ndarray, np.ndarray]:
    """PO-MOESP (Verhaegen and Verdult 2007, sec. 9.6): from one stretch of ``y`` (N, ny)
    and ``u`` (N, nu), the left singular vectors and singular values of the projection
    whose column space is the extended observability matrix (s block rows)."""
    N, ny = y.shape
    cols = N - 2 * s + 1
    Up, Uf = _hankel(u, 0, s, cols), _hankel(u, s, s, cols)
    Yp, Yf = _hankel(y, 0, s, cols), _hankel(y, s, s, cols)
    R = np.linalg.qr(np.concatenate([Uf, Up, Yp, Yf]).T / math.sqrt(cols), mode="r")
    L = R.T
    a, b = Uf.shape[0], Uf.shape[0] + Up.shape[0] + Yp.shape[0]
    U, sv, _ = np.linalg.svd(L[b:, a:b], full_matrices=False)
    return U, sv


@fixed_blas
def moesp_model(U: np.ndarray, sv: np.ndarray, n: int, y: np.ndarray,
                u: np.ndarray) -> Subspace:
    """Order-``n`` model: A, C from the observability matrix ``U[:, :n] sqrt(sv[:n])``;
    B, D, the output offset and the initial state by least squares on the stretch."""
    ny, nu = y.shape[1], u.shape[1]
    G = U[:, :n] * np.sqrt(sv[:n])
    C = G[:ny]
    A = np.linalg.lstsq(G[:-ny], G[ny:], rcond=None)[0]
    # y(k) = C A^k x0 + sum_{t<k} C A^(k-t-1) B u(t) + D u(k) + d0: linear in x0, B, D, d0
    N = y.shape[0]
    X = np.zeros((N, ny, n + n * nu + ny * nu + ny))
    X[:, :, n + n * nu:-ny] = np.einsum("ab,kj->kabj", np.eye(ny), u).reshape(N, ny, ny * nu)
    X[:, :, -ny:] = np.eye(ny)
    Ak = np.eye(n)
    Z = np.zeros((n, n, nu))            # Z[:, i, j] = sum_{t<k} A^(k-t-1) e_i u_j(t)
    diag = np.eye(n)[:, :, None]
    for k in range(N):
        X[k, :, :n] = C @ Ak
        X[k, :, n:n + n * nu] = C @ Z.reshape(n, n * nu)
        Ak = A @ Ak
        Z = (A @ Z.reshape(n, n * nu)).reshape(n, n, nu) + diag * u[k]
    theta = np.linalg.lstsq(X.reshape(N * ny, -1), y.reshape(-1), rcond=None)[0]
    B = theta[n:n + n * nu].reshape(n, nu)
    D = theta[n + n * nu:n + n * nu + ny * nu].reshape(ny, nu)
    stable = bool(np.max(np.abs(np.linalg.eigvals(A))) < 1.0)
    return Subspace(A, B, C, D, theta[-ny:], stable)


@fixed_blas
def fit_subspace(y: np.ndarray, u: np.ndarray, segment: tuple[int, int],
                 select: tuple[np.ndarray, np.ndarray], orders=SUBSPACE_ORDERS
                 ) -> tuple[Subspace, dict[str, float]]:
    """PO-MOESP on one experiment stretch ``segment`` of standardised ``y``, ``u``; the
    stable order with least open-loop error over the estimation windows ``select`` =
    (yw, uw) (:func:`open_loop_score`). Returns the model and {order: that error}."""
    a, b = segment
    ny = y.shape[1]
    with np.errstate(all="ignore"):
        U, sv = moesp_observability(y[a:b], u[a:b])
    best, scores = None, {}
    for n in orders:
        if n > min(ny * BLOCK_ROWS, int(np.sum(sv > sv[0] * 1e-12))):
            break
        with np.errstate(all="ignore"):
            model = moesp_model(U, sv, n, y[a:b], u[a:b])
        score = open_loop_score(model, *select)
        scores[str(n)] = score
        key = (not model.stable, score)
        if best is None or key < best[0]:
            best = (key, model)
    if best is None or not math.isfinite(best[0][1]):
        raise ValueError("no subspace model with finite predictions")
    return best[1], scores


# ----------------------------------------------------------------------- evaluate
@fixed_blas
def evaluate(y: np.ndarray, u: np.ndarray, experiment: np.ndarray, k0: np.ndarray,
             horizon: int, held: np.ndarray, estimation,
             names=YARDSTICKS, input_names: tuple[str, ...] | None = None
             ) -> dict[str, YardstickPrediction]:
    """The yardsticks' predictions over the windows ``k0 .. k0 + horizon``.

    Parameters
    ----------
    y : (N, ny) outputs (the first columns are the validated channels; more columns, e.g.
        the econ model's measured T_int and T_shell, are predicted alongside).
    u : (N, nu) inputs and measured disturbances, as measured.
    experiment : (N,) experiment id of each sample.
    k0 : (S,) start indices; horizon : H steps.
    held : (nu,) bool, inputs held at their value at ``k0`` over a window (as the model).
    estimation : (lo, hi) samples the fitted yardsticks are fitted on, or a list of such
        ranges (e.g. the first half of each record).
    names : which yardsticks.
    input_names : names of the columns of ``u`` (for the settings).

    Returns
    -------
    {name: YardstickPrediction}, predictions in the unit of ``y``; a yardstick that cannot
    be fitted (too few estimation samples, no finite model) is left out with a warning.
    """
    y, u = np.asarray(y, dtype=float), np.asarray(u, dtype=float)
    held = np.asarray(held, dtype=bool)
    k0 = np.asarray(k0, dtype=int)
    input_names = tuple(input_names or (f"u{j}" for j in range(u.shape[1])))
    out: dict[str, YardstickPrediction] = {}
    if "persistence" in names:
        out["persistence"] = persistence(y, k0, horizon)
    fitted = [n for n in names if n in ("arx", "subspace")]
    if not fitted:
        return out
    ranges = estimation_ranges(estimation, y.shape[0])
    seg = [s for lo, hi in ranges for s in _segments(experiment[lo:hi], lo)]
    seg = [(a, b) for a, b in seg if b - a >= MIN_ESTIMATION_SAMPLES]
    if not seg:
        text = ", ".join(f"{lo}..{hi - 1}" for lo, hi in ranges)
        warnings.warn(f"yardsticks ARX and subspace left out: the estimation part (samples "
                      f"{text}) has no experiment of {MIN_ESTIMATION_SAMPLES} samples",
                      UserWarning, stacklevel=3)  # the caller, past fixed_blas
        return out
    est = np.concatenate([np.arange(a, b) for a, b in seg])
    keep = u[est].std(axis=0) > CONSTANT_STD
    ys, us = _Scaler.of(y[est]), _Scaler.of(u[est][:, keep])
    yz, uz = ys(y), us(u[:, keep])
    first = segment_first(experiment)
    used = [n for n, k in zip(input_names, keep, strict=True) if k]
    common = {"estimation_samples": [int(v) for v in ranges[0]] if len(ranges) == 1
              else [[int(lo), int(hi)] for lo, hi in ranges],
              "estimation_used": [[int(a), int(b)] for a, b in seg],
              "inputs": used,
              "held_inputs": [n for n, h, k in zip(input_names, held, keep, strict=True)
                              if h and k]}

    # windows on the estimation part (its longest experiment) that choose the orders, the
    # inputs held as over the validation windows
    a, b = max(seg, key=lambda s: s[1] - s[0])
    h_sel = max(1, min(horizon, b - a - PAST_SAMPLES - 1))
    adm = np.arange(a + PAST_SAMPLES, b - h_sel)
    if adm.size == 0:
        adm = np.array([a])
    sel = np.unique(adm[np.round(np.linspace(0, adm.size - 1, ORDER_WINDOWS)).astype(int)])
    in_seg = np.full(y.shape[0], a)
    select = (windows(yz, sel, h_sel, PAST_SAMPLES, in_seg),
              windows(uz, sel, h_sel, PAST_SAMPLES, in_seg, held[keep]))
    rule = (f"least mean squared standardised open-loop error over {sel.size} windows of "
            f"{h_sel} steps on the estimation part (inputs held as in the validation), "
            "among stable candidates")

    def run(model) -> np.ndarray:
        yw = windows(yz, k0, horizon, PAST_SAMPLES, first)
        uw = windows(uz, k0, horizon, PAST_SAMPLES, first, held[keep])
        with np.errstate(all="ignore"):
            return ys.back(model.simulate(yw, uw, PAST_SAMPLES)[:, PAST_SAMPLES:])

    if "arx" in names:
        m, scores = fit_arx(yz, uz, seg, select=select)
        out["arx"] = YardstickPrediction(
            "arx", run(m),
            f"ARX na={m.na}, nb={m.nb} (lags 0..{m.nb - 1}), least open-loop error on the "
            f"estimation part over na, nb in 1..{max(ARX_ORDERS)}"
            f"{'' if m.stable else ' (no stable candidate)'}",
            {**common, "na": m.na, "nb": m.nb, "nk": 0, "aic": m.aic, "stable": m.stable,
             "order_scores": scores, "rule": f"{rule}; na, nb in 1..{max(ARX_ORDERS)}"})
    if "subspace" in names:
        try:
            m, scores = fit_subspace(yz, uz, (a, b), select)
        except ValueError as exc:
            warnings.warn(f"yardstick subspace left out: {exc}", UserWarning,
                          stacklevel=3)  # the caller, past fixed_blas
        else:
            out["subspace"] = YardstickPrediction(
                "subspace", run(m),
                f"subspace (PO-MOESP) order {m.order}, least open-loop error on the estimation "
                f"part over orders 1..{max(SUBSPACE_ORDERS)}"
                f"{'' if m.stable else ' (no stable candidate)'}",
                {**common, "order": m.order, "block_rows": BLOCK_ROWS, "stable": m.stable,
                 "state_from_past_samples": PAST_SAMPLES, "fitted_on": [int(a), int(b)],
                 "order_scores": scores,
                 "rule": f"{rule}; orders 1..{max(SUBSPACE_ORDERS)}"})
    return out


def estimation_ranges(estimation, n: int) -> list[tuple[int, int]]:
    """``estimation`` as a list of (lo, hi) sample ranges inside 0 .. n: one (lo, hi) pair
    or a sequence of them (e.g. the first half of each record), sorted, empty ones dropped."""
    pairs = [estimation] if len(estimation) == 2 and all(
        np.ndim(v) == 0 for v in estimation) else list(estimation)
    out = []
    for p in pairs:
        if len(p) != 2:
            raise ConfigError(f"estimation: a range is (lo, hi), got {p!r}")
        lo, hi = max(0, int(p[0])), min(n, int(p[1]))
        if hi > lo:
            out.append((lo, hi))
    if not out:
        raise ConfigError(f"estimation: no samples inside 0..{n - 1} in {estimation!r}")
    return sorted(out)


def _segments(experiment: np.ndarray, offset: int) -> list[tuple[int, int]]:
    cut = np.flatnonzero(np.diff(experiment) != 0) + 1
    edges = np.concatenate(([0], cut, [experiment.shape[0]])) + offset
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]
