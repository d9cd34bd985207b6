"""The report shows each finding with its robustness when the run has ``sensitivity.json``."""
from __future__ import annotations

from cassi.harness.evaluation.sensitivity import sensitivity
from cassi.harness.farm.results import normalize
from cassi.harness.rubric.registry import CHECKS
from cassi.reports.report import write_report

from reports_fixtures import write_run


def _row(version, check, value):
    c = CHECKS[check]
    return dict(subject="JW11", task=19, rep=1, version=version, view="geometry", frame=-1,
                check=check, table=c.table, component=c.component, value=value, unit=c.unit,
                threshold=c.threshold, negatives=c.grade(value), detail="", synthetic=True)


def test_the_report_shows_the_findings_with_the_settings_that_flip_them(tmp_path):
    # jaw_long 1.16 against 1.14: cassi-2.0's better face shape rests on the 1.15 threshold
    results = normalize([_row("cassi-1.0", "jaw_long", 1.16), _row("cassi-2.0", "jaw_long", 1.14)])
    run = write_run(tmp_path / "run", results)
    assert "Robustness of these findings" not in write_report(run, tmp_path / "r0").read_text()
    sensitivity(run, only="thresholds")
    html = write_report(run, tmp_path / "r1").read_text()
    assert "Robustness of these findings" in html
    assert "cassi-2.0 better than cassi-1.0 on face shape (fewer negatives)" in html
    assert "jaw_long = 1.13 (a tie); jaw_long = 1.165 (a tie)" in html
    assert (tmp_path / "r1" / "tables" / "sensitivity.csv").is_file()
