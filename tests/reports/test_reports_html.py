"""The HTML report: content, self-containment, escaping, comparison, command."""
from __future__ import annotations

import re

import pandas as pd

from reports_fixtures import image, results_rows, write_run
from cassi.harness.cli import main
from cassi.harness.farm.results import normalize
from cassi.reports.report import slug, write_report


def _run(tmp_path, name, negatives, subjects=("JW11", "JW12")):
    res = results_rows(negatives, subjects=subjects)
    images = {(s, 19, v, view, f): image(hash((s, v, view, f)) % 1000)
              for s in subjects for v in ("cassi-1.0", "cassi-2.0") for view in ("front", "side")
              for f in (0, 7)}
    return write_run(tmp_path / name, res, images=images, meta={"git_revision": "abc123"})


def test_report_has_tables_banner_images_and_csv(tmp_path):
    run = _run(tmp_path, "run", {("cassi-1.0", "JW11", "lip_gap_start"): 2})
    index = write_report(run, tmp_path / "report")
    html = index.read_text()
    assert "Synthetic corpus" in html and "not real speakers" in html
    assert "Teeth, lips and tongue per subject (thesis Table 5.3)" in html
    assert "GOOD" in html and "abc123" in html
    # Every referenced local file exists (self-contained: no network, images alongside).
    for ref in re.findall(r'(?:src|href)="([^"#]+)"', html):
        assert not ref.startswith(("http:", "https:", "//")), ref
        assert (index.parent / ref).exists(), ref
    page = (index.parent / "subjects" / "JW11.html").read_text()
    assert "lip_gap_start" in page and "frame pointed at: 7" in page
    for ref in re.findall(r'src="([^"]+)"', page):
        assert (index.parent / "subjects" / ref).resolve().is_file(), ref
    # table cells link to the subject's evidence, which leads with what fired
    links = re.findall(r'<a class="cell" href="([^"]+)"', html)
    assert "subjects/JW11.html#cassi-1.0-table-A" in links
    for link in links:
        target, anchor = link.split("#")
        assert f'id="{anchor}"' in (index.parent / target).read_text(), link
    evidence = page[page.index('id="cassi-1.0-table-A"'):]
    fired = evidence.index('class="fired"')
    assert fired < evidence.index("silent check")        # what fired first, silent ones folded
    block = evidence[fired:evidence.index("</div>", evidence.index('class="views"', fired))]
    assert "threshold 0.5" in block and "2 negatives" in block and "front" in block
    assert "How the tables are counted" in html and "One fault, one charge" in html
    csv = pd.read_csv(index.parent / "tables" / "table_A_cassi-1.0.csv")
    assert set(csv["rating"]) == {"GOOD", "EXCELLENT"}
    assert (index.parent / "tables" / "rating_counts_C.md").read_text().startswith("| version")


def test_strings_from_data_are_escaped(tmp_path):
    evil = "<script>alert(1)</script>"
    run = _run(tmp_path, "run", {("cassi-1.0", evil, "lip_gap_start"): 1}, subjects=(evil,))
    index = write_report(run, tmp_path / "report")
    html = index.read_text()
    assert "<script>" not in html and "&lt;script&gt;" in html
    pages = list((index.parent / "subjects").iterdir())
    assert len(pages) == 1 and pages[0].name == f"{slug(evil)}.html" and "/" not in slug(evil)
    assert "<script>" not in pages[0].read_text()


def test_compare_and_command(tmp_path):
    old = _run(tmp_path, "old", {("cassi-2.0", "JW11", "lip_gap_start"): 2})
    new = _run(tmp_path, "new", {})
    assert main(["report", str(new), "--compare", str(old), "--out", str(tmp_path / "rep")]) == 0
    html = (tmp_path / "rep" / "index.html").read_text()
    assert "Changes since old" in html and "▲ better" in html
    assert main(["report", str(tmp_path / "missing"), "--out", str(tmp_path / "r2")]) == 2


def test_report_lists_the_2_1_criterion_margin_per_task_file(tmp_path):
    """The criterion rows (view ``criterion``, written by run_geometry_checks for cassi-2.1) get a
    section and a table of their own, one line per task file; they change no rating."""
    res = results_rows({})
    crit = [dict(subject=s, task=t, rep=1, version="cassi-2.1", view="criterion", frame=-1,
                 check="low_lips_margin", table=None, component=None, value=m, unit="mm",
                 threshold=0.0, negatives=0, detail=f"reading results: margin {m:+.2f}",
                 synthetic=True)
            for (s, t), m in {("JW11", 19): 3.85, ("JW11", 21): -0.4, ("JW12", 19): 1.25}.items()]
    plain = write_run(tmp_path / "plain", res)
    both = write_run(tmp_path / "run", pd.concat([res, normalize(crit)], ignore_index=True))
    html = write_report(both, tmp_path / "report").read_text()
    assert "lip criterion (thesis 4.3.1)" in html
    section = html[html.index('id="low-lips-criterion"'):]
    assert section.count("<td>cassi-2.1</td>") == 3 and "+3.85" in section and "-0.40" in section
    table = pd.read_csv(tmp_path / "report" / "tables" / "low_lips_criterion.csv")
    assert sorted(zip(table["subject"], table["task"], table["margin_mm"])) == [
        ("JW11", 19, 3.85), ("JW11", 21, -0.4), ("JW12", 19, 1.25)]
    assert "lip criterion" not in write_report(plain, tmp_path / "r2").read_text()
    a = pd.read_csv(tmp_path / "report" / "tables" / "table_A_cassi-2.1.csv")
    assert a.equals(pd.read_csv(tmp_path / "r2" / "tables" / "table_A_cassi-2.1.csv"))


