"""`cassi nightly` end to end on a small real evaluation: dated runs, reports, history, the
comparison with the previous night, and a gate that fails on a planted regression."""
from __future__ import annotations

import datetime as dt
import json

import pandas as pd
import pytest

from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.nightly import nightly
from cassi.reports.nightly import review_night

from reports_fixtures import rewrite_results

pytestmark = pytest.mark.render

SMALL = RunConfig(subjects=("JW45",), tasks=(13,), versions=("cassi-1.0", "cassi-2.0"),
                  views=("front",), stride=0, extremes=1, workers=1)


def test_two_nights_then_a_planted_regression_fails_the_gate(tmp_path):
    day1, day2, day3 = (dt.date(2026, 11, d) for d in (20, 21, 22))
    ok1, index1 = nightly(tmp_path, review=review_night, config=SMALL, today=day1, progress=False)
    assert ok1 and index1 == tmp_path / "reports" / "2026-11-20" / "index.html"
    gate1 = json.loads((tmp_path / "runs" / "2026-11-20" / "gate.json").read_text())
    assert gate1["passed"] and gate1["gates"] == []  # first night: nothing to compare with
    # ... and it says so, not "0 passed, 0 failed"
    assert gate1["baseline_recorded"]
    assert (tmp_path / "runs" / "2026-11-20" / "gate.md").read_text().startswith(
        "# Gates: baseline recorded")
    assert "Gates: baseline recorded" in index1.read_text()
    assert "0 passed" not in index1.read_text()
    assert "Synthetic corpus" in index1.read_text()

    ok2, index2 = nightly(tmp_path, review=review_night, config=SMALL, today=day2, progress=False)
    assert ok2, (tmp_path / "runs" / "2026-11-21" / "gate.md").read_text()
    html = index2.read_text()
    assert "Changes since 2026-11-20" in html and "trend.png" in html
    gate2 = json.loads((tmp_path / "runs" / "2026-11-21" / "gate.json").read_text())
    assert {g["gate"] for g in gate2["gates"]} == {"metric", "image"}
    assert not gate2["baseline_recorded"] and "Gates: PASSED" in html
    # Same code, same data, fixed seeds: every image gate passes against the previous night.
    assert all(g["status"] == "pass" for g in gate2["gates"]), gate2
    history = pd.read_csv(tmp_path / "history.csv")
    assert sorted(history["night"].unique()) == ["2026-11-20", "2026-11-21"]
    assert (tmp_path / "latest.txt").read_text().strip() == "2026-11-21"

    # Plant a regression: make the previous night look better than tonight will be (one check
    # loses its negatives there), so tonight "gains" negatives and the metric gate must fail.
    prev = tmp_path / "runs" / "2026-11-21" / "results.parquet"
    res = pd.read_parquet(prev)
    fired = res[(res["frame"] == -1) & (res["negatives"] > 0)]
    assert len(fired), "the small evaluation fired no check; pick another task"
    res.loc[fired.index[:1], "negatives"] = 0
    rewrite_results(prev.parent, res)
    ok3, _ = nightly(tmp_path, review=review_night, config=SMALL, today=day3, progress=False)
    assert not ok3
    gate3 = (tmp_path / "runs" / "2026-11-22" / "gate.md").read_text()
    assert "FAILED" in gate3 and str(fired["check"].iloc[0]) in gate3
