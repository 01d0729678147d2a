"""Speed-aware compressor power model: eq. 4 with a speed-dependent efficiency eta_cop(v).

The paper's eq. 4, ``P_c = c_p / eta_cop * W_bl * (T_amb - T_ain)``, uses one constant
``eta_cop``; its assumption 3 says the sensitivity to vehicle speed is not in the prediction
model (ram air through the condenser lowers the condensing pressure and the compressor work
when the vehicle is fast). Here ``eta_cop`` becomes a function of the vehicle speed ``v``
(m/s), identified from plant data:

* ``"linear"``:      ``eta_cop(v) = eta0 + eta1 * v``
* ``"saturating"``:  ``eta_cop(v) = eta0 * (1 + k * v / (1 + v / v_sat))`` (``v_sat`` fixed)

Identification (:func:`fit_speed_efficiency`): nonlinear least squares on the compressor
power itself, ``P_comp[k] = c_p W_bl[k] (T_amb - T_ain[k]) / eta_cop(v[k]) + e[k]`` (W), over
the samples where the compressor runs (``P_comp > p_min``) and the air-side term is positive;
started from the linear regression ``c_p W (T_amb - T_ain) = eta0 P + eta1 P v``. Standard
errors from the Gauss-Newton covariance ``s^2 (J^T J)^-1`` (white residuals assumed, so they
are optimistic for the correlated residuals of a dynamic plant). Quality: R^2 and fit % on
P_comp, RMSE (W), and the same numbers for the best constant ``eta_cop`` as the baseline.

Data: :func:`identify_from_plant` excites the high-fidelity plant with APRBS inputs while it
drives a standard cycle (``ExcitationSpec(cycle=...)``), discarding the hot-soak pull-down.

The returned :class:`SpeedEfficiency` evaluates ``eta_cop(v)`` on floats, numpy arrays and
CasADi symbols alike (only ``+ - * /``). :class:`SpeedAwareNMPC` is the paper's NMPC with
``eta_cop(v(i|k))`` over the previewed speed at every stage.

What the speed-aware NMPC can and cannot do with the paper's model
------------------------------------------------------------------
In eqs. 1-5 the compressor power does not depend on T_cab (eq. 4 uses ``T_amb - T_ain``),
and the only storage the optimiser controls is the cabin air, which relaxes towards its
equilibrium by about half per 5 s step (``1 - gamma1 - gamma2 - gamma3 W_bl``); the heavy
interior and shell are measured disturbances held constant over the horizon. Cold "stored"
in the cabin air at one stage is therefore mostly lost by the next, and pre-cooling pays only
when ``eta_cop`` changes by a large factor within the horizon: with the paper's parameters
(N = 12, T_cab at 25 degC) an ``eta_cop`` 3x higher over the first four stages still leaves
the plan on the bound; 5x moves it by 0.08 K. The identified change between 0 and 25 m/s is
about 16 %, so on drive cycles the speed-aware NMPC plans the same inputs as the paper's NMPC
(``acid cav-study`` measures it). Exploiting speed needs a prediction model with the interior
mass as a state, not only a speed-dependent eq. 4.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acid.control.nmpc import NMPC, NMPCConfig
from acid.errors import ConfigError, DataError
from acid.models.paper import compressor_power
from acid.models.params import ModelParams
from acid.paper import TABLE_II

FORMS = ("linear", "saturating")


@dataclass(frozen=True)
class SpeedEfficiency:
    """``eta_cop(v)`` of eq. 4, identified from data (dimensionless; v in m/s).

    Attributes
    ----------
    eta0 : efficiency at standstill, 1.
    eta1 : ``"linear"``: slope, 1/(m/s); ``"saturating"``: the gain ``k``, 1/(m/s).
    form : ``"linear"`` or ``"saturating"``.
    v_sat : saturation speed of the ``"saturating"`` form, m/s (unused for ``"linear"``).
    stderr : (stderr of eta0, stderr of eta1), same units.
    quality : fit statistics (``r2``, ``fit_pct``, ``rmse_W``, ``n``, and the constant-eta
        baseline ``const_eta``, ``const_r2``, ``const_rmse_W``).
    source : provenance (cycle, duration, seed, plant).
    """

    eta0: float
    eta1: float = 0.0
    form: str = "linear"
    v_sat: float = 15.0
    stderr: tuple[float, float] = (float("nan"), float("nan"))
    quality: dict = field(default_factory=dict, compare=False)
    source: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        if self.form not in FORMS:
            raise ConfigError(f"speed efficiency form must be one of {FORMS}, got {self.form!r}")
        if not (np.isfinite(self.eta0) and self.eta0 > 0):
            raise ConfigError(f"eta0 must be positive, got {self.eta0}")
        if not self.v_sat > 0:
            raise ConfigError(f"v_sat must be positive (m/s), got {self.v_sat}")

    def eta_cop(self, v):
        """Efficiency at speed ``v`` (m/s); float, numpy array or CasADi symbol."""
        if self.form == "linear":
            return self.eta0 + self.eta1 * v
        return self.eta0 * (1.0 + self.eta1 * v / (1.0 + v / self.v_sat))

    def ratio(self, v_high: float, v_low: float = 0.0) -> float:
        """``eta_cop(v_high) / eta_cop(v_low)``: how much more efficient fast than slow."""
        return float(self.eta_cop(float(v_high)) / self.eta_cop(float(v_low)))

    @classmethod
    def constant(cls, eta: float) -> SpeedEfficiency:
        """The paper's model: no speed dependence (``eta1 = 0``)."""
        return cls(eta0=float(eta), eta1=0.0, stderr=(0.0, 0.0), source={"constant": True})

    def to_json_dict(self) -> dict:
        """Estimates, standard errors, fit quality and provenance (SI units)."""
        unit1 = "1/(m/s)"
        return {"form": self.form, "eta0": self.eta0, "eta1": self.eta1,
                "eta1_unit": unit1, "v_sat_m_s": self.v_sat if self.form == "saturating"
                else None, "stderr": {"eta0": self.stderr[0], "eta1": self.stderr[1]},
                "eta_at_0_10_20_30_m_s": [float(self.eta_cop(v)) for v in (0, 10, 20, 30)],
                "quality": self.quality, "source": self.source}


