"""Report pages reused by content (reports.memo, reports.pagekeys): a page whose inputs are
unchanged is linked from the media cache, not made again; one whose inputs changed is made
again; what reads the previous run or the history is made every time."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from reports_fixtures import image, results_rows, rewrite_results, write_run
from cassi.harness.evaluation.stages import masks_blob
from cassi.harness.farm.tableset import write_table_set
from cassi.harness.rubric import ratings_table
from cassi.reports import memo as memo_mod
from cassi.reports import report, viewer
from cassi.reports.report import write_report


def _run(root: Path, negatives: dict | None = None) -> Path:
    res = results_rows(negatives or {("cassi-1.0", "JW11", "lip_gap_start"): 2,
                                      ("cassi-2.0", "JW12", "tongue_through_teeth"): 1})
    images = {(s, 19, v, view, f): image(i)
              for i, (s, v, view, f) in enumerate(
                  (s, v, view, f) for s in ("JW11", "JW12") for v in ("cassi-1.0", "cassi-2.0")
                  for view in ("front", "side") for f in (0, 7))}
    return write_run(root, res, images=images)


def _folder(path: Path) -> dict[str, bytes]:
    return {p.relative_to(path).as_posix(): p.read_bytes()
            for p in sorted(path.rglob("*")) if p.is_file()}


def _counting(monkeypatch) -> dict[str, int]:
    """Count the subject pages and thesis tables made (not linked)."""
    made = {"subject": 0, "tables": 0}
    subject_page, table_sections = report._subject_page, report._table_sections

    def count_subject(*a, **k):
        made["subject"] += 1
        return subject_page(*a, **k)

    def count_tables(*a, **k):
        made["tables"] += 1
        return table_sections(*a, **k)
    monkeypatch.setattr(report, "_subject_page", count_subject)
    monkeypatch.setattr(report, "_table_sections", count_tables)
    return made


def test_an_unchanged_run_links_its_pages_and_writes_the_same_folder(tmp_path, monkeypatch):
    run = _run(tmp_path / "run")
    cache = tmp_path / "media"
    slow = write_report(run, tmp_path / "slow").parent  # no cache: everything made
    made = _counting(monkeypatch)
    first = write_report(run, tmp_path / "first", media_cache=cache).parent
    assert made == {"subject": 2, "tables": 1}
    second = write_report(run, tmp_path / "second", media_cache=cache).parent
    assert made == {"subject": 2, "tables": 1}, "a page of unchanged inputs was made again"
    assert _folder(slow) == _folder(first) == _folder(second)
    # linked, not copied: the second report's pages are the first one's files
    for rel in ("subjects/JW11.html", "tables/rating_counts_A.csv", "plots/ratings_A.png"):
        assert os.path.samefile(first / rel, second / rel), rel


def test_a_changed_result_makes_its_pages_again(tmp_path, monkeypatch):
    run = _run(tmp_path / "run")
    cache = tmp_path / "media"
    write_report(run, tmp_path / "first", media_cache=cache)
    res = pd.read_parquet(run / "results.parquet")
    hit = (res["subject"] == "JW12") & (res["check"] == "tongue_through_teeth") \
        & (res["version"] == "cassi-2.0")
    res.loc[hit, "value"] = res.loc[hit, "value"] + 0.25  # one value, same negatives
    rewrite_results(run, res)
    made = _counting(monkeypatch)
    second = write_report(run, tmp_path / "second", media_cache=cache).parent
    assert made == {"subject": 1, "tables": 1}  # JW12's page and the tables; JW11's linked
    assert _folder(second) == _folder(write_report(run, tmp_path / "slow").parent)
    assert "1.25" in (second / "subjects" / "JW12.html").read_text()
    assert not os.path.samefile(tmp_path / "first" / "subjects" / "JW12.html",
                                second / "subjects" / "JW12.html")
    assert os.path.samefile(tmp_path / "first" / "subjects" / "JW11.html",
                            second / "subjects" / "JW11.html")


def test_changed_code_makes_every_page_again(tmp_path, monkeypatch):
    run = _run(tmp_path / "run")
    cache = tmp_path / "media"
    write_report(run, tmp_path / "first", media_cache=cache)
    made = _counting(monkeypatch)
    monkeypatch.setattr(memo_mod, "code_digest", lambda: "another template")
    write_report(run, tmp_path / "second", media_cache=cache)
    assert made == {"subject": 2, "tables": 1}


def test_the_comparison_and_trend_are_made_fresh(tmp_path):
    run = _run(tmp_path / "run")
    before = _run(tmp_path / "before", {("cassi-1.0", "JW11", "lip_gap_start"): 3})
    cache = tmp_path / "media"
    history = pd.DataFrame({"night": ["n1", "n2"], "version": ["cassi-1.0"] * 2,
                            "negatives": [3, 2]})
    write_report(run, tmp_path / "first", media_cache=cache)
    second = write_report(run, tmp_path / "second", media_cache=cache, compare=before,
                          history=history).parent
    slow = write_report(run, tmp_path / "slow", compare=before, history=history).parent
    assert _folder(second) == _folder(slow)
    assert "before" in (second / "index.html").read_text()
    other = history.assign(negatives=[4, 2])
    third = write_report(run, tmp_path / "third", media_cache=cache, history=other).parent
    assert (third / "plots" / "trend.png").read_bytes() != (second / "plots" / "trend.png") \
        .read_bytes()


def test_a_blob_gone_from_the_cache_makes_the_page_again(tmp_path, monkeypatch):
    run = _run(tmp_path / "run")
    cache = tmp_path / "media"
    write_report(run, tmp_path / "first", media_cache=cache)
    for blob in (cache / memo_mod.MEMO_DIR / "blobs").rglob("*"):
        if blob.is_file():
            blob.unlink()
    made = _counting(monkeypatch)
    second = write_report(run, tmp_path / "second", media_cache=cache).parent
    assert made == {"subject": 2, "tables": 1}
    assert _folder(second) == _folder(tmp_path / "first")


def test_group_digests_see_one_cell_and_the_row_order():
    df = pd.DataFrame({"subject": ["a", "a", "b"], "value": [1.0, 2.0, 3.0],
                       "text": ["x", None, "y"]})
    base = memo_mod.group_digests(df, ["subject"])
    changed = memo_mod.group_digests(df.assign(value=[1.0, 2.5, 3.0]), ["subject"])
    assert changed[("a",)] != base[("a",)] and changed[("b",)] == base[("b",)]
    none_as_text = memo_mod.group_digests(df.assign(text=["x", "None", "y"]), ["subject"])
    assert none_as_text[("a",)] != base[("a",)]
    swapped = memo_mod.group_digests(df.iloc[[1, 0, 2]].reset_index(drop=True), ["subject"])
    assert swapped[("a",)] != base[("a",)]


def test_content_ids_name_store_objects_by_name_and_other_files_by_content(tmp_path):
    digest = "ab" + "0" * 62
    assert memo_mod.content_ids([f"/x/run/objects/ab/{digest}.png"]) == [digest]
    plain = tmp_path / "r.png"
    plain.write_bytes(b"one")
    first = memo_mod.content_ids([plain])
    plain.unlink()
    plain.write_bytes(b"two")
    assert memo_mod.content_ids([plain]) != first


def test_a_mask_overlay_is_drawn_once_per_blob_and_frame(tmp_path, monkeypatch):
    mask = np.zeros((40, 60), np.uint8)
    mask[10:20, 10:50] = 2
    mask[20:24, 15:45] = 3
    depth = np.where(mask > 0, 100.0, np.inf).astype(np.float32)
    names = ("background", "skin", "lips", "teeth_upper", "tongue", "teeth_lower")
    blob = tmp_path / "masks.npz"
    blob.write_bytes(masks_blob(mask, depth, names))
    cache = tmp_path / "media"
    drawn = []
    overlay = viewer.mask_overlay
    monkeypatch.setattr(viewer, "mask_overlay",
                        lambda *a: drawn.append(a[1]) or overlay(*a))
    a = viewer.stored_overlay(blob, 7, tmp_path / "a" / "m.png", cache)
    b = viewer.stored_overlay(blob, 7, tmp_path / "b" / "m.png", cache)
    assert drawn == [7] and a.read_bytes() == b.read_bytes() and os.path.samefile(a, b)
    viewer.stored_overlay(blob, 8, tmp_path / "c" / "m.png", cache)
    assert drawn == [7, 8]  # another frame is another overlay


def test_a_page_without_result_rows_has_no_key(tmp_path):
    """A subject no row names (a missing subject reads as "" in the verdicts) is made anew,
    never linked under a key that cannot tell its inputs apart."""
    from cassi.reports.pagekeys import PageKeys
    from cassi.reports.runio import load_run

    keys = PageKeys(load_run(_run(tmp_path / "run")))
    assert keys.subject("", []) is None and keys.viewer("JW11", 99, 1) is None
    assert keys.subject("JW11", [])["results"] and keys.viewer("JW11", 19, 1)["results"]


def test_cassi_report_made_twice_with_a_media_cache_links_its_pages(tmp_path):
    from cassi.harness.cli import main

    run = _run(tmp_path / "run")
    for out in ("one", "two"):
        assert main(["report", str(run), "--out", str(tmp_path / out),
                     "--media-cache", str(tmp_path / "media")]) == 0
    assert os.path.samefile(tmp_path / "one" / "subjects" / "JW12.html",
                            tmp_path / "two" / "subjects" / "JW12.html")
    assert _folder(tmp_path / "one") == _folder(tmp_path / "two")


@pytest.fixture(scope="module")
def real_run(tmp_path_factory) -> Path:
    """A small real run with viewer data and masks: JW11 task 106, two versions, front view."""
    from cassi.harness.cli import main

    run = tmp_path_factory.mktemp("viewer") / "run"
    assert main(["run", "--subjects", "JW11", "--versions", "cassi-1.0", "cassi-2.1",
                 "--tasks", "106", "--views", "front", "--no-progress", "--out", str(run)]) == 0
    return run


def _rewrite(run: Path, results: pd.DataFrame) -> None:
    """The run's results replaced, its other tables (attachments too) kept, as one set."""
    tables = {name: pd.read_parquet(run / f"{name}.parquet")
              for name in ("renders", "attachments")}
    summary = json.loads((run / "summary.json").read_text())
    write_table_set(run, {"results": results, "ratings": ratings_table(results), **tables},
                    summary)


