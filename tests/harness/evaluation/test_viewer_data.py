"""The task viewer's data: what the geometry stage keeps (frames, quantised positions, pellets,
topology) and what the report writes for the page (links, escaping, events)."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from cassi.harness.actions import task_positions
from cassi.harness.cli import main as cli_main
from cassi.harness.evaluation.frames import VIEWER_STRIDE, viewer_frames
from cassi.harness.evaluation.caches import get_corpus, get_profile
from cassi.harness.evaluation.viewerdata import (STEP_UNITS, read_viewer_blob, viewer_blob)
from cassi.harness.rubric.fidelity import virtual_pellets
from cassi.reports.report import _env, write_report
from cassi.reports.runio import load_run
from cassi.reports.viewer import _events, version_payload, table_legend, viewer_href
from cassi.versions.mapping import XrmbToParke


def test_viewer_frames_keep_the_grid_the_last_row_and_every_evidence_frame():
    frames = np.arange(10, 60)
    rows = pd.DataFrame({"frame": [-1, 13, 13, 57, 22], "view": ["geometry", "geometry", "side",
                                                                  "geometry", "trace"]})
    kept = viewer_frames(frames, rows, stride=8)
    assert kept == sorted({10, 18, 26, 34, 42, 50, 58, 59, 13, 57})
    assert 22 not in kept            # a fidelity trace row is data, not a check's frame
    assert viewer_frames(frames, None) == sorted(set(range(10, 60, VIEWER_STRIDE)) | {59})


@pytest.fixture(scope="module")
def jw11_106():
    face, frames, positions, _ = task_positions(None, "JW11", 106, 1, "cassi-1.0")
    corpus = get_corpus(None)
    rec = corpus.subject("JW11").load(106, 1)
    return face, frames, positions, rec, get_profile(corpus, "JW11")


def test_a_blob_gives_back_every_kept_frame_within_half_a_step(jw11_106):
    face, frames, positions, rec, profile = jw11_106
    keep = viewer_frames(frames, None)
    idx = np.searchsorted(frames, keep)
    blob = viewer_blob(face, positions[idx], np.asarray(keep), np.asarray(rec.time_us)[keep],
                       np.asarray(rec.xy_mm)[keep], np.asarray(rec.valid)[keep],
                       profile.jaw_length_mm)
    vd = read_viewer_blob(blob)
    assert vd.frames.tolist() == keep
    err = np.abs(vd.positions() - positions[idx]).max()
    assert err <= STEP_UNITS / 2 + 1e-4
    # only vertices that move are stored per frame; the still ones are exact
    still = np.setdiff1d(np.arange(positions.shape[1]), vd.moving)
    assert len(vd.moving) < positions.shape[1] / 2
    assert np.array_equal(vd.positions()[:, still], np.repeat(positions[idx][:1, still],
                                                              len(keep), axis=0))
    # the model's pellet sites are Table F's (the same mapping, same frames)
    mapping = XrmbToParke.from_face(face.vertices, profile.jaw_length_mm)
    assert np.allclose(vd.model, virtual_pellets(positions[idx], mapping), atol=1e-3)
    assert np.allclose(vd.measured[np.asarray(rec.valid)[keep]],
                       np.asarray(rec.xy_mm)[keep][np.asarray(rec.valid)[keep]], atol=1e-4)
    # the merged topology draws every triangle from face rows
    assert vd.triangles.max() < len(vd.gather) and vd.gather.max() < positions.shape[1]
    assert set(vd.parts) >= {"skin", "lips", "tongue"}
    # a small blob: well under the float positions of the kept frames
    assert len(blob) < positions[idx].nbytes / 10


def test_a_blob_keeps_the_map_that_places_the_pellets_on_the_face(jw11_106):
    """The viewer places pellets in 3D and turns Parke units into mm with the version's own
    XRMB -> Parke map (thesis 4.1.1): scale p / d and vertex 226 as the XRMB origin."""
    face, frames, positions, rec, profile = jw11_106
    keep = viewer_frames(frames, None)
    idx = np.searchsorted(frames, keep)
    vd = read_viewer_blob(viewer_blob(
        face, positions[idx], np.asarray(keep), np.asarray(rec.time_us)[keep],
        np.asarray(rec.xy_mm)[keep], np.asarray(rec.valid)[keep], profile.jaw_length_mm))
    mapping = XrmbToParke.from_face(face.vertices, profile.jaw_length_mm)
    assert vd.units_per_mm == pytest.approx(face.units_per_mm) == pytest.approx(mapping.scale)
    assert np.array_equal(vd.xrmb_origin, mapping.origin)
    # the model's sites map back onto the vertices they were read from (upper lip: vertex N.UL)
    from cassi.data.face import numbering as N
    ul = vd.model[:, 0] * vd.units_per_mm + vd.xrmb_origin
    assert np.allclose(ul, positions[idx][:, N.UL - 1][:, [0, 2]], atol=1e-3)


def test_a_format_2_blob_still_reads_without_the_map(jw11_106):
    """Stores written before format 3 still report: no map, so no pellet markers or mm."""
    import io
    face, frames, positions, rec, profile = jw11_106
    keep = viewer_frames(frames, None)[:20]
    idx = np.searchsorted(frames, keep)
    blob = viewer_blob(face, positions[idx], np.asarray(keep), np.asarray(rec.time_us)[keep],
                       np.asarray(rec.xy_mm)[keep], np.asarray(rec.valid)[keep],
                       profile.jaw_length_mm)
    with np.load(io.BytesIO(blob)) as z:
        old = {k: z[k] for k in z.files if k not in ("units_per_mm", "xrmb_origin")}
    buf = io.BytesIO()
    np.savez(buf, **{**old, "format": np.int64(2)})
    vd = read_viewer_blob(buf.getvalue())
    assert vd.units_per_mm is None and vd.xrmb_origin is None
    assert np.array_equal(vd.positions(), read_viewer_blob(blob).positions())
    payload = version_payload(vd, [], [])
    assert payload["units_per_mm"] is None and payload["xrmb_origin"] is None


def test_a_blob_of_another_format_is_refused(jw11_106):
    import io
    buf = io.BytesIO()
    np.savez(buf, format=np.int64(99))
    with pytest.raises(ValueError, match="format 99"):
        read_viewer_blob(buf.getvalue())


def test_viewer_links_quote_what_they_carry():
    href = viewer_href("JW11", 106, 1, frame=12, a="v&1", check="a#b", base="../")
    assert href == "../viewer/JW11/106_1.html#frame=12&a=v%261&check=a%23b"
    assert viewer_href("JW11", 5, 2) == "viewer/JW11/005_2.html"


def test_a_viewer_link_opens_in_the_view_its_check_is_judged_from():
    from cassi.harness.rubric import CHECKS
    assert CHECKS["jaw_long"].view == "side"
    assert viewer_href("JW15", 9, 1, frame=4, check="jaw_long").endswith("&check=jaw_long&view=side")
    # a view given wins; an unknown check names no view
    assert viewer_href("JW15", 9, 1, check="jaw_long", view="top").endswith("view=top")
    assert "view=" not in viewer_href("JW15", 9, 1, check="no-such-check")


def test_the_viewer_charges_a_fault_once_as_the_report_does():
    # lips_do_not_close is charged with lips_apart_at_start (registry): the viewer lists both,
    # the second with no negative of its own and the report's note saying why
    from cassi.harness.rubric import CHECKS

    def rows(check, neg, frame):
        base = dict(subject="JW11", task=106, rep=1, version="cassi-1.0", view="geometry",
                    table=CHECKS[check].table, component="lips", check=check, value=5.0,
                    unit="mm", threshold=1.5, detail="", synthetic=True)
        return [{**base, "frame": -1, "negatives": neg}, {**base, "frame": frame, "negatives": neg}]
    res = pd.DataFrame(rows("lips_apart_at_start", 2, 40) + rows("lips_do_not_close", 1, 0)
                       + rows("lips_pressed", 0, 7))
    ev = {e["check"]: e for e in _events(res)[("JW11", 106, 1, "cassi-1.0")]}
    assert (ev["lips_apart_at_start"]["negatives"], ev["lips_apart_at_start"]["note"]) == (2, "")
    closing = ev["lips_do_not_close"]
    assert (closing["negatives"], closing["raw_negatives"]) == (0, 1)
    assert "lips_apart_at_start" in closing["note"]
    assert (ev["lips_pressed"]["negatives"], ev["lips_pressed"]["raw_negatives"]) == (0, 0)
    # fired first, by what is charged
    assert [e["check"] for e in _events(res)[("JW11", 106, 1, "cassi-1.0")]] == [
        "lips_apart_at_start", "lips_do_not_close", "lips_pressed"]


def test_an_event_shows_the_value_the_subject_page_shows():
    """The viewer's event names a check and shows that check's whole-file value (the subject
    pages' and tables' source), never an evidence row's value of a frame in another unit."""
    base = dict(subject="JW11", task=19, rep=1, version="cassi-1.0", view="geometry", table="C",
                component="lips", check="lips_do_not_close", unit="fraction", threshold=0.5,
                detail="", synthetic=True)
    res = pd.DataFrame([{**base, "frame": -1, "negatives": 0, "value": 0.0},
                        {**base, "frame": 812, "negatives": 0, "value": 16.51, "unit": "J"},
                        {**base, "frame": 900, "negatives": 0, "value": -6.69}])
    (event,) = _events(res)[("JW11", 19, 1, "cassi-1.0")]
    assert (event["value"], event["unit"], event["frames"]) == (0.0, "fraction", [812, 900])


