"""A nightly directory's nights in order: by (date, sequence), never by their names as strings
(``-10`` sorts before ``-2``), so that each night is gated against the one before it, ``cassi
gc`` keeps the newest nights and the one ``latest.txt`` names, and no name is used twice."""
from __future__ import annotations

import datetime as dt
import json

import pandas as pd
import pytest

from cassi.common.errors import CassiInputError
from cassi.harness.evaluation.nights import NIGHT_DONE, gc, night_key, night_name, previous_night
from cassi.harness.farm.tableset import write_table_set

DAY = dt.date(2026, 12, 7)
NAMES = ["2026-12-06"] + ["2026-12-07"] + [f"2026-12-07-{n}" for n in range(2, 11)]


def _night(root, name: str) -> None:
    """A finished night whose run is complete (its table set verifies, no job failed)."""
    run_dir = root / "runs" / name
    run_dir.mkdir(parents=True)
    (run_dir / "run.json").write_text("{}")
    write_table_set(run_dir, {n: pd.DataFrame() for n in ("results", "ratings", "renders")},
                    {"failed": 0})
    (run_dir / NIGHT_DONE).write_text(json.dumps({"night": name}))
    (root / "reports" / name).mkdir(parents=True)
    (root / "latest.txt").write_text(name + "\n")


@pytest.fixture
def ten_nights(tmp_path):
    for name in NAMES:
        _night(tmp_path, name)
    return tmp_path


def test_each_night_is_gated_against_the_night_before_it(ten_nights):
    runs = ten_nights / "runs"
    assert previous_night(runs, "2026-12-07-10") == runs / "2026-12-07-9"
    assert previous_night(runs, "2026-12-07-2") == runs / "2026-12-07"
    assert previous_night(runs, "2026-12-07") == runs / "2026-12-06"
    assert previous_night(runs, "2026-12-06") is None
    assert night_name(runs, DAY) == "2026-12-07-11"
    assert sorted(NAMES, key=night_key) == NAMES
    assert night_key("2026-12-07-1") is None and night_key("notes") is None


def test_gc_keeps_the_newest_nights_and_the_one_latest_names(ten_nights):
    (ten_nights / "runs" / "notes").mkdir()  # not a night: left alone
    out = gc(ten_nights, keep=2)
    assert out["nights_kept"] == ["2026-12-07-9", "2026-12-07-10"]
    assert "2026-12-07-10" not in out["nights_removed"] and "2026-12-07-2" in out["nights_removed"]
    assert (ten_nights / "runs" / "2026-12-07-10").is_dir()
    assert (ten_nights / "runs" / "notes").is_dir()
    # latest.txt naming an older night (the newest was interrupted): that night stays too
    (ten_nights / "latest.txt").write_text("2026-12-07-9\n")
    out = gc(ten_nights, keep=1)
    assert out["nights_kept"] == ["2026-12-07-9", "2026-12-07-10"] and not out["nights_removed"]


def test_a_name_is_never_used_again_after_gc(ten_nights):
    runs = ten_nights / "runs"
    gc(ten_nights, keep=1)
    assert sorted(p.name for p in runs.iterdir()) == ["2026-12-07-10"]
    name = night_name(runs, DAY)
    assert name == "2026-12-07-11"  # not 2026-12-07 again, which would record a new baseline
    assert previous_night(runs, name) == runs / "2026-12-07-10"
    # even with the night gone, the name latest.txt holds is not used again
    (runs / "2026-12-07-10" / NIGHT_DONE).unlink()
    assert night_name(runs, DAY) == "2026-12-07-10"  # the newest, unfinished: resumed
    (runs / "2026-12-07-10").rename(runs / "gone")
    assert night_name(runs, DAY) == "2026-12-07-11"
    assert night_name(runs, DAY + dt.timedelta(days=1)) == "2026-12-08"


def test_a_clock_behind_the_newest_night_is_refused(ten_nights):
    with pytest.raises(CassiInputError, match=r"2026-12-07-10, is dated after today \(2026-12-06\)"):
        night_name(ten_nights / "runs", DAY - dt.timedelta(days=1))


def test_gc_forgets_the_page_memo_and_the_analyses_no_kept_night_uses(ten_nights):
    """A report's page memo keeps files hard-linked into reports: gc removes those no report
    links any more, the page records naming them and stale staging folders; and the kept
    robustness analyses of removed nights."""
    import os
    import time

    from cassi.harness.evaluation.nights import SENSITIVITY_MEMO, STORE_DIR
    from cassi.reports.memo import STALE_STAGE_S

    pages = ten_nights / STORE_DIR / "media" / "pages"
    kept_report = ten_nights / "reports" / "2026-12-07-10"
    for digest, linked in (("aa" + "1" * 62, True), ("bb" + "2" * 62, False)):
        blob = pages / "blobs" / digest[:2] / digest
        blob.parent.mkdir(parents=True, exist_ok=True)
        blob.write_text(digest)
        if linked:
            os.link(blob, kept_report / "index.html")
        (pages / f"{'c' * 63}{int(linked)}.json").write_text(
            json.dumps({"files": [["index.html", digest]], "value": None}))
    stale, fresh = pages / ".stage-old", pages / ".stage-new"
    stale.mkdir(), fresh.mkdir()
    old = time.time() - STALE_STAGE_S - 60
    os.utime(stale, (old, old))
    memo = ten_nights / STORE_DIR / SENSITIVITY_MEMO
    memo.mkdir(parents=True)
    (memo / "a.json").write_text(json.dumps({"run": str(ten_nights / "runs" / "2026-12-07-2")}))
    (memo / "b.json").write_text(json.dumps({"run": str(ten_nights / "runs" / "2026-12-07-10")}))
    gc(ten_nights, keep=1)
    assert (pages / "blobs" / "aa" / ("aa" + "1" * 62)).is_file()
    assert not (pages / "blobs" / "bb" / ("bb" + "2" * 62)).exists()
    assert [p.name for p in pages.glob("*.json")] == [f"{'c' * 63}1.json"]
    assert not stale.exists() and fresh.is_dir()
    assert [p.name for p in memo.iterdir()] == ["b.json"]
