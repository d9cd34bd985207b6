"""What a run reproduces of the judges' findings (thesis 6.1, chapter 5), by rules declared here.

Each finding is the thesis's sentence and one rule over the run's thesis tables (the one
aggregation, :func:`~cassi.harness.rubric.tables.component_ratings`): the run says by itself
which findings it reproduces, and nobody types the table. The words "about half", "two thirds",
"little" and "large" have no figure in the thesis; the rules read them as declared below (before
any run was judged by them), and a finding is never a target: the rubric is not tuned toward it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import pandas as pd

from cassi.harness.rubric.model import GOOD_RATINGS
from cassi.harness.rubric.tables import component_ratings, table_totals

__all__ = ["ThesisFinding", "THESIS_FINDINGS", "reproduced", "ABOUT_HALF", "ABOUT_TWO_THIRDS"]

#: "about half": a share within these bounds (a third of the way either side of a half is no
#: longer "about" it).
ABOUT_HALF = (0.35, 0.65)
#: "two thirds of the time": within these bounds (clearly more than half, fewer than four in five).
ABOUT_TWO_THIRDS = (0.55, 0.80)
V10, V20, V21 = "cassi-1.0", "cassi-2.0", "cassi-2.1"


@dataclass(frozen=True)
class ThesisFinding:
    """One finding of the judges: its table, where the thesis says it, its words, the rule that
    reads it, and the rule as a function of the run's ratings (None: the run cannot judge it,
    with the reason)."""

    table: str
    source: str
    finding: str
    rule: str
    versions: tuple[str, ...]
    judge: Callable[[pd.DataFrame], tuple[bool, str]]


def _totals(cr: pd.DataFrame, table: str) -> dict[str, int]:
    """Negatives per version in ``table``: the one aggregation's table totals."""
    t = table_totals(pd.DataFrame(), ratings=cr)
    t = t[t["table"] == table]
    return dict(zip(t["version"], t["negatives"].astype(int)))


def _share(cr: pd.DataFrame, table: str, version: str, ratings) -> tuple[float, int]:
    t = cr[(cr["table"] == table) & (cr["version"] == version)]
    return (float(t["rating"].isin(ratings).mean()) if len(t) else float("nan")), len(t)


def _band(share: float, band: tuple[float, float]) -> bool:
    return band[0] <= share <= band[1]


def _table_a(cr):
    share, n = _share(cr, "A", V10, GOOD_RATINGS)
    return _band(share, ABOUT_HALF), f"{share:.0%} of {n} cells EXCELLENT or VERY GOOD"


def _table_b(cr):
    share, n = _share(cr, "B", V10, ("EXCELLENT",))
    fair, _ = _share(cr, "B", V10, ("EXCELLENT", "VERY GOOD", "GOOD"))
    return (_band(share, ABOUT_TWO_THIRDS) and fair == 1.0,
            f"{share:.0%} of {n} cells EXCELLENT, {1 - fair:.0%} worse than GOOD")


def _steps(cr, table):
    """How many fewer negatives ``table`` has from 1.0 to 2.0 and from 2.0 to 2.1."""
    t = _totals(cr, table)
    return t[V10] - t[V20], t[V20] - t[V21]


def _table_c(cr):
    first, second = _steps(cr, "C")
    return second > first >= 0, f"{V10} -> {V20}: {first:+d} fewer, {V20} -> {V21}: {second:+d} fewer"


def _table_d(cr):
    first, second = _steps(cr, "D")
    return first > second >= 0, f"{V10} -> {V20}: {first:+d} fewer, {V20} -> {V21}: {second:+d} fewer"


def _table_e(cr):
    t = _totals(cr, "E")
    return t[V10] > t[V20] > t[V21], f"{t[V10]} / {t[V20]} / {t[V21]}"


def _summary(cr):
    t = {v: sum(_totals(cr, table).get(v, 0) for table in "CDE") for v in (V10, V21)}
    return t[V10] > t[V21], f"C + D + E: {t[V10]} against {t[V21]}"


#: The judges' findings, in the thesis's order (6.1 summarises chapter 5).
THESIS_FINDINGS = (
    ThesisFinding("A", "5.3, 6.1", "CASSI 1.0's lips, teeth and tongue: EXCELLENT or VERY GOOD "
                  "animations about half the time", f"{ABOUT_HALF[0]:.0%}-{ABOUT_HALF[1]:.0%} of "
                  "cassi-1.0's Table A cells rated EXCELLENT or VERY GOOD", (V10,), _table_a),
    ThesisFinding("B", "5.4, 6.1", "CASSI 1.0's face shape: EXCELLENT two thirds of the time, VERY "
                  "GOOD or GOOD one third", f"{ABOUT_TWO_THIRDS[0]:.0%}-{ABOUT_TWO_THIRDS[1]:.0%} "
                  "of cassi-1.0's Table B cells EXCELLENT and none worse than GOOD", (V10,),
                  _table_b),
    ThesisFinding("C", "5.5, 5.6, 6.1", "lip placement and movement: little improvement from 1.0 "
                  "to 2.0, large improvement from 2.0 to 2.1", "Table C's negatives fall more "
                  "from 2.0 to 2.1 than from 1.0 to 2.0, and do not rise from 1.0 to 2.0",
                  (V10, V20, V21), _table_c),
    ThesisFinding("D", "5.8, 6.1", "lip rounding (task 118): a marked improvement from 1.0 to 2.0, "
                  "little further from 2.0 to 2.1", "Table D's negatives fall more from 1.0 to 2.0 "
                  "than from 2.0 to 2.1, and do not rise from 2.0 to 2.1", (V10, V20, V21),
                  _table_d),
    ThesisFinding("E", "5.9, 6.1", "jaw wagging (task 106): the lips improved from 1.0 to 2.0 and "
                  "from 2.0 to 2.1", "Table E's negatives fall from 1.0 to 2.0 and from 2.0 to 2.1",
                  (V10, V20, V21), _table_e),
    ThesisFinding("C-E", "6.1", "the motion and placement of the lips improved from CASSI 1.0 to "
                  "2.1", "Tables C, D and E together: fewer negatives for 2.1 than for 1.0",
                  (V10, V21), _summary),
)


def reproduced(results: pd.DataFrame, *, ratings: pd.DataFrame | None = None) -> pd.DataFrame:
    """One row per finding of :data:`THESIS_FINDINGS`: table, source, finding, rule, what the run
    gives, and ``reproduced`` ("yes", "no", or "not judged" when the run lacks a version)."""
    cr = component_ratings(results) if ratings is None else ratings
    rows = []
    for f in THESIS_FINDINGS:
        tables = ("C", "D", "E") if f.table == "C-E" else (f.table,)
        present = set(cr.loc[cr["table"].isin(tables), "version"])
        missing = [v for v in f.versions if v not in present]
        if missing:
            verdict, seen = "not judged", f"the run has no Table {'/'.join(tables)} of {', '.join(missing)}"
        else:
            ok, seen = f.judge(cr)
            verdict = "yes" if ok else "no"
        rows.append({"table": f.table, "thesis": f.source, "finding": f.finding, "rule": f.rule,
                     "this run": seen, "reproduced": verdict})
    return pd.DataFrame(rows, columns=["table", "thesis", "finding", "rule", "this run",
                                       "reproduced"])
