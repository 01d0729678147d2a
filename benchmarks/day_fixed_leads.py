"""Independent check of ``acid day``'s timer tuning: a scan of fixed pre-conditioning leads.

For each season's training days (the study's own, indices 0..n-1, departures known), this
script runs the day on the plant once per fixed lead, 0 to 40 min in 1-min steps, with its
own controller (the production controller switched on ``lead`` minutes before the departure
while plugged) and picks the best lead by its own rule: the cheapest mean cost among the
leads whose mean K.min outside the band in the first 10 min of a plugged departure is at
most 1 K.min. It then compares that lead and its cost with what the study's tuning makes of
the same days (``day_study``'s rule: its coarse scan ``LEADS_MIN``, refined to the minute by
``fine_leads``, chosen by ``tune_timer``, on ``Timer`` runs of the same days). The timer
passes when its cost is at most the scan's best (within 1e-9 USD) and it meets the same
comfort target.

Uses the day's plant and accounting (``run_day``); the scan's controller and rule are its own:
    python benchmarks/day_fixed_leads.py --days 3 --season summer winter
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import dataclass

import numpy as np

from acid.studies import day as D


@dataclass(frozen=True)
class FixedLead:
    """The production controller from ``lead_min`` before the departure, plugged only."""

    lead_min: float
    name: str = "fixed-lead"

    def blocks(self, car, trip, tariff):
        if not trip.plugged or self.lead_min <= 0:
            return []
        return [(trip.forecast_s - 60.0 * self.lead_min, math.inf)]


def per_plug_Kmin(outs) -> float:
    plugs = sum(1 for o in outs for t in o.trips if t.plugged)
    return sum(t.Kmin_window for o in outs for t in o.trips if t.plugged) / max(plugs, 1)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--days", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--season", nargs="+", default=list(D.SEASONS))
    ap.add_argument("--max-lead", type=int, default=40)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    out = {}
    for s in a.season:
        t0 = time.time()
        days = D.make_days(s, a.days, a.seed, 0.0, first_index=0)
        scan = {}
        for L in range(0, a.max_lead + 1):
            outs = [D.run_day(d, FixedLead(float(L))) for d in days]
            scan[L] = (float(np.mean([o.cost_USD for o in outs])), per_plug_Kmin(outs),
                       float(np.mean([o.E_battery_kWh for o in outs])))
        ok = {L: v for L, v in scan.items() if v[1] <= D.COMFORT_TARGET_KMIN}
        best = min(ok, key=lambda L: (ok[L][0], L)) if ok else None
        # the study's tuning on Timer runs of the same days (coarse, then to the minute)
        timer = {}

        def timer_runs(leads, days=days, timer=timer):
            for L in leads:
                if L not in timer:
                    timer[L] = [D.run_day(d, D.Timer(float(L))) for d in days]

        timer_runs(D.LEADS_MIN)
        timer_runs(D.fine_leads(timer, D.LEADS_MIN))
        tuned = D.tune_timer(dict(sorted(timer.items())))
        t_cost, t_K = float(np.mean([o.cost_USD for o in timer[tuned]])), \
            D.plugged_Kmin(timer[tuned])
        passed = best is not None and t_K <= D.COMFORT_TARGET_KMIN \
            and t_cost <= ok[best][0] + 1e-9
        out[s] = {"scan": {str(L): v for L, v in scan.items()}, "best_fixed_lead_min": best,
                  "best_fixed": ok.get(best), "timer_lead_min": tuned,
                  "timer_cost_USD": t_cost, "timer_Kmin": t_K, "pass": passed,
                  "seconds": time.time() - t0}
        print(f"{s}: best fixed lead {best} min (cost {ok[best][0]:.4f} USD, "
              f"{ok[best][1]:.3f} K.min/plug); timer {tuned:g} min (cost {t_cost:.4f} USD, "
              f"{t_K:.3f} K.min/plug): {'PASS' if passed else 'FAIL'} "
              f"({time.time() - t0:.0f} s)", flush=True)
        for L in sorted(scan):
            c, k, e = scan[L]
            print(f"  {L:2d} min: {c:.4f} USD  {k:7.3f} K.min/plug  {e:.3f} kWh battery")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
