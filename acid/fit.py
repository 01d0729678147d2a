"""Estimators for the control-oriented model (paper section II-B, eqs. 1-5).

Three methods, one result type (:class:`FitResult`):

``"ls"``  equation error (one-step) linear least squares, one regression per equation:

    eq. 1  T_cab(k+1) - T_cab(k) = g1 (T_int - T_cab) + g2 (T_shell - T_cab)
                                   + g3 (T_ain - T_cab) W_bl + tau1        (T_ain measured)
    eq. 2  T_evap(k+1)           = g4 T_evap + g5 (T_evap - T_evap_set) + tau2
    eq. 3  T_ain(k)              = g6 T_evap + g7 W_bl + tau3
    eq. 5  P_bl(k)               = b1 W_bl^2 + b2 W_bl + b3

    The regressors are not written out by hand: they are read off ``acid.model`` (each
    equation is linear in its parameters, so column j is the model evaluated with the j-th
    parameter set to one and the others to zero, minus the model with all set to zero). Rows
    never span an experiment boundary (``Dataset.transition_mask``). Temperatures are in
    kelvin, so a column of ~280 K sits next to the constant column: every regression is
    solved with centred, scaled columns and mapped back exactly (an affine map, which also
    carries the covariance).

``"cvx"`` the same regressions as convex programs (CVXPY) with physically meaningful
    constraints: g1, g2, g3 >= 0 (heat flows from warmer to colder), g5 <= 0 (a higher
    set-point raises the evaporator temperature), 0 <= g4 + g5 <= 1 - eps (a stable,
    non-oscillating evaporator pole), g6, g7 >= 0, b1 >= 0 and P_bl >= 0 over the measured
    blower range; optionally the Huber loss (robust to outliers). Standard errors of a
    constrained fit are those of the unconstrained problem evaluated at the constrained
    solution (exact when no constraint is active; conservative otherwise).

``"oe"``  output error: starting from the least-squares estimate, minimise the multi-step
    simulation error of T_cab, T_evap and T_ain (eqs. 1-3 simulated with ``acid.model.
    simulate``; T_int and T_shell measured along the way) over windows of ``oe_window``
    samples, each started from its own (estimated) initial state, with
    ``scipy.optimize.least_squares`` and the exact Jacobian of the window simulations,
    which CasADi differentiates from the same ``acid.model.step`` (no hand-derived
    sensitivities).
    With measurement noise on the states and output, equation error is biased (errors in
    variables: the noisy T_cab, T_evap, T_ain appear among the regressors) while output error
    is consistent; the model is also judged on 300-step predictions, not one step.

Standard errors (``covariance``): "white" is sigma^2 (X^T X)^-1 per equation and
sigma^2 (J^T J)^-1 for output error, right only when the residuals are white; "hac" (the
default) is the Newey & West (1987) sandwich with Bartlett weights and the automatic lag of
Newey & West (1994), lag products kept inside each experiment. On high-fidelity plant data
(model mismatch, strongly autocorrelated residuals) the white errors are ~3x too small (seed-
to-seed spread / mean stderr 1.7-6.6 over 20 two-hour records), the HAC ones 0.3-2.1
(median 0.7 least squares, 0.9 output error); on white-noise model-plant data both cover
the truth ~95 % of the time (30 seeds: OE 0.96 / 0.97, LS with process noise 0.97 / 0.93).

Rank deficiency (a parameter the data do not excite, e.g. W_bl constant makes gamma7
collinear with tau3) emits :class:`acid.errors.IdentifiabilityWarning` naming the parameter
and holds it at the reference value (the paper's by default), or raises ``DataError`` with
``on_rank_deficiency="raise"``; an equation in which nothing but the mean is excited is
refused with ``DataError``.
"""

from __future__ import annotations

import functools
import math
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.optimize
import scipy.stats

from acid import __version__, model
from acid._io import file_sha256, json_safe
from acid.data import MODEL_CHANNELS, Dataset
from acid.errors import ConfigError, DataError, IdentifiabilityWarning, SolverWarning
from acid.hac import hac_meat, resolve_bandwidth, segment_ids
from acid.metrics import fit_percent
from acid.params import BETA, DYNAMICS, GAMMA, PARAMETER_TABLE, TAU, ModelParams, paper

#: Parameter names in ``PARAMETER_TABLE`` order (gamma1..7, tau1..3, beta1..3).
PARAM_NAMES: tuple[str, ...] = tuple(row[0] for row in PARAMETER_TABLE)
PARAM_UNITS: dict[str, str] = {row[0]: row[1] for row in PARAMETER_TABLE}
N_PARAMS = len(PARAM_NAMES)
_INDEX = {n: i for i, n in enumerate(PARAM_NAMES)}

#: Parameters of each regression, intercept last (it is the column of ones).
EQUATIONS: dict[str, tuple[str, ...]] = {
    "eq1": ("gamma1", "gamma2", "gamma3", "tau1"),
    "eq2": ("gamma4", "gamma5", "tau2"),
    "eq3": ("gamma6", "gamma7", "tau3"),
    "eq5": ("beta1", "beta2", "beta3"),
}
#: What each regression predicts (the channel of its one-step fit).
EQUATION_CHANNEL = {"eq1": "T_cab", "eq2": "T_evap", "eq3": "T_ain", "eq5": "P_bl"}
#: The parameters of the dynamics (eqs. 1-3: gamma, tau), refined by output error.
DYNAMIC_PARAMS: tuple[str, ...] = PARAM_NAMES[DYNAMICS]

METHODS = ("ls", "cvx", "oe")
LOSSES = ("squared", "huber")
COVARIANCES = ("white", "hac")
#: The default of ``ModelFitter(covariance=...)`` and ``acid fit --covariance`` (see README).
DEFAULT_COVARIANCE = "hac"

_RANK_RTOL = 1e-8       # singular value ratio below which a direction counts as not excited
_COND_WARN = 1e4        # scaled condition number above which the data excite a direction poorly
_HUBER_M = 1.345        # Huber threshold in robust standard deviations (95 % efficiency)
_EVAP_POLE_MARGIN = 1e-3


