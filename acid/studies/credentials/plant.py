"""``acid plant-check``: the plant's credentials, each computed beside a published reference.

Checks, each a row ``CheckRow(name, value, reference, unit, passed)``:

(a) Table I: the nominal controller at 0-25 m/s for 600 s (compressor + blower), each speed
    within +-5 % of the paper, strictly decreasing, E(25)/E(0) in 0.77-0.83 [Wang2018];
(b) balance closure over a 600 s run: evaporator and condenser walls, cabin (air + interior +
    shell) and cabin water, relative residual below 0.1 %; and the refrigerant cycle
    recomputed independently with CoolProp at the plant's operating points (COP, condensing
    temperature, mass flow, condenser heat; the loop's own balance Q_c = Q_e + W holds by
    construction and checks nothing);
(c) step-size convergence: 600 s energy at the default internal step within 0.12 % of 0.01 s;
(d) idle service chart: low- and high-side gauge pressures after 10 min at idle, max cold,
    max blower, windows open, in the shade, 60 % RH, at 25/30/35/40 degC, inside the bands of
    a published performance chart [NissanGTR];
(e) pull-down: cabin air 10 min after a 55 degC soak against the JAF user test [JAF2016], and,
    as information without a verdict, the time from a 60 degC soak at 43 degC ambient and
    1000 W/m^2 to 25 degC beside the 20-30 min that acid's plant design takes for real cars (the
    project's design target: no published test with its conditions was found);
(f) steady COP over compressor speed, vehicle speed and ambient (directions of the plant design
    behaviours 2-4) and the steady COP at 30 degC, standstill, 1.8 kW of cooling;
(g) steady COP at 25 m/s against standstill at equal cooling load (1.8 kW, 30 degC).

Everything runs through the plant protocol (``reset`` / ``step`` / ``measure``) of a plant
built by ``acid.plant.make_plant``. A check that needs what a plant does not offer (pressure
channels, a nominal controller, a configuration to vary, a steady-state cycle) is reported
with ``passed = None`` and "not available on this plant". References: ``datasets/plant/
SOURCES.md``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from acid.claims import TABLE_I, Verdict, claim, judge_value
from acid.errors import ConfigError
from acid.plant.base import Plant
from acid.plant.config import PlantConfig
from acid.units import C2K, K2C

#: Paper Table I (600 s, compressor + blower), MJ at 0, 5, ..., 25 m/s (``acid.claims``).
TABLE_I_SPEEDS = TABLE_I.speeds_mps
TABLE_I_MJ = TABLE_I.energy_MJ

#: [NissanGTR] ambient-to-operating-pressure table, gauge kPa: degC -> (high lo, high hi,
#: low lo, low hi).
SERVICE_CHART = {25.0: (1204.0, 1471.0, 171.0, 209.0), 30.0: (1300.0, 1590.0, 196.0, 240.0),
                 35.0: (1500.0, 1820.0, 229.0, 280.0), 40.0: (1870.0, 2285.0, 292.0, 357.0)}
SERVICE_CHART_SOURCE = ("[NissanGTR] Nissan GT-R (R35) 2010 ESM, HAC 'Performance chart': "
                        "ambient air temperature-to-operating pressure table")

#: [JAF2016]: 55 degC air at face level; A/C auto Lo, windows closed, parked; after 10 min:
#: recirculation 27.5 degC, fresh air 29.5 degC.
JAF_SOAK_C, JAF_FRESH_10MIN_C, JAF_RECIRC_10MIN_C = 55.0, 29.5, 27.5
JAF_TOL_K = 3.0

#: What real cars show: at 43 degC ambient with 1000 W/m^2 of sun, breath-level
#: air reaches 25-30 degC after 20-30 min: acid's design target for the time from a 60 degC
#: soak to 25 degC (a reviewer's typical value, not a citation).
HOT_AMBIENT_C, HOT_SUN_W_M2, HOT_SOAK_C = 43.0, 1000.0, 60.0
HOT_PULLDOWN_MIN = (20.0, 30.0)

#: A sun-soaked cabin relative to its air (K): interior surfaces (dash, seat covers) 13 K
#: above, the interior cores (``T_int_slow``) at the air, the shell 3 K below (assumption;
#: the JAF start of (e): 55 degC air, 68 / 55 / 52 degC).
SOAK_OFFSETS_K = {"T_cab": 0.0, "T_int": 13.0, "T_int_slow": 0.0, "T_shell": -3.0}

NA = "not available on this plant"

#: what the search behind the paper vehicle (``datasets/plant/table_i_20cc.toml``) did and
#: did not establish
SEARCH_NOTE = ("The paper vehicle (--plant-config paper, example:table_i_20cc.toml) meets "
               "every published test here (Table I, the GT-R service chart, JAF 2016); it "
               "came from about 1,000 parameter sets (960 random, then a local search) "
               "inside the cited ranges. That search was not exhaustive: no set meeting the "
               "hot pull-down target as well was found, which does not show that none exists.")


@dataclass(frozen=True)
class CheckRow:
    """One computed credential beside its reference.

    ``passed`` is None when the check could not run on this plant (``note`` says why) and
    for a row of information (``info``: a design target, not a published test: no verdict).
    """

    name: str
    value: float | None
    reference: str
    unit: str
    passed: bool | None
    group: str = ""
    note: str = ""
    info: bool = False

    def to_json_dict(self) -> dict:
        v = self.value
        if v is not None and not math.isfinite(v):
            v = None
        return {"name": self.name, "value": v, "reference": self.reference, "unit": self.unit,
                "passed": self.passed, "group": self.group, "note": self.note,
                "info": self.info}


@dataclass(frozen=True)
class PlantCheckResult:
    """All rows plus the data behind the figures (temperatures in degC, powers W, MJ);
    ``config``: the plant's configuration (``Plant.config()``) with its absolute temperatures
    in degC (``PlantConfig.in_file_units``)."""

    plant: str
    rows: tuple
    cop_steady_30C_standstill: float | None
    cop_gain_25_vs_0_equal_load_pct: float | None
    table_i: dict = field(default_factory=dict)
    service: dict = field(default_factory=dict)
    pulldown: dict = field(default_factory=dict)
    cop_map: dict = field(default_factory=dict)
    config: dict = field(default_factory=dict)
    cycle_check: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        """Every row that could run passed."""
        return all(r.passed for r in self.rows if r.passed is not None)

    def to_json_dict(self) -> dict:
        from acid._io import json_safe

        return json_safe({
            "plant": self.plant, "passed": self.passed,
            "checks": [r.to_json_dict() for r in self.rows],
            "cop_steady_30C_standstill": self.cop_steady_30C_standstill,
            "cop_gain_25_vs_0_equal_load_pct": self.cop_gain_25_vs_0_equal_load_pct,
            "table_i": self.table_i, "service_chart": self.service, "pulldown": self.pulldown,
            "cop_map": self.cop_map, "plant_config": self.config,
            "cycle_check": self.cycle_check, "search_note": SEARCH_NOTE,
        })


# ----------------------------------------------------------------------------- plant access
def _hifi(plant: Plant):
    """The high-fidelity plant behind ``plant`` (its config can be varied), else None."""
    from acid.plant.hifi import HifiPlant

    return plant if isinstance(plant, HifiPlant) else None


def _variant(plant: Plant, mode: str = "direct", **changes) -> Plant | None:
    """A fresh plant of the same kind with configuration ``changes`` (hifi only), else None."""
    from acid.plant.hifi import HifiPlant

    h = _hifi(plant)
    if h is None:
        return None
    return HifiPlant(h.cfg.replace(**changes), mode=mode)


class ExternalNominal(Plant):
    """The paper's nominal controller around any plant: blower PI on the cabin set-point at the
    sample time, evaporator set-point fixed (used when a plant has no nominal mode).

    Gains as ``PlantConfig``'s blower loop, discretised at Ts.
    """

    def __init__(self, plant: Plant, T_cab_set: float = C2K(22.0),
                 T_evap_set: float = C2K(3.0)):
        c = PlantConfig()
        self.plant, self.Ts, self.name = plant, plant.Ts, f"{plant.name}+nominal"
        self.T_cab_set, self.T_evap_set = T_cab_set, T_evap_set
        self.Kp, self.Ki, self.W_min, self.W_max = c.Kp_bl, c.Ki_bl, c.W_bl_min, c.W_bl_max
        self.integ = self.W_min

    def reset(self, initial=None):
        self.integ = self.W_min
        return self.plant.reset(initial)

    def measure(self):
        return self.plant.measure()

    def config(self):
        return self.plant.config()

    def step(self, W_bl=0.0, T_evap_set=0.0, v_veh=0.0, **kw):
        e = self.plant.measure()["T_cab"] - self.T_cab_set
        u = self.Kp * e + self.integ
        if not ((u >= self.W_max and e > 0) or (u <= self.W_min and e < 0)):
            self.integ += self.Ki * e * self.Ts
        W = min(max(u, self.W_min), self.W_max)
        return self.plant.step(W, self.T_evap_set, v_veh, **kw)


def _nominal(plant: Plant, factory: Callable[[], Plant] | None = None) -> Plant:
    """The plant under its own nominal controller: ``factory()`` (e.g. an FMU plant built in
    its nominal mode), ``plant.nominal()``, or the paper's controller around it."""
    if factory is not None:
        return factory()
    nominal = getattr(plant, "nominal", None)
    return nominal() if callable(nominal) else ExternalNominal(plant)


