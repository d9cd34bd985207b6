"""Agreement statistics (cassi.harness.rubric.agreement) on hand-computed examples."""
from __future__ import annotations

import numpy as np
import pytest

from cassi.harness.rubric.agreement import (agreement_stats, bootstrap_kappa, confusion,
                                            quadratic_kappa)

# Confusion (rows first rater, columns second) [[2, 1, 0], [0, 2, 1], [1, 0, 3]], n = 10.
FIRST = [0, 0, 0, 1, 1, 1, 2, 2, 2, 2]
SECOND = [0, 0, 1, 1, 1, 2, 0, 2, 2, 2]


def test_quadratic_kappa_on_a_hand_computed_3x3_example():
    assert confusion(FIRST, SECOND, 3).tolist() == [[2, 1, 0], [0, 2, 1], [1, 0, 3]]
    # weights (i-j)^2: observed 1*1 + 1*1 + 4*1 = 6; marginals (3, 3, 4) both ways, expected
    # E = r c / 10: 0.9 + 4*1.2 + 0.9 + 1.2 + 4*1.2 + 1.2 = 13.8; kappa = 1 - 6/13.8 = 13/23
    assert quadratic_kappa(FIRST, SECOND, 3) == pytest.approx(13 / 23)
    # the unused categories of the whole 7-word scale change nothing
    assert quadratic_kappa(FIRST, SECOND) == pytest.approx(13 / 23)


def test_perfect_chance_and_undefined_kappa():
    assert quadratic_kappa([0, 1, 2, 5], [0, 1, 2, 5]) == pytest.approx(1.0)
    # independent raters: observed = expected
    assert quadratic_kappa([0, 0, 1, 1], [0, 1, 0, 1]) == pytest.approx(0.0)
    # one rating throughout for both: no disagreement is expected, kappa is undefined
    assert np.isnan(quadratic_kappa([3, 3], [3, 3]))


def test_agreement_stats_exact_within_one_and_a_reproducible_interval():
    s = agreement_stats(FIRST, SECOND, n_boot=400, seed=1)
    assert s["n"] == 10
    assert s["exact"] == pytest.approx(0.7)           # the diagonal: 2 + 2 + 3
    assert s["within_one"] == pytest.approx(0.9)      # all but the (2, 0) pair
    assert s["kappa"] == pytest.approx(13 / 23)
    assert s["kappa_low"] <= s["kappa"] <= s["kappa_high"] <= 1.0
    assert (s["kappa_low"], s["kappa_high"]) == bootstrap_kappa(FIRST, SECOND, n=400, seed=1)
    assert len(s["confusion"]) == 7 and sum(map(sum, s["confusion"])) == 10
