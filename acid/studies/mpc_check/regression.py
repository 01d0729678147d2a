"""Stored regression references for the closed loops of ``acid mpc-check``.

Short runs of the three scenarios with the paper's parameters (:func:`measure`): (a) on the
control-oriented model (125 s, both initial conditions), (b) on the high-fidelity plant
(60 s, both initial conditions) and (c) the CAV paper comparison (Case 1 and Case 2, 100 s,
no counterfactual). For each run: the A/C energy (MJ), the largest violation after the
first step and at the first step (K) and the first move (W_bl kg/s, T_evap_set K).

``tests/references/closed_loop.json`` stores these numbers with their tolerances;
``tests/test_regression_references.py`` fails when a closed loop drifts beyond them (an
energy by more than 2 %). When a change is intended (a new plant, a new controller), run::

    python -m acid.studies.mpc_check.regression --update

which re-measures, prints what changed against the stored file, and rewrites it (keeping the
stored tolerances); commit the diff with the change that caused it.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

from acid import __version__
from acid._io import write_json
from acid.numbers import format_number

#: the stored references of a source checkout
REFERENCE_FILE = Path(__file__).resolve().parents[3] / "tests" / "references" / "closed_loop.json"


@dataclass(frozen=True)
class Tolerance:
    """``|now - reference| <= abs + rel |reference|``."""

    rel: float = 0.0
    abs: float = 0.0

    def allows(self, ref: float, now: float) -> bool:
        if not (math.isfinite(ref) and math.isfinite(now)):
            return math.isnan(ref) and math.isnan(now)
        return abs(now - ref) <= self.abs + self.rel * abs(ref)

    def describe(self) -> str:
        parts = ([f"{100 * self.rel:g} %"] if self.rel else []) + \
            ([f"{self.abs:g}"] if self.abs else [])
        return " + ".join(parts) or "exact"


#: default tolerances per quantity (used when the stored file has none)
TOLERANCES: dict[str, Tolerance] = {
    "energy_MJ": Tolerance(rel=0.02),
    "max_violation_K": Tolerance(rel=0.05, abs=0.01),
    "first_step_violation_K": Tolerance(rel=0.05, abs=0.01),
    "first_W_bl_kg_s": Tolerance(abs=1e-3),
    "first_T_evap_set_K": Tolerance(abs=0.05),
}


def _run_numbers(run, window=None) -> dict[str, float]:
    return {"energy_MJ": run.energy_J(window) / 1e6,
            "max_violation_K": run.max_violation_K,
            "first_step_violation_K": run.first_step_violation_K,
            "first_W_bl_kg_s": float(run.W_bl[0]),
            "first_T_evap_set_K": float(run.T_evap_set[0])}


def measure(plant_duration_s: float = 60.0) -> dict[str, dict[str, float]]:
    """{case: {quantity: value}} of the short reference runs (paper parameters, defaults)."""
    from acid.models.params import paper
    from acid.studies.mpc_check.scenarios import (
        cav_scenario,
        make_hifi,
        run_cav_comparison,
        run_model_scenario,
        run_plant_scenario,
    )

    p = paper()
    out: dict[str, dict[str, float]] = {}
    for run in run_model_scenario(p).runs:
        out[f"model.{run.label.replace(' ', '_')}"] = _run_numbers(run)
    for run in run_plant_scenario(p, duration_s=plant_duration_s).runs:
        out[f"plant.{run.label.replace(' ', '_')}"] = _run_numbers(run)
    sc = cav_scenario(p, cycles=1)
    comp = run_cav_comparison(sc, sc.comparisons[0], make_hifi)
    out["cav.case1"] = _run_numbers(comp.case1, comp.spec.window_s)
    out["cav.case2"] = _run_numbers(comp.case2, comp.spec.window_s)
    return out


@dataclass(frozen=True)
class Drift:
    """One stored number against the current one."""

    case: str
    quantity: str
    reference: float
    now: float
    tolerance: Tolerance

    @property
    def ok(self) -> bool:
        return self.tolerance.allows(self.reference, self.now)

    def describe(self) -> str:
        if math.isnan(self.reference):
            return f"{self.case} {self.quantity}: new, {self.now:.6g}"
        if math.isnan(self.now):
            return f"{self.case} {self.quantity}: {self.reference:.6g}, no longer measured"
        rel = (f" ({format_number(100 * (self.now - self.reference) / self.reference, '+.2f')}"
               " %)" if self.reference else "")
        return (f"{self.case} {self.quantity}: {self.reference:.6g} -> {self.now:.6g}{rel}, "
                f"tolerance {self.tolerance.describe()}")


def tolerances_of(stored: dict) -> dict[str, Tolerance]:
    """The tolerances of a stored reference (defaults for quantities it does not name)."""
    tol = dict(TOLERANCES)
    for k, v in (stored.get("tolerances") or {}).items():
        tol[k] = Tolerance(rel=float(v.get("rel", 0.0)), abs=float(v.get("abs", 0.0)))
    return tol


def compare(stored: dict, measured: dict[str, dict[str, float]]) -> list[Drift]:
    """Every stored number beside the measured one (missing cases or quantities are NaN)."""
    tol = tolerances_of(stored)
    out = []
    cases = stored.get("cases", {})
    for case in sorted(set(cases) | set(measured)):
        ref, now = cases.get(case, {}), measured.get(case, {})
        for q in sorted(set(ref) | set(now)):
            out.append(Drift(case, q, float(ref.get(q, math.nan)),
                             float(now.get(q, math.nan)), tol.get(q, Tolerance())))
    return out


def load(path: Path = REFERENCE_FILE) -> dict:
    return json.loads(Path(path).read_text())


def reference_dict(measured: dict[str, dict[str, float]], tolerances: dict[str, Tolerance]
                   ) -> dict:
    """The JSON written to the reference file."""
    return {"generated_by": "python -m acid.studies.mpc_check.regression --update",
            "acid_version": __version__,
            "about": "short closed loops of acid mpc-check with the paper's parameters "
                     "(acid.studies.mpc_check.regression.measure); energies MJ, violations K, "
                     "first moves kg/s and K",
            "tolerances": {k: {"rel": t.rel, "abs": t.abs} for k, t in tolerances.items()},
            "cases": measured}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m acid.studies.mpc_check.regression",
                                 description="Check (default) or --update the stored "
                                             "closed-loop regression references.")
    ap.add_argument("--update", action="store_true", help="rewrite the reference file")
    ap.add_argument("--file", type=Path, default=REFERENCE_FILE, help="reference JSON")
    args = ap.parse_args(argv)
    if not args.file.is_file() and not args.update:
        print(f"error: {args.file}: no reference file (a source checkout has "
              "tests/references/closed_loop.json; --file PATH, or --update to create one)",
              file=sys.stderr)
        return 2
    stored = load(args.file) if args.file.is_file() else {}
    measured = measure()
    drifts = compare(stored, measured)
    changed = [d for d in drifts if not (d.reference == d.now)]
    for d in changed:
        print(("  " if d.ok else "! ") + d.describe())
    bad = [d for d in drifts if not d.ok]
    print(f"{len(drifts)} numbers, {len(changed)} changed, {len(bad)} beyond tolerance")
    if args.update:
        write_json(args.file, reference_dict(measured, tolerances_of(stored)))
        print(f"references written to {args.file}")
        return 0
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