def _energy_MJ(rows, Ts, fan=False) -> float:
    keys = ("P_comp", "P_bl", "P_fan") if fan else ("P_comp", "P_bl")
    return float(sum(sum(r.get(k, 0.0) for k in keys) for r in rows) * Ts / 1e6)


def _agrees(claim_id: str, value: float) -> bool:
    """The claims registry's verdict on ``value`` for one of the paper's Table I claims."""
    return judge_value(claim_id, value)[0] is Verdict.AGREES


def _rule_text(claim_id: str) -> str:
    c = claim(claim_id)
    return c.rule_text.replace("within ", "+-")


# ----------------------------------------------------------------------------- the checks
def check_table_i(plant: Plant, progress=None, nominal_factory=None
                  ) -> tuple[list[CheckRow], dict, Plant]:
    """(a) Table I through the nominal controller; returns rows, data and the 0 m/s plant."""
    E, E_fan, first = [], [], None
    n = int(round(600.0 / plant.Ts))
    for i, v in enumerate(TABLE_I_SPEEDS):
        p = _nominal(plant, nominal_factory)
        p.reset()
        rows = [p.step(0.0, C2K(3.0), v) for _ in range(n)]
        E.append(_energy_MJ(rows, p.Ts))
        E_fan.append(_energy_MJ(rows, p.Ts, fan=True))
        if first is None:
            first = p
        if progress:
            progress(i + 1)
    # verdicts by the claims registry's rules, so that this check and the report agree
    out = []
    for v, e, ref in zip(TABLE_I_SPEEDS, E, TABLE_I_MJ, strict=True):
        out.append(CheckRow(f"Table I: E({v:g} m/s), 600 s", e,
                            f"{ref} {_rule_text(f'table1.energy.{v:g}mps')} [Wang2018] Table I",
                            "MJ", _agrees(f"table1.energy.{v:g}mps", e), "a"))
    dec = -np.diff(E)
    out.append(CheckRow("Table I: smallest decrement (strictly decreasing)", float(dec.min()),
                        "> 0 [Wang2018] Table I", "MJ", bool(np.all(dec > 0)), "a"))
    ratio = E[-1] / E[0]
    paper_ratio = claim("table1.ratio").paper.value
    out.append(CheckRow("Table I: E(25)/E(0)", ratio,
                        f"{paper_ratio:.3f} {_rule_text('table1.ratio')} [Wang2018] Table I", "1",
                        _agrees("table1.ratio", ratio), "a",
                        "see datasets/plant/SOURCES.md: the cited physics gives less"
                        if ratio < paper_ratio and not _agrees("table1.ratio", ratio) else ""))
    data = {"speeds_mps": list(TABLE_I_SPEEDS), "energy_MJ": E, "energy_with_fan_MJ": E_fan,
            "paper_MJ": list(TABLE_I_MJ), "ratio": ratio, "ratio_with_fan": E_fan[-1] / E_fan[0]}
    return out, data, first


