"""Thesis-style tables, comparisons and summaries from results tables."""
from __future__ import annotations

from reports_fixtures import results_rows
from cassi.reports import compare as cmp
from cassi.reports.tables import (component_ratings, markdown_table, rating_counts, thesis_table,
                                  verdicts, version_summaries)


def test_fault_counts_once_per_subject_and_sums_per_component():
    res = results_rows({("cassi-1.0", "JW11", "lip_gap_start"): 2,
                        ("cassi-1.0", "JW11", "tongue_through_teeth"): 1})
    cr = component_ratings(res).set_index(["version", "table", "subject", "component"])
    # Per-frame evidence rows (frame 7) must not be counted on top of the whole-task verdict.
    assert cr.loc[("cassi-1.0", "A", "JW11", "lips"), "negatives"] == 2
    assert cr.loc[("cassi-1.0", "A", "JW11", "lips"), "rating"] == "GOOD"
    assert cr.loc[("cassi-1.0", "A", "JW11", "tongue"), "rating"] == "VERY GOOD"
    assert cr.loc[("cassi-1.0", "A", "JW12", "lips"), "rating"] == "EXCELLENT"
    text = cr.loc[("cassi-1.0", "A", "JW11", "lips"), "text"]
    assert text == "-- lip_gap_start"   # two negatives, as the thesis writes them


def test_verdict_is_worst_task_and_names_the_files():
    res = results_rows({("cassi-2.0", "JW12", "lower_lip_below_teeth"): 3})
    v = verdicts(res)
    row = v[(v.version == "cassi-2.0") & (v.subject == "JW12") & (v.check == "lower_lip_below_teeth")]
    assert row["negatives"].item() == 3 and row["tasks"].item() == "19"


def test_thesis_table_layout_and_counts():
    res = results_rows({("cassi-1.0", "JW11", "lower_lip_below_teeth"): 1})
    wide = thesis_table(res, "A", "cassi-1.0")
    assert list(wide.index) == ["JW11", "JW12"]
    assert wide[("lips", "rating")].tolist() == ["EXCELLENT", "EXCELLENT"]
    counts = rating_counts(res, "C")
    assert counts.loc["cassi-1.0", "VERY GOOD"] == 1 and counts.loc["cassi-1.0", "EXCELLENT"] == 1
    assert counts.loc["cassi-2.1", "EXCELLENT"] == 2
    assert list(counts.index) == ["cassi-1.0", "cassi-2.0", "cassi-2.1"]


def test_version_summary_sentences():
    res = results_rows({("cassi-1.0", "JW11", "lower_lip_below_teeth"): 2,
                        ("cassi-1.0", "JW12", "lower_lip_below_teeth"): 2,
                        ("cassi-2.0", "JW12", "lower_lip_below_teeth"): 2})
    lines = version_summaries(res)
    assert any(x.startswith("cassi-2.0 improves lip placement over cassi-1.0: 1 VERY GOOD/EXCELLENT "
                            "cells against 0") for x in lines)
    assert any(x.startswith("cassi-2.1 improves lip placement over cassi-2.0: 2 VERY GOOD/EXCELLENT "
                            "cells against 1") and "decided by lower_lip_below_teeth" in x
               for x in lines)


def test_compare_marks_better_and_worse():
    before = results_rows({("cassi-2.0", "JW11", "lip_gap_start"): 2})
    after = results_rows({("cassi-2.0", "JW12", "tongue_through_teeth"): 1})
    diff = cmp.compare_checks(before, after).set_index(["version", "table", "subject", "check"])
    assert diff.loc[("cassi-2.0", "A", "JW11", "lip_gap_start"), "change"] == "▲ better"
    assert diff.loc[("cassi-2.0", "A", "JW12", "tongue_through_teeth"), "change"] == "▼ worse"
    summary = cmp.change_summary(cmp.compare_components(before, after)).set_index("version")
    # the lip fault is judged in Table A and again in Table C (Table A's lip criteria per version)
    assert summary.loc["cassi-2.0", "better"] == 2 and summary.loc["cassi-2.0", "worse"] == 1
    assert summary.loc["cassi-2.0", "net_negatives"] == -3


def test_markdown_escapes_pipes():
    import pandas as pd
    md = markdown_table(pd.DataFrame({"a": ["x|y"], "b": [1]}))
    assert "x\\|y" in md and md.splitlines()[1] == "|---|---|"
