"""acid.studies.sweep.results: the per-controller summary carries the verdict of its savings
over the scenarios, read from their interval."""

import pandas as pd

from acid.studies.sweep.results import controller_summary


def _table(savings: dict[str, list[float]], tails: bool = True) -> pd.DataFrame:
    rows = []
    for label, values in savings.items():
        for i, s in enumerate(values):
            rows.append({"scenario": f"s{i}", "controller": label, "status": "ok",
                         "energy_MJ": 1.0, "saving_pct": s + 0.5,
                         "saving_tail_corrected_pct": s if tails else float("nan")})
    rows.append({"scenario": "s9", "controller": "econ", "status": "failed",
                 "energy_MJ": float("nan"), "saving_pct": float("nan"),
                 "saving_tail_corrected_pct": float("nan")})
    return pd.DataFrame(rows)


def test_each_controller_gets_the_verdict_of_its_tail_corrected_savings():
    df = _table({"pi": [0.0] * 6, "econ": [1.2, 0.9, 1.4, 1.1, 1.0, 1.3],
                 "icm": [0.8, -1.1, 0.3, -0.6, 0.9, -0.2]})
    s = controller_summary(df, "pi")
    assert "verdict" not in s["pi"]                     # the baseline judges no one
    v = s["econ"]["verdict"]
    assert v["words"] == "saves" and v["n"] == 6 and v["saving"] == "saving_tail_corrected_pct"
    assert v["against"] == "pi" and v["lo"] > 0.0
    assert s["icm"]["verdict"]["words"] == "no resolvable difference"


def test_raw_savings_without_tails_and_too_few_scenarios_are_not_resolved():
    s = controller_summary(_table({"pi": [0.0] * 3, "econ": [2.0, 2.1, 1.9]}, tails=False), "pi")
    v = s["econ"]["verdict"]
    assert v["saving"] == "saving_pct" and v["words"] == "not resolved" and v["n"] == 3