def check_balance(plant0: Plant) -> list[CheckRow]:
    """(b) balances of the 600 s standstill Table I run (the refrigerant loop's own balance,
    ``Q_c = Q_e + W`` by construction of the cycle, is not a check: see
    :func:`check_refrigerant_cycle`)."""
    balance = getattr(plant0, "balance", None) or getattr(getattr(plant0, "plant", None),
                                                          "balance", None)
    names = ("evaporator_wall", "condenser_wall", "cabin", "water")
    if not callable(balance):
        return [CheckRow(f"balance: {k.replace('_', ' ')}", None, "< 0.1 %", "%", None, "b", NA)
                for k in names]
    b = balance()
    return [CheckRow(f"balance: {k.replace('_', ' ')} (600 s at 0 m/s)", 100.0 * b[k]["relative"],
                     "< 0.1 % of the integrated flows", "%", b[k]["relative"] < 1e-3, "b")
            for k in names]


#: tolerances of the independent cycle check (b'): the plant interpolates property tables
#: (0.5 K / 1 K grids) and scales the isentropic lift from the suction saturation state to the
#: actual suction temperature (ideal-gas); CoolProp evaluates every state directly
CYCLE_TOL_REL = 0.005     # COP, mass flow, condenser heat: 0.5 %
CYCLE_TOL_TC_K = 0.1     # condensing temperature, K