def _shape(form: str, v: np.ndarray, v_sat: float) -> np.ndarray:
    """The regressor multiplying eta1 (v or v / (1 + v / v_sat))."""
    return v if form == "linear" else v / (1.0 + v / v_sat)


def fit_speed_efficiency(P_comp, W_bl, T_ain, v_veh, T_amb, c_p: float = TABLE_II.c_p,
                         form: str = "linear", v_sat: float = 15.0, p_min: float = 50.0,
                         source: dict | None = None) -> SpeedEfficiency:
    """Least-squares fit of ``eta_cop(v)`` in eq. 4 from samples (SI units, K).

    Parameters
    ----------
    P_comp : (n,) mean compressor power per sample, W.
    W_bl : (n,) blower flow, kg/s.
    T_ain : (n,) inlet air temperature (mean over the sample), K.
    v_veh : (n,) vehicle speed, m/s.
    T_amb : ambient temperature, K (scalar or (n,)).
    c_p : specific heat of air in eq. 4, J/(kg K).
    form : ``"linear"`` or ``"saturating"`` (see the module docstring).
    v_sat : saturation speed of the saturating form, m/s.
    p_min : samples with ``P_comp <= p_min`` (compressor off or idling) are excluded, W.
    source : provenance to record.

    Returns
    -------
    SpeedEfficiency with estimates, standard errors and fit quality.
    """
    from scipy.optimize import least_squares

    if form not in FORMS:
        raise ConfigError(f"speed efficiency form must be one of {FORMS}, got {form!r}")
    P, W, Ta, v = (np.asarray(a, dtype=float).ravel() for a in (P_comp, W_bl, T_ain, v_veh))
    Tamb = np.broadcast_to(np.asarray(T_amb, dtype=float), P.shape)
    q = compressor_power(W, Ta, Tamb, c_p, 1.0)  # eq. 4's numerator (eta_cop = 1), W
    m = np.isfinite(P) & np.isfinite(q) & np.isfinite(v) & (P > p_min) & (q > 0)
    if m.sum() < 10:
        raise DataError(f"speed efficiency fit: only {int(m.sum())} usable samples "
                        f"(P_comp > {p_min:g} W and T_ain < T_amb); need 10")
    P, q, v = P[m], q[m], v[m]
    s = _shape(form, v, v_sat)
    # linear start: q = eta0 P + eta0 k P s (saturating) or q = eta0 P + eta1 P v (linear)
    th0, *_ = np.linalg.lstsq(np.column_stack([P, P * s]), q, rcond=None)
    if form == "saturating":
        th0 = np.array([th0[0], th0[1] / th0[0]])

    def eta(th):
        return th[0] + th[1] * s if form == "linear" else th[0] * (1.0 + th[1] * s)

    def resid(th):
        return q / eta(th) - P

    res = least_squares(resid, th0, method="lm")
    th = res.x
    r = res.fun
    n, k = r.size, 2
    sigma2 = float(r @ r) / max(n - k, 1)
    J = res.jac
    try:
        cov = sigma2 * np.linalg.inv(J.T @ J)
        se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        se = np.array([np.nan, np.nan])
    ss_tot = float(np.sum((P - P.mean()) ** 2))
    rmse = float(np.sqrt(np.mean(r ** 2)))
    eta_c = float(np.sum(q * q) / np.sum(q * P))  # LS of P = q / eta: 1/eta = q.P / q.q
    r_c = q / eta_c - P
    quality = {
        "n": int(n), "r2": 1.0 - float(r @ r) / ss_tot, "rmse_W": rmse,
        "fit_pct": 100.0 * (1.0 - np.linalg.norm(r) / np.linalg.norm(P - P.mean())),
        "const_eta": eta_c, "const_r2": 1.0 - float(r_c @ r_c) / ss_tot,
        "const_rmse_W": float(np.sqrt(np.mean(r_c ** 2))),
        "speed_range_m_s": [float(v.min()), float(v.max())],
        "note": "stderr assume white residuals (optimistic for dynamic-plant data)",
    }
    return SpeedEfficiency(eta0=float(th[0]), eta1=float(th[1]), form=form, v_sat=float(v_sat),
                           stderr=(float(se[0]), float(se[1])), quality=quality,
                           source=dict(source or {}))


