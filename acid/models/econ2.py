"""acid's economic model with a second, slow interior node: the econ model
(:mod:`acid.models.econ`) plus ``T_is``, the interior's slow mass (seat foam cores, dash
substrate, floor) that the fast interior node exchanges heat with (beyond the paper).

After a hot soak every mass sits at the soak temperature. The one-interior econ model
releases the interior's soak heat through one time constant; the slow part of a real interior
keeps warming the cabin for 10-30 minutes (measured on acid's plant: 3-6 K of soak heat left
in its slow interior after 10-20 min). This declaration carries it::

    C_int dT_int/dt = hA_int (T_cab - T_int) + hA_is (T_is - T_int) + Q_int
    C_is  dT_is/dt  = hA_is (T_int - T_is)

every other equation as in :mod:`acid.models.econ` (same parameter names and values, in the
same order; ``C_is`` and ``hA_is`` appended after them, so the first ``econ.model.np``
entries of a parameter vector are an econ parameter vector).

``T_is`` is latent (no sensor in a car). Its value in a record is set from the record's start
and propagated by its own equation driven by the measured fast interior (:func:`slow_trace`):
a record that starts soaked (a pull-down) or settled starts with every interior mass at the
measured interior temperature (the declared ``initial``), and the slow node's equation needs
nothing else (no source term: the sun heats the surfaces, the fast node).

Priors (``prior``, a Gaussian on the value for output error): the design's interior is
100-150 kJ/K in all, better split into a fast and a slow node (acid's plant: 35 + 90 kJ/K,
25 min between them, ``acid/plant/config.py``): ``C_is`` 90 +- 30 kJ/K, ``hA_is`` 60 +- 30 W/K.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from acid.models import econ
from acid.models.declaration import RK4, Model, Parameter, State

TS = econ.TS
STATES = econ.STATES + ("T_is",)
STATE_UNITS = econ.STATE_UNITS + ("K",)
#: (name, unit, start, min, max, prior (mean, sd), meaning) of the slow node
SLOW = (
    ("C_is", "J/K", 90.0e3, 1.0e2, 1.0e7, (90.0e3, 30.0e3),
     "heat capacity of the slow interior (foam cores, dash substrate, floor)"),
    ("hA_is", "W/K", 60.0, 1.0, 2.0e3, (60.0, 30.0),
     "fast <-> slow interior conductance"),
)
SLOW_NAMES = tuple(r[0] for r in SLOW)


def derivatives(s, x, u, d, dist=None):
    """Time derivatives of the six states and the air side (as
    :func:`acid.models.econ.derivatives`; ``dist`` additive terms on the first five)."""
    T_int, T_is = x[1], x[5]
    flow = s.hA_is * (T_is - T_int)
    add = [0.0, flow / s.C_int, 0.0, 0.0, 0.0]
    if dist is not None:
        add = [a + b for a, b in zip(add, dist, strict=True)]
    dx, air = econ.derivatives(s, list(x[:5]), u, d, add)
    return [*dx, -flow / s.C_is], air


def interval(s, x, u, d, dt: float = TS, n_sub: int | None = None,
             dist=None) -> econ.Interval:
    """One interval with ``u`` and ``d`` held (as :func:`acid.models.econ.interval`, six
    states)."""
    nx = len(STATES)

    def f(z):
        dx, air = derivatives(s, ca.vertsplit(z)[:nx], u, d, dist)
        return ca.vertcat(*dx, air.T_ain, air.Q_coil, z[3])

    z0 = ca.vertcat(*x, 0.0, 0.0, 0.0)
    z = ca.vertsplit(RK4(econ.n_substeps(dt) if n_sub is None else int(n_sub)).integrate(
        f, z0, float(dt)))
    inv = 1.0 / float(dt)
    T_ain, Q_coil, T_ev = z[nx] * inv, z[nx + 1] * inv, z[nx + 2] * inv
    Q_e = econ.refrigerant_heat(s, Q_coil, x[3], z[3], dt)
    return econ.Interval(x=tuple(z[:nx]), T_ain=T_ain, Q_coil=Q_coil, T_evap=T_ev, Q_e=Q_e,
                         P_comp=econ.compressor_power(s, Q_e, T_ev, d[0], d[1]),
                         P_bl=econ.blower_power(s, u[0]), dt=float(dt))


def step(s):
    r = interval(s, [s[n] for n in STATES], (s.W_bl, s.T_evap_set), (s.v_veh, s.T_amb))
    Q_e = econ.refrigerant_heat(s, r.Q_coil, s.T_evap, s.next.T_evap, TS)
    return {**dict(zip(STATES, r.x, strict=True)), "T_ain": r.T_ain,
            "P_comp": econ.compressor_power(s, Q_e, r.T_evap, s.v_veh, s.T_amb), "P_bl": r.P_bl}


def plausibility(s) -> list[str]:
    out = econ.plausibility(s)
    out += [f"{n} must be positive, got {getattr(s, n):g}" for n in SLOW_NAMES
            if getattr(s, n) <= 0]
    return out


def slow_trace(T_int, experiment, C_is: float, hA_is: float, Ts: float = TS,
               T0=None) -> np.ndarray:
    """The latent slow interior (K) along a record: started at each experiment's first
    measured interior temperature (or ``T0``, one value per experiment), then its equation
    ``C_is dT_is/dt = hA_is (T_int - T_is)`` integrated exactly with ``T_int`` (K, measured)
    held over each sample (causal: sample k uses the interior up to k - 1)."""
    T_int = np.asarray(T_int, dtype=float)
    exp = np.zeros(T_int.size, dtype=int) if experiment is None else np.asarray(experiment)
    a = float(np.exp(-float(hA_is) * float(Ts) / float(C_is)))
    out = np.empty_like(T_int)
    starts = np.r_[0, np.flatnonzero(np.diff(exp) != 0) + 1]
    for j, k0 in enumerate(starts):
        out[k0] = T_int[k0] if T0 is None else float(np.atleast_1d(T0)[j])
    for k in range(1, T_int.size):
        if exp[k] != exp[k - 1]:
            continue
        out[k] = T_int[k - 1] + a * (out[k - 1] - T_int[k - 1])
    return out


def _slow_start(m):
    """A record's ``T_is`` where it carries the trace :func:`slow_trace` computed (from the
    record's soaked or settled start), else the measured interior (all masses equal)."""
    T_is = np.asarray(m.T_is, dtype=float)
    return np.where(np.isfinite(T_is), T_is, m.T_int)