@dataclass(frozen=True)
class IndependentCycle:
    """The vapour-compression cycle recomputed with CoolProp from the plant's operating point.

    Inputs (the plant's): evaporating, suction and condensing pressures ``p_e``, ``p_s``,
    ``p_c`` (Pa), superheat and subcooling (K), isentropic efficiency and the cooling ``Q_e``
    (W). Outputs: condensing temperature ``T_c`` (K), enthalpies h1 (evaporator outlet at
    (p_e, T_sat(p_e) + SH), isenthalpic to the suction), h2 (discharge: h1 + (h(p_c, s(p_s,
    h1)) - h1) / eta_is), h3 = h4 (liquid line at (p_c, T_sat(p_c) - SC)), J/kg; mass flow
    ``m_r = Q_e / (h1 - h4)`` (kg/s); ``COP = (h1 - h4) / (h2 - h1)`` (refrigerant side,
    shaft power); ``Q_c = m_r (h2 - h3)`` (W).
    """

    T_c: float
    h1: float
    h2: float
    h3: float
    m_r: float
    COP: float
    Q_c: float


def coolprop_cycle(fluid: str, p_e: float, p_s: float, p_c: float, superheat: float,
                   subcool: float, eta_is: float, Q_e: float) -> IndependentCycle:
    """The cycle at given pressures with CoolProp (``PropsSI``, nothing from acid's tables)."""
    from CoolProp.CoolProp import PropsSI

    T_e = PropsSI("T", "P", p_e, "Q", 1.0, fluid)
    T_c = PropsSI("T", "P", p_c, "Q", 0.0, fluid)
    h1 = PropsSI("H", "P", p_e, "T", T_e + superheat, fluid)
    s_suc = PropsSI("S", "P", p_s, "H", h1, fluid)
    h2s = PropsSI("H", "P", p_c, "S", s_suc, fluid)
    h2 = h1 + (h2s - h1) / eta_is
    h3 = PropsSI("H", "P", p_c, "T", T_c - subcool, fluid)
    m_r = Q_e / (h1 - h3)
    return IndependentCycle(T_c=T_c, h1=h1, h2=h2, h3=h3, m_r=m_r,
                            COP=(h1 - h3) / (h2 - h1), Q_c=m_r * (h2 - h3))


#: the quantities of the independent cycle check; the condensing temperature's deviation is
#: in K, the others' in %
CYCLE_CHECKS = ("COP Q_e / W (refrigerant side)", "condensing temperature",
                "mass flow Q_e / (h1 - h4)", "condenser heat m_r (h2 - h3)")


def cycle_deviations(cfg, r) -> tuple[dict[str, float], dict]:
    """The plant's cycle solution ``r`` (``acid.plant.cycle.CycleResult``) against CoolProp:
    ({check: plant minus CoolProp (K for the condensing temperature, else %)}, the numbers
    of both, JSON-ready)."""
    ind = coolprop_cycle(cfg.refrigerant, r.p_e, r.p_s, r.p_c, cfg.superheat, cfg.subcool,
                         r.eta_is, r.Q_e)
    plant_cop = r.Q_e / r.W_comp
    devs = dict(zip(CYCLE_CHECKS, (100.0 * (plant_cop / ind.COP - 1.0), r.T_c - ind.T_c,
                                   100.0 * (r.m_r / ind.m_r - 1.0),
                                   100.0 * (r.Q_c / ind.Q_c - 1.0)), strict=True))
    point = {"p_e_bar": r.p_e / 1e5, "p_s_bar": r.p_s / 1e5, "p_c_bar": r.p_c / 1e5,
             "eta_is": r.eta_is, "Q_e_W": r.Q_e,
             "plant": {"COP": plant_cop, "T_c_C": K2C(r.T_c), "m_r_kg_s": r.m_r,
                       "Q_c_W": r.Q_c, "COP_electric": r.COP},
             "coolprop": {"COP": ind.COP, "T_c_C": K2C(ind.T_c), "m_r_kg_s": ind.m_r,
                          "Q_c_W": ind.Q_c}}
    return devs, point


