"""What changed between two runs: per version, table, subject, component and check."""
from __future__ import annotations

import pandas as pd

from cassi.harness.rubric import component_ratings, verdicts

ARROWS = {-1: "▲ better", 0: "= same", 1: "▼ worse"}


def _diff(before: pd.DataFrame, after: pd.DataFrame, keys: list[str]) -> pd.DataFrame:
    merged = before[keys + ["negatives"]].merge(after[keys + ["negatives"]], on=keys, how="outer",
                                               suffixes=("_before", "_after"))
    for side in ("before", "after"):
        merged[f"negatives_{side}"] = merged[f"negatives_{side}"].astype("Int64")
    merged["delta"] = (merged["negatives_after"].fillna(0) - merged["negatives_before"].fillna(0)).astype(int)
    merged["change"] = [
        "new" if pd.isna(b) else "gone" if pd.isna(a) else ARROWS[(d > 0) - (d < 0)]
        for b, a, d in zip(merged["negatives_before"], merged["negatives_after"], merged["delta"])]
    return merged.sort_values(keys, kind="mergesort").reset_index(drop=True)


def compare_components(before: pd.DataFrame, after: pd.DataFrame, *,
                       ratings: tuple[pd.DataFrame | None, pd.DataFrame | None] = (None, None)
                       ) -> pd.DataFrame:
    """Component negatives of two results tables side by side, with ``delta`` and ``change``
    (``▲ better`` = fewer negatives, ``▼ worse``, ``= same``, ``new``, ``gone``); ``ratings``:
    their :func:`component_ratings` where made already."""
    keys = ["version", "table", "subject", "component"]
    a, b = (component_ratings(r) if cr is None else cr for r, cr in zip((before, after), ratings))
    return _diff(a, b, keys)


def compare_checks(before: pd.DataFrame, after: pd.DataFrame) -> pd.DataFrame:
    """Check verdicts of two results tables side by side (same columns as compare_components
    plus ``check``)."""
    keys = ["version", "table", "subject", "component", "check"]
    return _diff(verdicts(before), verdicts(after), keys)


def change_summary(diff: pd.DataFrame) -> pd.DataFrame:
    """Per version: how many cells got better, worse or stayed, and the net change in negatives."""
    if diff.empty:
        return pd.DataFrame(columns=["version", "better", "worse", "same", "net_negatives"])
    g = diff.groupby("version", sort=False)
    return pd.DataFrame({
        "better": g["delta"].apply(lambda d: int((d < 0).sum())),
        "worse": g["delta"].apply(lambda d: int((d > 0).sum())),
        "same": g["delta"].apply(lambda d: int((d == 0).sum())),
        "net_negatives": g["delta"].sum().astype(int),
    }).reset_index()