# --------------------------------------------------------------------------- result
@dataclass(frozen=True)
class FitResult:
    """What a fit found, with the evidence to judge it (no printing here).

    Attributes
    ----------
    params : the fitted ``ModelParams`` (provenance: data file, sha256, method, ...).
    names, units : the 13 parameter names and units (``PARAMETER_TABLE`` order).
    reference : (13,) reference values (the paper's unless another set was given).
    estimates, stderr : (13,) estimates and standard errors (NaN where not estimated).
    ci95 : (13, 2) 95 % t-intervals (low, high); NaN where not estimated.
    param_status : per parameter, "estimated", "fixed" (not excited: held at the reference)
        or "reference" (no data for it, e.g. no P_bl channel).
    covariance : {block: (p, p) array} over the parameters ``covariance_names[block]``
        (blocks "eq1", "eq2", "eq3", "eq5" of the equation-error fits; output error adds the
        joint "oe" block over its free gamma/tau, which is what its ``stderr`` come from).
    condition_number : {equation: scaled condition number} (centred, unit-norm columns: what
        the data excite); ``condition_number_raw`` the same for the raw kelvin regressors.
    rank : {equation: numerical rank}; ``n_regressors`` {equation: number of columns}.
    fit_percent_one_step : {channel: MATLAB ``compare`` fit %} of one-step predictions of
        T_cab, T_evap, T_ain (eqs. 1-3 with the fitted parameters) and P_bl (eq. 5).
    fit_percent_simulation : {channel: fit %} of ``oe_window``-step simulations from the
        measured states (the paper judges the model on 300-step predictions).
    residual_std : {equation: residual standard deviation} (K, or W for eq. 5).
    active_constraints : constraints at their bound at the solution (``"cvx"`` only).
    solver_status : {equation or "oe": status string}.
    warnings : identifiability and solver warnings, one line each.
    notes : informational lines (method caveats, kept reference values).
    eta_cop, eta_cop_stderr : COP estimated from P_comp with eq. 4 (NaN when the data lack
        P_comp or T_amb); kept out of ``params`` unless the fitter was asked to use it.
    n_samples : samples in the estimation data; ``n_rows`` regression rows per equation.
    method, loss : the estimator and loss used; ``elapsed_s`` wall time of the fit, s.
    covariance_kind : "white" (``sigma^2 (X^T X)^-1``, ``sigma^2 (J^T J)^-1``) or "hac"
        (Newey-West sandwich); what ``stderr``, ``ci95`` and ``covariance`` are.
    hac_bandwidth : {block: Bartlett truncation lag, samples} of the HAC estimate (empty for
        "white").
    """

    params: ModelParams
    names: tuple[str, ...]
    units: tuple[str, ...]
    reference: np.ndarray
    estimates: np.ndarray
    stderr: np.ndarray
    ci95: np.ndarray
    param_status: tuple[str, ...]
    covariance: dict[str, np.ndarray]
    covariance_names: dict[str, tuple[str, ...]]
    condition_number: dict[str, float]
    condition_number_raw: dict[str, float]
    rank: dict[str, int]
    n_regressors: dict[str, int]
    fit_percent_one_step: dict[str, float]
    fit_percent_simulation: dict[str, float]
    residual_std: dict[str, float]
    active_constraints: tuple[str, ...]
    solver_status: dict[str, str]
    warnings: tuple[str, ...]
    notes: tuple[str, ...]
    eta_cop: float
    eta_cop_stderr: float
    n_samples: int
    n_rows: dict[str, int]
    method: str
    loss: str
    elapsed_s: float = field(default=float("nan"), compare=False)
    covariance_kind: str = "white"
    hac_bandwidth: dict[str, int] = field(default_factory=dict)

    def table(self) -> list[tuple[str, str, float, float, float, float, float]]:
        """Rows (name, unit, paper/reference value, estimate, stderr, ci_low, ci_high).

        A last row ``eta_cop`` is added when the data allowed estimating it (eq. 4).
        """
        rows = [(n, u, float(r), float(e), float(s), float(lo), float(hi))
                for n, u, r, e, s, (lo, hi) in zip(self.names, self.units, self.reference,
                                                   self.estimates, self.stderr, self.ci95,
                                                   strict=True)]
        if math.isfinite(self.eta_cop):
            se = self.eta_cop_stderr
            rows.append(("eta_cop", "1", float(paper().eta_cop), float(self.eta_cop), se,
                         self.eta_cop - 1.96 * se, self.eta_cop + 1.96 * se))
        return rows

    def equations(self) -> list[str]:
        """The identified model as readable equations (kelvin, kg/s, W)."""
        v = {n: f"{x:.6g}" for n, x in self.params.as_dict().items()}
        return [
            f"T_cab(k+1) = T_cab + {v['gamma1']} (T_int - T_cab) + {v['gamma2']} "
            f"(T_shell - T_cab) + {v['gamma3']} (T_ain - T_cab) W_bl + {v['tau1']}   (eq. 1)",
            f"T_evap(k+1) = {v['gamma4']} T_evap + {v['gamma5']} (T_evap - T_evap_set)"
            f" + {v['tau2']}   (eq. 2)",
            f"T_ain = {v['gamma6']} T_evap + {v['gamma7']} W_bl + {v['tau3']}   (eq. 3)",
            f"P_bl = {v['beta1']} W_bl^2 + {v['beta2']} W_bl + {v['beta3']}   (eq. 5)",
        ]

    def to_json_dict(self) -> dict:
        """The estimation report as JSON-safe data (non-finite numbers become ``null``)."""
        params = [
            {"name": n, "unit": u, "reference": r, "estimate": e, "stderr": s,
             "ci95_low": lo, "ci95_high": hi, "status": st}
            for (n, u, r, e, s, lo, hi), st in zip(self.table(), self.param_status + ("",),
                                                   strict=False)
        ]
        blocks = {}
        for eq in EQUATIONS:
            blocks[eq] = {
                "parameters": list(EQUATIONS[eq]), "channel": EQUATION_CHANNEL[eq],
                "rank": self.rank.get(eq), "n_regressors": self.n_regressors.get(eq),
                "condition_number": self.condition_number.get(eq),
                "condition_number_raw": self.condition_number_raw.get(eq),
                "residual_std": self.residual_std.get(eq), "n_rows": self.n_rows.get(eq),
                "solver_status": self.solver_status.get(eq),
            }
        d = {
            "method": self.method, "loss": self.loss, "n_samples": self.n_samples,
            "covariance_kind": self.covariance_kind, "hac_bandwidth": self.hac_bandwidth,
            "elapsed_s": self.elapsed_s, "parameters": params, "equations": blocks,
            "covariance": {k: {"names": list(self.covariance_names[k]), "matrix": v}
                           for k, v in self.covariance.items()},
            "fit_percent_one_step": self.fit_percent_one_step,
            "fit_percent_simulation": self.fit_percent_simulation,
            "active_constraints": list(self.active_constraints),
            "solver_status": self.solver_status, "warnings": list(self.warnings),
            "notes": list(self.notes),
            "eta_cop_estimate": {"value": self.eta_cop, "stderr": self.eta_cop_stderr},
        }
        return json_safe(d)