def _operating_points(plant: Plant, plant0: Plant) -> tuple[list[tuple[str, object]], object]:
    """[(label, CycleResult)] of the plant's cycle: the end of the 600 s standstill Table I
    run and the steady 1.8 kW points of (f)/(g) at 0 and 25 m/s (hifi plants only), and the
    high-fidelity plant they belong to (None for other plants)."""
    from acid.plant.cycle import cycle

    h0 = _hifi(plant0) or _hifi(getattr(plant0, "plant", None))
    h = _hifi(plant)
    out = []
    if h0 is not None and h0.N > 0.0:
        out.append(("end of the 600 s Table I run at 0 m/s",
                    cycle(h0.N, h0.T_ew, h0.T_cw, h0.cfg, guess=(h0.T_e, h0.T_c))))
    if h is not None:
        cfg = h.cfg.replace(T_amb=C2K(30.0))
        for v in (0.0, 25.0):
            out.append((f"steady 1.8 kW at {v:g} m/s, 30 degC", _cop_at_load(cfg, v)[0]))
    return out, (h0 or h)


def check_refrigerant_cycle(plant: Plant, plant0: Plant) -> tuple[list[CheckRow], dict]:
    """(b) the plant's cycle recomputed independently with CoolProp at its operating points.

    From the plant's evaporating, suction and condensing pressures, superheat, subcooling,
    isentropic efficiency and cooling, CoolProp gives the condensing temperature, the
    refrigerant mass flow Q_e / (h1 - h4), the refrigerant-side COP Q_e / W and the condenser
    heat; each is compared with what the plant reports (tolerances ``CYCLE_TOL_*``).
    """
    points, h = _operating_points(plant, plant0)
    names = CYCLE_CHECKS
    if not points:
        return [CheckRow(f"cycle vs CoolProp: {n}", None, "CoolProp at the operating point",
                         "%", None, "b", NA + " (needs the plant's cycle state)")
                for n in names], {}
    cfg = h.cfg
    rows, data = [], {"tolerance_rel": CYCLE_TOL_REL, "tolerance_T_c_K": CYCLE_TOL_TC_K,
                      "fluid": cfg.refrigerant, "points": []}
    worst = {n: (0.0, "") for n in CYCLE_CHECKS}
    for label, r in points:
        devs, point = cycle_deviations(cfg, r)
        for n, d in devs.items():
            if abs(d) >= abs(worst[n][0]):
                worst[n] = (d, label)
        data["points"].append({"label": label, **point})
    tol = 100.0 * CYCLE_TOL_REL
    for n in names:
        d, label = worst[n]
        is_T = n == names[1]
        lim = CYCLE_TOL_TC_K if is_T else tol
        rows.append(CheckRow(
            f"cycle vs CoolProp: {n}", d,
            f"|plant - CoolProp| <= {lim:g} {'K' if is_T else '%'}", "K" if is_T else "%",
            abs(d) <= lim, "b",
            f"largest deviation of {len(points)} operating points ({label}); CoolProp PropsSI "
            "at the plant's pressures, superheat, subcooling and isentropic efficiency"))
    return rows, data


def check_step_size(plant: Plant) -> list[CheckRow]:
    """(c) 600 s nominal energy at the default internal step against 0.01 s."""
    h = _hifi(plant)
    if h is None:
        return [CheckRow("step size: 600 s energy vs 0.01 s", None, "< 0.12 %", "%", None, "c",
                         NA)]
    E = []
    for dt in (h.cfg.dt_int, 0.01):
        p = _variant(plant, "nominal", dt_int=dt)
        p.reset()
        E.append(_energy_MJ([p.step(0.0, 0.0, 0.0) for _ in range(120)], p.Ts))
    d = 100.0 * abs(E[0] / E[1] - 1.0)
    return [CheckRow(f"step size: 600 s energy at {h.cfg.dt_int:g} s vs 0.01 s", d, "< 0.12 %",
                     "%", d < 0.12, "c")]