def test_a_viewer_page_is_linked_when_unchanged_and_made_when_its_rows_change(
        real_run, tmp_path, monkeypatch):
    run = tmp_path / "run"
    shutil.copytree(real_run, run)
    cache = tmp_path / "media"
    made = []
    write_viewer = viewer._write_viewer
    monkeypatch.setattr(viewer, "_write_viewer", lambda *a, **k: made.append(a[3:6])
                        or write_viewer(*a, **k))
    first = write_report(run, tmp_path / "first", media_cache=cache).parent
    assert made == [("JW11", 106, 1)]
    overlays = sorted((first / "images" / "masks").rglob("*.png"))
    second = write_report(run, tmp_path / "second", media_cache=cache).parent
    assert made == [("JW11", 106, 1)], "an unchanged viewer page was made again"
    page = Path("viewer/JW11/106_1.js")
    assert os.path.samefile(first / page, second / page)
    assert _folder(first) == _folder(second)
    # one whole-file value of a check changes: the page shows it, so it is made again
    res = pd.read_parquet(run / "results.parquet")
    row = res.index[(res["frame"] == -1) & res["table"].notna()
                    & (res["version"] == "cassi-2.1")][0]
    res.loc[row, "value"] = float(res.loc[row, "value"]) + 0.125 \
        if pd.notna(res.loc[row, "value"]) else 0.125
    _rewrite(run, res)
    third = write_report(run, tmp_path / "third", media_cache=cache).parent
    assert made == [("JW11", 106, 1)] * 2
    assert (third / page).read_bytes() != (first / page).read_bytes()
    slow = write_report(run, tmp_path / "slow").parent
    assert _folder(third) == _folder(slow)
    # the overlays of the page made again came from the cache, drawn once
    assert overlays
    for path in overlays:
        rel = path.relative_to(first)
        assert os.path.samefile(first / rel, third / rel)


