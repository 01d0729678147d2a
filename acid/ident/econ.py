"""The econ model's identification (``acid fit --model econ``): acid.ident's staged fit of the
declaration :mod:`acid.models.econ` (its ``FIT_STAGES``) into :class:`EconParams`; nothing is
read from a plant's configuration."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acid.errors import DataError
from acid.ident.envelope import envelope_ranges
from acid.ident.fit import DeclaredFitResult
from acid.models import econ
from acid.models.econ import MAP_INPUTS, PowerMap
from acid.models.econ_params import NAMES, EconParams

# ------------------------------------------------------------------ identification
#: Channels ``acid fit --model econ`` needs (P_bl optional: eq. 5 then keeps its start).
REQUIRED = econ.STATES + ("W_bl", "T_evap_set", "v_veh", "T_amb", "T_ain", "P_comp")
#: |dT_cab/dt| and |dT_evap/dt| below this count as near-steady (the map's steady error), K/s
_STEADY_RATE = 0.02


@dataclass(frozen=True)
class EconFit:
    """The econ model identified by :func:`identify`: ``params`` (with the power map's
    domain and quality) and ``fit``, acid.ident's report of the staged fit."""

    params: EconParams
    fit: DeclaredFitResult

    @property
    def power_map_quality(self) -> dict:
        return self.params.power_map.quality

    @property
    def warnings(self) -> tuple[str, ...]:
        return self.fit.warnings

    def to_json_dict(self) -> dict:
        return {**self.fit.to_json_dict(), "power_map_quality": self.power_map_quality}


def identify(ds, covariance: str = "hac", hac_bandwidth="auto",
             skip_s: float = econ.FIT_SKIP_S) -> EconFit:
    """Identify the econ model from ``ds`` (channels ``REQUIRED``) with acid.ident's staged
    fit of the declaration (``acid.models.econ.FIT_STAGES``); warnings (``warnings.warn``,
    ``IdentifiabilityWarning``) where the excitation leaves a part unidentified. ``skip_s``:
    seconds left out at each experiment's start (``acid.models.econ.FIT_SKIP_S``)."""
    import warnings

    from acid.errors import IdentifiabilityWarning
    from acid.ident.stages import Stage, fit_stages

    ds.validate(require=REQUIRED, min_samples=20)
    for name, unit, need in (("v_veh", "m/s", 5.0), ("T_amb", "K", 2.0)):
        if float(np.ptp(ds.get(name, unit))) < need:
            warnings.warn(f"{name} varies by only {np.ptp(ds.get(name, unit)):.3g} {unit} in "
                          f"the data: the power map and the shell balance are not identified "
                          f"in {name} (use `acid excite --model econ`)", IdentifiabilityWarning,
                          stacklevel=2)
    for name, unit, need, part in (("W_bl", "kg/s", 0.02, "air side"),
                                   ("T_evap_set", "K", 1.0, "evaporator")):
        if float(np.ptp(ds.get(name, unit))) < need:
            raise DataError(f"{ds.source}: {name} is (nearly) constant: the {part} is not "
                            "identifiable; excite it")
    fit = fit_stages(econ.model, ds, [Stage(*s) for s in econ.FIT_STAGES],
                     covariance=covariance, hac_bandwidth=hac_bandwidth,
                     skip_s=skip_s)
    params = _econ_params(ds, np.asarray(fit.values)[:econ.model.np],
                          {e.name: e.stderr for e in fit.estimates}, skip_s)
    return EconFit(params=params, fit=fit)


