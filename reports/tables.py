"""Report-side table helpers: the thesis layout of one table and Markdown output.

Every number comes from the rubric's one aggregation (:mod:`cassi.harness.rubric.tables`):
verdicts, component ratings with Table C's rules, rating counts and the "versions compared"
sentences are re-exported here for the report's modules and never recomputed.
"""
from __future__ import annotations

import pandas as pd

from cassi.harness.rubric import (GOOD_RATINGS, RATINGS, component_ratings, rating_counts,
                                  table_title, verdicts, version_summaries, version_totals)

__all__ = ["RATINGS", "GOOD_RATINGS", "component_ratings", "rating_counts", "table_title",
           "verdicts", "version_summaries", "version_totals", "thesis_table", "markdown_table"]


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
