"""Robustness of the version-level findings: which ones hold when a constant the project chose
moves within its plausible range.

A finding is, per rubric table and per version against the one before it (the report's
"versions compared"), which of the two is better:

- ``totals``: fewer negatives in the table (:func:`~.tables.component_ratings`, the one
  aggregation);
- ``paired``: more task files where its measure is better than fewer, summed over the table's
  measures (:func:`~.paired.paired_comparisons`' wins and losses).

A setting moves one constant to one end of its declared range, everything else as it is:
a rubric threshold (``Check.ranges``, re-applied to the stored values by the check's own
grading, :meth:`~.model.Check.grade`; nothing is measured or rendered again) or a version
constant (:mod:`cassi.versions.ranges`; the harness animates and checks again,
:mod:`cassi.harness.evaluation.sensitivity`). A threshold never changes a measured value, so
the paired findings are judged under the version settings only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.harness.rubric.model import TABLE_TOPICS, Check
from cassi.harness.rubric.paired import paired_comparisons
from cassi.harness.rubric.registry import CHECKS, TABLE_C_FROM_A
from cassi.harness.rubric.tables import component_ratings, order_versions

__all__ = ["Setting", "TABLE_COLUMNS", "robustness_table", "threshold_ranges", "threshold_settings", "regraded", "verify_grades", "findings",
           "robustness", "FINDING_KINDS", "TIE"]

#: How a finding is judged (module docstring).
FINDING_KINDS = ("totals", "paired")
#: The outcome when neither version is better.
TIE = "tie"


@dataclass(frozen=True)
class Setting:
    """One constant at one end of its range: ``name`` as the report prints it
    (``lips_never_touch[1] = 2`` / ``lips_constants.RHO = 0.2``), ``kind`` threshold or version."""

    kind: str
    constant: str
    value: float
    base: float

    @property
    def name(self) -> str:
        return f"{self.constant} = {self.value:g}"


def _threshold_label(check: Check, index: int) -> str:
    return check.name if len(check.thresholds) == 1 else f"{check.name}[{index + 1}]"


def threshold_ranges() -> list[dict]:
    """Every ranged threshold: constant (its label), check, index, value, low, high, reason."""
    return [dict(kind="threshold", constant=_threshold_label(c, i), check=c.name, index=i,
                 value=float(c.thresholds[i]), low=float(r[0]), high=float(r[1]),
                 reason=c.range_reason)
            for c in CHECKS.values() for i, r in enumerate(c.ranges) if r is not None]


def threshold_settings() -> list[tuple[Setting, Check]]:
    """Every ranged threshold at its low and its high end: (setting, the check with it)."""
    return [(Setting("threshold", t["constant"], t[end], t["value"]),
             CHECKS[t["check"]].with_threshold(t["index"], t[end]))
            for t in threshold_ranges() for end in ("low", "high")]


def _regrade(check: Check, values: pd.Series) -> np.ndarray:
    if not check.counted:
        return np.zeros(len(values), dtype=np.int64)
    return np.asarray([check.grade(v) for v in values.astype(float)], dtype=np.int64)


def regraded(results: pd.DataFrame, check: Check) -> pd.DataFrame:
    """``results`` with the whole-task rows of ``check.name`` graded by ``check`` (its
    thresholds as given; the stored values as measured)."""
    out = results.copy()
    at = (out["frame"] == -1) & (out["check"] == check.name)
    out.loc[at, "negatives"] = _regrade(check, out.loc[at, "value"])
    return out


def verify_grades(results: pd.DataFrame, source: str = "results") -> None:
    """Refuse results whose stored negatives the ranged checks' grading does not reproduce
    (judged by another registry, or a check that grades in its measure): a threshold re-applied
    to them would describe another rubric."""
    whole = results[results["frame"] == -1]
    for c in CHECKS.values():
        if not any(r is not None for r in c.ranges):
            continue
        rows = whole[whole["check"] == c.name]
        got = _regrade(c, rows["value"])
        bad = np.flatnonzero(got != rows["negatives"].to_numpy(np.int64))
        if len(bad):
            r = rows.iloc[bad[0]]
            raise CassiInputError(
                f"the stored negatives of {c.name} ({int(r['negatives'])} for value "
                f"{float(r['value']):g}, {r['version']} {r['subject']} task {int(r['task'])}) are "
                f"not what its thresholds {list(c.thresholds)} give: the run was judged by another "
                f"rubric; run it again before re-applying thresholds", path=source)


def _pairs(versions) -> list[tuple[str, str]]:
    names = order_versions(versions)
    return list(zip(names[1:], names))


def _winner(a: str, b: str, score_a: float, score_b: float) -> str:
    """The better of ``a`` and ``b`` by a score where higher is better."""
    return a if score_a > score_b else b if score_b > score_a else TIE


def tables_reached(check: Check) -> set[str]:
    """The tables whose cells a change of ``check``'s grades can move: its own, Table C for the
    lip rows of Table A it repeats, and Table A whenever C is reached (C is aggregated from
    them). Findings of every other table stay the baseline's."""
    reached = {check.table}
    if check.table == "A" and check.component in TABLE_C_FROM_A:
        reached.add("C")
    if "C" in reached:
        reached.add("A")
    return reached