def _econ_params(ds, values, se: dict, skip_s: float,
                 how: str = "acid.ident staged fit (acid.models.econ.FIT_STAGES)") -> EconParams:
    """:class:`EconParams` of the econ declaration's ``values`` fitted on ``ds``: the power
    map's domain, quality and envelope on the rows it was fitted on."""
    from acid.ident.fit import provenance

    # the map's domain and quality on the rows it was fitted on, as fitted: the model's coil
    # load from the measured state, the wall's storage from the measured end state
    x = np.column_stack([ds.get(n, u) for n, u in zip(econ.STATES, econ.STATE_UNITS,
                                                      strict=True)])
    keep = np.zeros(len(ds), dtype=bool)
    for a, b in ds.segments():
        keep[a + int(round(skip_s / ds.Ts)): b - 1] = True
    k = np.flatnonzero(keep)
    u = np.column_stack([ds.get("W_bl", "kg/s"), ds.get("T_evap_set", "K")])[k]
    d = np.column_stack([ds.get("v_veh", "m/s"), ds.get("T_amb", "K")])[k]
    out = econ.casadi_interval(ds.Ts).map(k.size)(x[k].T, u.T, d.T,
                                                  np.tile(values, (k.size, 1)).T,
                                                  np.zeros((len(econ.STATES), k.size)))
    Q_coil, T_ev = (np.asarray(out[j]).ravel() for j in (5, 6))
    s = econ.parameters(values)
    Q_e = econ.refrigerant_heat(s, Q_coil, x[k, 3], x[k + 1, 3], ds.Ts)
    P_hat = econ.compressor_power(s, Q_e, T_ev, d[:, 0], d[:, 1])
    P = ds.get("P_comp", "W")[k]
    e = P - P_hat
    steady = (np.abs(x[k + 1, 0] - x[k, 0]) / ds.Ts < _STEADY_RATE) & \
        (np.abs(x[k + 1, 3] - x[k, 3]) / ds.Ts < _STEADY_RATE) & (P > 0.05 * P.max())
    rms = float(np.sqrt(np.mean(e**2)))
    quality = {"n": int(P.size), "rms_W": rms, "rms_pct": 100.0 * rms / float(np.mean(P)),
               "max_abs_W": float(np.max(np.abs(e))),
               "r2": 1.0 - float(e @ e) / float(np.sum((P - P.mean()) ** 2)),
               "mean_P_W": float(np.mean(P)), "n_steady": int(steady.sum())}
    if steady.sum() >= 10:
        quality.update(steady_rms_pct=100.0 * float(np.sqrt(np.mean((e / P)[steady] ** 2))),
                       steady_max_pct=100.0 * float(np.max(np.abs(e / P)[steady])))
    domain = {n: (float(v.min()), float(v.max())) for (n, _), v in
              zip(MAP_INPUTS, (Q_e, T_ev, d[:, 0], d[:, 1]), strict=True)}
    envelope = envelope_ranges(Q_e=Q_e, T_evap=T_ev, T_cab=x[k, 0], W_bl=u[:, 0],
                               T_amb=d[:, 1])
    prov = {**provenance(ds, how),
            "skip_s": skip_s, **({"data_seed": ds.metadata["seed"]}
                                          if "seed" in ds.metadata else {})}
    return EconParams.from_vector(
        values, power_map=PowerMap(coef=values[len(NAMES) + 1:len(NAMES) + 16],
                                       stderr=tuple(se[n] for n in econ.MAP_NAMES),
                                       domain=domain, quality=quality, envelope=envelope),
        stderr={n: se[n] for n in NAMES + ("C_ew",)}, Ts=float(ds.Ts), name="econ-fit",
        provenance=prov)


# ------------------------------------------------ the model with a slow interior node
#: what the interior's output-error stage fits (the slow node's pair and the fast interior's
#: own balance; :func:`interior_output_error`)
INTERIOR = ("C_int", "Q_int", "C_is", "hA_is")


@dataclass(frozen=True)
class Econ2Fit:
    """The econ model with a slow interior node (:mod:`acid.models.econ2`) identified by
    :func:`identify_slow`: ``values`` (the declaration's vector), ``stderr`` by name,
    ``params`` the econ part as :class:`EconParams` (what the economic NMPC runs on; its
    ``C_int`` is the fast interior), the interior stage's report ``interior`` (rms error of
    the simulated interior, K, prior terms, parameters on a bound) and the staged fit."""

    values: np.ndarray
    stderr: dict
    params: EconParams
    interior: dict
    fit: DeclaredFitResult

    @property
    def C_is(self) -> float:
        return float(self.values[_econ2_names().index("C_is")])

    @property
    def hA_is(self) -> float:
        return float(self.values[_econ2_names().index("hA_is")])

    @property
    def tau_is_s(self) -> float:
        return self.C_is / self.hA_is

    def slow_state(self, T_int_K, experiment=None, Ts: float | None = None) -> np.ndarray:
        """The latent slow interior (K) along a record of the measured interior (K)."""
        from acid.models import econ2

        return econ2.slow_trace(T_int_K, experiment, self.C_is, self.hA_is,
                                Ts or self.params.Ts)


