"""Paired version comparisons (cassi.harness.rubric.paired) on hand-computed examples."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from cassi.harness import rubric as R
from cassi.harness.farm.results import normalize
from cassi.harness.rubric.paired import (bootstrap_median, paired_comparisons, paired_sentence,
                                         sign_test)


def rows(version, check, values, *, view="geometry", subject="JW11"):
    """One whole-task row per task file 1..n with the given values."""
    c = R.CHECKS[check]
    return [dict(subject=subject, task=t, rep=1, version=version, view=view, frame=-1, check=check,
                 table=c.table, component=c.component, value=v, unit=c.unit,
                 threshold=c.threshold, negatives=0, detail="") for t, v in enumerate(values, 1)]


def test_wins_losses_ties_median_and_sign_test_by_hand():
    # lips_never_touch: higher is worse. d = a - b = [-2, -1, 0, 1, -3]:
    # wins where d < 0 (3), one loss, one tie; median -1; sign test on 3 of 4:
    # P(X<=1) + P(X>=3) for Bin(4, 1/2) = (1 + 4 + 4 + 1) / 16 = 0.625
    res = normalize(rows("cassi-1.0", "lips_never_touch", [3, 5, 2, 4, 6])
                    + rows("cassi-2.0", "lips_never_touch", [1, 4, 2, 5, 3]))
    p = paired_comparisons(res)
    assert len(p) == 1                  # Table A's lip row judged again in C counts once
    r = p.iloc[0]
    assert (r["a"], r["b"], r["files"]) == ("cassi-2.0", "cassi-1.0", 5)
    assert (r["wins"], r["losses"], r["ties"]) == (3, 1, 1)
    assert r["median"] == -1.0
    assert r["p"] == pytest.approx(0.625)
    assert -3 <= r["low"] <= r["median"] <= r["high"] <= 1
    s = paired_sentence(r)
    assert s.startswith("cassi-2.0 beats cassi-1.0 on lips_never_touch in 3 of 5 files "
                        "(1 worse, 1 tied), median cassi-2.0 − cassi-1.0 -1 mm")
    assert "lower is better" in s and "p = 0.625" in s


def test_lower_is_worse_flips_the_winner_and_the_sentence_names_it_first():
    # tongue_back_v: lower is worse; 2.1's values are lower in every one of 6 files
    res = normalize(rows("cassi-2.0", "tongue_back_v", [10, 11, 12, 13, 14, 15])
                    + rows("cassi-2.1", "tongue_back_v", [9, 10, 11, 12, 13, 14]))
    r = paired_comparisons(res).iloc[0]
    assert (r["wins"], r["losses"], r["ties"]) == (0, 6, 0)
    assert r["p"] == pytest.approx(2 / 64)
    assert (r["median"], r["low"], r["high"]) == (-1.0, -1.0, -1.0)   # constant differences
    assert paired_sentence(r).startswith("cassi-2.0 beats cassi-2.1 on tongue_back_v in 6 of 6 "
                                         "files (0 worse, 0 tied), median cassi-2.0 − cassi-2.1 +1 deg [+1, +1]")


def test_only_shared_finite_files_most_significant_first_and_noise_is_a_tie():
    res = normalize(
        rows("cassi-1.0", "lips_never_touch", [1, 1, 1, 1, 1, 1, 7])
        + rows("cassi-2.0", "lips_never_touch", [0, 0, 0, 0, 0, 0, np.nan])
        + rows("cassi-1.0", "lips_overlap", [2, 2, 2])
        + rows("cassi-2.0", "lips_overlap", [2 + 1e-12, 1, 3]))
    p = paired_comparisons(res)
    assert list(p["measure"]) == ["lips_never_touch", "lips_overlap"]     # p 1/32 before p 1
    assert p.iloc[0]["files"] == 6                   # the file with no value for 2.0 is left out
    assert tuple(p.iloc[1][["wins", "losses", "ties"]]) == (1, 1, 1)
    assert p.iloc[1]["p"] == 1.0


def test_bootstrap_is_reproducible_with_its_seed_and_contains_the_median():
    d = np.array([-2.0, -1.0, 0.0, 1.0, -3.0, -0.5, 0.7, -1.2])
    a, b = bootstrap_median(d, n=500, seed=3), bootstrap_median(d, n=500, seed=3)
    assert a == b
    assert a[0] <= np.median(d) <= a[1]
    assert d.min() <= a[0] < a[1] <= d.max()
    assert np.isnan(bootstrap_median([], n=10)).all()


def test_sign_test_without_wins_or_losses():
    assert sign_test(0, 0) == 1.0
    assert sign_test(6, 0) == pytest.approx(0.03125)
    assert sign_test(1, 9) == pytest.approx(22 / 1024)


def test_a_check_in_several_views_is_one_measure_per_view():
    res = normalize(rows("cassi-1.0", "lip_shape_image", [1.0, 1.0], view="front")
                    + rows("cassi-2.0", "lip_shape_image", [2.0, 2.0], view="front")
                    + rows("cassi-1.0", "lip_shape_image", [1.0, 1.0], view="side")
                    + rows("cassi-2.0", "lip_shape_image", [1.0, 0.5], view="side"))
    p = paired_comparisons(res).set_index("measure")
    assert set(p.index) == {"lip_shape_image (front)", "lip_shape_image (side)"}
    assert p.loc["lip_shape_image (front)", "wins"] == 2          # lower is worse: 2 beats 1
    assert p.loc["lip_shape_image (side)", "losses"] == 1
