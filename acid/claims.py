"""The registry of the paper's claims: its numbers, where acid measures them, how they are judged.

This module is the **only** place where the paper's numbers are written (Wang, Kolmanovsky,
Amini & Sun, "Model Predictive Climate Control of Connected and Automated Vehicles for
Improved Energy Efficiency", ACC 2018). Everything else reads them from here: the parameter
preset (:func:`acid.params.paper`), the speed sweep's Table I, the CAV scenario's window,
the report, ``summary.json`` and the README's headline table.

A :class:`Claim` is one result of the paper:

* ``paper``: its value, unit, where in the paper it is and, for qualitative or approximate
  statements, the paper's words (:class:`PaperValue`);
* ``measured``: where acid measures it, as a stage result class of
  :mod:`acid.stage_results` and a path to one of its fields (checked against the declared
  fields when the registry is built), plus the conditions under which the two are comparable
  (e.g. a 600 s sweep) (:class:`Measured`, :class:`Requires`);
* ``rule``: how the verdict is reached: :class:`Within` a tolerance, :class:`AtMost` a
  limit (a stated reading of a qualitative claim), :class:`SameSign` (agrees in direction
  only), :class:`NotComparable` (with its reason) or :class:`BeyondThePaper` (acid's own
  measurement, no paper value);
* ``implies``: claims that must not disagree when this one agrees (the consistency check
  that keeps the report from contradicting itself).

:func:`evaluate` turns the registry and the typed stage results into :class:`ClaimVerdict`
objects; :func:`contradictions` lists violated implications; :func:`headline_markdown`
renders the README's headline table from a ``summary.json``.

Adding a claim (for a new stage or study): give the stage a result class in
:mod:`acid.stage_results`, then append a ``Claim`` to ``CLAIMS`` below (and, if it belongs in
the README, its id to a :class:`HeadlineRow` in ``HEADLINE``). ``python -m acid.claims``
lists the registry; ``python -m acid.claims summary.json`` prints the headline table.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
import sys
import typing
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

from acid.report.numbers import format_estimate, format_number
from acid.stage_results import (
    CavStudyStage,
    Estimate,
    FitStage,
    MpcStage,
    StageResult,
    StudyResults,
    SweepStage,
    ValidationStage,
    field_type,
)

PAPER_CITATION = ("H. Wang, I. Kolmanovsky, M. R. Amini and J. Sun, Model Predictive Climate "
                  "Control of Connected and Automated Vehicles for Improved Energy Efficiency, "
                  "ACC 2018")


# =============================================================================
# The paper's numbers (written here and nowhere else)
# =============================================================================
@dataclass(frozen=True)
class PaperTableI:
    """Table I: A/C energy of the nominal controller over ``duration_s`` at constant speeds.

    ``energy_MJ_per_km`` is None at standstill ("NA" in the paper).
    """

    speeds_mps: tuple[float, ...] = (0.0, 5.0, 10.0, 15.0, 20.0, 25.0)
    energy_MJ: tuple[float, ...] = (1.33, 1.23, 1.17, 1.13, 1.10, 1.07)
    energy_MJ_per_km: tuple[float | None, ...] = (None, 0.410, 0.195, 0.126, 0.092, 0.071)
    duration_s: float = 600.0
    #: section II-A: "the efficiency ... increases by approximately 30 %" from 0 to 25 m/s
    efficiency_gain_pct: float = 30.0

    def energy_at(self, speed_mps: float) -> float | None:
        """Table I energy (MJ) at ``speed_mps``, None if the paper has no such speed."""
        for v, e in zip(self.speeds_mps, self.energy_MJ, strict=True):
            if abs(v - float(speed_mps)) < 1e-9:
                return e
        return None


@dataclass(frozen=True)
class PaperModel:
    """Identified parameters (section II-B-2, eq. 5; kelvin convention, Ts = 5 s)."""

    gamma: tuple[float, ...] = (0.2451, 0.0867, 1.2999, 1.0047, -0.5176, 0.4553, 34.9579)
    tau: tuple[float, ...] = (-0.1842, -1.3226, 154.4995)
    beta: tuple[float, ...] = (24156.0, -1974.2, 49.318)


@dataclass(frozen=True)
class PaperTableII:
    """Table II (NMPC settings and constants) and the sample time of section III-A."""

    N: int = 6
    eta_cop: float = 3.5
    c_p: float = 1008.0
    T_amb_degC: float = 30.0
    T_evap_max_degC: float = 12.0
    W_bl_max: float = 0.15
    T_evap_set_max_degC: float = 10.0
    T_cab_min_degC: float = 20.0
    T_evap_min_degC: float = 0.0
    W_bl_min: float = 0.05
    T_evap_set_min_degC: float = 3.0
    slack_penalty: float = 1e5
    Ts: float = 5.0


@dataclass(frozen=True)
class PaperStudies:
    """Settings and results of the validation, the NMPC runs and the CAV case."""

    validation_starts: int = 60
    validation_horizon: int = 300
    #: "within a couple of degrees for most of the time"
    validation_error_K: float = 2.0
    closed_loop_duration_s: float = 125.0
    #: "average time ... less than one eighth of the sampling period"
    computation_fraction_of_Ts: float = 1.0 / 8.0
    cav_window_s: tuple[float, float] = (10.0, 85.0)
    cav_shutoff_s: tuple[float, float] = (60.0, 80.0)
    cav_case1_MJ: float = 0.113
    cav_case2_MJ: float = 0.124
    cav_saving_pct: float = 9.0


TABLE_I = PaperTableI()
MODEL = PaperModel()
TABLE_II = PaperTableII()
STUDIES = PaperStudies()


# =============================================================================
# Claims and rules
# =============================================================================
class Verdict(str, Enum):
    """How acid's measurement compares with the paper's result."""

    AGREES = "agrees"
    DIRECTION = "agrees in direction"
    DISAGREES = "disagrees"
    NOT_COMPARABLE = "not comparable"
    NOT_MEASURED = "not measured"
    BEYOND = "beyond the paper"


@dataclass(frozen=True)
class PaperValue:
    """A result as the paper states it.

    value : the number (None for a qualitative statement).
    unit : its unit ("1" for a ratio, "%" for a percentage).
    source : where in the paper ("Table I", "section IV-B, Fig. 7").
    text : the paper's words, for qualitative or approximate statements.
    spec : format of ``value`` in tables.
    """

    value: float | None
    unit: str
    source: str
    text: str = ""
    spec: str = ".3g"

    def display(self) -> str:
        if self.value is None:
            return f'"{self.text}"'
        return format_number(self.value, self.spec)


@dataclass(frozen=True)
class Requires:
    """A condition for comparability: the field at ``path`` equals ``value`` (else the
    claim is "not comparable" in this run, e.g. a ``--quick`` run's 300 s sweep)."""

    path: str
    value: float
    what: str


@dataclass(frozen=True)
class Measured:
    """Where acid measures a claim: ``stage`` result class and a field path in it.

    Paths are dotted field names with ``[i]`` indices into tuples and names as keys of
    dicts: ``"energy_MJ[2]"``, ``"channels.T_cab.p90_abs"``, ``"parameters.gamma1"``. A path
    ending at an :class:`acid.stage_results.Estimate` carries its standard error and 95 %
    interval into the report. ``spec`` formats the value; ``unit`` is its unit when the
    claim has no paper value (otherwise the paper's unit applies).
    """

    stage: type[StageResult]
    path: str
    requires: tuple[Requires, ...] = ()
    spec: str = ".3g"
    unit: str = ""

    def where(self) -> str:
        return f"{self.stage.STAGE}: {self.stage.__name__}.{self.path}"


class Rule:
    """Base of the verdict rules: ``judge(paper, acid) -> (Verdict, reason)``."""

    def judge(self, paper: float | None, acid: float, unit: str = "") -> tuple[Verdict, str]:
        """(verdict, reason) for acid's value against the paper's (both in ``unit``)."""
        raise NotImplementedError

    def describe(self, unit: str, paper: float | None = None) -> str:
        """The rule in words (``paper``: the paper's value, when the rule refers to it)."""
        raise NotImplementedError

    def to_json_dict(self) -> dict:
        return {"kind": type(self).__name__, **dataclasses.asdict(self)}


@dataclass(frozen=True)
class Within(Rule):
    """Agrees when ``|acid - paper| <= abs + rel |paper|``."""

    rel: float = 0.0
    abs: float = 0.0

    def describe(self, unit: str, paper: float | None = None) -> str:
        parts = []
        if self.rel:
            parts.append(f"{format_number(100 * self.rel, '.3g')} %")
        if self.abs:
            parts.append(f"{format_number(self.abs, '.3g')} {_unit(unit)}".rstrip())
        return "within " + " + ".join(parts or ["0"])

    def judge(self, paper, acid, unit=""):
        tol = self.abs + self.rel * abs(paper)
        diff = acid - paper
        rel = f" ({format_number(100 * diff / paper, '+.1f')} %)" if paper else ""
        u = " points" if unit == "%" else _unit_suffix(unit)
        off = f"off by {format_number(diff, '+.3g')}{u}{rel}"
        return (Verdict.AGREES if abs(diff) <= tol else Verdict.DISAGREES), off


@dataclass(frozen=True)
class AtMost(Rule):
    """Agrees when ``acid <= limit``; ``limit`` defaults to the paper's value, and
    ``reading`` states how a qualitative claim was turned into this limit."""

    limit: float | None = None
    reading: str = ""

    def describe(self, unit: str, paper: float | None = None) -> str:
        limit = paper if self.limit is None else self.limit
        lim = "the paper's value" if limit is None else \
            f"{format_number(limit, '.3g')}{_unit_suffix(unit)}"
        return f"at most {lim}" + (f", acid's reading of {self.reading}" if self.reading else "")

    def judge(self, paper, acid, unit=""):
        limit = paper if self.limit is None else self.limit
        ok = acid <= limit
        return (Verdict.AGREES if ok else Verdict.DISAGREES), \
            f"{'within' if ok else 'above'} the limit {format_number(limit, '.3g')}" \
            f"{_unit_suffix(unit)}"


@dataclass(frozen=True)
class SameSign(Rule):
    """Agrees in direction when acid's number has the paper's sign (magnitude not judged).

    ``meaning`` says what the paper's sign means ("Case 1 uses less energy than Case 2");
    ``deadband`` counts ``|acid| <= deadband`` as no direction at all.
    """

    meaning: str
    deadband: float = 0.0

    def describe(self, unit: str, paper: float | None = None) -> str:
        return f"same sign as the paper ({self.meaning}); magnitude not judged"

    def judge(self, paper, acid, unit=""):
        same = abs(acid) > self.deadband and math.copysign(1.0, acid) == math.copysign(1.0, paper)
        return (Verdict.DIRECTION if same else Verdict.DISAGREES), \
            (self.meaning if same else f"not so: {self.meaning} fails")


@dataclass(frozen=True)
class NotComparable(Rule):
    """acid measures the quantity, but the comparison means nothing (``reason`` says why)."""

    reason: str

    def describe(self, unit: str, paper: float | None = None) -> str:
        return "not compared"

    def judge(self, paper, acid, unit=""):
        return Verdict.NOT_COMPARABLE, self.reason


@dataclass(frozen=True)
class BeyondThePaper(Rule):
    """acid's own measurement of something the paper did not study (no verdict)."""

    def describe(self, unit: str, paper: float | None = None) -> str:
        return "no paper value"

    def judge(self, paper, acid, unit=""):
        return Verdict.BEYOND, "not studied in the paper"


@dataclass(frozen=True)
class Claim:
    """One result of the paper (or, with ``BeyondThePaper``, one of acid's own findings)."""

    id: str
    section: str
    quantity: str
    paper: PaperValue | None
    measured: Measured | None
    rule: Rule
    note: str = ""
    implies: tuple[str, ...] = ()

    @property
    def rule_text(self) -> str:
        """The verdict rule in words, with the paper's value where the rule refers to it."""
        return self.rule.describe(self.unit, self.paper.value if self.paper else None)

    @property
    def unit(self) -> str:
        if self.paper is not None:
            return self.paper.unit
        return self.measured.unit if self.measured is not None else ""

    def to_json_dict(self) -> dict:
        p = self.paper
        return {"id": self.id, "section": self.section, "quantity": self.quantity,
                "paper": None if p is None else {"value": p.value, "unit": p.unit,
                                                 "source": p.source, "text": p.text},
                "measured_at": None if self.measured is None else self.measured.where(),
                "requires": [dataclasses.asdict(r) for r in (self.measured.requires
                                                             if self.measured else ())],
                "rule": self.rule.to_json_dict(), "rule_text": self.rule_text,
                "note": self.note, "implies": list(self.implies)}


@dataclass(frozen=True)
class ClaimVerdict:
    """The verdict on one claim in one run."""

    claim: Claim
    verdict: Verdict
    value: float
    estimate: Estimate | None
    reason: str

    @property
    def acid_text(self) -> str:
        spec = self.claim.measured.spec if self.claim.measured else ".3g"
        if self.estimate is not None:
            e = self.estimate
            return format_estimate(e.value, e.stderr, e.ci95_low, e.ci95_high, spec)
        return format_number(self.value, spec) + _unit_suffix(self.claim.unit) \
            if math.isfinite(self.value) else "n/a"

    @property
    def paper_text(self) -> str:
        p = self.claim.paper
        if p is None:
            return "not studied"
        return p.display() + (_unit_suffix(p.unit) if p.value is not None else "")

    def to_json_dict(self) -> dict:
        d = self.claim.to_json_dict()
        d.update({"verdict": self.verdict.value, "reason": self.reason,
                  "acid": {"value": self.value if math.isfinite(self.value) else None,
                           **({"stderr": _none(self.estimate.stderr),
                               "ci95": [_none(self.estimate.ci95_low),
                                        _none(self.estimate.ci95_high)]}
                              if self.estimate is not None else {})},
                  "paper_text": self.paper_text, "acid_text": self.acid_text})
        return d


def _none(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _unit(unit: str) -> str:
    return "" if unit == "1" else unit


def _unit_suffix(unit: str) -> str:
    u = _unit(unit)
    return "" if not u else (" %" if u == "%" else f" {u}")


# =============================================================================
# Paths into the typed stage results
# =============================================================================
_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")


def _tokens(path: str) -> list[str | int]:
    out: list[str | int] = []
    for part in path.split("."):
        m = _TOKEN.fullmatch(part)
        if not m:
            raise ValueError(f"bad field path {path!r}")
        out.append(m[1])
        out += [int(i) for i in re.findall(r"\[(\d+)\]", m[2])]
    return out


def _strip_optional(tp):
    if typing.get_origin(tp) in (typing.Union, __import__("types").UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0]
    return tp


def check_path(stage: type, path: str) -> type:
    """The declared type at ``path`` in ``stage`` (``ValueError`` naming the bad part)."""
    tp = stage
    seen = stage.__name__
    for tok in _tokens(path):
        tp = _strip_optional(tp)
        origin = typing.get_origin(tp)
        if isinstance(tok, int):
            if origin is not tuple:
                raise ValueError(f"{seen} is not a tuple: cannot index [{tok}] ({path!r})")
            args = typing.get_args(tp)
            tp = args[0] if len(args) == 2 and args[1] is Ellipsis else args[tok]
        elif origin is dict:
            tp = typing.get_args(tp)[1]
        else:
            try:
                tp = field_type(tp, tok)
            except KeyError:
                raise ValueError(f"{seen} has no field {tok!r} ({stage.__name__}.{path})") \
                    from None
        seen = f"{seen}.{tok}" if isinstance(tok, str) else f"{seen}[{tok}]"
    tp = _strip_optional(tp)
    if tp not in (float, int, bool, Estimate):
        raise ValueError(f"{stage.__name__}.{path} is {tp!r}, not a number or an Estimate")
    return tp


def resolve(obj, path: str):
    """The value at ``path`` in ``obj`` (None when a part is missing or None)."""
    for tok in _tokens(path):
        if obj is None:
            return None
        if isinstance(tok, int):
            obj = obj[tok] if tok < len(obj) else None
        elif isinstance(obj, Mapping):
            obj = obj.get(tok)
        else:
            obj = getattr(obj, tok)
    return obj


# =============================================================================
# The registry
# =============================================================================
def _table_i_claims() -> list[Claim]:
    full = Requires("duration_s", TABLE_I.duration_s,
                    f"a {TABLE_I.duration_s:g} s run at each speed")
    out, per_km = [], []
    for i, (v, e, ekm) in enumerate(zip(TABLE_I.speeds_mps, TABLE_I.energy_MJ,
                                        TABLE_I.energy_MJ_per_km, strict=True)):
        at = Requires(f"speeds_mps[{i}]", v, f"{v:g} m/s")
        out.append(Claim(
            f"table1.energy.{v:g}mps", "Table I",
            f"A/C energy over {TABLE_I.duration_s:g} s at {v:g} m/s",
            PaperValue(e, "MJ", "Table I", spec=".2f"),
            Measured(SweepStage, f"energy_MJ[{i}]", (full, at), ".3f"), Within(rel=0.05)))
        if ekm is not None:
            per_km.append(Claim(
                f"table1.per_km.{v:g}mps", "Table I", f"A/C energy per distance at {v:g} m/s",
                PaperValue(ekm, "MJ/km", "Table I", spec=".3f"),
                Measured(SweepStage, f"energy_MJ_per_km[{i}]", (full, at), ".3f"),
                Within(rel=0.05)))
    out += per_km
    e0, e_last = TABLE_I.energy_MJ[0], TABLE_I.energy_MJ[-1]
    steps = [b - a for a, b in zip(TABLE_I.energy_MJ, TABLE_I.energy_MJ[1:], strict=False)]
    out += [
        Claim("table1.ratio", "Table I",
              f"E({TABLE_I.speeds_mps[-1]:g} m/s) / E({TABLE_I.speeds_mps[0]:g} m/s)",
              PaperValue(e_last / e0, "1", "Table I", spec=".3f"),
              Measured(SweepStage, "ratio_last_first", (full,), ".3f"), Within(abs=0.03),
              note="ram air through the condenser lowers the condensing pressure"),
        Claim("table1.falls_with_speed", "Table I",
              "largest change of energy from one speed to the next",
              PaperValue(max(steps), "MJ", "Table I", spec="+.2f"),
              Measured(SweepStage, "max_energy_step_MJ", (), "+.3f"),
              SameSign("the energy falls with every speed step")),
        Claim("table1.efficiency_gain", "Table I",
              f"efficiency gain from {TABLE_I.speeds_mps[0]:g} to "
              f"{TABLE_I.speeds_mps[-1]:g} m/s, E(0) / E(25) - 1",
              PaperValue(TABLE_I.efficiency_gain_pct, "%", "section II-A",
                         "increases by approximately 30 %", spec=".0f"),
              Measured(SweepStage, "efficiency_gain_pct", (full,), ".1f"), Within(abs=10.0),
              note=f"the paper's own Table I gives {100 * (e0 / e_last - 1):.0f} %"),
    ]
    return out


def _identification_claims() -> list[Claim]:
    why = "acid's plant is not CoolSim: identified values depend on the plant"
    out = []
    for name, values, unit in (("gamma", MODEL.gamma, None), ("tau", MODEL.tau, "K")):
        for i, v in enumerate(values, start=1):
            out.append(Claim(
                f"identification.{name}{i}", "Identification (eqs. 1-3)", f"{name}{i}",
                PaperValue(v, unit or _GAMMA_UNITS[i - 1], "section II-B-2", spec=".7g"),
                Measured(FitStage, f"parameters.{name}{i}", spec=".4g"), NotComparable(why)))
    for i, v in enumerate(MODEL.beta, start=1):
        out.append(Claim(
            f"identification.beta{i}", "Identification (eq. 5)", f"beta{i}",
            PaperValue(v, _BETA_UNITS[i - 1], "eq. 5", spec=".7g"),
            Measured(FitStage, f"parameters.beta{i}", spec=".5g"),
            NotComparable("acid's plant uses the paper's eq. 5 for its blower: recovering it "
                          "checks the estimator, not the plant")))
    return out


_GAMMA_UNITS = ("1", "1", "s/kg", "1", "1", "1", "K s/kg")
_BETA_UNITS = ("W s^2/kg^2", "W s/kg", "W")


def _validation_claims() -> list[Claim]:
    req = (Requires("starts", STUDIES.validation_starts,
                    f"{STUDIES.validation_starts} starts"),
           Requires("horizon", STUDIES.validation_horizon,
                    f"{STUDIES.validation_horizon}-step predictions"))
    return [Claim(
        f"validation.{ch}", "Validation (Figs. 5-6)",
        f"{ch}: 90th percentile of |error| over {STUDIES.validation_horizon}-step "
        f"predictions from {STUDIES.validation_starts} starts",
        PaperValue(STUDIES.validation_error_K, "K", "section II-B-3, Fig. 6",
                   "within a couple of degrees for most of the time", spec=".0f"),
        Measured(ValidationStage, f"channels.{ch}.p90_abs", req, ".2f"),
        AtMost(reading="'a couple of degrees for most of the time' as the 90th "
                       "percentile"))
        for ch in ("T_cab", "T_evap", "T_ain")]


def _nmpc_claims() -> list[Claim]:
    Ts_ms = 1000.0 * TABLE_II.Ts
    return [
        Claim("nmpc.model.violation", "NMPC on the model (Fig. 7)",
              "largest state-bound violation after the first step",
              PaperValue(0.0, "K", "section IV-B, Fig. 7",
                         "all the constraints ... are satisfied", spec=".0f"),
              Measured(MpcStage, "model.max_violation_K", spec=".4f"),
              AtMost(limit=0.01, reading="'satisfied'")),
        Claim("nmpc.model.rides_bound", "NMPC on the model (Fig. 7)",
              "|T_cab - upper bound| over the last 20 s",
              PaperValue(0.0, "K", "section IV-B, Fig. 7",
                         "the cabin temperature approaches the upper limits in steady state",
                         spec=".0f"),
              Measured(MpcStage, "model.ride_error_K", spec=".4f"),
              AtMost(limit=0.05, reading="'approaches'")),
        Claim("nmpc.plant.violation", "NMPC on the plant (Fig. 8)",
              "largest state-bound violation after the first step",
              PaperValue(None, "K", "section IV-B, Fig. 8",
                         "satisfied during most of the simulation period, with slight "
                         "violations at some time instants"),
              Measured(MpcStage, "plant.max_violation_K", spec=".3f"),
              AtMost(limit=0.5, reading="'slight violations'")),
        Claim("nmpc.computation", "Computation",
              "NMPC time per step (acid: the largest, which bounds the average)",
              PaperValue(Ts_ms * STUDIES.computation_fraction_of_Ts, "ms", "section IV-B",
                         "average time ... less than one eighth of the sampling period "
                         "(2.2 GHz laptop, MPCTools)", spec=".0f"),
              Measured(MpcStage, "timing.max_ms", spec=".2f"), AtMost()),
    ]


def _cav_claims() -> list[Claim]:
    s = STUDIES
    w = f"{s.cav_window_s[0]:g}-{s.cav_window_s[1]:g} s"
    light = ("the paper does not publish the initial state or the loads of this case; "
             "acid's start (cabin 24 degC, interior 26 degC) is a light load")
    return [
        Claim("cav.case1_energy", "CAV case (Figs. 9-10)",
              f"A/C energy over {w}, Case 1 (ICM bound)",
              PaperValue(s.cav_case1_MJ, "MJ", "section IV-C", spec=".3f"),
              Measured(MpcStage, "cav_paper.case1_energy_MJ", spec=".4f"), Within(rel=0.25),
              note=light),
        Claim("cav.case2_energy", "CAV case (Figs. 9-10)",
              f"A/C energy over {w}, Case 2 (constant bound)",
              PaperValue(s.cav_case2_MJ, "MJ", "section IV-C", spec=".3f"),
              Measured(MpcStage, "cav_paper.case2_energy_MJ", spec=".4f"), Within(rel=0.25),
              note=light),
        Claim("cav.case1_below_case2", "CAV case (Figs. 9-10)",
              "energy of Case 2 minus Case 1",
              PaperValue(s.cav_case2_MJ - s.cav_case1_MJ, "MJ", "section IV-C", spec="+.3f"),
              Measured(MpcStage, "cav_paper.energy_difference_MJ", spec="+.4f"),
              SameSign("Case 1 uses less energy than Case 2")),
        Claim("cav.saving", "CAV case (Figs. 9-10)", "energy saving of Case 1 over Case 2",
              PaperValue(s.cav_saving_pct, "%", "section IV-C, abstract", spec=".0f"),
              Measured(MpcStage, "cav_paper.saving_pct", spec=".1f"), Within(rel=0.5),
              implies=("cav.case1_below_case2",),
              note="over a fixed window Case 1 ends warmer: part of its saving is heat left "
                   "in the cabin"),
        Claim("cav.saving_from_speed", "CAV case (Figs. 9-10)",
              "part of the saving owed to speed-dependent A/C efficiency (plant minus "
              "speed-blind twin)",
              PaperValue(s.cav_saving_pct, "%", "abstract, conclusions",
                         "by utilizing the vehicle speed preview ... improvements of up to 9 %",
                         spec=".0f"),
              Measured(MpcStage, "cav_paper.saving_from_speed_pct", spec=".1f"),
              Within(rel=0.5),
              note="the paper attributes its saving to speed preview; acid measures what "
                   "disappears when the plant's efficiency no longer depends on speed"),
        Claim("cav.periodic_saving", "Beyond the paper",
              "CAV saving over repeated stop-and-go cycles (stored heat cancels)", None,
              Measured(MpcStage, "cav_periodic.saving_pct", spec=".1f", unit="%"),
              BeyondThePaper(),
              note="the stop-and-go cycle repeated; energy over all cycles but the first, "
                   "whose boundaries see the same cabin state in both cases"),
        Claim("cav.end_T_cab_difference", "Beyond the paper",
              f"T_cab of Case 1 minus Case 2 at the end of the {w} window", None,
              Measured(MpcStage, "cav_paper.T_cab_end_difference_K", spec="+.2f", unit="K"),
              BeyondThePaper(),
              note="heat Case 1 leaves in the cabin: part of its saving in the paper's window"),
    ]


_CYCLE_NOTE = ("acid cav-study: the constant bound tuned to the ICM case's mean T_cab; the "
               "heat left at the end charged back by a measured continuation")


def _cycle_claims() -> list[Claim]:
    out = []
    for key, label in (("B", "ICM bound"), ("C", "speed-aware NMPC")):
        for kind, what in (("raw", "raw"), ("tail_corrected", "end state charged back")):
            out.append(Claim(
                f"cycle.{key}.{kind}", "Beyond the paper",
                f"drive cycle at equal mean T_cab: {label} saving vs constant bound, {what}",
                None, Measured(CavStudyStage, f"savings_pct.{key}.{kind}", spec=".2f", unit="%"),
                BeyondThePaper(), note=_CYCLE_NOTE))
    out.append(Claim(
        "cycle.B.from_speed", "Beyond the paper",
        "drive cycle: part of the ICM saving owed to speed, end state charged back",
        None, Measured(CavStudyStage, "saving_from_speed_pct.B.tail_corrected", spec=".2f",
                       unit="points"),
        BeyondThePaper(), note="saving on the plant minus the same on its speed-blind twin"))
    return out


CLAIMS: tuple[Claim, ...] = tuple(
    _table_i_claims() + _identification_claims() + _validation_claims() + _nmpc_claims()
    + _cav_claims() + _cycle_claims())


@dataclass(frozen=True)
class HeadlineRow:
    """One row of the README's headline table: claims shown together, verdicts combined."""

    label: str
    claims: tuple[str, ...]


def _ids(prefix: str, claims: Sequence[Claim] = CLAIMS) -> tuple[str, ...]:
    return tuple(c.id for c in claims if c.id.startswith(prefix))


HEADLINE: tuple[HeadlineRow, ...] = (
    HeadlineRow("Table I: A/C energy over 600 s at "
                + " / ".join(f"{v:g}" for v in TABLE_I.speeds_mps) + " m/s (MJ)",
                _ids("table1.energy.")),
    HeadlineRow("Table I: per distance at "
                + " / ".join(f"{v:g}" for v in TABLE_I.speeds_mps[1:]) + " m/s (MJ/km)",
                _ids("table1.per_km.")),
    HeadlineRow("E(25 m/s) / E(0 m/s); energy falls with speed",
                ("table1.ratio", "table1.falls_with_speed")),
    HeadlineRow("identified gamma1..7 (kelvin convention)", _ids("identification.gamma")),
    HeadlineRow("identified tau1..3 (K)", _ids("identification.tau")),
    HeadlineRow("300-step prediction error, 60 starts: p90 |error| of T_cab / T_evap / T_ain",
                _ids("validation.")),
    HeadlineRow("NMPC on the model (Fig. 7): largest violation after the first step",
                ("nmpc.model.violation",)),
    HeadlineRow("NMPC on the plant (Fig. 8): largest violation after the first step",
                ("nmpc.plant.violation",)),
    HeadlineRow("CAV case, energy over 10-85 s, Case 1 (ICM) / Case 2 (constant bound)",
                ("cav.case1_energy", "cav.case2_energy")),
    HeadlineRow("CAV case: Case 1 uses less energy than Case 2 (difference)",
                ("cav.case1_below_case2",)),
    HeadlineRow("CAV saving", ("cav.saving",)),
    HeadlineRow("CAV saving owed to speed-dependent efficiency", ("cav.saving_from_speed",)),
    HeadlineRow("NMPC computation per step", ("nmpc.computation",)),
    HeadlineRow("*beyond the paper*: CAV saving over repeated cycles (stored heat cancels)",
                ("cav.periodic_saving",)),
    HeadlineRow("*beyond the paper*: drive cycle at equal mean T_cab, ICM bound / speed-aware "
                "NMPC saving vs a constant bound, end state charged back",
                ("cycle.B.tail_corrected", "cycle.C.tail_corrected")),
)


def claim(claim_id: str, claims: Sequence[Claim] = CLAIMS) -> Claim:
    """The claim with id ``claim_id`` (``KeyError`` if the registry has none)."""
    for c in claims:
        if c.id == claim_id:
            return c
    raise KeyError(f"no claim {claim_id!r} in the registry")


def validate_registry(claims: Sequence[Claim] = CLAIMS,
                      headline: Sequence[HeadlineRow] = HEADLINE) -> None:
    """Check ids are unique, paths exist in their stage classes, implications and headline
    rows name known claims (``ValueError`` on the first problem)."""
    ids = Counter(c.id for c in claims)
    dup = [i for i, n in ids.items() if n > 1]
    if dup:
        raise ValueError(f"duplicate claim ids: {dup}")
    for c in claims:
        if c.measured is not None:
            check_path(c.measured.stage, c.measured.path)
            for r in c.measured.requires:
                check_path(c.measured.stage, r.path)
        if (c.paper is None) != isinstance(c.rule, BeyondThePaper):
            raise ValueError(f"claim {c.id}: BeyondThePaper is for claims without a paper "
                             "value, and only for them")
        for j in c.implies:
            if j not in ids:
                raise ValueError(f"claim {c.id} implies unknown claim {j!r}")
    for row in headline:
        for j in row.claims:
            if j not in ids:
                raise ValueError(f"headline row {row.label!r} names unknown claim {j!r}")


validate_registry()


# =============================================================================
# Evaluation
# =============================================================================
def judge(claim: Claim, results: StudyResults) -> ClaimVerdict:
    """The verdict on one claim from the typed stage results."""
    m = claim.measured
    if m is None:
        return ClaimVerdict(claim, Verdict.NOT_MEASURED, math.nan, None,
                            "acid does not measure this")
    res = results.get(m.stage)
    if res is None:
        return ClaimVerdict(claim, Verdict.NOT_MEASURED, math.nan, None,
                            f"stage {m.stage.STAGE!r} did not run")
    raw = resolve(res, m.path)
    est = raw if isinstance(raw, Estimate) else None
    value = est.value if est is not None else (math.nan if raw is None else float(raw))
    if not math.isfinite(value):
        return ClaimVerdict(claim, Verdict.NOT_MEASURED, value, est, _why_missing(res, m.path))
    for r in m.requires:
        have = resolve(res, r.path)
        if have is None or abs(float(have) - r.value) > 1e-9 * max(1.0, abs(r.value)):
            return ClaimVerdict(claim, Verdict.NOT_COMPARABLE, value, est,
                                f"this run has {r.path} = {format_number(have, 'g')}; the "
                                f"paper's result is for {r.what}")
    paper = claim.paper.value if claim.paper is not None else None
    verdict, reason = claim.rule.judge(paper, value, claim.unit)
    return ClaimVerdict(claim, verdict, value, est, reason)


def _why_missing(res, path: str) -> str:
    head = path.split(".")[0]
    skipped = getattr(getattr(res, head, None), "skipped", None)
    return f"not measured: {skipped}" if skipped else f"not measured in this run ({path})"


def evaluate(results: StudyResults, claims: Iterable[Claim] | None = None
             ) -> list[ClaimVerdict]:
    """Verdicts on every claim of ``claims`` (default: the registry ``CLAIMS``, in order)."""
    return [judge(c, results) for c in (CLAIMS if claims is None else claims)]


def contradictions(verdicts: Sequence[ClaimVerdict]) -> list[str]:
    """Violated implications: a claim that agrees while a claim it implies disagrees."""
    by_id = {v.claim.id: v for v in verdicts}
    out = []
    for v in verdicts:
        if v.verdict is not Verdict.AGREES:
            continue
        for j in v.claim.implies:
            w = by_id.get(j)
            if w is not None and w.verdict is Verdict.DISAGREES:
                out.append(f"{v.claim.id} agrees but {j}, which it implies, disagrees")
    return out


def counts(verdicts: Iterable[ClaimVerdict]) -> dict[str, int]:
    """{verdict: number of claims} for every verdict kind (zeros included)."""
    c = Counter(v.verdict.value for v in verdicts)
    return {k.value: int(c.get(k.value, 0)) for k in Verdict}


def summary_claims(verdicts: Sequence[ClaimVerdict]) -> dict:
    """The ``claims`` block of ``summary.json``: every verdict, the counts, contradictions."""
    return {"registry": "acid.claims", "paper": PAPER_CITATION,
            "counts": counts(verdicts), "contradictions": contradictions(verdicts),
            "items": [v.to_json_dict() for v in verdicts]}


# =============================================================================
# The README headline table (from summary.json alone)
# =============================================================================
def _combined_verdict(items: Sequence[Mapping]) -> str:
    verdicts = [i["verdict"] for i in items]
    kinds = Counter(verdicts)
    if len(kinds) == 1:
        v = verdicts[0]
        rule = items[0]["rule_text"]
        if v == Verdict.BEYOND.value:
            return "—"
        if v in (Verdict.NOT_COMPARABLE.value, Verdict.NOT_MEASURED.value):
            reasons = {i["reason"] for i in items}
            return f"{v}: {reasons.pop()}" if len(reasons) == 1 else v
        same_rule = all(i["rule_text"] == rule for i in items)
        scope = ("each " if len(items) > 1 else "") + rule if same_rule else ""
        if not scope or v == Verdict.DIRECTION.value:
            return v
        return f"{v} ({scope})" if v == Verdict.AGREES.value else f"{v} (rule: {scope})"
    return "mixed: " + ", ".join(f"{n} {k}" for k, n in kinds.items())


def headline_rows(summary: Mapping, headline: Sequence[HeadlineRow] = HEADLINE
                  ) -> list[tuple[str, str, str, str]]:
    """(result, paper, acid, verdict) per headline row, from a ``summary.json`` dict."""
    items = {i["id"]: i for i in summary["claims"]["items"]}
    rows = []
    for row in headline:
        its = [items[j] for j in row.claims if j in items]
        if not its:
            continue
        paper = " / ".join(i["paper_text"] for i in its)
        if len({i["paper_text"] for i in its}) == 1 and len(its) > 1:
            paper = its[0]["paper_text"]
        acid = " / ".join(_compact(i["acid_text"]) for i in its)
        rows.append((row.label, paper, acid, _combined_verdict(its)))
    return rows


def _compact(text: str) -> str:
    """An estimate without its interval (the headline keeps value ± stderr)."""
    return text.split(" [", 1)[0]


def headline_markdown(summary: Mapping, headline: Sequence[HeadlineRow] = HEADLINE) -> str:
    """The README's headline table as markdown, from a ``summary.json`` dict."""
    c = summary["claims"]["counts"]
    lines = ["| result | paper | acid | verdict |", "|---|---|---|---|"]
    for r in headline_rows(summary, headline):
        lines.append("| " + " | ".join(x.replace("|", "\\|") for x in r) + " |")
    lines.append("")
    lines.append(f"{c['agrees']} claims agree, {c['agrees in direction']} agree in direction "
                 f"only, {c['disagrees']} disagree, {c['not comparable']} are not comparable"
                 + (f", {c['not measured']} not measured" if c["not measured"] else "")
                 + f" ({len(summary['claims']['items'])} registry entries, "
                 f"{c['beyond the paper']} beyond the paper).")
    return "\n".join(lines) + "\n"


def registry_rows(claims: Sequence[Claim] = CLAIMS) -> list[tuple[str, str, str, str, str]]:
    """(id, paper value, where acid measures it, rule, note) for listing the registry."""
    rows = []
    for c in claims:
        paper = "—" if c.paper is None else (
            c.paper.display() + _unit_suffix(c.paper.unit) if c.paper.value is not None
            else c.paper.display())
        rows.append((c.id, paper, c.measured.where() if c.measured else "—",
                     c.rule_text, c.note or getattr(c.rule, "reason", "")))
    return rows


def load_summary(path: str | Path) -> dict:
    """A ``summary.json`` of ``acid reproduce`` (``DataError`` naming the file if it is not)."""
    from acid.errors import DataError

    path = Path(path)
    try:
        summary = json.loads(path.read_text())
    except FileNotFoundError:
        raise DataError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{path}: not a JSON file ({exc.__class__.__name__})") from None
    if not isinstance(summary, dict) or not isinstance(summary.get("claims"), dict):
        raise DataError(f"{path}: no 'claims' block (not a summary.json of acid reproduce)")
    return summary


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m acid.claims [summary.json]``: the registry, or the headline table."""
    from acid.errors import AcidError

    argv = list(sys.argv[1:] if argv is None else argv)
    if argv:
        try:
            summary = load_summary(argv[0])
        except AcidError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        sys.stdout.write(headline_markdown(summary))
        return 0
    for row in registry_rows():
        print(" | ".join(row))
    return 0


if __name__ == "__main__":
    sys.exit(main())


__all__ = ["CLAIMS", "HEADLINE", "MODEL", "STUDIES", "TABLE_I", "TABLE_II", "AtMost",
           "BeyondThePaper", "Claim", "ClaimVerdict", "claim", "HeadlineRow", "Measured",
           "NotComparable", "PaperValue", "Requires", "Rule", "SameSign", "Verdict", "Within",
           "contradictions", "counts", "evaluate", "headline_markdown", "judge", "load_summary",
           "summary_claims", "validate_registry"]