# ------------------------------------------------------------------------ estimator
class ModelFitter:
    """Identify gamma, tau (eqs. 1-3) and beta (eq. 5) from a dataset.

    Parameters
    ----------
    method : "ls" (equation-error least squares), "cvx" (constrained, CVXPY) or "oe"
        (output error, started from the least-squares estimate).
    loss : "squared" or "huber" (robust; needs "cvx" or "oe").
    fit_blower : fit beta from the P_bl channel (kept at the reference values when False or
        when the data have no P_bl).
    oe_window : samples per output-error simulation window (300 = 1500 s, as in the paper's
        validation); also the horizon of ``fit_percent_simulation``.
    oe_weighting : "noise" (weight each channel by 1 / its residual std, re-estimated once)
        or "none" (plain kelvin).
    oe_estimate_x0 : estimate each window's initial [T_cab, T_evap] (the measured values are
        then observations of it) instead of starting from the noisy measurement.
    use_eta_cop : put the eta_cop estimated from P_comp (eq. 4) into ``params``.
    on_rank_deficiency : "fix" (warn, hold the parameter at its reference value) or "raise".
    reference : parameter set used beside the estimates and for held parameters; the paper's
        by default.
    solver : CVXPY solver name for ``"cvx"`` (default: CVXPY's choice).
    covariance : how standard errors and intervals are computed.

        * ``"white"``: the textbook ``sigma^2 (X^T X)^-1`` per equation and
          ``sigma^2 (J^T J)^-1`` for output error; right when the residuals are white
          (model-plant data with white noise).
        * ``"hac"``: the heteroskedasticity-and-autocorrelation-consistent sandwich of
          Newey & West (1987), ``n/(n-p) B^-1 S B^-1`` with ``B = X^T X`` (``J^T J``) and
          ``S`` the Bartlett-weighted long-run covariance of the scores ``x_t e_t`` (for
          output error: the Jacobian rows times residuals, summed over the three channels of
          one instant). Lag products never cross an experiment boundary; output-error
          windows of one experiment are contiguous in time, so they do cross windows. Needed
          when the model does not contain the plant (high-fidelity or real data): the
          residuals are then strongly autocorrelated and white intervals far too narrow.
    hac_bandwidth : Bartlett truncation lag L (weights ``1 - l/(L+1)``): ``"auto"`` (the
        data-dependent rule of Newey & West 1994, per equation / for the output-error
        block), ``"nw"`` (the fixed rule ``floor(4 (n/100)^(2/9))``) or an integer >= 0
        (0: White's heteroskedasticity-consistent HC0 sandwich).

    References
    ----------
    Newey, W. K. and West, K. D. (1987). A simple, positive semi-definite,
    heteroskedasticity and autocorrelation consistent covariance matrix. Econometrica 55(3),
    703-708. Newey, W. K. and West, K. D. (1994). Automatic lag selection in covariance
    matrix estimation. Review of Economic Studies 61(4), 631-653.
    """

    def __init__(self, method: str = "ls", loss: str = "squared", fit_blower: bool = True,
                 oe_window: int = 300, oe_weighting: str = "noise", oe_estimate_x0: bool = True,
                 use_eta_cop: bool = False, on_rank_deficiency: str = "fix",
                 reference: ModelParams | None = None, solver: str | None = None,
                 covariance: str = DEFAULT_COVARIANCE, hac_bandwidth: str | int = "auto"):
        self.method = method
        self.loss = loss
        self.fit_blower = fit_blower
        self.oe_window = oe_window
        self.oe_weighting = oe_weighting
        self.oe_estimate_x0 = oe_estimate_x0
        self.use_eta_cop = use_eta_cop
        self.on_rank_deficiency = on_rank_deficiency
        self.reference = reference
        self.solver = solver
        self.covariance = covariance
        self.hac_bandwidth = hac_bandwidth

    def _check_options(self) -> None:
        if self.method not in METHODS:
            raise ConfigError(f"unknown fit method {self.method!r} (choose from "
                              f"{', '.join(METHODS)})")
        if self.loss not in LOSSES:
            raise ConfigError(f"unknown loss {self.loss!r} (choose from {', '.join(LOSSES)})")
        if self.loss == "huber" and self.method == "ls":
            raise ConfigError("the Huber loss needs --method cvx or oe "
                              "(linear least squares is the squared loss)")
        if self.on_rank_deficiency not in ("fix", "raise"):
            raise ConfigError(f"on_rank_deficiency must be 'fix' or 'raise', "
                              f"got {self.on_rank_deficiency!r}")
        if self.oe_weighting not in ("noise", "none"):
            raise ConfigError(f"oe_weighting must be 'noise' or 'none', got {self.oe_weighting!r}")
        if self.covariance not in COVARIANCES:
            raise ConfigError(f"unknown covariance {self.covariance!r} (choose from "
                              f"{', '.join(COVARIANCES)})")
        bw = self.hac_bandwidth
        if not (bw in ("auto", "nw") or (isinstance(bw, (int, np.integer))
                                         and not isinstance(bw, bool) and bw >= 0)):
            raise ConfigError(f"hac_bandwidth must be 'auto', 'nw' or an integer >= 0, "
                              f"got {bw!r}")
        if int(self.oe_window) < 5:
            raise ConfigError(f"oe_window must be at least 5 samples, got {self.oe_window}")

    def fit(self, ds: Dataset) -> FitResult:
        """Fit the model to ``ds`` (channels of ``acid.data.MODEL_CHANNELS``; P_bl optional).

        Returns a :class:`FitResult`; the fitted parameters are also kept as ``params_`` and
        the result as ``result_``.
        """
        self._check_options()
        t0 = time.perf_counter()
        ref = self.reference or paper()
        data = _Signals.from_dataset(ds)
        if abs(ds.Ts - ref.Ts) > 1e-9:
            raise DataError(f"{ds.source}: sample time {ds.Ts:g} s differs from the model's "
                            f"{ref.Ts:g} s (gamma/tau are per sample); resample the data")
        theta_ref = ref.theta
        warn_lines: list[str] = []
        notes: list[str] = []
        fits: dict[str, _EqFit] = {}
        for eq in EQUATIONS:
            if eq == "eq5" and (not self.fit_blower or data.P_bl is None):
                notes.append("beta kept at the reference values: " + (
                    "blower fit disabled" if not self.fit_blower else "the data have no P_bl"))
                continue
            fits[eq] = self._fit_equation(eq, data, theta_ref, warn_lines, ds.source)

        theta = theta_ref.copy()
        for f in fits.values():
            theta[[_INDEX[n] for n in f.names]] = f.theta
        status = ["reference"] * N_PARAMS
        stderr = np.full(N_PARAMS, np.nan)
        for f in fits.values():
            for n, fixed, se in zip(f.names, f.fixed, f.stderr, strict=True):
                status[_INDEX[n]] = "fixed" if fixed else "estimated"
                stderr[_INDEX[n]] = np.nan if fixed else se
        dof = {n: f.dof for f in fits.values() for n in f.names}
        covariance = {eq: f.cov for eq, f in fits.items()}
        cov_names = {eq: f.names for eq, f in fits.items()}
        solver_status = {eq: f.status for eq, f in fits.items()}
        bandwidths = {eq: f.bandwidth for eq, f in fits.items()}
        active = [c for f in fits.values() for c in f.active]

        if self.method == "oe":
            free = [n for n in DYNAMIC_PARAMS if status[_INDEX[n]] == "estimated"]
            oe = _output_error(data, theta, free, {eq: fits[eq] for eq in ("eq1", "eq2", "eq3")},
                               int(self.oe_window), self.oe_weighting, self.oe_estimate_x0,
                               self.loss, self.covariance, self.hac_bandwidth)
            theta = oe.theta
            for n, se in zip(free, oe.stderr, strict=True):
                stderr[_INDEX[n]] = se
                dof[n] = oe.dof
            covariance["oe"] = oe.cov
            cov_names["oe"] = tuple(free)
            solver_status["oe"] = oe.status
            notes.append(f"output error over {oe.n_windows} windows of <= {self.oe_window} "
                         "samples from the least-squares start; consistent under measurement "
                         "noise; standard errors from " + (
                             "sigma^2 (J^T J)^-1" if self.covariance == "white" else
                             f"the Newey-West sandwich (lag {oe.bandwidth})") + " at the optimum")
            bandwidths["oe"] = oe.bandwidth
            if not oe.success:
                msg = f"output-error refinement did not converge ({oe.status})"
                warnings.warn(msg, SolverWarning, stacklevel=2)
                warn_lines.append(msg)
        else:
            notes.append("equation-error estimates are biased when the measured T_cab, T_evap, "
                         "T_ain are noisy (errors in variables); --method oe is consistent")

        ci = np.full((N_PARAMS, 2), np.nan)
        for i, n in enumerate(PARAM_NAMES):
            if n in dof and math.isfinite(stderr[i]):
                q = scipy.stats.t.ppf(0.975, max(dof[n], 1))
                ci[i] = theta[i] - q * stderr[i], theta[i] + q * stderr[i]

        eta, eta_se = _estimate_eta_cop(data, ref)
        if math.isfinite(eta):
            notes.append(f"eta_cop estimated from P_comp with eq. 4: {eta:.4g} "
                         f"(+/- {eta_se:.2g}); " + ("used in params" if self.use_eta_cop else
                                                    f"params keep {ref.eta_cop:g}"))
        provenance = {
            "data_file": ds.source, "method": self.method, "loss": self.loss,
            "n_samples": len(ds), "time_span_s": [float(ds.time[0]), float(ds.time[-1])],
            "acid_version": __version__,
        }
        if Path(ds.source).is_file():
            provenance["data_sha256"] = file_sha256(ds.source)
        if "seed" in ds.metadata:
            provenance["data_seed"] = ds.metadata["seed"]
        params = ref.with_theta(
            theta,
            eta_cop=eta if (self.use_eta_cop and math.isfinite(eta) and eta > 0) else ref.eta_cop,
            name=f"fit-{self.method}", provenance=provenance)

        one_step = _one_step_fit(data, params)
        simulation = _simulation_fit(data, params, int(self.oe_window))
        resid_std = {eq: f.residual_std for eq, f in fits.items()}
        if self.method == "oe":
            resid_std.update(oe.channel_rms)
        result = FitResult(
            params=params, names=PARAM_NAMES, units=tuple(PARAM_UNITS[n] for n in PARAM_NAMES),
            reference=theta_ref, estimates=theta, stderr=stderr, ci95=ci,
            param_status=tuple(status), covariance=covariance, covariance_names=cov_names,
            condition_number={eq: f.cond for eq, f in fits.items()},
            condition_number_raw={eq: f.cond_raw for eq, f in fits.items()},
            rank={eq: f.rank for eq, f in fits.items()},
            n_regressors={eq: len(f.names) for eq, f in fits.items()},
            fit_percent_one_step=one_step, fit_percent_simulation=simulation,
            residual_std=resid_std, active_constraints=tuple(active),
            solver_status=solver_status, warnings=tuple(warn_lines), notes=tuple(notes),
            eta_cop=eta, eta_cop_stderr=eta_se, n_samples=len(ds),
            n_rows={eq: f.n_rows for eq, f in fits.items()}, method=self.method,
            loss=self.loss, elapsed_s=time.perf_counter() - t0,
            covariance_kind=self.covariance,
            hac_bandwidth={k: int(v) for k, v in bandwidths.items() if v is not None},
        )
        self.params_ = params
        self.result_ = result
        return result

    # ------------------------------------------------------------------ one equation
    def _fit_equation(self, eq: str, data: _Signals, theta_ref: np.ndarray,
                      warn_lines: list[str], source: str) -> _EqFit:
        """One regression: rank check, (constrained / robust) solve, covariance.

        Covariance over the free columns: ``"white"`` sigma^2 (X^T X)^-1, sigma^2 = RSS / (N - p)
        (for the Huber loss sigma is the MAD-based robust standard deviation of the
        residuals); ``"hac"`` N/(N - p) (Z^T Z)^-1 S (Z^T Z)^-1 in the scaled variables, S the
        Newey-West long-run covariance of the scores z_t e_t (Huber: psi(e_t) z_t, the bread
        divided by the fraction of unclipped residuals), mapped back with the affine map.
        """
        names = EQUATIONS[eq]
        y, offset, X = _regression(eq, data)
        if X.shape[0] <= X.shape[1] + 1:
            raise DataError(f"{source}: {X.shape[0]} usable rows for eq. {eq[2:]}, "
                            f"need more than {X.shape[1] + 1}")
        target = y - offset
        diag = _diagnose(X, names)
        fixed = np.zeros(len(names), dtype=bool)
        if diag.rank <= 1:
            if eq == "eq5":
                msg = ("eq. 5 (blower power): the data do not excite the blower curve "
                       "(W_bl constant); beta kept at the reference values")
                warnings.warn(msg, IdentifiabilityWarning, stacklevel=3)
                warn_lines.append(msg)
                fixed[:] = True
            else:
                raise DataError(f"{source}: eq. {eq[2:]} ({EQUATION_CHANNEL[eq]}) is not "
                                f"identifiable: its regressors are constant "
                                f"(rank {diag.rank} of {len(names)}); excite the inputs")
        elif diag.not_excited:
            lost = [names[j] for j in diag.not_excited]
            partners = sorted({names[j] for j in diag.partners} - set(lost))
            held = ", ".join(f"{n} = {theta_ref[_INDEX[n]]:.6g}" for n in lost)
            msg = (f"eq. {eq[2:]} ({EQUATION_CHANNEL[eq]}): the data do not excite "
                   f"{', '.join(lost)} (collinear with {', '.join(partners) or 'the others'}; "
                   f"rank {diag.rank} of {len(names)})")
            if self.on_rank_deficiency == "raise":
                raise DataError(f"{source}: {msg}")
            msg += f"; held at the reference value: {held}"
            warnings.warn(msg, IdentifiabilityWarning, stacklevel=3)
            warn_lines.append(msg)
            fixed[diag.not_excited] = True
        elif diag.cond > _COND_WARN:
            msg = (f"eq. {eq[2:]} ({EQUATION_CHANNEL[eq]}): poorly excited (scaled condition "
                   f"number {diag.cond:.3g}); standard errors will be large")
            warnings.warn(msg, IdentifiabilityWarning, stacklevel=3)
            warn_lines.append(msg)

        theta_eq = theta_ref[[_INDEX[n] for n in names]].copy()
        free = ~fixed
        active: list[str] = []
        status = "fixed"
        bandwidth = None
        cov = np.zeros((len(names), len(names)))
        sigma = 0.0
        n_rows = X.shape[0]
        dof = max(n_rows - int(free.sum()), 1)
        if free.any():
            t_fix = target - X[:, fixed] @ theta_eq[fixed]
            sc = _Affine.of(X[:, free], t_fix)
            Z, yn = sc.Z, sc.yn
            if self.method == "cvx" or self.loss == "huber":
                phi, status, active = _solve_cvx(eq, names, free, theta_eq, sc, self.loss,
                                                 data, self.solver,
                                                 constrained=self.method == "cvx")
                if phi is None:
                    msg = (f"eq. {eq[2:]}: CVXPY returned {status}; "
                           "using the unconstrained least-squares estimate")
                    warnings.warn(msg, SolverWarning, stacklevel=3)
                    warn_lines.append(msg)
                    phi = np.linalg.lstsq(Z, yn, rcond=None)[0]
            else:
                phi = np.linalg.lstsq(Z, yn, rcond=None)[0]
                status = "optimal (lstsq)"
            theta_eq[free] = sc.A @ phi + sc.b
            r = t_fix - X[:, free] @ theta_eq[free]
            if self.loss == "huber":
                sigma = _robust_std(r)
            else:
                sigma = float(np.sqrt(r @ r / dof))
            _, s, Vt = np.linalg.svd(Z, full_matrices=False)
            inv_ztz = (Vt.T / s**2) @ Vt
            if self.covariance == "hac":
                rows = np.flatnonzero(data.transition) if eq in ("eq1", "eq2") \
                    else np.arange(n_rows)
                groups = segment_ids(rows, data.segments)
                e = r / sc.sy
                frac = 1.0
                if self.loss == "huber":  # M-estimator: scores psi(e) z, bread E[psi'] Z^T Z
                    c = _HUBER_M * max(sigma / sc.sy, 1e-12)
                    frac = max(float(np.mean(np.abs(e) <= c)), 1.0 / n_rows)
                    e = np.clip(e, -c, c)
                scores = Z * e[:, None]
                bandwidth = resolve_bandwidth(self.hac_bandwidth, scores, groups)
                meat = hac_meat(scores, groups, bandwidth)
                cov_phi = n_rows / dof * (inv_ztz @ meat @ inv_ztz) / frac**2
            else:
                cov_phi = sigma**2 / sc.sy**2 * inv_ztz
            idx = np.flatnonzero(free)
            cov[np.ix_(idx, idx)] = sc.A @ cov_phi @ sc.A.T
        resid = target - X @ theta_eq
        if not free.any():
            sigma = float(np.sqrt(np.mean(resid**2)))
        return _EqFit(names=names, theta=theta_eq, fixed=tuple(bool(f) for f in fixed),
                      stderr=np.sqrt(np.clip(np.diag(cov), 0, None)), cov=cov, dof=dof,
                      cond=diag.cond, cond_raw=diag.cond_raw, rank=diag.rank, status=status,
                      active=tuple(active), n_rows=n_rows, residual_std=sigma,
                      bandwidth=bandwidth)


