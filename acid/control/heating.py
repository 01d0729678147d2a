"""The heating controllers: an economic NMPC, the simple rule and the
heat-pump servo they share, on the heating plant; their comparison at equal comfort is
:mod:`acid.studies.heating_control`.

Controllers (all on :class:`acid.plant.heating.HeatingPlant`; energy = the plant's
``P_total``: compressor with defrost, coolant heater, blower, front fan):

* ``production``: the plant's own controller (``mode="nominal"``: blower rule, heat pump
  first, heater staging, recirculation with its anti-fog override), set-point ``T_set``.
* ``rule``: the best tuned simple rule: PI on ``T_cab`` giving a heat demand; the heat pump
  first up to its limit (inner-condenser air at ``T_a1_max``), the coolant heater for the
  rest; recirculation held at a share; blower held at ``W_BL_HOLD``. Tuned by a search over
  the recirculation share (the largest that keeps the fogging margin >= ``fog_min``) and the
  PI gains (lowest energy among those that keep comfort).
* ``nmpc``: the economic NMPC (:class:`HeatingNMPC`) over the declared
  ``acid.models.heating_control`` (values from the plant's configuration), built by
  :class:`acid.control.ocp.OCP`::

      min  sum_i Ts (P_hp + P_heater)  + penalties on the slacks
      s.t. x_{i+1} = F(x_i, u_i, d_i)                (heating_control, RK4)
           T_lo - s <= T_cab <= T_hi + s               (soft comfort band)
           fog_margin >= fog_min - s                   (soft, K)
           T_a1 <= T_a1_max + s                        (head-pressure limit of the plant)
           0 <= Q_hp <= Q_hp_max, 0 <= P_heater <= P_max, 0 <= recirc <= r_max

  with ``d_i = (T_amb, v_veh)`` previewed (the cycle as it will be driven: perfect preview,
  stated) or held at the current values (``preview=False``: the share owed to preview).
  The state is the plant's (perfect state knowledge, stated; no estimator here).

Both ``rule`` and ``nmpc`` command a heat-pump heat ``Q_hp``; :class:`HeatPumpServo` turns it
into a compressor speed from the plant's measured condenser heat (the same servo for both).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass

import numpy as np

from acid.control.codegen.solver import NLPSolver
from acid.control.ocp import OCP, OCPSpec, SoftBound
from acid.errors import SolverWarning
from acid.executor import check_interrupt
from acid.models.declaration import Model
from acid.models.heating_control import W_BL_HOLD, declare
from acid.plant.config import PlantConfig
from acid.plant.heating import HeatingPlant, shell_conductance
from acid.plant.heating_config import HeatingConfig, winter_plant_config
from acid.units import C2K

#: The plant states the control model reads, in its order.
STATE_KEYS = ("T_cab", "T_int", "T_int_slow", "T_shell", "T_glass", "T_cool", "T_icw",
              "w_cab")
#: The smallest heater power commanded, W (below it the heater and its pump stay off).
P_HEATER_ON = 50.0
#: Below the band's lower edge by more than this (K) the NMPC's solve starts from a fresh
#: guess with the heater at ``COLD_GUESS_HEATER`` (W) (``HeatingNMPC.make_step``).
COLD_GUESS_K, COLD_GUESS_HEATER = 2.0, 3000.0


def heating_control_model(heating: HeatingConfig | None = None,
                          config: PlantConfig | None = None,
                          W_bl: float = W_BL_HOLD, Ts: float = 10.0) -> Model:
    """``acid.models.heating_control`` with its values derived from the heating plant's
    configuration (that module's docstring); ``W_bl`` the held blower flow (kg/s), ``Ts`` the
    sample (s)."""
    h = heating or HeatingConfig()
    c = config or winter_plant_config()
    f_ws = h.A_ws / c.A_shell

    def eps(UA0):  # epsilon-NTU of a core at the held flow (the plant's UA ~ W^n_hc)
        return 1.0 - math.exp(-UA0 * (W_bl / h.W_hc0) ** h.n_hc / (W_bl * c.c_p_air))

    eps_hc = eps(h.UA_hc0)
    k = {  # name: (value, unit, description)
        "C_cab": (c.C_cab, "J/K", "cabin air (PlantConfig.C_cab)"),
        "C_int": (c.C_int, "J/K", "fast interior (PlantConfig.C_int)"),
        "C_is": (c.C_int_slow, "J/K", "slow interior (PlantConfig.C_int_slow)"),
        "C_sh": (c.C_sh * (1.0 - f_ws), "J/K", "shell without the windscreen"),
        "C_ws": (h.C_ws, "J/K", "windscreen glass (HeatingConfig.C_ws)"),
        "C_cool": (h.C_cool, "J/K", "coolant loop (HeatingConfig.C_cool)"),
        "C_icw": (h.C_icw, "J/K", "inner-condenser wall (HeatingConfig.C_icw)"),
        "eps_ic": (eps(h.UA_ic0), "1", "inner-condenser effectiveness at W_bl (UA_ic0)"),
        "hA_int": (c.hA_int, "W/K", "interior <-> cabin air"),
        "hA_is": (c.hA_int_slow, "W/K", "fast <-> slow interior"),
        "hA_sh": (shell_conductance(c, h), "W/K", "cabin air -> shell, winter envelope"),
        "hA_gi": (h.h_ws_in * h.A_ws, "W/K", "cabin air -> windscreen inner surface"),
        "hA_ext0": (c.hA_ext0, "W/K", "shell -> ambient, parked"),
        "hA_ext_v": (c.hA_ext_v, "W/K/(m/s)^0.8", "shell -> ambient, forced"),
        "f_ws": (f_ws, "1", "windscreen share of the shell area"),
        "f_def": (h.f_def0, "1", "supply-air share at the windscreen (normal heating)"),
        "m_inf0": (c.m_inf0, "kg/s", "infiltration, parked"),
        "k_inf": (c.k_inf if c.cabin_speed else 0.0, "kg/s/(m/s)", "infiltration per m/s"),
        "Q_pass": (c.Q_pass * h.n_pass, "W", "occupants' sensible heat"),
        "m_moist": (c.m_moist_pass * h.n_pass, "kg/s", "occupants' moisture"),
        "W_bl": (W_bl, "kg/s", "blower flow, held"),
        "beta1": (c.beta1, "W s^2/kg^2", "blower power map"),
        "beta2": (c.beta2, "W s/kg", "blower power map"),
        "beta3": (c.beta3, "W", "blower power map"),
        "f_bl_heat": (c.f_bl_heat, "1", "blower power into the air"),
        "c_p": (c.c_p_air, "J/(kg K)", "air"),
        "p_atm": (c.p_atm, "Pa", "ambient pressure"),
        "RH_amb": (c.RH_amb, "1", "ambient relative humidity"),
        "eps_hc": (eps_hc, "1", "heater-core effectiveness at W_bl (UA_hc0, n_hc)"),
        "eta_heater": (h.eta_heater, "1", "coolant heater efficiency"),
        "G_cool": (h.m_cool * h.c_cool, "W/K", "coolant flow x c_cool"),
        "UA_cool": (h.UA_cool_loss, "W/K", "coolant loop -> under-hood air"),
    }
    return declare(k, Ts)


@dataclass(frozen=True)
class HeatingControlConfig:
    """Options shared by the heating controllers (temperatures in K, powers in W).

    Attributes
    ----------
    T_set : the comfort target (the rule's set-point; the others are matched to its mean).
    band : width of the NMPC's comfort band above its lower edge, K.
    fog_min : required fogging margin (glass minus dew point), K.
    T_a1_max : inner-condenser outlet air limit (the plant's head pressure derates near
        70-75 degC of outlet air), K.
    Q_hp_max : heat-pump heat bound, W (the plant's 3.4-5.6 kW at full speed).
    N : NMPC horizon, samples of the control model's Ts (default 60 x 10 s = 10 min).
    Ts : control sample, s (a multiple of the plant's 5 s).
    slack_penalty, fog_penalty : W per K of violation (per second).
    pull_up_s : the pull-up allowance from a cold soak, s: the rule's comfort test (mean
        within 0.3 K of the set-point, never 1.5 K below it) looks at the samples after it
        (0: at all of them, a warm start).
    """

    T_set: float = C2K(22.0)
    band: float = 1.0
    fog_min: float = 2.0
    T_a1_max: float = C2K(65.0)
    Q_hp_max: float = 5000.0
    N: int = 60
    Ts: float = 10.0
    slack_penalty: float = 2e4
    fog_penalty: float = 2e4
    r_max: float = 0.95
    tol: float = 1e-6
    max_iter: int = 200
    pull_up_s: float = 0.0

    def replace(self, **changes) -> HeatingControlConfig:
        return dataclasses.replace(self, **changes)


def energy_cost(s) -> dict:
    """Electric energy of one sample, J: heat pump + coolant heater (the blower is held)."""
    return {"E": s.dt * (s.P_hp + s.P_heater)}


def ocp_spec(c: HeatingControlConfig, P_heater_max: float) -> OCPSpec:
    """The heating NMPC as a configuration of :class:`acid.control.ocp.OCP`."""
    return OCPSpec(
        N=c.N, stage_cost=energy_cost,
        input_bounds={"Q_hp": (0.0, c.Q_hp_max), "P_heater": (0.0, P_heater_max),
                      "recirc": (0.0, c.r_max)},
        soft_bounds=(SoftBound("T_cab", c.T_set, c.T_set + c.band, c.slack_penalty,
                               per_second=True),
                     SoftBound("fog_margin", lower=c.fog_min, penalty=c.fog_penalty,
                               per_second=True),
                     SoftBound("T_a1", upper=c.T_a1_max, penalty=c.slack_penalty,
                               per_second=True)),
        u_offset={"Q_hp": 2000.0, "P_heater": 1000.0, "recirc": 0.5},
        u_scale={"Q_hp": 1e-3, "P_heater": 1e-3, "recirc": 1.0},
        x_offset={k: 290.0 for k in ("T_cab", "T_int", "T_is", "T_shell", "T_glass", "T_cool",
                                     "T_icw")},
        x_scale={"T_cab": 10.0, "T_int": 10.0, "T_is": 10.0, "T_shell": 10.0,
                 "T_glass": 10.0, "T_cool": 20.0, "T_icw": 20.0, "w_cab": 1e-3},
        cost_scale=1e-4)


class HeatingNMPC:
    """Economic NMPC of the heating (module docstring). ``make_step(x, d_preview)`` returns
    ``{"Q_hp", "P_heater", "recirc"}`` for the next control sample."""

    def __init__(self, model, config: HeatingControlConfig, P_heater_max: float,
                 T_lo: float | None = None):
        self.model, self.config = model, config
        self.ocp = OCP(model, ocp_spec(config, P_heater_max))
        self.theta = model.values
        self._solver = NLPSolver(
            "acid_heating_nmpc", self.ocp.nlp, "ipopt",
            {"print_time": False, "calc_lam_p": False,
             "ipopt": {"print_level": 0, "sb": "yes", "tol": config.tol,
                       "max_iter": config.max_iter}},
            compiled=False)
        self.set_band(config.T_set if T_lo is None else T_lo)
        self._w = None
        self.fallbacks = 0
        self._last = np.array([0.0, 0.0, 0.0])

    def set_band(self, T_lo: float) -> None:
        N, c = self.ocp.N, self.config
        self.T_lo = float(T_lo)
        self._par = self.ocp.parameters(
            np.zeros(self.ocp.par.size), theta=self.theta,
            bounds={("T_cab", "lo"): np.full(N, T_lo), ("T_cab", "hi"): np.full(N, T_lo + c.band),
                    ("fog_margin", "lo"): np.full(N, c.fog_min),
                    ("T_a1", "hi"): np.full(N, c.T_a1_max)})
        self._w = None

    def make_step(self, x, d_preview) -> dict:
        check_interrupt()  # a Ctrl-C its last solve swallowed stops here
        ocp = self.ocp
        d = np.asarray(d_preview, dtype=float).reshape(ocp.N, self.model.nd)
        par = ocp.parameters(self._par.copy(), x0=x, d=d)
        # far below the band (a pull-up) the solve starts afresh with the heater on: the
        # heater core gives nothing while the coolant is colder than the inner condenser's
        # air (max(0, ...)), so from a plan with the heater off its gradient is zero and the
        # solver never finds it (found from a -10 degC cold soak: heater never used)
        cold = x[0] < self.T_lo - COLD_GUESS_K
        guess = ocp.guess(x, d, self.theta,
                          np.array([1500.0, COLD_GUESS_HEATER if cold else 0.0, 0.3]),
                          None if cold else self._w)
        res = self._solver.solve(guess, par, ocp.lbx, ocp.ubx, ocp.lbg, ocp.ubg)
        if res.success:
            self._w = res.x
            self._last = np.clip(ocp.plan(res.x)[0], ocp.u_min, ocp.u_max)
        else:
            self.fallbacks += 1
            self._w = None
            check_interrupt()  # the failure was the interrupt: say only that
            warnings.warn(f"heating NMPC solve failed ({res.status}); the last move holds",
                          SolverWarning, stacklevel=2)
        return dict(zip(("Q_hp", "P_heater", "recirc"), map(float, self._last), strict=True))


class HeatPumpServo:
    """Compressor speed (rpm) for a commanded heat-pump heat ``Q_hp`` (W): a multiplicative
    integral loop on the plant's measured condenser heat, started from ``q_per_rpm``; below
    ``Q_on`` the heat pump is off (the plant's speed floor gives about 0.7-1.2 kW)."""

    def __init__(self, N_min: float, N_max: float, q_per_rpm: float = 0.9, Q_on: float = 400.0):
        self.N_min, self.N_max, self.q, self.Q_on = N_min, N_max, q_per_rpm, Q_on
        self.N = 0.0

    def __call__(self, Q_cmd: float, Q_meas: float) -> float:
        if Q_cmd < self.Q_on:
            self.N = 0.0
        elif self.N <= 0.0 or Q_meas <= 100.0:
            self.N = min(max(Q_cmd / self.q, self.N_min), self.N_max)
        else:
            ratio = min(max(Q_cmd / Q_meas, 0.7), 1.4)
            self.N = min(max(self.N * ratio, self.N_min), self.N_max)
        return self.N


@dataclass(frozen=True)
class SimpleRule:
    """The simple rule: PI on ``T_cab`` -> heat demand (W); heat pump first up to the heat
    that brings its outlet air to ``T_a1_max``, coolant heater for the rest; recirculation
    share held. ``Kp`` W/K, ``Ki`` W/(K s); ``i_band`` (K) a practitioner's anti-windup for
    pull-ups: no integration far from the set-point."""

    T_set: float
    recirc: float
    Kp: float = 800.0
    Ki: float = 4.0
    T_a1_max: float = C2K(65.0)
    P_heater_max: float = 5700.0
    #: conditional integration (anti-windup): the integral moves only while the cabin is within
    #: this many K of the set-point (None: always, but for saturation), K
    i_band: float | None = None

    def run(self, W_cp: float, Q0: float = 0.0):
        """A stateful law ``u = step(measurement, T_amb, Ts)``; the integral starts at the
        heat ``Q0`` (W, bumpless from the controller that heated before)."""
        integral = [Q0 / self.Ki]

        def step(m: dict, T_amb: float, Ts: float) -> dict:
            e = self.T_set - m["T_cab"]
            raw = self.Kp * e + self.Ki * (integral[0] + e * Ts)
            T_mix = T_amb + self.recirc * (m["T_cab"] - T_amb)
            Q_hp_max = max(W_cp * (self.T_a1_max - T_mix), 0.0)
            q = min(max(raw, 0.0), Q_hp_max + self.P_heater_max)
            inside = self.i_band is None or abs(e) <= self.i_band
            if inside and (q == raw or (raw < 0.0) != (e > 0.0)):
                integral[0] += e * Ts
            Q_hp = min(q, Q_hp_max)
            return {"Q_hp": Q_hp, "P_heater": q - Q_hp, "recirc": self.recirc}

        return step


def heat_pump_map(ambients_C=(-10.0, -5.0, 0.0, 4.0, 7.0), recircs=(0.0, 0.4, 0.8),
                  speeds=(800, 1400, 2000, 2800, 3500, 4500), T_a1_below: float = C2K(68.0)):
    """The heat pump's COP law of ``acid.models.heating_control`` fitted to the heating
    plant: direct-mode runs (3 min at 10 m/s from a warm cabin, blower ``W_BL_HOLD``), power
    ``P = Q_cond / (COP_0 + COP_amb (T_amb - 273.15) - COP_lift (T_a1 - T_amb))`` by least
    squares in relative error. Returns ``({COP_0, COP_amb, COP_lift}, rms, n)``."""
    from scipy.optimize import least_squares

    data = []
    for a in ambients_C:
        for r in recircs:
            for N in speeds:
                p = HeatingPlant(config=winter_plant_config(C2K(a)), mode="direct")
                p.reset({"T_cab": C2K(21), "T_int": C2K(21), "T_int_slow": C2K(20),
                         "T_shell": C2K(10), "T_glass": C2K(12), "T_icw": C2K(35),
                         "T_cool": C2K(21)})
                for _ in range(36):
                    row = p.step(W_bl=W_BL_HOLD, v_veh=10.0, N_hp=N, recirc=r)
                if row["T_hp_out"] < T_a1_below:
                    data.append((C2K(a), row["T_hp_out"], row["Q_cond"], row["P_comp"]))
    d = np.array(data)

    def res(th):
        cop = th[0] + th[1] * (d[:, 0] - 273.15) - th[2] * (d[:, 1] - d[:, 0])
        return (d[:, 2] / cop - d[:, 3]) / np.maximum(d[:, 3], 100.0)

    s = least_squares(res, [5.0, 0.05, 0.05])
    return (dict(zip(("COP_0", "COP_amb", "COP_lift"), map(float, s.x), strict=True)),
            float(math.sqrt(np.mean(s.fun ** 2))), len(d))
