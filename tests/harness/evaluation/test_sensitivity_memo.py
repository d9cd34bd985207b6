"""A night whose results table is an earlier night's, graded by the same code and rubric, takes
that night's robustness analysis from the store, saying so; anything else computes it anew."""
from __future__ import annotations

import json

from cassi.harness.evaluation.sensitivity import sensitivity
from cassi.harness.farm.results import normalize
from cassi.harness.rubric.registry import CHECKS

from reports_fixtures import write_run

PROVENANCE = {"code_digest": "c" * 64, "versions_code_digest": "v" * 64,
              "rubric_digest": "r" * 64, "packages": {"numpy": "2"}}


def _results(value):
    c = CHECKS["jaw_long"]
    return normalize([dict(subject="JW11", task=19, rep=1, version=v, view="geometry", frame=-1,
                           check="jaw_long", table=c.table, component=c.component, value=x,
                           unit=c.unit, threshold=c.threshold, negatives=c.grade(x), detail="",
                           synthetic=True)
                      for v, x in (("cassi-1.0", 1.16), ("cassi-2.0", value))])


def _night(tmp_path, name, value, provenance=PROVENANCE):
    return write_run(tmp_path / name, _results(value), meta={"provenance": provenance})


def test_the_same_results_and_code_reuse_the_analysis(tmp_path):
    memo, said = tmp_path / "store" / "derived", []
    first = sensitivity(_night(tmp_path, "n1", 1.14), only="thresholds", memo=memo,
                        log=said.append)
    assert "reused_from" not in first and not said
    second = sensitivity(_night(tmp_path, "n2", 1.14), only="thresholds", memo=memo,
                         log=said.append)
    assert second["reused_from"] == first["run"] and second["run"].endswith("n2")
    assert second["findings"] == first["findings"] and "reused" in said[0]
    on_disk = json.loads((tmp_path / "n2" / "sensitivity.json").read_text())
    assert on_disk["reused_from"] == first["run"]
    assert "Reused from" in (tmp_path / "n2" / "sensitivity.md").read_text()
    # a third night like them names the night that computed it, not the one that reused it
    third = sensitivity(_night(tmp_path, "n3", 1.14), only="thresholds", memo=memo)
    assert third["reused_from"] == first["run"]


def test_other_results_code_or_rubric_compute_anew(tmp_path):
    memo = tmp_path / "store" / "derived"
    sensitivity(_night(tmp_path, "n1", 1.14), only="thresholds", memo=memo)
    other_rubric = {**PROVENANCE, "rubric_digest": "s" * 64}
    for name, value, prov in (("values", 1.13, PROVENANCE), ("rubric", 1.14, other_rubric)):
        doc = sensitivity(_night(tmp_path, name, value, prov), only="thresholds", memo=memo)
        assert "reused_from" not in doc, name
    # a run that records no provenance is never recognised
    doc = sensitivity(write_run(tmp_path / "bare", _results(1.14)), only="thresholds", memo=memo)
    assert "reused_from" not in doc


def test_a_version_changed_without_changing_its_results_reuses_the_threshold_analysis(tmp_path):
    """Re-grading under other thresholds reads the results and the rubric, no version's code:
    only an analysis that animates the versions again keys on their code."""
    memo = tmp_path / "store" / "derived"
    sensitivity(_night(tmp_path, "n1", 1.14), only="thresholds", memo=memo)
    refactored = {**PROVENANCE, "versions_code_digest": "w" * 64}
    doc = sensitivity(_night(tmp_path, "n2", 1.14, refactored), only="thresholds", memo=memo)
    assert doc["reused_from"].endswith("n1")
    other_code = {**PROVENANCE, "code_digest": "d" * 64}
    doc = sensitivity(_night(tmp_path, "n3", 1.14, other_code), only="thresholds", memo=memo)
    assert "reused_from" not in doc