def _econ2_names():
    from acid.models import econ2

    return econ2.model.parameter_names


def with_slow_trace(ds, C_is: float, hA_is: float):
    """``ds`` with the latent slow interior ``T_is`` (K) filled by
    :func:`acid.models.econ2.slow_trace` from the measured interior (every interior mass at
    the measured interior at each experiment's start)."""
    from acid.data import Dataset
    from acid.models import econ2

    T_is = econ2.slow_trace(ds.get("T_int", "K"), ds.experiment, C_is, hA_is, ds.Ts)
    return Dataset(ds.time, {**ds.channels, "T_is": T_is}, {**ds.units, "T_is": "K"}, ds.Ts,
                   ds.experiment, {**ds.roles, "T_is": "auxiliary"}, dict(ds.metadata),
                   source=ds.source)


def simulate_interior(theta, T_cab, T_int0, experiment, Ts: float,
                      hA_int: float = 190.0) -> np.ndarray:
    """(N, 2) fast and slow interior (K) simulated from each experiment's start (both at the
    measured interior ``T_int0`` there) by the econ2 interior equations driven by the measured
    cabin ``T_cab`` (K), held over each sample (exact discretisation); ``theta`` the values of
    ``INTERIOR`` (``hA_int``: the cabin-interior conductance, W/K)."""
    import scipy.linalg

    C_int, Q_int, C_is, hA_is = (float(v) for v in theta)
    A = np.array([[-(hA_int + hA_is) / C_int, hA_is / C_int], [hA_is / C_is, -hA_is / C_is]])
    B = np.array([[hA_int / C_int, Q_int / C_int], [0.0, 0.0]])
    M = scipy.linalg.expm(np.block([[A, B], [np.zeros((2, 4))]]) * Ts)
    Ad, Bd = M[:2, :2], M[:2, 2:]
    T_cab = np.asarray(T_cab, dtype=float)
    X = np.empty((T_cab.size, 2))
    exp = np.asarray(experiment)
    for k in range(T_cab.size):
        if k == 0 or exp[k] != exp[k - 1]:
            X[k] = T_int0[k]
        else:
            X[k] = Ad @ X[k - 1] + Bd @ np.array([T_cab[k - 1], 1.0])
    return X


def interior_output_error(ds, hA_int: float, start: dict, bounds: dict, priors: dict
                          ) -> tuple[dict, dict, dict]:
    """The interior's output-error stage: ``INTERIOR`` fitted so that the simulated fast
    interior (:func:`simulate_interior`, from each experiment's start) follows the measured one
    over whole experiments, ``hA_int`` held (it sets the scale: the interior's equations
    alone are unchanged when every capacity and conductance is scaled), plus Gaussian prior
    terms ``priors`` {name: (mean, sd)} (MAP, as a
    declaration's ``prior``). Returns (values, standard errors (white residuals, from the
    Jacobian: optimistic for the correlated errors of a simulation), report)."""
    import scipy.optimize

    T_cab, T_int = ds.get("T_cab", "K"), ds.get("T_int", "K")
    names = INTERIOR
    scale = np.array([abs(start[n]) or 1.0 for n in names])
    lo = np.array([bounds[n][0] for n in names]) / scale
    hi = np.array([bounds[n][1] for n in names]) / scale

    def resid(z):
        X = simulate_interior(z * scale, T_cab, T_int, ds.experiment, ds.Ts, hA_int)
        r = X[:, 0] - T_int
        pr = [(z[i] * scale[i] - priors[n][0]) / priors[n][1]
              for i, n in enumerate(names) if n in priors]
        return np.r_[r / sigma, pr]

    sigma = 1.0
    z0 = np.clip(np.array([start[n] for n in names]) / scale, lo + 1e-9, hi - 1e-9)
    sol = scipy.optimize.least_squares(lambda z: resid(z)[:T_int.size], z0, bounds=(lo, hi),
                                       x_scale="jac")
    sigma = float(np.sqrt(np.mean(sol.fun ** 2)))   # the data's weight against the priors
    sol = scipy.optimize.least_squares(resid, sol.x, bounds=(lo, hi), x_scale="jac")
    J = sol.jac
    cov = np.linalg.pinv(J.T @ J)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0)) * scale
    values = dict(zip(names, sol.x * scale, strict=True))
    X = simulate_interior(sol.x * scale, T_cab, T_int, ds.experiment, ds.Ts, hA_int)
    on_bound = [n for i, n in enumerate(names)
                if min(abs(sol.x[i] - lo[i]), abs(sol.x[i] - hi[i])) <= 1e-6 * (1 + abs(sol.x[i]))]
    report = {"rms_T_int_K": float(np.sqrt(np.mean((X[:, 0] - T_int) ** 2))),
              "sigma_K": sigma, "n": int(T_int.size), "on_bound": on_bound,
              "priors": {n: list(priors[n]) for n in names if n in priors},
              "status": sol.message}
    return values, dict(zip(names, se, strict=True)), report