def check_service_chart(plant: Plant, progress=None) -> tuple[list[CheckRow], dict]:
    """(d) idle pressures against [NissanGTR] at 25/30/35/40 degC."""
    rows, data = [], {"ambient_C": [], "high_kPa": [], "low_kPa": [], "chart": SERVICE_CHART,
                      "source": SERVICE_CHART_SOURCE}
    h = _hifi(plant)
    p_atm = h.cfg.p_atm if h is not None else 101325.0
    for i, (T, (hlo, hhi, llo, lhi)) in enumerate(SERVICE_CHART.items()):
        K = C2K(T)
        if h is not None:  # shade, 60 % RH, windows open (cabin air ~ ambient), all at ambient
            p = _variant(plant, T_amb=K, RH_amb=0.6, G_solar=0.0, m_inf0=0.5, k_inf=0.0,
                         T_cab0=K, T_int0=K, T_shell0=K, T_ew0=K, T_cw0=K)
        else:
            p = plant
        p.reset()
        W = h.cfg.W_bl_max if h is not None else 0.15
        recs = [p.step(W, C2K(3.0), 0.0, T_amb=K) for _ in range(120)]
        hi = np.array([r.get("p_dis", np.nan) for r in recs[-12:]], dtype=float)
        lo = np.array([r.get("p_suc", np.nan) for r in recs[-12:]], dtype=float)
        if progress:
            progress(i + 1)
        if not (np.all(np.isfinite(hi)) and np.all(np.isfinite(lo))):
            rows += [CheckRow(f"idle high side at {T:g} degC", None, f"{hlo:g}-{hhi:g}",
                              "kPa gauge", None, "d", NA + " (no p_dis / p_suc channels)"),
                     CheckRow(f"idle low side at {T:g} degC", None, f"{llo:g}-{lhi:g}",
                              "kPa gauge", None, "d", NA + " (no p_dis / p_suc channels)")]
            continue
        hk, lk = (hi.mean() - p_atm) / 1e3, (lo.mean() - p_atm) / 1e3
        data["ambient_C"].append(T)
        data["high_kPa"].append(hk)
        data["low_kPa"].append(lk)
        # the chart's conditions (shade, windows open, 60 % RH, soaked at ambient) can only be
        # set on acid's own plant; elsewhere the value is reported without a verdict
        note = "" if h is not None else ("chart conditions cannot be set on this plant: its "
                                         "own configuration at this ambient, no verdict")
        rows.append(CheckRow(f"idle high side at {T:g} degC", hk, f"{hlo:g}-{hhi:g} [NissanGTR]",
                             "kPa gauge", (hlo <= hk <= hhi) if h is not None else None, "d",
                             note))
        rows.append(CheckRow(f"idle low side at {T:g} degC", lk, f"{llo:g}-{lhi:g} [NissanGTR]",
                             "kPa gauge", (llo <= lk <= lhi) if h is not None else None, "d",
                             note))
    return rows, data


def check_pulldown(plant: Plant) -> tuple[list[CheckRow], dict]:
    """(e) pull-down: JAF's 55 degC soak (10 min) and a 60 degC soak at 43 degC, 1000 W/m^2."""
    h = _hifi(plant)
    data: dict = {}
    rows = []
    n = int(round(2700.0 / plant.Ts))
    # JAF: cabin air 55 degC; 30 degC, 850 W/m^2 (assumed: the test's ambient is not
    # published); A/C at full cooling (set-point 18 degC). Hot: 43 degC, 1000 W/m^2, cabin
    # air 60 degC; set-point 22 degC. Surfaces from SOAK_OFFSETS_K in both.
    rise = SOAK_OFFSETS_K
    for label, T_set, T_amb, G in (("jaf", 18.0, None, None),
                                   ("hot43", 22.0, HOT_AMBIENT_C, HOT_SUN_W_M2)):
        soak = C2K(JAF_SOAK_C if label == "jaf" else HOT_SOAK_C)
        init = {k: soak + d for k, d in rise.items()}
        if h is not None:
            changes = {"T_cab_set": C2K(T_set)}
            if T_amb is not None:
                changes.update(T_amb=C2K(T_amb), G_solar=G, T_ew0=C2K(T_amb), T_cw0=C2K(T_amb))
            p = _variant(plant, "nominal", **changes)
        elif T_amb is not None:  # the sun cannot be set on this plant
            data[label] = None
            continue
        else:
            init.pop("T_int_slow")
            p = ExternalNominal(plant, T_cab_set=C2K(T_set))
        p.reset(init)
        recs = [p.step(0.0, C2K(3.0), 0.0) for _ in range(n)]
        T = K2C(np.array([r["T_cab"] for r in recs]))
        data[label] = {"time_s": (np.arange(n) * p.Ts).tolist(), "T_cab_C": T.tolist(),
                       "T_int_C": K2C(np.array([r["T_int"] for r in recs])).tolist()}
    T10 = data["jaf"]["T_cab_C"][int(round(600.0 / plant.Ts))]
    lo, hi = JAF_RECIRC_10MIN_C - JAF_TOL_K, JAF_FRESH_10MIN_C + JAF_TOL_K
    rows.append(CheckRow("pull-down: cabin air 10 min after a 55 degC soak", T10,
                         f"{JAF_RECIRC_10MIN_C}-{JAF_FRESH_10MIN_C} +-{JAF_TOL_K:g} [JAF2016]",
                         "degC", lo <= T10 <= hi, "e",
                         "JAF: 27.5 recirculation, 29.5 fresh air (the plant starts on fresh air "
                         "and recirculates once below ambient); +-3 K for the unpublished "
                         "ambient (30 degC, 850 W/m^2 assumed) and the car"))
    name = (f"pull-down: {HOT_SOAK_C:g} degC soak at {HOT_AMBIENT_C:g} degC, "
            f"{HOT_SUN_W_M2:g} W/m2, to 25 degC")
    ref = (f"{HOT_PULLDOWN_MIN[0]:g}-{HOT_PULLDOWN_MIN[1]:g} min: acid's design target, "
           "not a published test")
    if data["hot43"] is None:
        rows.append(CheckRow(name, None, ref, "min", None, "e",
                             NA + " (ambient and sun cannot be set)", info=True))
        return rows, data
    T43 = np.asarray(data["hot43"]["T_cab_C"])
    below = np.nonzero(T43 <= 25.0)[0]
    t25 = float(below[0] * plant.Ts / 60.0) if below.size else math.inf
    data["t25_min"] = t25
    inside = HOT_PULLDOWN_MIN[0] <= t25 <= HOT_PULLDOWN_MIN[1]
    rows.append(CheckRow(name, t25, ref, "min", None, "e",
                         f"information, no verdict: {'inside' if inside else 'outside'} the "
                         f"target; cabin air {T43[int(round(1800.0 / plant.Ts))]:.1f} degC "
                         f"after 30 min, {T43[-1]:.1f} degC after 45 min; real cars: "
                         "breath-level air 25-30 degC after 20-30 min (a design target; no "
                         "published test with these conditions was found)", info=True))
    return rows, data