def test_the_page_escapes_what_it_is_given():
    html = _env().get_template("viewer.html.j2").render(
        subject="<script>alert(1)</script>", task=1, rep=1, synthetic=True,
        versions=['"><img src=x onerror=alert(1)>'], data="001_1.js", static="../../static",
        index="../../index.html", subject_page="x.html", legend=table_legend(), stride=4)
    assert "<script>alert(1)" not in html and "&lt;script&gt;" in html
    assert "<img src=x" not in html


@pytest.mark.render
def test_the_report_writes_one_viewer_per_task_file_with_its_events(tmp_path):
    run = tmp_path / "run"
    assert cli_main(["run", "--subjects", "JW11", "--versions", "cassi-1.0", "cassi-2.1",
                     "--tasks", "106", "--views", "front", "--no-progress",
                     "--out", str(run)]) == 0
    write_report(run, tmp_path / "report")
    page = tmp_path / "report" / "viewer" / "JW11" / "106_1.html"
    text = (page.with_suffix(".js")).read_text()
    assert text.startswith("window.CASSI_VIEWER = ") and text.endswith(";\n")
    data = json.loads(text[len("window.CASSI_VIEWER = "):-2])
    assert data["versions"] == ["cassi-1.0", "cassi-2.1"] and data["synthetic"] is True
    res = pd.read_parquet(run / "results.parquet")
    for version in data["versions"]:
        events = {e["check"]: e for e in data["version_data"][version]["events"]}
        ev = res[(res["version"] == version) & (res["frame"] >= 0) & res["table"].notna()
                 & (res["view"] != "trace")]
        assert set(events) == set(ev["check"])
        for check, g in ev.groupby("check"):
            assert events[check]["frames"] == sorted(set(g["frame"].astype(int)))
        # every value shown is the results table's whole-file value of that check: 0 differ
        whole = res[(res["version"] == version) & (res["frame"] == -1) & res["table"].notna()]
        for check, row in whole.drop_duplicates("check").set_index("check").iterrows():
            if check in events:
                assert events[check]["value"] == pytest.approx(float(row["value"]), nan_ok=True)
                assert events[check]["unit"] == ("" if pd.isna(row["unit"]) else row["unit"])
        # the renders beside the 3D view are linked from the page's folder
        for r in data["version_data"][version]["renders"]:
            assert (page.parent / r["href"]).is_file()
    for name in ("three.min.js", "three.LICENSE.txt", "viewer.js"):
        assert (tmp_path / "report" / "static" / name).is_file()
    index = (tmp_path / "report" / "index.html").read_text()
    assert 'href="viewer/JW11/106_1.html"' in index
    # a run written before the attachment index has no viewer, and still reports
    (run / "attachments.parquet").unlink()
    (run / "attachments.csv").unlink()
    doc = json.loads((run / "tables.json").read_text())
    doc["files"] = {k: v for k, v in doc["files"].items() if not k.startswith("attachments")}
    (run / "tables.json").write_text(json.dumps(doc))
    assert len(load_run(run).attachments) == 0
    shutil.rmtree(tmp_path / "report")
    write_report(run, tmp_path / "report")
    assert not (tmp_path / "report" / "viewer").exists()