def identify_slow(ds, skip_s: float = econ.FIT_SKIP_S, covariance: str = "hac") -> Econ2Fit:
    """Identify :mod:`acid.models.econ2` from ``ds`` (channels ``REQUIRED``): (1) the econ
    model's own fit (:func:`identify`, its stages), of which ``hA_int`` is kept (the cabin's
    one-step equation measures it from the measured cabin and interior, whatever heats the
    interior); (2) the interior's output error (:func:`interior_output_error`: ``INTERIOR``
    from the simulated fast interior over whole experiments, each started with every
    interior mass at the measured interior, the declaration's priors); then the econ
    stages again with the interior held: (3) eq. 5 by least squares, (4) the other thermal
    parameters by one-step prediction error of the five measured states and the supply air,
    the latent slow interior propagated along the record (:func:`with_slow_trace`), (5) C_ew
    and the power map on P_comp. One-step prediction error alone cannot see the slow node (measured:
    ``hA_is`` goes to its lower bound at every time constant tried): over one 5 s step its
    heat is indistinguishable from a constant load."""
    import warnings

    from acid.ident.stages import Stage, fit_stages
    from acid.models import econ2

    ds.validate(require=REQUIRED, min_samples=20)
    m = econ2.model
    start = {n: m.parameter(n).value for n in INTERIOR}
    bounds = {n: (m.parameter(n).min, m.parameter(n).max) for n in INTERIOR}
    priors = {n: m.parameter(n).prior for n in INTERIOR if m.parameter(n).prior is not None}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        one = identify(ds, covariance=covariance, skip_s=skip_s)
    hA_int = float(one.params.values["hA_int"]) if hasattr(one.params.values, "keys") \
        else float(one.params.hA_int)
    inner, inner_se, report = interior_output_error(ds, hA_int, start, bounds, priors)
    inner["hA_int"] = hA_int
    inner_se["hA_int"] = next(e.stderr for e in one.fit.estimates if e.name == "hA_int")
    d = with_slow_trace(ds, inner["C_is"], inner["hA_is"])
    rest = tuple(n for n in econ.THERMAL_NAMES if n not in inner)
    stages = [Stage(*econ.FIT_STAGES[0]),
              Stage(rest, econ.STATES + ("T_ain",), "ee"),
              Stage(*econ.FIT_STAGES[2])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_stages(econ2.traced_model, d, stages, covariance=covariance,
                         skip_s=skip_s, fix=inner)
    values = np.asarray(fit.values, dtype=float)
    se = {e.name: e.stderr for e in fit.estimates}
    se.update(inner_se)
    base = _econ_params(ds, values[:econ.model.np], se, skip_s,
                        "acid.ident.econ.identify_slow (acid.models.econ2)")
    return Econ2Fit(values, se, base, report, fit)
