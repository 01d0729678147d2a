"""acid.studies.verdict: the words of a paired comparison come from its interval."""

import math

import numpy as np
import pytest
import scipy.stats

from acid.studies.verdict import Verdict, paired_verdict


@pytest.mark.parametrize(("savings", "words"), [
    ([3.1, 2.8, 3.4, 2.9, 3.2], "saves"),
    ([-1.0, -1.2, -0.8, -1.1, -0.9, -1.3], "costs"),
    ([3.0, -2.5, 1.0, -1.5, 0.4], "no resolvable difference"),
    ([10.0, 9.0, 11.0, 10.5], "not resolved"),
    ([], "not resolved"),
])
def test_the_words_come_from_the_interval(savings, words):
    v = paired_verdict(savings)
    assert v.words == words
    if words != "not resolved":
        assert v.lo < v.mean < v.hi and v.boot_lo < v.mean < v.boot_hi


def test_a_large_mean_with_a_wide_spread_is_not_a_saving():
    v = paired_verdict([12.0, -6.0, 9.0, -5.0, 0.0])
    assert v.mean > 0 and v.words == "no resolvable difference"


def test_a_controller_against_itself_makes_no_resolvable_difference():
    """Paired differences of a controller with itself, up to noise of either sign."""
    rng = np.random.default_rng(3)
    v = paired_verdict(rng.normal(0.0, 0.2, 12))
    assert v.words == "no resolvable difference"


def test_the_t_interval_is_the_textbook_one_and_covers_the_truth():
    """Against scipy's own t-interval, and coverage near 95 % over seeded samples."""
    x = [1.2, 0.4, 2.2, 1.9, 0.8, 1.4, 1.1]
    v = paired_verdict(x)
    lo, hi = scipy.stats.t.interval(0.95, len(x) - 1, loc=np.mean(x), scale=scipy.stats.sem(x))
    assert math.isclose(v.lo, lo, rel_tol=1e-12) and math.isclose(v.hi, hi, rel_tol=1e-12)
    rng = np.random.default_rng(0)
    covered = 0
    for _ in range(400):
        s = rng.normal(1.0, 2.0, 8)
        w = paired_verdict(s, n_boot=50)
        covered += w.lo < 1.0 < w.hi
    assert 0.91 < covered / 400 < 0.98


def test_failed_scenarios_are_dropped_not_counted_as_zero_and_the_bootstrap_is_seeded():
    v = paired_verdict([2.0, None, 2.5, float("nan"), 1.8, 2.2, 2.4])
    assert v.n == 5 and v.words == "saves"
    assert paired_verdict([1.0, 2.0, 3.0, 2.0, 1.5], seed=4) == \
        paired_verdict([1.0, 2.0, 3.0, 2.0, 1.5], seed=4)
    assert Verdict.from_dict(v.to_dict()) == v
    with pytest.raises(ValueError, match="level"):
        paired_verdict([1.0] * 6, level=1.5)
