"""Sweep results on disk: one JSON record per finished scenario, then one tidy table.

``OUT/scenarios/<key>.json`` is written (atomically) the moment a scenario finishes, so an
interrupted sweep keeps everything it finished. A rerun skips every scenario that has a
record: ``"ok"``, or ``"error"`` (it ran, and a controller or the plant raised: running it
again gives the same error; ``retry_failed`` does). Records of tasks that never reported
(``"lost"``: a worker died, the cluster went away) are always run again. The key is the hash
of the scenario, its controllers, its parameters and acid's version
(:meth:`acid.sweep.spec.SweepSpec.scenario_key`).

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


class ResultStore:
    """The per-scenario records of one output folder."""

    def __init__(self, out: str | Path):
        self.dir = Path(out) / "scenarios"

    def path(self, key: str) -> Path:
        return self.dir / f"{key}.json"

    def load(self, key: str) -> dict | None:
        """The record of ``key``, or None (absent or unreadable)."""
        try:
            return json.loads(self.path(key).read_text())
        except (OSError, ValueError):
            return None

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
    """``results.parquet`` (pyarrow) and ``results.csv``, atomically."""
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
    savings, cabin temperature, comfort violation; median solve time."""
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
        out[label] = d
    return out


__all__ = ["ResultStore", "results_table", "write_table", "controller_summary",
           "failure_record"]
