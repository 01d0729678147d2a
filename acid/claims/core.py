"""What a claim is and how its verdict is reached (the registry itself is in
:mod:`acid.claims.registry`).

A :class:`Claim` is one result of the paper: its value (:class:`PaperValue`), where acid
measures it (:class:`Measured`: a typed stage result class of :mod:`acid.claims.results` and
a field path, with :class:`Requires` conditions for comparability) and the :class:`Rule` of
its verdict (:class:`Within`, :class:`AtMost`, :class:`SameSign`, :class:`NotComparable`,
:class:`BeyondThePaper`). :func:`judge` applies it to the results of one run.
"""

from __future__ import annotations

import abc
import dataclasses
import math
import re
import types
import typing
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import Enum

from acid.claims.results import Estimate, StageResult, StudyResults, field_type
from acid.numbers import format_estimate, format_number


class Verdict(str, Enum):
    """How acid's measurement compares with the paper's result."""

    AGREES = "agrees"
    DIRECTION = "agrees in direction"
    DISAGREES = "disagrees"
    NOT_COMPARABLE = "not comparable"
    NOT_MEASURED = "not measured"
    BEYOND = "beyond the paper"
    NOT_JUDGED = "not judged (quick run)"


#: verdicts that say nothing about agreement (shown with their reason, never as a verdict)
NO_VERDICT = (Verdict.NOT_COMPARABLE, Verdict.NOT_MEASURED, Verdict.NOT_JUDGED)


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
    ending at an :class:`acid.claims.results.Estimate` carries its standard error and 95 %
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


class Rule(abc.ABC):
    """Base of the verdict rules: ``judge(paper, acid) -> (Verdict, reason)``."""

    @abc.abstractmethod
    def judge(self, paper: float | None, acid: float, unit: str = "") -> tuple[Verdict, str]:
        """(verdict, reason) for acid's value against the paper's (both in ``unit``)."""

    @abc.abstractmethod
    def describe(self, unit: str, paper: float | None = None) -> str:
        """The rule in words (``paper``: the paper's value, when the rule refers to it)."""

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
        u = " points" if unit == "%" else unit_suffix(unit)
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
            f"{format_number(limit, '.3g')}{unit_suffix(unit)}"
        return f"at most {lim}" + (f", acid's reading of {self.reading}" if self.reading else "")

    def judge(self, paper, acid, unit=""):
        limit = paper if self.limit is None else self.limit
        ok = acid <= limit
        return (Verdict.AGREES if ok else Verdict.DISAGREES), \
            f"{'within' if ok else 'above'} the limit {format_number(limit, '.3g')}" \
            f"{unit_suffix(unit)}"


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
        return format_number(self.value, spec) + unit_suffix(self.claim.unit) \
            if math.isfinite(self.value) else "n/a"

    @property
    def paper_text(self) -> str:
        p = self.claim.paper
        if p is None:
            return "not studied"
        return p.display() + (unit_suffix(p.unit) if p.value is not None else "")

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


def unit_suffix(unit: str) -> str:
    u = _unit(unit)
    return "" if not u else (" %" if u == "%" else f" {u}")



# ------------------------------------------------------------ paths into stage results
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
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
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



# ------------------------------------------------------------------------ verdicts
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


def not_judged(v: ClaimVerdict, why: str) -> ClaimVerdict:
    """``v`` as "not judged (quick run)": the value kept, the verdict withheld (a claim that
    was not measured, or that the paper's study cannot be compared with anyway, keeps its
    own verdict)."""
    if v.verdict is Verdict.NOT_MEASURED or isinstance(v.claim.rule, NotComparable):
        return v
    return dataclasses.replace(v, verdict=Verdict.NOT_JUDGED, reason=why)


def _why_missing(res, path: str) -> str:
    head = path.split(".")[0]
    skipped = getattr(getattr(res, head, None), "skipped", None)
    return f"not measured: {skipped}" if skipped else f"not measured in this run ({path})"


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