def fit(ds: Dataset, method: str = "ls", **options) -> FitResult:
    """Convenience: ``ModelFitter(method=method, **options).fit(ds)``."""
    return ModelFitter(method=method, **options).fit(ds)


# ---------------------------------------------------------------------- internals
@dataclass(frozen=True)
class _Signals:
    """The estimation data in model units (K, kg/s, W) and the experiment structure."""

    T_cab: np.ndarray
    T_evap: np.ndarray
    T_ain: np.ndarray
    W_bl: np.ndarray
    T_evap_set: np.ndarray
    T_int: np.ndarray
    T_shell: np.ndarray
    P_bl: np.ndarray | None
    P_comp: np.ndarray | None
    T_amb: np.ndarray | None
    transition: np.ndarray      # (N-1,) True where k -> k+1 stays in one experiment
    segments: tuple[tuple[int, int], ...]

    @classmethod
    def from_dataset(cls, ds: Dataset) -> _Signals:
        ds.validate(require=MODEL_CHANNELS, min_samples=8)
        temps = {n: ds.get(n, "K") for n in ("T_cab", "T_evap", "T_ain", "T_evap_set",
                                             "T_int", "T_shell")}
        return cls(W_bl=ds.get("W_bl", "kg/s"),
                   P_bl=ds.get("P_bl", "W") if "P_bl" in ds else None,
                   P_comp=ds.get("P_comp", "W") if "P_comp" in ds else None,
                   T_amb=ds.get("T_amb", "K") if "T_amb" in ds else None,
                   transition=ds.transition_mask(), segments=tuple(ds.segments()), **temps)