def test_an_analysis_taken_from_an_earlier_night_keeps_the_tables_linked(tmp_path, monkeypatch):
    """A night that reuses an earlier night's robustness analysis rewrites only where it was
    made (``run``, ``reused_from``), which the section does not show: the tables stay linked;
    a changed finding makes them again."""
    from cassi.reports.sensitivity import SENSITIVITY_FILE
    run = _run(tmp_path / "run")
    doc = {"run": "/nights/runs/2026-12-06", "synthetic": True, "only": "thresholds",
           "settings_per_constant": 2, "timing": {"baseline_s": 0.1},
           "constants": [{"kind": "threshold", "constant": "lip_gap_start", "value": 1.5,
                          "low": 1.0, "high": 2.0, "reason": "r"}],
           "findings": [], "note": "n"}
    (run / SENSITIVITY_FILE).write_text(json.dumps(doc))
    cache = tmp_path / "media"
    made = _counting(monkeypatch)
    write_report(run, tmp_path / "first", media_cache=cache)
    assert made["tables"] == 1
    (run / SENSITIVITY_FILE).write_text(json.dumps(
        {**doc, "run": "/nights/runs/2026-12-07", "reused_from": "/nights/runs/2026-12-06"}))
    write_report(run, tmp_path / "second", media_cache=cache)
    assert made["tables"] == 1, "the tables were made again for a rewritten provenance"
    (run / SENSITIVITY_FILE).write_text(json.dumps({**doc, "note": "another note"}))
    write_report(run, tmp_path / "third", media_cache=cache)
    assert made["tables"] == 2