def fit_from_dataset(ds, c_p: float = TABLE_II.c_p, form: str = "linear", v_sat: float = 15.0,
                     skip_s: float = 600.0, p_min: float = 50.0) -> SpeedEfficiency:
    """:func:`fit_speed_efficiency` on a dataset with P_comp, W_bl, T_ain, v_veh, T_amb.

    ``skip_s`` seconds at the start (the hot-soak pull-down) are left out.
    """
    for name in ("P_comp", "W_bl", "T_ain", "v_veh", "T_amb"):
        if name not in ds.units:
            raise DataError(f"{ds.source}: channel {name!r} needed for the speed efficiency fit")
    k0 = int(round(skip_s / float(ds.Ts)))
    sl = slice(k0, None)
    return fit_speed_efficiency(
        ds.get("P_comp", "W")[sl], ds.get("W_bl", "kg/s")[sl], ds.get("T_ain", "K")[sl],
        ds.get("v_veh", "m/s")[sl], ds.get("T_amb", "K")[sl], c_p=c_p, form=form,
        v_sat=v_sat, p_min=p_min,
        source={"dataset": str(ds.source), "skip_s": skip_s, "samples": int(len(ds))})


def identify_from_plant(plant=None, cycle: str = "udds", duration_s: float = 7200.0,
                        seed: int = 0, c_p: float = TABLE_II.c_p, form: str = "linear",
                        skip_s: float = 600.0) -> SpeedEfficiency:
    """Excite the high-fidelity plant (APRBS inputs, drive-cycle speed) and fit eta_cop(v).

    Parameters
    ----------
    plant : plant to excite (default ``HifiPlant()`` in direct mode).
    cycle : drive cycle from ``datasets/drive_cycles`` (repeated to fill ``duration_s``).
    duration_s : record length, s.
    seed : excitation seed.
    c_p : specific heat of air in eq. 4, J/(kg K).
    form : ``"linear"`` or ``"saturating"``.
    skip_s : initial seconds left out (hot-soak pull-down), s.
    """
    from acid.excite import ExcitationSpec, excite

    if plant is None:
        from acid.plant.hifi import HifiPlant

        plant = HifiPlant()
    if skip_s >= duration_s:
        raise ConfigError(f"skip_s ({skip_s:g} s) must be shorter than the record "
                          f"({duration_s:g} s)")
    ds = excite(plant, ExcitationSpec(cycle=cycle, duration=duration_s, seed=seed))
    fit = fit_from_dataset(ds, c_p=c_p, form=form, skip_s=skip_s)
    src = dict(fit.source, plant=getattr(plant, "name", type(plant).__name__), cycle=cycle,
               duration_s=duration_s, seed=seed, excitation="APRBS (W_bl, T_evap_set)")
    return SpeedEfficiency(eta0=fit.eta0, eta1=fit.eta1, form=fit.form, v_sat=fit.v_sat,
                           stderr=fit.stderr, quality=fit.quality, source=src)


