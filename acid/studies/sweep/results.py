"""Sweep results on disk: one JSON record per finished scenario, then one tidy table.

``OUT/scenarios/<key>.json`` is written (atomically) the moment a scenario finishes, so an
interrupted sweep keeps everything it finished. A rerun skips every scenario that has a
record: ``"ok"``, or ``"error"`` (it ran, and a controller or the plant raised: running it
again gives the same error; ``retry_failed`` does). Records of tasks that never reported
(``"lost"``: a worker died, the cluster went away) are always run again. The key is the hash
of the scenario, its controllers, its parameters and acid's version
(:meth:`acid.studies.sweep.spec.SweepSpec.scenario_key`).

The table has one row per scenario x controller: the scenario's conditions, the controller,
``status``/``error``, energy (MJ, and MJ/km), savings against the baseline (%, raw and with
the end state charged back), cabin temperatures (degC), comfort violations (K s, K), solve
times (ms) and provenance (scenario key, parameters, worker, acid version, elapsed s).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from acid._io import atomic_path, write_json
from acid.studies.verdict import paired_verdict

#: columns first in the table, in this order (the rest follow alphabetically)
LEADING = ("scenario", "label", "cycle", "duration_s", "ambient_C", "humidity_pct",
           "solar_W_m2", "refrigerant", "setpoint_C", "band_low_C", "band_high_C",
           "warmup_s", "tail_s", "params", "plant", "controller", "controller_type",
           "baseline", "status", "error", "energy_MJ", "saving_pct",
           "saving_tail_corrected_pct", "energy_MJ_per_km", "energy_with_fan_MJ",
           "mean_T_cab_C", "max_T_cab_C", "min_T_cab_C", "end_T_cab_C",
           "comfort_violation_Ks", "max_comfort_violation_K", "max_state_violation_K",
           "solve_ms_median", "solve_ms_p95", "solve_ms_max", "fallbacks", "steps",
           "distance_km", "tail_energy_MJ")


#: statuses of a record and of its rows
STATUSES = ("ok", "error", "lost")
#: row entries that must be numbers (or null) and texts (or null) in a record
NUMERIC = tuple(c for c in LEADING if c not in (
    "label", "cycle", "refrigerant", "params", "plant", "controller", "controller_type",
    "baseline", "status", "error")) + ("solve_ms_median",)
TEXT = ("label", "refrigerant", "params", "controller", "controller_type", "baseline",
        "status", "error")
#: largest record file read back, bytes (a record is a few kB)
MAX_RECORD_BYTES = 4 * 1024 * 1024


def record_problem(rec, key: str, controllers: tuple[str, ...] | None = None) -> str:
    """Why ``rec`` is not a record acid wrote for scenario ``key`` (empty when it is one):
    its key, status, rows (one per controller, in ``controllers`` when given), and the type
    of every row entry the table and the summary read."""
    if not isinstance(rec, dict):
        return "not a JSON object"
    if rec.get("key") != key:
        return f"key {_short(rec.get('key'))} does not match its file name"
    if rec.get("status") not in STATUSES:
        return f"status {_short(rec.get('status'))} is not one of {', '.join(STATUSES)}"
    rows = rec.get("rows")
    if not isinstance(rows, list) or not rows or not all(isinstance(r, dict) for r in rows):
        return "rows must be a non-empty list of objects"
    for i, row in enumerate(rows):
        for k in NUMERIC:
            v = row.get(k)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
                return f"rows[{i}].{k} = {_short(v)} is not a number"
        for k in TEXT:
            v = row.get(k)
            if v is not None and not isinstance(v, str):
                return f"rows[{i}].{k} = {_short(v)} is not a text"
        if row.get("status") not in STATUSES:
            return f"rows[{i}].status = {_short(row.get('status'))} is not one of " \
                   f"{', '.join(STATUSES)}"
        if not isinstance(row.get("cycle", ""), (str, int, float)):
            return f"rows[{i}].cycle is not a cycle"
    labels = [r.get("controller") for r in rows]
    if controllers is not None and sorted(labels) != sorted(controllers):
        return f"its controllers {labels} are not this spec's {list(controllers)}"
    return ""


def _short(v) -> str:
    text = json.dumps(v) if isinstance(v, (str, int, float, bool, type(None))) else \
        type(v).__name__
    return text if len(text) <= 30 else text[:27] + "..."


class ResultStore:
    """The per-scenario records of one output folder.

    A record that is not what acid wrote (unreadable, not JSON, a wrong key, status or row
    entry, other controllers: tampered or damaged) counts as absent: it is run again, and
    ``tampered`` says which key and why.
    """

    def __init__(self, out: str | Path, controllers: tuple[str, ...] | None = None):
        self.dir = Path(out) / "scenarios"
        self.controllers = controllers
        self.tampered: dict[str, str] = {}

    def path(self, key: str) -> Path:
        return self.dir / f"{key}.json"

    def load(self, key: str) -> dict | None:
        """The record of ``key``, or None (absent, unreadable or not a valid record)."""
        from acid._readers import load_json
        from acid.errors import AcidError

        path = self.path(key)
        if not path.exists() and not path.is_symlink():
            return None
        try:
            rec = load_json(path, "scenario record", max_bytes=MAX_RECORD_BYTES, top=None)
        except AcidError as exc:
            self.tampered[key] = str(exc).removeprefix(f"{path}: ")
            return None
        problem = record_problem(rec, key, self.controllers)
        if problem:
            self.tampered[key] = problem
            return None
        self.tampered.pop(key, None)
        return rec

    def finished(self, key: str, retry_failed: bool = False) -> bool:
        """True when ``key`` needs no new run: its record is ``"ok"``, or ``"error"`` unless
        ``retry_failed``."""
        rec = self.load(key)
        done = ("ok",) if retry_failed else ("ok", "error")
        return rec is not None and rec.get("status") in done

    def save(self, record: dict) -> Path:
        """Write a record atomically (non-finite numbers as null)."""
        from acid._io import json_safe

        return write_json(self.path(record["key"]), json_safe(record))


def failure_record(key: str, index: int, label: str, controllers, baseline: str,
                   error: str, status: str = "lost") -> dict:
    """A record for a scenario whose task did not report: ``"lost"`` (worker or cluster
    gone: run again next time) or ``"error"`` (its identification step raised)."""
    rows = [{"scenario_key": key, "scenario": index, "label": label, "controller": c.label,
             "controller_type": c.kind, "baseline": baseline, "status": status,
             "error": error} for c in controllers]
    return {"key": key, "index": index, "label": label, "status": status, "error": error,
            "rows": rows, "tracebacks": {}, "elapsed_s": None, "worker": None}


def results_table(records: list[dict]):
    """The tidy table (pandas) of the given records, rows in scenario then controller order."""
    import pandas as pd

    rows = [r for rec in records for r in rec["rows"]]
    df = pd.DataFrame(rows)
    lead = [c for c in LEADING if c in df.columns]
    df = df[lead + sorted(c for c in df.columns if c not in LEADING)]
    for c in df.columns:  # JSON null -> NaN in numeric columns
        if c not in ("error", "label", "plant", "info") and df[c].dtype == object:
            conv = pd.to_numeric(df[c], errors="coerce")
            if conv.notna().sum() == df[c].notna().sum():
                df[c] = conv
    return df.reset_index(drop=True)


def write_table(df, out: Path) -> dict[str, Path]:
    """``results.parquet`` (pyarrow) and ``results.csv``, atomically; the controllers'
    ``info`` in degC (``acid.units.json_in_degC``: ``bound_C``, not ``bound_K``)."""
    from acid.units import json_in_degC

    if "info" in df.columns:
        df = df.assign(info=df["info"].map(
            lambda s: json.dumps(json_in_degC(json.loads(s)), sort_keys=True)
            if isinstance(s, str) else s))
    files = {}
    parquet = out / "results.parquet"
    with atomic_path(parquet) as tmp:
        df.to_parquet(tmp, engine="pyarrow", index=False)
    files["parquet"] = parquet
    csv = out / "results.csv"
    with atomic_path(csv) as tmp:
        df.to_csv(tmp, index=False)
    files["csv"] = csv
    return files


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None


def controller_summary(df, baseline: str) -> dict:
    """Per controller over its successful scenarios: counts and mean / min / max of energy,
    savings, cabin temperature, comfort violation; median solve time; and the verdict of its
    savings against the baseline over the scenarios (``acid.studies.verdict``: the paired
    savings' 95 % interval and the words read from it; tail-corrected savings when the sweep
    has tails)."""
    out = {}
    for label, g in df.groupby("controller", sort=False):
        ok = g[g["status"] == "ok"]
        d = {"scenarios_ok": int(len(ok)), "scenarios_failed": int(len(g) - len(ok))}
        for col in ("energy_MJ", "saving_pct", "saving_tail_corrected_pct", "mean_T_cab_C",
                    "comfort_violation_Ks", "max_T_cab_C"):
            if col not in ok or ok[col].isna().all() or (col.startswith("saving")
                                                          and label == baseline):
                continue
            v = ok[col].to_numpy(dtype=float)
            v = v[np.isfinite(v)]
            if v.size:
                d[col] = {"mean": _num(v.mean()), "min": _num(v.min()), "max": _num(v.max())}
        if "solve_ms_median" in ok and ok["solve_ms_median"].notna().any():
            d["solve_ms_median"] = _num(np.nanmedian(ok["solve_ms_median"].to_numpy(float)))
        if label != baseline:
            col = "saving_tail_corrected_pct" if "saving_tail_corrected_pct" in ok and \
                ok["saving_tail_corrected_pct"].notna().any() else "saving_pct"
            if col in ok:
                d["verdict"] = {"against": baseline, "saving": col, **paired_verdict(
                    ok[col].to_numpy(dtype=float)).to_dict()}
        out[label] = d
    return out


def prediction_roles(df) -> dict | None:
    """The labels a prediction comparison needs, from the controller types: the first
    ``econ`` controller, the ``pi`` controllers (references) and the first ``plan`` (None
    when the sweep has no econ or no PI controller)."""
    kinds = df.drop_duplicates("controller").set_index("controller")["controller_type"]
    econ = [c for c, k in kinds.items() if k == "econ"]
    refs = [c for c, k in kinds.items() if k == "pi"]
    plan = [c for c, k in kinds.items() if k == "plan"]
    if not econ or not refs:
        return None
    return {"econ": econ[0], "references": refs, "plan": plan[0] if plan else None}


#: mean cabin temperatures further apart than this are not a comparison at equal comfort, K
EQUAL_COMFORT_K = 0.05


def unequal_comfort(g, econ: str, others: list) -> list[str]:
    """The controllers of one scenario's rows ``g`` whose mean cabin temperature misses the
    econ controller's by more than :data:`EQUAL_COMFORT_K` (e.g. a fixed coil too warm to
    pull a soaked cabin down): their savings are not at equal comfort."""
    ok = g[g["status"] == "ok"].set_index("controller")["mean_T_cab_C"]
    if econ not in ok:
        return []
    return [lab for lab in others
            if lab and lab in ok and abs(ok[lab] - ok[econ]) > EQUAL_COMFORT_K]


def _rh_pct(g, label: str) -> float | None:
    """Mean cabin RH (%) a controller's row reports in its ``info`` (None if it does not)."""
    info = g[g["controller"] == label]["info"].dropna() if "info" in g else []
    rh = json.loads(info.iloc[0]).get("rh_mean") if len(info) else None
    return None if rh is None else _num(100.0 * rh)