@dataclass(frozen=True)
class _EqFit:
    names: tuple[str, ...]
    theta: np.ndarray
    fixed: tuple[bool, ...]
    stderr: np.ndarray
    cov: np.ndarray
    dof: int
    cond: float
    cond_raw: float
    rank: int
    status: str
    active: tuple[str, ...]
    n_rows: int
    residual_std: float
    bandwidth: int | None = None   # HAC truncation lag (None: white covariance)


def _unit_params(values: dict[str, float]) -> ModelParams:
    """A parameter set with the given entries and zeros elsewhere (to read off regressors)."""
    th = np.zeros(N_PARAMS)
    for n, v in values.items():
        th[_INDEX[n]] = v
    return ModelParams(gamma=th[GAMMA], tau=th[TAU], beta=th[BETA])


def _linear_in_params(fun, names: tuple[str, ...], n: int) -> tuple[np.ndarray, np.ndarray]:
    """(offset, X) with fun(p) = offset + X theta, for a model function linear in ``names``."""
    f0 = np.broadcast_to(np.asarray(fun(_unit_params({})), dtype=float), (n,))
    cols = [np.broadcast_to(np.asarray(fun(_unit_params({m: 1.0})), dtype=float), (n,)) - f0
            for m in names]
    return np.array(f0), np.column_stack(cols)


