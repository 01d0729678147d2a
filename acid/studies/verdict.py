"""A saving as a verdict: paired differences over scenarios (or cases, days, trips), their 95 %
interval and the words read from it, never from the point value.

``paired_verdict(values)`` takes the paired savings of one controller against another, one per
held-out scenario (%, or any unit: the verdict is about the sign), and returns a
:class:`Verdict`:

* the mean and the two-sided ``level`` interval of the mean: Student's t over the scenarios
  and, beside it, a paired bootstrap (``n_boot`` resamples of the scenarios, percentile
  interval, seeded: same seed, same bits);
* the words: **"saves"** when the whole t-interval lies above zero, **"costs"** when below,
  **"no resolvable difference"** when it holds zero, and **"not resolved"** below
  ``min_count`` scenarios (no interval is computed from so few). The t-interval decides by
  default (``decide="t"``: it is the wider of the two for the small counts of a study); the
  bootstrap is reported so a reader can see when the two disagree (``agree``), and decides
  with ``decide="bootstrap"`` (skewed savings over many scenarios); ``decide="both"`` reads
  "saves" or "costs" only when both intervals exclude zero on the same side.

Reference: B. Efron and R. J. Tibshirani, *An Introduction to the Bootstrap*, Chapman & Hall,
1993, ch. 13 (percentile intervals) and ch. 15 (paired comparisons).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass

import numpy as np

#: the fewest paired values behind a verdict: below, "not resolved"
MIN_COUNT = 5
#: the words a verdict may read
WORDS = ("saves", "no resolvable difference", "costs", "not resolved")


@dataclass(frozen=True)
class Verdict:
    """A paired comparison over ``n`` scenarios: ``mean`` of the savings, the t-interval
    ``(lo, hi)`` and the bootstrap interval ``(boot_lo, boot_hi)`` at ``level``, the ``words``
    (one of :data:`WORDS`) and, when not resolved, ``why``. Intervals are None below
    ``min_count``."""

    n: int
    mean: float | None
    lo: float | None
    hi: float | None
    boot_lo: float | None
    boot_hi: float | None
    level: float
    words: str
    why: str = ""
    decided_by: str = "t"

    @property
    def agree(self) -> bool | None:
        """Whether the bootstrap interval reads the same words as the t-interval."""
        if self.boot_lo is None:
            return None
        return _words(self.boot_lo, self.boot_hi) == _words(self.lo, self.hi)

    def to_dict(self) -> dict:
        return {**asdict(self), "agree": self.agree}

    @classmethod
    def from_dict(cls, d: dict) -> Verdict:
        return cls(**{k: d[k] for k in ("n", "mean", "lo", "hi", "boot_lo", "boot_hi",
                                        "level", "words", "why", "decided_by") if k in d})

    def summary(self, unit: str = "%") -> str:
        """One line: the words, the mean and its interval, the count."""
        if self.lo is None:
            return f"{self.words} ({self.why})"
        return (f"{self.words}: mean {self.mean:+.2f} {unit}, {100 * self.level:.0f} % interval "
                f"{self.lo:+.2f} to {self.hi:+.2f} {unit} over {self.n} (bootstrap "
                f"{self.boot_lo:+.2f} to {self.boot_hi:+.2f})")

    def __repr__(self) -> str:
        return f"Verdict({self.summary()})"


#: fewest paired scenarios the comparison engine reads a word from (else "not resolved")
MIN_SCENARIOS = 5
#: comfort gaps beyond which a saving is not read (candidate minus baseline, mean over the
#: pairs): discomfort, K min per pass, and mean cabin temperature, K (0.02 K ~ 0.1 % energy)
MAX_DISCOMFORT_GAP_KMIN = 0.1
MAX_WARMER_K = 0.05
UNEQUAL = "not at equal comfort"


def at_equal_comfort(words: str, discomfort_gap_Kmin: float = 0.0,
                     T_cab_gap_K: float = 0.0) -> str:
    """The engine's comfort rule: a candidate less comfortable than its baseline that would
    "save" or show no difference reads "not at equal comfort"."""
    if words in ("saves", "no resolvable difference") and (
            discomfort_gap_Kmin > MAX_DISCOMFORT_GAP_KMIN or T_cab_gap_K > MAX_WARMER_K):
        return UNEQUAL
    return words


def _words(lo: float, hi: float) -> str:
    return "saves" if lo > 0.0 else "costs" if hi < 0.0 else "no resolvable difference"


def paired_verdict(values: Iterable[float | None], *, level: float = 0.95,
                   min_count: int = MIN_COUNT, n_boot: int = 10_000, seed: int = 0,
                   decide: str = "t") -> Verdict:
    """The verdict of paired savings ``values`` (None or non-finite entries are dropped: a
    scenario that failed is not a zero). See the module docstring."""
    import scipy.stats

    if not 0.5 < level < 1.0:
        raise ValueError(f"level must lie in (0.5, 1), got {level!r}")
    if decide not in ("t", "bootstrap", "both"):
        raise ValueError(f"decide must be 't', 'bootstrap' or 'both', got {decide!r}")
    x = np.asarray([float(v) for v in values if v is not None and math.isfinite(float(v))])
    n = int(x.size)
    if n < max(min_count, 2):
        return Verdict(n, float(x.mean()) if n else None, None, None, None, None, level,
                       "not resolved", f"{n} paired values, fewer than {max(min_count, 2)}")
    m = float(x.mean())
    h = float(scipy.stats.t.ppf(0.5 + level / 2.0, n - 1) * x.std(ddof=1) / math.sqrt(n))
    rng = np.random.default_rng(seed)
    boot = x[rng.integers(0, n, size=(n_boot, n))].mean(axis=1)
    a = 100.0 * (1.0 - level) / 2.0
    b_lo, b_hi = (float(v) for v in np.percentile(boot, [a, 100.0 - a]))
    w_t, w_b = _words(m - h, m + h), _words(b_lo, b_hi)
    words = {"t": w_t, "bootstrap": w_b}.get(decide) or (
        w_t if w_t == w_b else "no resolvable difference")
    return Verdict(n, m, m - h, m + h, b_lo, b_hi, level, words, decided_by=decide)