@pytest.mark.render
def test_a_corpus_with_sound_and_an_alignment_gives_the_timeline_both(tmp_path):
    from praatio import textgrid
    from praatio.data_classes.interval_tier import IntervalTier
    from scipy.io import wavfile

    from cassi.harness.evaluation.caches import corpus_root

    src, corpus = corpus_root(None), tmp_path / "corpus"
    (corpus / "JW11").mkdir(parents=True)
    shutil.copy(src / "Headmeasures.txt", corpus)
    for name in ("Mis.dat", "PAL.DAT", "PHA.DAT", "tp106.txy"):
        shutil.copy(src / "JW11" / name, corpus / "JW11")
    rate = 16000
    t = np.arange(rate * 8) / rate
    wavfile.write(corpus / "JW11" / "tp106.wav", rate,
                  (0.3 * np.sin(2 * np.pi * 220 * t) * 32767).astype(np.int16))
    tg = textgrid.Textgrid()
    tg.addTier(IntervalTier("word", [(0.5, 1.0, "sa"), (1.2, 1.8, "<b>x</b>")], 0, 8))
    tg.addTier(IntervalTier("phone", [(0.5, 0.7, "s"), (0.7, 1.0, "aa")], 0, 8))
    tg.save(str(corpus / "JW11" / "tp106.TextGrid"), format="long_textgrid",
            includeBlankSpaces=True)
    run = tmp_path / "run"
    assert cli_main(["run", "--corpus", str(corpus), "--subjects", "JW11", "--tasks", "106",
                     "--versions", "cassi-1.0", "--views", "front", "--no-progress",
                     "--out", str(run)]) == 0
    write_report(run, tmp_path / "report")
    page = tmp_path / "report" / "viewer" / "JW11" / "106_1.html"
    text = page.with_suffix(".js").read_text()
    data = json.loads(text[len("window.CASSI_VIEWER = "):-2])
    assert data["audio"] == "106_1.wav" and (page.parent / "106_1.wav").is_file()
    assert data["waveform"]["seconds"] == pytest.approx(8.0)
    assert max(data["waveform"]["max"]) == pytest.approx(0.3, abs=0.01)
    assert [w[2] for w in data["labels"]["words"] if w[2]] == ["sa", "<b>x</b>"]
    assert [p[2] for p in data["labels"]["phones"] if p[2]] == ["s", "aa"]
    assert "<b>x</b>" not in page.read_text()   # labels reach the page only as JSON text


def test_a_table_b_verdict_opens_beside_parkes_face():
    from cassi.harness.rubric import shown_beside
    run = {"parke-1974", "cassi-1.0", "cassi-2.1"}
    # Table B's figures are ratios over Parke's neutral face: shown beside it when the run has it
    assert shown_beside("B", "cassi-1.0", run) == "parke-1974"
    assert shown_beside("B", "parke-1974", run) is None
    assert shown_beside("B", "cassi-1.0", {"cassi-1.0", "cassi-2.1"}) is None
    assert shown_beside("C", "cassi-1.0", run) is None
    href = viewer_href("JW15", 9, 1, frame=4, a="cassi-1.0",
                       b=shown_beside("B", "cassi-1.0", run), check="jaw_long")
    assert href.endswith("#frame=4&a=cassi-1.0&b=parke-1974&check=jaw_long&view=side")
