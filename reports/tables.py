"""Thesis-style evaluation tables computed from a run's long results table.

The thesis rates each component (teeth, lips, tongue, ...) of each subject from the faults seen
over that subject's task files: a fault counts once per subject however many files show it.
Here a check's verdict for a subject is therefore its largest whole-task negatives over the
subject's files, and a component's negatives are the sum over its checks.
"""
from __future__ import annotations

import pandas as pd


#: Rating words in the thesis's order (Table 5.2), best first.
RATINGS = ("EXCELLENT", "VERY GOOD", "GOOD", "FAIR", "POOR", "VERY POOR", "UNACCEPTABLE")
GOOD_RATINGS = ("EXCELLENT", "VERY GOOD")

#: Titles for the rubric's tables; a table the rubric names otherwise is shown by its name.
TABLE_TITLES = {
    "A": "Teeth, lips and tongue per subject (thesis Table 5.3)",
    "B": "Overall face shape at initialization (thesis Table 5.4)",
    "C": "Lip placement and movement across versions (thesis Tables 5.5, 5.6)",
    "D": "Maximum lip protrusion, task 118 (thesis Table 5.8)",
    "E": "Jaw wagging, task 106 (thesis Table 5.9)",
}
#: What each table judges, for summary sentences ("2.1 improves lip placement over 2.0").
TABLE_TOPICS = {"A": "teeth, lips and tongue", "B": "face shape", "C": "lip placement",
                "D": "maximum lip protrusion", "E": "jaw wagging"}


def rate(negatives: int) -> str:
    """Thesis Table 5.2 (the rubric's one rating scale)."""
    from cassi.harness.rubric import rate as rubric_rate  # noqa: PLC0415

    return rubric_rate(int(negatives))


def check_text(check: str) -> str:
    """The negative as the thesis writes it, from the rubric registry (else the check name)."""
    try:
        from cassi.harness.rubric import CHECKS  # noqa: PLC0415
    except ImportError:
        return check
    entry = CHECKS.get(check) if hasattr(CHECKS, "get") else None
    return getattr(entry, "text", None) or check


def table_title(table: str) -> str:
    return TABLE_TITLES.get(str(table), f"Table {table}")


def verdicts(results: pd.DataFrame) -> pd.DataFrame:
    """One row per (version, table, subject, component, check): the subject's verdict.

    Columns: version, table, subject, component, check, negatives (max over the subject's task
    files), tasks (the task files where it fired, as ``task`` or ``task_rep`` text), value (the
    value in the file that earned the most negatives), unit, threshold.
    """
    df = results[(results["frame"] == -1) & results["table"].notna()].copy()
    if df.empty:
        return pd.DataFrame(columns=["version", "table", "subject", "component", "check",
                                     "negatives", "tasks", "value", "unit", "threshold"])
    df["file"] = [f"{t}" if r == 1 else f"{t}_{r}" for t, r in zip(df["task"], df["rep"])]
    df = df.sort_values(["negatives", "task", "rep"], ascending=[False, True, True], kind="mergesort")
    keys = ["version", "table", "subject", "component", "check"]
    worst = df.groupby(keys, sort=True, dropna=False).first().reset_index()
    fired = (df[df["negatives"] > 0].groupby(keys, dropna=False)["file"]
             .agg(lambda s: ", ".join(sorted(set(s), key=lambda x: (len(x), x)))).rename("tasks"))
    worst = worst.merge(fired, on=keys, how="left")
    worst["tasks"] = worst["tasks"].fillna("")
    worst["negatives"] = worst["negatives"].astype(int)
    return worst[keys + ["negatives", "tasks", "value", "unit", "threshold"]]


def negatives_text(rows: pd.DataFrame) -> str:
    """``- fault; - fault (2)`` for the checks that earned negatives, thesis style."""
    parts = []
    for check, neg in zip(rows["check"], rows["negatives"]):
        if neg > 0:
            parts.append(f"- {check_text(check)}" + (f" ({neg})" if neg > 1 else ""))
    return "; ".join(parts)


def component_ratings(results: pd.DataFrame) -> pd.DataFrame:
    """Per version, table, subject and component: negatives, rating and negatives as text."""
    v = verdicts(results)
    cols = ["version", "table", "subject", "component", "negatives", "rating", "text"]
    if v.empty:
        return pd.DataFrame(columns=cols)
    rows = []
    for (version, table, subject, component), g in v.groupby(
            ["version", "table", "subject", "component"], sort=True, dropna=False):
        neg = int(g["negatives"].sum())
        rows.append((version, table, subject, component, neg, rate(neg), negatives_text(g)))
    return pd.DataFrame(rows, columns=cols)


def thesis_table(results: pd.DataFrame, table: str, version: str) -> pd.DataFrame:
    """The thesis layout of one table for one version: a row per subject, a column per
    component, each cell ``RATING`` with its negatives as text beneath (``rating``/``text``
    pairs, as a DataFrame with MultiIndex columns (component, field))."""
    cr = component_ratings(results)
    cr = cr[(cr["table"] == table) & (cr["version"] == version)]
    if cr.empty:
        return pd.DataFrame()
    wide = cr.pivot(index="subject", columns="component", values=["rating", "negatives", "text"])
    wide = wide.swaplevel(0, 1, axis=1).sort_index(axis=1, level=0, sort_remaining=False)
    return wide


def rating_counts(results: pd.DataFrame, table: str) -> pd.DataFrame:
    """Thesis Table 5.6: how many (subject, component) cells of ``table`` got each rating,
    per version (rows: versions; columns: RATINGS)."""
    from cassi.reports.runio import order_versions  # noqa: PLC0415 - avoid an import cycle

    cr = component_ratings(results)
    cr = cr[cr["table"] == table]
    counts = pd.crosstab(cr["version"], cr["rating"]) if not cr.empty else pd.DataFrame()
    counts = counts.reindex(columns=list(RATINGS), fill_value=0)
    return counts.reindex(order_versions(cr["version"].unique()), fill_value=0).astype(int)


def version_summaries(results: pd.DataFrame) -> list[str]:
    """Sentences comparing each version with the one before it, per table, like the thesis:
    "cassi-2.1 improves lip placement over cassi-2.0: 10 VERY GOOD/EXCELLENT against 6"."""
    out = []
    for table in sorted(results.loc[results["table"].notna(), "table"].unique()):
        counts = rating_counts(results, table)
        good = counts[list(GOOD_RATINGS)].sum(axis=1)
        names = list(counts.index)
        topic = TABLE_TOPICS.get(str(table), f"table {table}")
        for prev, cur in zip(names, names[1:]):
            a, b = int(good[cur]), int(good[prev])
            verb = "improves" if a > b else "worsens" if a < b else "matches"
            out.append(f"{cur} {verb} {topic} over {prev}: {a} VERY GOOD/EXCELLENT against {b}")
    return out


def markdown_table(df: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table of ``df`` (no extra dependency: tabulate is not ours)."""
    flat = df.copy()
    if isinstance(flat.columns, pd.MultiIndex):
        flat.columns = [" ".join(str(c) for c in col) for col in flat.columns]
    flat = flat.reset_index() if flat.index.name or not isinstance(flat.index, pd.RangeIndex) else flat

    def cell(x) -> str:
        return ("" if pd.isna(x) else str(x)).replace("|", "\\|").replace("\n", " ")

    header = "| " + " | ".join(cell(c) for c in flat.columns) + " |"
    rule = "|" + "---|" * len(flat.columns)
    body = ["| " + " | ".join(cell(x) for x in row) + " |" for row in flat.itertuples(index=False)]
    return "\n".join([header, rule, *body]) + "\n"