def _cop_at_load(cfg, v, Q=1800.0, T_ew=278.15, T_amb=None):
    """Steady cycle delivering ``Q`` W of cooling at evaporator wall ``T_ew`` (K, default
    5 degC): bisection on compressor speed."""
    from acid.plant.hifi import front_end, steady_cycle

    lo, hi, res = cfg.N_min, cfg.N_max, None
    for _ in range(40):
        N = 0.5 * (lo + hi)
        res, T_cw = steady_cycle(N, T_ew, v, cfg, T_amb=T_amb)
        lo, hi = (lo, N) if res.Q_e > Q else (N, hi)
    fe = front_end(cfg, v, T_amb)
    lev = fe.level(res.p_c, cfg)
    return res, fe.P_fan[lev]


def check_cop(plant: Plant) -> tuple[list[CheckRow], dict, float | None, float | None]:
    """(f) steady COP map and the standstill COP; (g) COP gain at equal load."""
    h = _hifi(plant)
    if h is None:
        rows = [CheckRow(n, None, ref, u, None, g, NA + " (needs a steady-state cycle)")
                for n, ref, u, g in (("steady COP at 30 degC, 0 m/s, 1.8 kW", "2.5-3.8", "1",
                                      "f"),
                                     ("COP gain 25 vs 0 m/s at equal load", ">= 10 %", "%",
                                      "g"))]
        return rows, {}, None, None
    from acid.plant.hifi import steady_cycle

    cfg = h.cfg.replace(T_amb=C2K(30.0))
    grid = {"N_rpm": [1500.0, 3000.0, 5000.0, 8000.0], "v_mps": [0.0, 25.0],
            "T_amb_C": [25.0, 35.0, 45.0]}
    cop = {}
    for Ta in grid["T_amb_C"]:
        for v in grid["v_mps"]:
            cop[f"{Ta:g}C_{v:g}mps"] = [steady_cycle(N, C2K(5.0), v, cfg, T_amb=C2K(Ta))[0].COP
                                        for N in grid["N_rpm"]]
    rows = []
    falls_N = all(np.all(np.diff(c[1:]) < 0) for c in cop.values())
    low = min(c[0] / c[1] for c in cop.values())
    rows.append(CheckRow("steady COP falls with compressor speed, 3000-8000 rpm", None,
                         "design expectation", "1", falls_N, "f",
                         "T_ew 5 degC, 25/35/45 degC, 0/25 m/s; below 3000 rpm leakage and "
                         f"motor part-load losses take over (COP(1500)/COP(3000) down to "
                         f"{low:.2f})"))
    rises_v = all(np.all(np.array(cop[f"{Ta:g}C_25mps"]) > np.array(cop[f"{Ta:g}C_0mps"]))
                  for Ta in grid["T_amb_C"])
    rows.append(CheckRow("steady COP rises with vehicle speed", None, "design expectation",
                         "1", rises_v, "f"))
    falls_T = all(cop[f"25C_{v:g}mps"][i] > cop[f"35C_{v:g}mps"][i] > cop[f"45C_{v:g}mps"][i]
                  for v in grid["v_mps"] for i in range(len(grid["N_rpm"])))
    rows.append(CheckRow("steady COP falls with ambient", None, "design expectation", "1",
                         falls_T, "f"))
    r0, fan0 = _cop_at_load(cfg, 0.0)
    r25, fan25 = _cop_at_load(cfg, 25.0)
    rows.append(CheckRow("steady COP at 30 degC, 0 m/s, 1.8 kW cooling", r0.COP,
                         "2.5-3.8 (a credible e-scroll map)", "1",
                         2.5 <= r0.COP <= 3.8, "f", f"compressor {r0.P_comp:.0f} W"))
    gain = 100.0 * (r25.COP / r0.COP - 1.0)
    rows.append(CheckRow("COP gain 25 vs 0 m/s at equal load (1.8 kW, 30 degC)", gain,
                         ">= 10 % (design expectation)", "%", gain >= 10.0, "g"))
    dp = (r0.p_c - r25.p_c) / 1e5
    rows.append(CheckRow("head pressure idle minus 25 m/s at equal load", dp,
                         "> 0, several bar (design expectation)", "bar", dp > 0.0, "g"))
    with_fan = 100.0 * ((r25.Q_e / (r25.P_comp + fan25)) / (r0.Q_e / (r0.P_comp + fan0)) - 1.0)
    data = {"grid": grid, "cop": cop, "standstill": {"COP": r0.COP, "T_c_C": K2C(r0.T_c),
                                                      "p_dis_bar": r0.p_c / 1e5, "P_fan_W": fan0},
            "v25": {"COP": r25.COP, "T_c_C": K2C(r25.T_c), "p_dis_bar": r25.p_c / 1e5,
                    "P_fan_W": fan25},
            "gain_with_fan_pct": with_fan}
    return rows, data, r0.COP, gain