def _regression(eq: str, d: _Signals) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(y, offset, X) of one equation: y = offset + X theta, rows within experiments."""
    names = EQUATIONS[eq]
    if eq in ("eq1", "eq2"):
        k = np.flatnonzero(d.transition)
        if eq == "eq1":  # eq. 1 with the measured T_ain
            def fun(p):
                return model.cabin_step(d.T_cab[k], d.T_int[k], d.T_shell[k], d.T_ain[k],
                                        d.W_bl[k], p)
            y = d.T_cab[k + 1]
        else:  # eq. 2
            def fun(p):
                return model.evap_step(d.T_evap[k], d.T_evap_set[k], p)
            y = d.T_evap[k + 1]
    elif eq == "eq3":
        def fun(p):
            return model.inlet_air(d.T_evap, d.W_bl, p)
        y = d.T_ain
    else:  # eq. 5
        def fun(p):
            return model.blower_power(d.W_bl, p)
        y = d.P_bl
    offset, X = _linear_in_params(fun, names, y.shape[0])
    return y, offset, X


@dataclass(frozen=True)
class _Diagnosis:
    rank: int
    cond: float
    cond_raw: float
    not_excited: tuple[int, ...]   # column indices to hold fixed
    partners: tuple[int, ...]      # columns they are collinear with


def _diagnose(X: np.ndarray, names: tuple[str, ...]) -> _Diagnosis:
    """Rank and conditioning of a regressor with the constant column last.

    The scaled matrix has centred, unit-norm columns plus the normalised constant column, so
    its condition number measures what the data excite, not the kelvin offset; the raw
    condition number (columns as they are) is reported beside it.
    """
    n, p = X.shape
    Z = np.empty_like(X)
    Z[:, -1] = 1.0 / math.sqrt(n)
    for j in range(p - 1):
        c = X[:, j] - X[:, j].mean()
        nrm = np.linalg.norm(c)
        ref = max(np.linalg.norm(X[:, j]), 1e-300)
        Z[:, j] = c / nrm if nrm > 1e-10 * ref else 0.0
    s_raw = np.linalg.svd(X, compute_uv=False)
    cond_raw = float(s_raw[0] / s_raw[-1]) if s_raw[-1] > 0 else math.inf
    _, s, Vt = np.linalg.svd(Z, full_matrices=False)
    small = s <= _RANK_RTOL * s[0]
    rank = int(p - small.sum())
    cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    not_excited: list[int] = []
    partners: set[int] = set()
    for v in Vt[small]:
        order = [j for j in np.argsort(-np.abs(v)) if j != p - 1 and j not in not_excited]
        if order:
            not_excited.append(int(order[0]))
        implicated = {int(j) for j in np.flatnonzero(np.abs(v) > 0.2)}
        if np.linalg.norm(Z[:, order[0] if order else 0]) == 0.0:
            implicated.add(p - 1)  # a constant column is collinear with the intercept
        partners |= implicated
    return _Diagnosis(rank=rank, cond=cond, cond_raw=cond_raw,
                      not_excited=tuple(not_excited), partners=tuple(sorted(partners)))


@dataclass(frozen=True)
class _Affine:
    """Centred, scaled regression ``Z phi = yn`` and the exact map ``theta = A phi + b``.

    ``X theta = y`` with the constant column last; ``Z`` has columns (X_j - c_j) / s_j and a
    column of ones, ``yn = (y - ybar) / sy``.
    """

    Z: np.ndarray
    yn: np.ndarray
    A: np.ndarray
    b: np.ndarray
    sy: float

    @classmethod
    def of(cls, X: np.ndarray, y: np.ndarray) -> _Affine:
        n, p = X.shape
        c = X[:, :-1].mean(axis=0)
        s = X[:, :-1].std(axis=0)
        s = np.where(s > 1e-12 * np.maximum(np.abs(c), 1.0), s, 1.0)
        ybar = float(y.mean())
        sy = float(y.std()) or 1.0
        Z = np.empty_like(X)
        Z[:, :-1] = (X[:, :-1] - c) / s
        Z[:, -1] = 1.0
        A = np.zeros((p, p))
        A[np.arange(p - 1), np.arange(p - 1)] = sy / s
        A[-1, :-1] = -c * sy / s
        A[-1, -1] = sy
        b = np.zeros(p)
        b[-1] = ybar
        return cls(Z=Z, yn=(y - ybar) / sy, A=A, b=b, sy=sy)


def _robust_std(r: np.ndarray) -> float:
    """1.4826 x median absolute deviation: a standard deviation immune to a few outliers."""
    return float(1.4826 * np.median(np.abs(r - np.median(r))))


def _constraints(eq: str, th: dict, d: _Signals) -> list[tuple[str, object]]:
    """Physically meaningful constraints of one equation as (label, cvxpy constraint)."""
    if eq == "eq1":
        return [(f"{n} >= 0", th[n] >= 0) for n in ("gamma1", "gamma2", "gamma3")]
    if eq == "eq2":
        pole = th["gamma4"] + th["gamma5"]
        return [("gamma4 + gamma5 >= 0 (evaporator pole)", pole >= 0),
                (f"gamma4 + gamma5 <= {1 - _EVAP_POLE_MARGIN:g} (stable evaporator pole)",
                 pole <= 1 - _EVAP_POLE_MARGIN),
                ("gamma5 <= 0 (set-point raises T_evap)", th["gamma5"] <= 0)]
    if eq == "eq3":
        return [(f"{n} >= 0", th[n] >= 0) for n in ("gamma6", "gamma7")]
    w = np.linspace(d.W_bl.min(), d.W_bl.max(), 11)
    power = th["beta1"] * w**2 + th["beta2"] * w + th["beta3"]
    return [("beta1 >= 0", th["beta1"] >= 0),
            ("P_bl >= 0 over the measured W_bl range", power >= 0)]


def _solve_cvx(eq, names, free, theta_eq, sc: _Affine, loss, d: _Signals, solver,
               constrained: bool = True):
    """Constrained and/or Huber fit of one equation in the scaled variables (CVXPY).

    Returns (phi, status, active constraint labels); phi is None when the solver failed.
    The Huber scale is 1.345 robust standard deviations of the residuals (MAD), estimated
    from the least-squares residuals and once more from the first Huber solution.
    """
    import cvxpy as cp

    phi = cp.Variable(int(free.sum()))
    theta_free = sc.A @ phi + sc.b
    th, j = {}, 0
    for n, f in zip(names, free, strict=True):
        if f:
            th[n] = theta_free[j]
            j += 1
        else:
            th[n] = float(theta_eq[names.index(n)])
    cons = [(label, c) for label, c in (_constraints(eq, th, d) if constrained else [])
            if hasattr(c, "variables") and c.variables()]
    resid = sc.Z @ phi - sc.yn
    if loss == "huber":
        ls_phi = np.linalg.lstsq(sc.Z, sc.yn, rcond=None)[0]
        scale = max(_robust_std(sc.Z @ ls_phi - sc.yn), 1e-4)
    prob = None
    for _ in range(2 if loss == "huber" else 1):
        if loss == "huber":
            objective = cp.sum(cp.huber(resid / scale, _HUBER_M))
        else:
            objective = cp.sum_squares(resid)
        prob = cp.Problem(cp.Minimize(objective), [c for _, c in cons])
        try:
            prob.solve(solver=solver)
        except cp.error.SolverError as exc:
            return None, f"solver error ({exc})", []
        if phi.value is None:
            return None, str(prob.status), []
        if loss == "huber":
            scale = max(_robust_std(sc.Z @ phi.value - sc.yn), 1e-4)
    tol = 1e-7 * (1.0 + float(np.max(np.abs(sc.A @ phi.value + sc.b))))
    active = [f"eq. {eq[2:]}: {label}" for label, c in cons
              if float(np.max(c.expr.value)) > -tol]
    return np.asarray(phi.value, dtype=float), str(prob.status), active


def _estimate_eta_cop(d: _Signals, ref: ModelParams) -> tuple[float, float]:
    """eta_cop from P_comp = c_p / eta_cop * W_bl (T_amb - T_ain) (eq. 4), through the origin.

    Uses samples with the compressor running and warm ambient air; NaN when the data lack
    P_comp or T_amb or fewer than 10 samples qualify.
    """
    if d.P_comp is None or d.T_amb is None:
        return math.nan, math.nan
    x = model.compressor_power(d.W_bl, d.T_ain, d.T_amb, ref.replace(eta_cop=1.0))
    use = (d.P_comp > 1.0) & (x > 1.0)
    if use.sum() < 10:
        return math.nan, math.nan
    x, y = x[use], d.P_comp[use]
    slope = float(x @ y / (x @ x))
    r = y - slope * x
    se_slope = math.sqrt(float(r @ r) / (x.size - 1) / float(x @ x))
    if slope <= 0:
        return math.nan, math.nan
    return 1.0 / slope, se_slope / slope**2


def _one_step_fit(d: _Signals, p: ModelParams) -> dict[str, float]:
    """Fit % of one-step predictions (eqs. 1-3 via ``model.one_step``, eq. 5) per channel."""
    k = np.flatnonzero(d.transition)
    cab, evap, _ = model.one_step(d.T_cab[k], d.T_evap[k], d.W_bl[k], d.T_evap_set[k],
                                  d.T_int[k], d.T_shell[k], p)
    out = {
        "T_cab": float(fit_percent(d.T_cab[k + 1], cab)),
        "T_evap": float(fit_percent(d.T_evap[k + 1], evap)),
        "T_ain": float(fit_percent(d.T_ain, model.inlet_air(d.T_evap, d.W_bl, p))),
    }
    if d.P_bl is not None:
        out["P_bl"] = float(fit_percent(d.P_bl, model.blower_power(d.W_bl, p)))
    return out


# --------------------------------------------------------------------- output error
@dataclass(frozen=True)
class _Windows:
    """Consecutive windows of each experiment, padded to one length (mask marks real samples).

    Arrays are (n_windows, L) in K and kg/s; each window starts at a measured sample.
    """

    idx: np.ndarray      # (nw, L) sample indices (padding repeats the last one)
    mask: np.ndarray     # (nw, L) True on real samples

    @classmethod
    def of(cls, segments, window: int) -> _Windows:
        rows = []
        for a, b in segments:
            n = b - a
            m = max(1, math.ceil(n / window))
            rows += [np.arange(a, b)[part] for part in np.array_split(np.arange(n), m)]
        rows = [r for r in rows if r.size >= 2]
        if not rows:
            raise DataError("no experiment is long enough to simulate (need 2 samples each)")
        L = max(r.size for r in rows)
        idx = np.array([np.pad(r, (0, L - r.size), mode="edge") for r in rows])
        mask = np.array([np.arange(L) < r.size for r in rows])
        return cls(idx=idx, mask=mask)


def _simulate_windows(d: _Signals, w: _Windows, p: ModelParams, x0: np.ndarray):
    """Simulate eqs. 1-3 over every window at once; returns (T_cab, T_evap, T_ain), (nw, L)."""
    i = w.idx
    cab, evap, ain = model.simulate(x0, d.W_bl[i], d.T_evap_set[i], d.T_int[i],
                                    d.T_shell[i], p)
    return cab[:, :-1], evap[:, :-1], ain


def _simulation_fit(d: _Signals, p: ModelParams, window: int) -> dict[str, float]:
    """Fit % of ``window``-step simulations started from the measured states."""
    w = _Windows.of(d.segments, window)
    x0 = np.stack([d.T_cab[w.idx[:, 0]], d.T_evap[w.idx[:, 0]]], axis=-1)
    sim = _simulate_windows(d, w, p, x0)
    meas = (d.T_cab, d.T_evap, d.T_ain)
    return {ch: float(fit_percent(m[w.idx][w.mask], s[w.mask]))
            for ch, s, m in zip(("T_cab", "T_evap", "T_ain"), sim, meas, strict=True)}


@functools.lru_cache(maxsize=8)
def _window_jacobian(L: int):
    """CasADi function: the Jacobian of one window's simulation (eqs. 1-3 of ``acid.model``).

    ``J = window_jacobian(theta, x0, u)`` with ``theta`` the dynamic parameters
    (``DYNAMIC_PARAMS`` order), ``x0`` the initial [T_cab, T_evap] (K) and ``u`` (4, L) the
    rows W_bl, T_evap_set, T_int, T_shell; ``J`` (3 L, n + 2) holds the derivatives of
    [T_cab(0..L-1), T_evap(0..L-1), T_ain(0..L-1)] with respect to [theta, x0]. The model is
    traced symbolically from :func:`acid.model.step` (one source of truth; CasADi's
    algorithmic differentiation, not hand-derived sensitivities).
    """
    import casadi as ca

    n = len(DYNAMIC_PARAMS)
    th = ca.SX.sym("theta", n)
    x = ca.SX.sym("x", 2)
    u = ca.SX.sym("u", 4)
    p = _SymbolicParams.of(th)
    cab1, evap1, ain = model.step(x[0], x[1], u[0], u[1], u[2], u[3], p)
    step = ca.Function("step", [x, u, th], [ca.vertcat(cab1, evap1),
                                            ca.vertcat(x[0], x[1], ain)])
    sim = step.mapaccum("window", L)
    TH, X0, U = ca.MX.sym("theta", n), ca.MX.sym("x0", 2), ca.MX.sym("u", 4, L)
    _, Y = sim(X0, U, ca.repmat(TH, 1, L))
    J = ca.jacobian(ca.vec(Y.T), ca.vertcat(TH, X0))
    return ca.Function("window_jacobian", [TH, X0, U], [J])


@dataclass(frozen=True)
class _SymbolicParams:
    """gamma and tau as CasADi symbols, in the shape ``acid.model`` reads parameters."""

    gamma: tuple
    tau: tuple

    @classmethod
    def of(cls, theta_dynamic) -> _SymbolicParams:
        idx = np.arange(N_PARAMS)[DYNAMICS]
        pos = {int(i): k for k, i in enumerate(idx)}
        return cls(gamma=tuple(theta_dynamic[pos[i]] for i in np.arange(N_PARAMS)[GAMMA]),
                   tau=tuple(theta_dynamic[pos[i]] for i in np.arange(N_PARAMS)[TAU]))


def _window_sensitivities(d: _Signals, w: _Windows, theta: np.ndarray,
                          x0: np.ndarray) -> np.ndarray:
    """(3, nw, L, n + 2) derivatives of the simulated T_cab, T_evap, T_ain of every window
    with respect to the dynamic parameters (``DYNAMIC_PARAMS`` order) and the window's
    initial [T_cab, T_evap] (CasADi, all windows in one call)."""
    i = w.idx
    nw, L = i.shape
    fn = _window_jacobian(L).map(nw)
    u = np.stack([d.W_bl[i], d.T_evap_set[i], d.T_int[i], d.T_shell[i]]).reshape(4, nw * L)
    J = np.asarray(fn(theta[DYNAMICS], x0.T, u))          # (3 L, nw (n + 2))
    return J.reshape(3, L, nw, -1).transpose(0, 2, 1, 3)


@dataclass(frozen=True)
class _OEResult:
    theta: np.ndarray
    stderr: np.ndarray
    cov: np.ndarray
    dof: int
    status: str
    success: bool
    channel_rms: dict[str, float]
    n_windows: int
    bandwidth: int | None = None


class _OEProblem:
    """Weighted multi-step simulation residuals and their Jacobian in scaled variables.

    Decision vector z = [phi (free gamma/tau, scaled per equation as in least squares),
    dx0 (per window: initial T_cab, T_evap minus their measured values, K)].
    """

    def __init__(self, d: _Signals, theta0: np.ndarray, free: list[str], fits: dict,
                 window: int, estimate_x0: bool):
        self.d = d
        self.theta0 = theta0.copy()
        self.free = free
        self.w = _Windows.of(d.segments, window)
        self.estimate_x0 = estimate_x0
        self.fidx = np.array([_INDEX[n] for n in free], dtype=int)
        # block-diagonal affine map theta_free = A phi + b, reusing each equation's scaling
        nf = len(free)
        self.A = np.zeros((nf, nf))
        self.b = np.zeros(nf)
        for eq in ("eq1", "eq2", "eq3"):
            f = fits[eq]
            cols = [j for j, (n, fx) in enumerate(zip(f.names, f.fixed, strict=True)) if not fx]
            if not cols:
                continue
            pos = [free.index(f.names[j]) for j in cols]
            y, offset, X = _regression(eq, d)
            fixed = np.array(f.fixed)
            sc = _Affine.of(X[:, ~fixed], y - offset - X[:, fixed] @ f.theta[fixed])
            self.A[np.ix_(pos, pos)] = sc.A
            self.b[pos] = sc.b
        self.Ainv = np.linalg.inv(self.A)
        i0 = self.w.idx[:, 0]
        self.x0_meas = np.stack([d.T_cab[i0], d.T_evap[i0]], axis=-1)
        self.meas = np.stack([d.T_cab[self.w.idx], d.T_evap[self.w.idx], d.T_ain[self.w.idx]])
        self.weights = np.ones(3)
        self.nw = self.w.idx.shape[0]

    def z0(self) -> np.ndarray:
        phi = self.Ainv @ (self.theta0[self.fidx] - self.b)
        return np.concatenate([phi, np.zeros(2 * self.nw if self.estimate_x0 else 0)])

    def unpack(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        nf = len(self.free)
        theta = self.theta0.copy()
        theta[self.fidx] = self.A @ z[:nf] + self.b
        x0 = self.x0_meas + (z[nf:].reshape(self.nw, 2) if self.estimate_x0 else 0.0)
        return theta, x0

    def _params(self, theta: np.ndarray) -> ModelParams:
        return ModelParams(gamma=theta[GAMMA], tau=theta[TAU], beta=theta[BETA])

    def channel_errors(self, z: np.ndarray) -> np.ndarray:
        """(3, nw, L) simulation minus measurement, K (padding included)."""
        theta, x0 = self.unpack(z)
        sim = np.stack(_simulate_windows(self.d, self.w, self._params(theta), x0))
        return sim - self.meas

    def residuals(self, z: np.ndarray) -> np.ndarray:
        e = self.channel_errors(z) / self.weights[:, None, None]
        return e[:, self.w.mask].ravel()

    def jacobian(self, z: np.ndarray) -> np.ndarray:
        theta, x0 = self.unpack(z)
        S = _window_sensitivities(self.d, self.w, theta, x0)      # (3, nw, L, n + 2)
        m = self.w.mask
        cols = self.fidx - DYNAMICS.start
        nd = len(DYNAMIC_PARAMS)
        J_th = np.concatenate([S[ch][m][:, cols] @ self.A / self.weights[ch]
                               for ch in range(3)])
        if not self.estimate_x0:
            return J_th
        nw = self.nw
        n_obs = int(m.sum())
        J_x = np.zeros((3 * n_obs, 2 * nw))
        win = np.broadcast_to(np.arange(nw)[:, None], m.shape)[m]
        rows = np.arange(n_obs)
        for ch in range(3):   # each observation depends on its own window's x0 only
            J_x[ch * n_obs + rows, 2 * win] = S[ch][m][:, nd] / self.weights[ch]
            J_x[ch * n_obs + rows, 2 * win + 1] = S[ch][m][:, nd + 1] / self.weights[ch]
        return np.hstack([J_th, J_x])


def _output_error(d: _Signals, theta0: np.ndarray, free: list[str], fits: dict, window: int,
                  weighting: str, estimate_x0: bool, loss: str, covariance: str = "white",
                  hac_bandwidth="auto") -> _OEResult:
    """Refine the free gamma/tau by minimising multi-step simulation errors (see module doc).

    The covariance of the free parameters is ``sigma^2 (J^T J)^-1`` (``covariance="white"``)
    or the Newey-West sandwich ``n/(n-p) (J^T J)^-1 S (J^T J)^-1`` over all decision
    variables (parameters and window initial states), of which the parameter block is kept.
    """
    prob = _OEProblem(d, theta0, free, fits, window, estimate_x0)
    z = prob.z0()
    if not free:
        raise DataError("output error: no free parameter in eqs. 1-3")
    m = prob.w.mask
    res = None
    passes = 2 if (weighting == "noise" or loss == "huber") else 1
    for it in range(passes):
        if it > 0:
            e = prob.channel_errors(z)[:, m]
            rms = np.sqrt(np.mean(e**2, axis=1)) if loss == "squared" else \
                np.array([_robust_std(row) for row in e])
            if weighting == "noise":
                floor = max(1e-3 * rms.max(), 1e-9)
                prob.weights = np.maximum(rms, floor)
            else:
                prob.weights = np.full(3, max(float(np.sqrt(np.mean(rms**2))), 1e-9))
        # MINPACK's Levenberg-Marquardt for the squared loss (no BLAS threads: fast on busy
        # machines); trust-region reflective where the robust loss needs it
        robust = loss == "huber" and it > 0
        kwargs = {"loss": "huber", "f_scale": _HUBER_M} if robust else {}
        res = scipy.optimize.least_squares(
            prob.residuals, z, jac=prob.jacobian, method="trf" if robust else "lm",
            x_scale="jac",
            ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=200, **kwargs)
        z = res.x
    theta, _ = prob.unpack(z)
    J = prob.jacobian(z)
    r = prob.residuals(z)
    n, p = J.shape
    if not estimate_x0:  # the first sample of each window is then reproduced exactly
        n -= 2 * prob.nw
    dof = max(n - p, 1)
    if loss == "huber":
        sigma2 = _robust_std(r) ** 2
    else:
        sigma2 = float(r @ r) / dof
    colnorm = np.linalg.norm(J, axis=0)
    colnorm[colnorm == 0] = 1.0
    _, s, Vt = np.linalg.svd(J / colnorm, full_matrices=False)
    s_inv2 = np.where(s > 1e-12 * s[0], 1.0 / s**2, 0.0)
    bread = ((Vt.T * s_inv2) @ Vt) / np.outer(colnorm, colnorm)   # (J^T J)^-1
    nf = len(free)
    bandwidth = None
    if covariance == "hac":
        # residual rows are [T_cab | T_evap | T_ain], each the masked (window, step) samples
        # in window-major order; the score of one instant sums its three channels (their
        # errors are correlated), then lags run along time inside each experiment
        n_obs = int(m.sum())
        frac = 1.0
        if loss == "huber":  # the last pass minimised Huber(r, f_scale=_HUBER_M)
            frac = max(float(np.mean(np.abs(r) <= _HUBER_M)), 1.0 / r.size)
            r = np.clip(r, -_HUBER_M, _HUBER_M)
        h = (J * r[:, None]).reshape(3, n_obs, p).sum(axis=0)
        sample = prob.w.idx[m]
        order = np.argsort(sample, kind="stable")
        h, groups = h[order], segment_ids(sample[order], d.segments)
        bandwidth = resolve_bandwidth(hac_bandwidth, h[:, :nf], groups)
        meat = hac_meat(h, groups, bandwidth)
        cov_z = n / dof * (bread @ meat @ bread) / frac**2
    else:
        cov_z = sigma2 * bread
    cov = prob.A @ cov_z[:nf, :nf] @ prob.A.T
    e = prob.channel_errors(z)[:, m]
    rms = np.sqrt(np.mean(e**2, axis=1))
    return _OEResult(theta=theta, stderr=np.sqrt(np.clip(np.diag(cov), 0, None)), cov=cov,
                     dof=dof, status=str(res.message), success=bool(res.status > 0),
                     channel_rms={f"oe_{c}": float(v) for c, v in
                                  zip(("T_cab", "T_evap", "T_ain"), rms, strict=True)},
                     n_windows=prob.nw, bandwidth=bandwidth)