def prediction_summary(df) -> list[dict] | None:
    """Per scenario: the economic NMPC's saving against each PI reference and the best known
    plan's, tail-corrected (%), the econ's gap to the plan (points of the first reference),
    the plan's spread, each controller's mean cabin RH (%) and the controllers not at equal
    comfort with the econ (:func:`unequal_comfort`) (None without the roles,
    :func:`prediction_roles`)."""

    roles = prediction_roles(df)
    if roles is None:
        return None
    ok = df[df["status"] == "ok"]
    econ, refs, plan = roles["econ"], roles["references"], roles["plan"]
    vs = {ref: corrected_saving(ok, econ, ref) for ref in refs}
    plan_vs = corrected_saving(ok, plan, refs[0]) if plan else None
    out = []
    for scen, g in df.groupby("scenario", sort=True):
        row = {"scenario": int(scen), "label": str(g["label"].iloc[0]),
               **{f"{econ}_vs_{ref}_pct": _num(vs[ref].get(scen, math.nan)) for ref in refs},
               "rh_mean_pct": {lab: _rh_pct(g, lab) for lab in [econ, *refs, plan] if lab},
               "unequal_comfort": unequal_comfort(g, econ, [*refs, plan])}
        if plan_vs is not None:
            p = _num(plan_vs.get(scen, math.nan))
            e = row[f"{econ}_vs_{refs[0]}_pct"]
            info = g[g["controller"] == plan]["info"].dropna()
            row[f"{plan}_vs_{refs[0]}_pct"] = p
            row[f"{econ}_gap_to_{plan}_points"] = None if p is None or e is None else p - e
            row["plan_spread_pct"] = (_num(json.loads(info.iloc[0]).get("plan_spread_pct",
                                                                        math.nan))
                                      if len(info) else None)
        out.append(row)
    return out


__all__ = ["ResultStore", "record_problem", "results_table", "write_table", "controller_summary",
           "failure_record", "prediction_roles", "prediction_summary", "unequal_comfort",
           "EQUAL_COMFORT_K"]


def corrected_saving(df, label: str, reference: str):
    """Per scenario, the saving of ``label`` against ``reference`` with both end states
    charged back, ``100 (E_ref + tail_ref - E - tail) / E_ref`` (%; raw energies when the
    sweep has no tail): a pandas Series indexed by scenario."""
    ok = df[df["status"] == "ok"]

    def corrected(lab):
        g = ok[ok["controller"] == lab].set_index("scenario")
        tail = g["tail_energy_MJ"].fillna(0.0) if "tail_energy_MJ" in g else 0.0
        return g["energy_MJ"] + tail, g["energy_MJ"]

    x, _ = corrected(label)
    r, e_r = corrected(reference)
    return (100.0 * (r - x) / e_r).dropna()
