"""A rating session in a real browser (Debian's headless Chromium, Playwright), opened from disk:
rate three cells, reload (the progress stays), export, and `cassi agree --key` reads the export
and un-blinds it."""
from __future__ import annotations

import json

import pytest

from browsers import BENIGN, browser_for
from cassi.harness.cli import main
from cassi.reports.agree import read_human_ratings, read_key
from cassi.reports.runio import load_run

pytestmark = [pytest.mark.browser]


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    root = tmp_path_factory.mktemp("ratebrowser")
    run = root / "run"
    assert main(["run", "--subjects", "JW11", "--versions", "cassi-1.0", "cassi-2.1", "--tasks",
                 "19", "106", "--views", "geometry", "--no-progress", "--out", str(run)]) == 0
    assert main(["rate", str(run), "--out", str(root / "study"), "--seed", "11"]) == 0
    return run, root / "study"


@pytest.fixture(scope="module")
def browser():
    with browser_for() as b:
        yield b


def test_rate_reload_export_and_agree(session, browser, tmp_path):
    run, study = session
    ctx = browser.new_context(viewport={"width": 1400, "height": 900}, accept_downloads=True)
    page = ctx.new_page()
    errors, requests = [], []
    page.on("console", lambda m: errors.append(m.text)
            if m.type == "error" and not BENIGN.search(m.text) else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("request", lambda r: requests.append(r.url))
    page.goto((study / "session" / "index.html").as_uri())
    page.wait_for_selector("#status[data-ready='1']")
    cell = page.frame_locator("#cell")
    cell.locator("#status[data-ready='1']").wait_for(timeout=60000)
    total = page.evaluate("window.CASSI_SESSION.cells.length")
    page.fill("#rater", "erin")
    words = ["GOOD", "UNACCEPTABLE", "VERY GOOD"]
    for i, word in enumerate(words):
        page.check(f"input[name=rating][value='{word}']")
        if i == 0:
            page.locator("input[name=fault]").first.check()
        if i == 1:
            page.fill("#note", "the chin wobbles, a lot")
        page.click("#next")
    assert page.text_content("#progress") == f"3 of {total} rated"

    page.reload()
    page.wait_for_selector("#status[data-ready='1']")
    assert page.text_content("#progress") == f"3 of {total} rated"
    assert page.input_value("#rater") == "erin"
    assert page.evaluate("cassiRate.state.current") == 3
    page.click("#strip button >> nth=0")
    assert page.is_checked("input[name=rating][value='GOOD']")
    assert page.locator("input[name=fault]").first.is_checked()
    page.click("#strip button >> nth=1")
    assert page.input_value("#note") == "the chin wobbles, a lot"

    with page.expect_download() as download:
        page.click("#export")
    export = tmp_path / "export.csv"
    download.value.save_as(export)
    assert errors == []
    assert all(u.startswith(("file://", "data:", "blob:")) for u in requests)
    ctx.close()

    page_cells = json.loads((study / "session" / "session.js").read_text()
                                    .removeprefix("window.CASSI_SESSION = ").rstrip().rstrip(";"))
    key = read_key(study / "key.json")
    assert main(["agree", str(run), "--ratings", str(export)]) == 2    # blinded: needs the key
    assert main(["agree", str(run), "--ratings", str(export), "--key", str(study / "key.json"),
                 "--out", str(tmp_path / "ag")]) == 0
    rows = read_human_ratings(export, load_run(run), key=key)
    first = page_cells["cells"][:3]
    assert list(zip(rows["subject"], rows["task"], rows["version"], rows["table"], rows["human"],
                    rows["rater"], rows["note"])) == \
        [(c["subject"], c["file"], key["codes"][c["code"]]["version"], c["table"], w, "erin",
          "the chin wobbles, a lot" if i == 1 else "")
         for i, (c, w) in enumerate(zip(first, words))]
    assert list(rows["faults"]) == [(page_cells["cells"][0]["faults"][0],), (), ()]