def test_versions_compared_states_the_paired_comparisons(tmp_path):
    # 2.0's tongue goes through the teeth in task 19 of both subjects; 1.0 and 2.1 never do
    run = _run(tmp_path, "run", {("cassi-2.0", s, "tongue_through_teeth"): 1 for s in ("JW11", "JW12")})
    index = write_report(run, tmp_path / "report")
    html = index.read_text()
    section = html[html.index('id="paired"'):html.index("How the tables are counted")]
    assert "Synthetic corpus:</strong> these comparisons describe the software" in section
    assert "2000 resamples of the files" in section and "seed 0" in section
    assert ("cassi-1.0 beats cassi-2.0 on tongue_through_teeth in 2 of 4 files (0 worse, 2 tied), "
            "median cassi-1.0 − cassi-2.0 -0.5 mm") in section
    assert "cassi-2.1 beats cassi-2.0 on tongue_through_teeth in 2 of 4 files" in section
    # measures where a pair never differs are left out of the section, kept in the table
    assert "lower_lip_below_teeth" not in section
    table = pd.read_csv(index.parent / "tables" / "paired_comparisons.csv")
    same = table[(table["a"] == "cassi-2.1") & (table["b"] == "cassi-1.0")]
    assert set(same["measure"]) == {"tongue_through_teeth", "lower_lip_below_teeth"}
    assert (same["ties"] == 4).all() and (same["p"] == 1.0).all()


def test_a_run_scored_under_another_rubric_says_its_tables_are_rescored(tmp_path):
    import json
    from cassi.harness.evaluation.provenance import rubric_digest
    from cassi.harness.farm.tableset import write_table_set
    from reports_fixtures import ratings
    run = _run(tmp_path, "run", {("cassi-1.0", "JW11", "lip_gap_start"): 2})
    meta = json.loads((run / "run.json").read_text())
    res = pd.read_parquet(run / "results.parquet")
    renders = pd.read_parquet(run / "renders.parquet")
    summary = json.loads((run / "summary.json").read_text())

    def rewrite(provenance, rated):  # run.json first, then its tables, as a run writes them
        (run / "run.json").write_text(json.dumps({**meta, "provenance": provenance}))
        write_table_set(run, {"results": res, "ratings": rated, "renders": renders}, summary)

    rewrite({"rubric_digest": rubric_digest()}, ratings(res))
    assert "Rescored with today" not in write_report(run, tmp_path / "r1").read_text()
    # the registry changed since the run
    rewrite({"rubric_digest": "0" * 64}, ratings(res))
    html = write_report(run, tmp_path / "r2").read_text()
    assert "Rescored with today" in html and "rubric registry" in html
    # the run's own ratings file disagrees with today's aggregation of its results
    old = ratings(res)
    old.loc[0, "negatives"] += 1
    rewrite({}, old)
    html = write_report(run, tmp_path / "r3").read_text()
    assert "1 cell(s) of the run" in html and "rubric registry" not in html
    # a pipeline's own ratings table (no rubric columns) is not compared, and breaks nothing
    rewrite({}, pd.DataFrame({"subject": ["JW11"], "score": [0.5]}))
    assert "Rescored with today" not in write_report(run, tmp_path / "r4").read_text()


def test_the_index_says_which_frames_the_checks_judged(monkeypatch):
    """A run on a sparser image grid than the nightly's can never pass for it: the index names
    the grid, in rows and seconds at the recordings' rate."""
    from types import SimpleNamespace

    from cassi.reports import report

    monkeypatch.setattr(report, "_period_for", lambda run: lambda s, t, r: 6866.0)
    tasks = [["JW11", 5, 1, False, "no file", ""], ["JW11", 19, 1, True, "", "ab"]]
    meta = {"tasks_resolved": tasks, "views_resolved": ["front", "side"], "animate_stride": 96,
            "extremes": 2, "stride": 0}
    said = report._frames_judged(SimpleNamespace(meta=meta))
    assert "every 96th row (0.659 s at 145.6 Hz)" in said
    assert "the first frame, every 96th row" in said and "up to 2 frames" in said
    said = report._frames_judged(SimpleNamespace(meta={**meta, "animate_stride": 0, "extremes": 1,
                                                       "stride": 22}))
    assert "the first frame, every 22nd row and up to 1 frame the geometric" in said
    said = report._frames_judged(SimpleNamespace(meta={**meta, "views_resolved": ["geometry"]}))
    assert "no image check judged" in said
    assert report._frames_judged(SimpleNamespace(meta={})) is None