def plant_check(plant: Plant, progress: Callable[[int, int], None] | None = None,
                nominal_factory: Callable[[], Plant] | None = None) -> PlantCheckResult:
    """Run checks (a)-(g) on ``plant`` (built by ``acid.plant.make_plant``).

    ``nominal_factory`` builds the plant under its own nominal controller (an FMU plant in its
    nominal mode); by default ``plant.nominal()`` or the paper's controller around ``plant``.
    ``progress(done, total)`` is called as the 6 + 4 + 3 parts finish.
    """
    total, done = 13, [0]

    def tick(_=None):
        done[0] += 1
        if progress:
            progress(done[0], total)

    rows_a, table, p0 = check_table_i(plant, progress=tick, nominal_factory=nominal_factory)
    rows_cyc, cycle_check = check_refrigerant_cycle(plant, p0)
    rows = rows_a + check_balance(p0) + rows_cyc
    rows += check_step_size(plant)
    rows_d, service = check_service_chart(plant, progress=tick)
    rows += rows_d
    rows_e, pull = check_pulldown(plant)
    rows += rows_e
    tick()
    rows_f, cop_map, cop0, gain = check_cop(plant)
    rows += rows_f
    tick()
    tick()
    return PlantCheckResult(plant=plant.name, rows=tuple(rows), cop_steady_30C_standstill=cop0,
                            cop_gain_25_vs_0_equal_load_pct=gain, table_i=table,
                            service=service, pulldown=pull, cop_map=cop_map,
                            cycle_check=cycle_check,
                            config=PlantConfig.in_file_units(plant.config()))


def build_plant(name: str = "hifi", config_path=None, T_amb: float | None = None,
                **kwargs) -> Plant:
    """The plant to check, through ``make_plant`` (``T_amb`` in K overrides the ambient;
    ``kwargs`` as ``make_plant``'s, e.g. ``fmu_map``, ``mode``)."""
    from acid.plant import make_plant

    if T_amb is not None and not 233.15 <= T_amb <= 330.15:
        raise ConfigError(f"--t-amb {K2C(T_amb):g} degC is outside the refrigerant property "
                          "tables (-40 to 57 degC)")
    return make_plant(name, config_path=config_path, T_amb=T_amb, **kwargs)


__all__ = ["CheckRow", "ExternalNominal", "IndependentCycle", "PlantCheckResult", "SEARCH_NOTE",
           "SERVICE_CHART", "build_plant", "check_refrigerant_cycle", "coolprop_cycle",
           "plant_check"]