def findings(results: pd.DataFrame, *, kinds=FINDING_KINDS) -> dict[tuple, str]:
    """(kind, table, version, previous version) -> the better version of the two, or
    :data:`TIE`, for every table and each version against the one before it."""
    out: dict[tuple, str] = {}
    if "totals" in kinds:
        cr = component_ratings(results)
        neg = cr.groupby(["table", "version"])["negatives"].sum()
        for table in sorted(cr["table"].unique()):
            for a, b in _pairs(neg[table].index):
                out[("totals", table, a, b)] = _winner(a, b, -neg[table][a], -neg[table][b])
    if "paired" in kinds:
        pairs = set(_pairs(results["version"].dropna().unique()))
        pc = paired_comparisons(results, n_boot=1)  # wins and losses only: no interval needed
        for (table, a, b), g in pc.groupby(["table", "a", "b"], sort=True):
            if (a, b) in pairs:
                out[("paired", table, a, b)] = _winner(a, b, g["wins"].sum(), g["losses"].sum())
    return out


def robustness(base: dict[tuple, str], settings: list[tuple[Setting, dict[tuple, str]]]
               ) -> list[dict]:
    """Each baseline finding with how many settings it holds in: ``holds`` of ``settings``
    (the baseline counted as one), and the settings that flip it with what they give."""
    rows = []
    for key, outcome in base.items():
        kind, table, a, b = key
        judged = [(s, f) for s, f in settings
                  if key in f and (kind == "totals" or s.kind == "version")]
        flips = [dict(setting=s.name, kind=s.kind, outcome=f[key]) for s, f in judged
                 if f[key] != outcome]
        rows.append(dict(kind=kind, table=table, topic=TABLE_TOPICS.get(table, table), a=a, b=b,
                         outcome=outcome, finding=_sentence(outcome, a, b, table, kind),
                         settings=len(judged) + 1, holds=len(judged) + 1 - len(flips),
                         flips=flips))
    return rows


def _sentence(outcome: str, a: str, b: str, table: str, kind: str) -> str:
    by = "fewer negatives" if kind == "totals" else "more files better, paired"
    topic = TABLE_TOPICS.get(table, f"table {table}")
    if outcome == TIE:
        return f"{a} and {b} tie on {topic} ({'same negatives' if kind == 'totals' else 'paired'})"
    other = b if outcome == a else a
    return f"{outcome} better than {other} on {topic} ({by})"


#: Columns of :func:`robustness_table`.
TABLE_COLUMNS = ["table", "finding", "holds", "flipped by"]


def robustness_table(doc: dict) -> pd.DataFrame:
    """A sensitivity document's findings as rows to print (the command's Markdown and the
    report read it): the finding, "holds in k of n", and the settings that flip it."""
    rows = []
    for f in doc.get("findings", []):
        flips = "; ".join(f"{x['setting']} ({_flip_text(x['outcome'], f)})" for x in f["flips"])
        rows.append({"table": f["table"], "finding": f["finding"],
                     "holds": f"{f['holds']} of {f['settings']}", "flipped by": flips})
    return pd.DataFrame(rows, columns=TABLE_COLUMNS)


def _flip_text(outcome: str, f: dict) -> str:
    return "a tie" if outcome == TIE else f"{outcome} better"
