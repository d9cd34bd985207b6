"""cassi sensitivity: a finding that flips when a ranged constant moves is reported as holding
in k < n settings with that constant named; the thresholds path animates and renders nothing."""
from __future__ import annotations

import json
import sys

import pandas as pd
import pytest

from cassi.common.errors import CassiInputError
from cassi.harness.evaluation import sensitivity as ES
from cassi.harness.farm.results import normalize
from cassi.harness.rubric import sensitivity as S
from cassi.harness.rubric.model import Check
from cassi.harness.rubric.registry import CHECKS
from cassi.versions.ranges import ranged_constants

from reports_fixtures import write_run

#: Table B's jaw_long (1.15, range 1.13-1.165) decides cassi-2.0 against cassi-1.0; Table A's
#: lips_pressed (2.0, range 1.0-3.0) decides it by more than its range can move.
PLANTED = {("cassi-1.0", "jaw_long"): 1.16, ("cassi-2.0", "jaw_long"): 1.14,
           ("cassi-1.0", "lips_pressed"): 3.5, ("cassi-2.0", "lips_pressed"): 0.0}


def _row(version, check, value, view="geometry"):
    c = CHECKS[check]
    return dict(subject="JW11", task=19, rep=1, version=version, view=view, frame=-1,
                check=check, table=c.table, component=c.component, value=value, unit=c.unit,
                threshold=c.threshold, negatives=c.grade(value), detail="", synthetic=True)


def _results(planted=PLANTED, extra=()):
    return normalize([_row(v, k, x) for (v, k), x in planted.items()] + list(extra))


def _run(tmp_path, results):
    meta = {"tasks_resolved": [["JW11", 19, 1, True, "", "0" * 64]],
            "versions_resolved": ["cassi-1.0", "cassi-2.0"], "corpus_resolved": str(tmp_path),
            "workers_resolved": 1}
    return write_run(tmp_path / "run", results, meta=meta)


def _finding(doc, kind, table):
    return next(f for f in doc["findings"] if f["kind"] == kind and f["table"] == table
                and f["a"] == "cassi-2.0" and f["b"] == "cassi-1.0")


def test_a_planted_threshold_flip_holds_in_k_of_n_and_names_the_threshold(tmp_path):
    run = _run(tmp_path, _results())
    doc = ES.sensitivity(run, only="thresholds")
    n = 1 + len(S.threshold_settings())
    b = _finding(doc, "totals", "B")
    assert b["outcome"] == "cassi-2.0" and b["settings"] == n and b["holds"] == n - 2
    assert [(x["setting"], x["outcome"]) for x in b["flips"]] == [
        ("jaw_long = 1.13", S.TIE), ("jaw_long = 1.165", S.TIE)]
    a = _finding(doc, "totals", "A")
    assert a["outcome"] == "cassi-2.0" and a["holds"] == a["settings"] == n and not a["flips"]
    # a threshold moves no measured value: the paired finding is the baseline alone
    assert _finding(doc, "paired", "B")["settings"] == 1
    md = (run / "sensitivity.md").read_text()
    assert f"{n - 2} of {n}" in md and "jaw_long = 1.13 (a tie)" in md
    assert json.loads((run / "sensitivity.json").read_text())["findings"] == doc["findings"]


def test_the_thresholds_path_animates_and_renders_nothing(tmp_path, monkeypatch):
    run = _run(tmp_path, _results())
    before = {p.name for p in run.iterdir()}

    def refuse(*_a, **_k):
        raise AssertionError("the thresholds path animated or rendered")
    monkeypatch.setattr(ES, "checked_animation", refuse)
    monkeypatch.setattr(ES, "_geometry_rows", refuse)
    monkeypatch.setattr("cassi.renderer.render.FaceRenderer.render", refuse)
    ES.sensitivity(run, tmp_path / "out", only="thresholds")
    assert {p.name for p in run.iterdir()} == before
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [ES.JSON_NAME, ES.MD_NAME]


