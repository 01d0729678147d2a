"""The one-step residual tests of ``acid validate`` on the validated samples: computed
(``acid.ident.analysis.resid``) and printed with what they mean."""

from __future__ import annotations

import math
import warnings

import numpy as np

from acid_cli._common import note, print_table, say


def _fmt(v: float, digits: int = 3) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.{digits}f}"


def residual_tests(ds, params, lo: int, hi: int):
    """One-step residual tests (``acid.ident.analysis.resid``) on the validated samples: their
    result, or (a ``str``) why they were skipped (the part is too short)."""
    from acid.errors import DataError
    from acid.ident.analysis import resid

    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            return resid(ds.window(lo, hi), params)
    except DataError as exc:
        return str(exc)


def residual_section(r) -> dict | None:
    """Print the residual tests ``r`` (``residual_tests``) with what they mean; returns
    their JSON summary (None when they were skipped)."""
    if isinstance(r, str):
        note(f"residual tests skipped: {r}")
        return None
    rows = []
    for i, c in enumerate(r.channels):
        a = np.abs(r.autocorrelation[1:, i])
        rows.append([c, "yes" if r.white[c] else "no",
                     _fmt(float(a.max()) if np.all(np.isfinite(a)) else math.nan, 2),
                     _fmt(r.ljung_box[c]["p_value"], 3),
                     ", ".join(u for u in r.inputs if not r.independent[u][c]) or "none"])
    print_table(f"One-step residuals on the validated samples (N = {r.n}, 99 % band "
                f"+-{r.band99:.3f})", ["_channel", "white", "max |acf|", "Ljung-Box p",
                                       "_correlated with"], rows)
    for c, text in r.interpretation.items():
        say(f"  {c}: {text}")
    d = r.to_json_dict()
    return {k: d[k] for k in ("n", "band99", "white", "independent", "ljung_box",
                              "interpretation")}
