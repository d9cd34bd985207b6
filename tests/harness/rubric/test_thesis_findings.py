"""The judges' findings read by declared rules over a run's thesis tables (planted ratings)."""
from __future__ import annotations

import pandas as pd

from cassi.harness.rubric.model import rate
from cassi.harness.rubric.thesis_findings import ABOUT_HALF, reproduced


def _ratings(cells: dict[tuple[str, str], list[int]]) -> pd.DataFrame:
    """(version, table) -> negatives per cell, as component_ratings gives them."""
    rows = [{"version": v, "table": t, "subject": f"JW{10 + i}", "component": "lips",
             "negatives": n, "rating": rate(n)}
            for (v, t), ns in cells.items() for i, n in enumerate(ns)]
    return pd.DataFrame(rows)


def _verdicts(cells) -> dict[str, str]:
    table = reproduced(pd.DataFrame(), ratings=_ratings(cells))
    return dict(zip(table["table"], table["reproduced"]))


def test_the_thesis_directions_are_reproduced_when_the_tables_follow_them():
    cells = {("cassi-1.0", "A"): [0, 1, 3, 5], ("cassi-1.0", "B"): [0, 0, 1],
             ("cassi-1.0", "C"): [4, 4], ("cassi-2.0", "C"): [4, 3], ("cassi-2.1", "C"): [1, 0],
             ("cassi-1.0", "D"): [5, 5], ("cassi-2.0", "D"): [1, 1], ("cassi-2.1", "D"): [1, 0],
             ("cassi-1.0", "E"): [3], ("cassi-2.0", "E"): [2], ("cassi-2.1", "E"): [1]}
    assert _verdicts(cells) == {"A": "yes", "B": "yes", "C": "yes", "D": "yes", "E": "yes",
                                "C-E": "yes"}


def test_a_direction_the_tables_do_not_follow_is_not_reproduced():
    # C: the big step at 1.0 -> 2.0 (the opposite of the judges'); E: 2.0 and 2.1 tie;
    # A: all of 1.0's cells good (not "about half"); B: a FAIR face shape
    cells = {("cassi-1.0", "A"): [0, 0, 1, 1], ("cassi-1.0", "B"): [0, 0, 3],
             ("cassi-1.0", "C"): [9, 9], ("cassi-2.0", "C"): [2, 2], ("cassi-2.1", "C"): [1, 2],
             ("cassi-1.0", "E"): [3], ("cassi-2.0", "E"): [0], ("cassi-2.1", "E"): [0]}
    v = _verdicts(cells)
    assert (v["A"], v["B"], v["C"], v["E"]) == ("no", "no", "no", "no")
    assert v["D"] == "not judged"  # the run has no Table D
    assert ABOUT_HALF[0] < 0.5 < ABOUT_HALF[1]


def test_a_run_without_the_thesis_versions_judges_nothing():
    v = _verdicts({("parke-1974", "C"): [3], ("cassi-3.0", "C"): [1]})
    assert set(v.values()) == {"not judged"}