def test_results_judged_by_other_thresholds_are_refused(tmp_path):
    r = _results()
    r.loc[(r["check"] == "jaw_long") & (r["version"] == "cassi-2.0"), "negatives"] = 1
    with pytest.raises(CassiInputError, match="jaw_long.*another rubric"):
        ES.sensitivity(_run(tmp_path, r), only="thresholds")


def fake_geometry_rows(corpus, subject, task, rep, version, constant, value):
    """Geometry rows as the planted run's, but cassi-2.0's jaw as long as 1.0's when RHO is at
    its high end (a worker process runs it: module level, picklable)."""
    jaw = PLANTED[(version, "jaw_long")]
    if version == "cassi-2.0" and constant == "lips_constants.RHO" and value == 0.2:
        jaw = 1.16
    return pd.DataFrame([_row(version, "jaw_long", jaw),
                         _row(version, "lips_pressed", PLANTED[(version, "lips_pressed")])])


def test_a_planted_version_constant_flip_is_named(tmp_path, monkeypatch):
    image = _row("cassi-2.0", "lips_centered_high", 0.9, view="front")  # kept: no render
    run = _run(tmp_path, _results(extra=[image]))
    monkeypatch.setattr(ES, "_geometry_rows", sys.modules[__name__].fake_geometry_rows)
    doc = ES.sensitivity(run, only="versions", workers=1, log=lambda *_: None)
    n = 1 + 2 * len(ranged_constants())
    for kind in ("totals", "paired"):
        f = _finding(doc, kind, "B")
        assert f["settings"] == n and f["holds"] == n - 1, kind
        assert [x["setting"] for x in f["flips"]] == ["lips_constants.RHO = 0.2"]
    assert doc["timing"]["version_settings"] == n - 1


def test_with_geometry_replaces_the_geometry_stage_rows_and_keeps_the_image_rows():
    image = _row("cassi-2.0", "lips_centered_high", 0.9, view="front")
    old = _results(extra=[image])
    new = ES._with_geometry(old, [pd.DataFrame([_row("cassi-2.0", "jaw_long", 1.2)])], True)
    assert sorted(zip(new["check"], new["value"])) == [("jaw_long", 1.2),
                                                      ("lips_centered_high", 0.9)]


def test_ranges_are_verified_as_the_registry_declares_them():
    base = dict(name="x", table="A", component="lips", view="front", unit="mm", frames="all",
                description="", negatives=(1, 2), direction="higher", reason="", text="",
                kind="geometry", measure="measures:m", thresholds=(1.0, 3.0))
    Check(**base, ranges=((0.5, 1.5), None), range_reason="why").verify_ranges()
    for bad in (((1.5, 2.0), None), ((0.5, 3.5), None), ((0.5, 1.5),)):
        with pytest.raises(ValueError):
            Check(**base, ranges=bad, range_reason="why").verify_ranges()
    with pytest.raises(ValueError, match="range_reason"):
        Check(**base, ranges=((0.5, 1.5), None)).verify_ranges()


def test_every_ranged_threshold_has_its_reason_and_the_self_graded_check_none():
    ranged = S.threshold_ranges()
    assert len(ranged) >= 25
    assert all(len(t["reason"]) > 20 for t in ranged)
    # m_tongue_teeth grades from both sets' depths: its stored value cannot be re-graded
    assert not CHECKS["tongue_through_teeth"].ranges


def test_a_threshold_reaches_its_table_and_the_tables_built_from_it():
    """Only these tables are aggregated again for a threshold setting (the others keep the
    baseline's findings): Table A's lip rows are Table C's too, and C is aggregated with them."""
    from cassi.harness.rubric import CHECKS
    from cassi.harness.rubric.sensitivity import tables_reached

    assert tables_reached(CHECKS["lips_pressed"]) == {"A", "C"}
    assert tables_reached(CHECKS["lips_do_not_close"]) == {"A", "C"}
    assert tables_reached(CHECKS["jaw_long"]) == {"B"}
    assert tables_reached(CHECKS["tongue_through_teeth"]) == {"A"}