def _declare(traced: bool) -> Model:
    slow = State("T_is", "K", measured=traced, initial=None if traced else _slow_start,
                 description="slow interior node: latent (its trace when a record carries "
                             "one, slow_trace, else the measured interior)" if not traced else
                             "slow interior node, read from the record's T_is channel (the "
                             "trace slow_trace computed: not a sensor)")
    return Model(
        "econ2",
        states=[State(n, u) for n, u in zip(econ.STATES, econ.STATE_UNITS, strict=True)]
        + [slow],
        inputs=list(econ.model.inputs), disturbances=list(econ.model.disturbances),
        outputs=list(econ.model.outputs),
        parameters=list(econ.model.parameters)
        + [Parameter(n, u, v, lo, hi, prior=pr, description=m)
           for n, u, v, lo, hi, pr, m in SLOW],
        constants=list(econ.model.constants), groups=dict(econ.model.groups),
        checks=plausibility, Ts=TS, step=step,
        description="acid's economic model with a slow interior node: cabin, interior (fast, "
                    "slow), shell, evaporator wall, humidity",
    )


#: The declaration (T_is latent).
model = _declare(traced=False)
#: The same equations with T_is read from a record's ``T_is`` channel (the trace
#: :func:`slow_trace` computed from the measured interior): what the one-step stages and
#: the validator use, since a latent state's channel is not read.
traced_model = _declare(traced=True)


class _ByName(dict):
    __getattr__ = dict.__getitem__


def parameters(theta) -> _ByName:
    """The parameters and constants by name (as :func:`acid.models.econ.parameters`)."""
    t = ca.vertsplit(theta) if isinstance(theta, (ca.SX, ca.MX)) \
        else np.asarray(theta, dtype=float).tolist()
    return _ByName(zip(model.parameter_names, t, strict=True),
               **{c.name: c.value for c in model.constants})