class SpeedAwareNMPC(NMPC):
    """The paper's NMPC with eq. 4's ``eta_cop`` replaced by ``eta_cop(v(i|k))``.

    The controller is given the vehicle speed profile of the whole run in advance (a CAV
    previews it, paper section IV-C) with :meth:`set_speed_profile`; at update ``k`` stage
    ``i`` of the horizon uses the mean speed over ``[t_{k+i}, t_{k+i+1})`` (the profile's last
    value beyond its end). The identified *relative* sensitivity is applied to the level of
    the model parameters: ``eta_cop(i|k) = params.eta_cop * eff.eta_cop(v) / eff.eta0``, so
    that the compressor/blower trade-off of the paper's model is unchanged and ``eta1 = 0``
    gives exactly the paper's NMPC. Everything else (constraints, slacks, solver, fallback)
    is :class:`acid.control.nmpc.NMPC`; ``make_step`` has the same signature, so
    :func:`acid.studies.mpc_check.scenarios.closed_loop` drives it unchanged (its ``reset``
    rewinds the preview to step 0).

    Parameters
    ----------
    params : model parameters (eqs. 1-5, kelvin convention).
    efficiency : the identified ``eta_cop(v)``.
    config : NMPC options.
    """

    def __init__(self, params: ModelParams, efficiency: SpeedEfficiency,
                 config: NMPCConfig | None = None):
        self.efficiency = efficiency
        self._v = np.zeros(1)
        self._k = 0
        super().__init__(params, config)

    def set_speed_profile(self, v_step) -> None:
        """The previewed speed per sample period (m/s) for the run that follows."""
        v = np.asarray(v_step, dtype=float).ravel()
        if v.size == 0 or not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ConfigError("speed profile must be a non-empty array of speeds >= 0 m/s")
        self._v = v
        self._k = 0

    def reset(self, u_initial=None) -> None:
        """As :meth:`NMPC.reset`, and rewind the speed preview to the first step."""
        super().reset(u_initial)
        self._k = 0

    def eta_preview(self, k: int) -> np.ndarray:
        """(N+1,) eta_cop of the stages i = 0 .. N at update ``k``."""
        idx = np.minimum(np.arange(k, k + self.N + 1), self._v.size - 1)
        eff = self.efficiency
        return self.params.eta_cop * np.asarray(eff.eta_cop(self._v[idx])) / eff.eta0

    def make_step(self, x, T_cab_max, T_int, T_shell, T_cab_min=None, T_amb=None,
                  eta_cop=None) -> np.ndarray:
        """:meth:`NMPC.make_step` with the previewed ``eta_cop(v)`` (unless given)."""
        eta = self.eta_preview(self._k) if eta_cop is None else eta_cop
        self._k += 1
        return super().make_step(x, T_cab_max, T_int, T_shell, T_cab_min=T_cab_min,
                                 T_amb=T_amb, eta_cop=eta)
