"""The report's first screen in a real browser (Playwright driving Debian's headless Chromium):
which version is best per table, what changed since the compared run, the gate, the synthetic
banner, all above the fold; the details below it stay folded sections that the links open."""
from __future__ import annotations

import json

import pytest

from browsers import chromium
from reports_fixtures import results_rows, write_run
from cassi.harness.rubric import table_totals, version_totals
from cassi.reports.report import write_report

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    exe = chromium()
    sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright not installed")
    root = tmp_path_factory.mktemp("overview")
    before = write_run(root / "before", results_rows({("cassi-1.0", "JW11", "lip_gap_start"): 5}))
    now = results_rows({("cassi-1.0", "JW11", "lip_gap_start"): 3,
                        ("cassi-2.0", "JW12", "tongue_through_teeth"): 6})
    run = write_run(root / "now", now)
    (run / "gate.json").write_text(json.dumps({"passed": False, "baseline_recorded": False,
                                               "counts": {"pass": 7, "fail": 1, "skip": 2}}))
    index = write_report(run, root / "report", compare=before)
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe, args=["--no-sandbox"])
        pg = b.new_page(viewport={"width": 1400, "height": 900})
        pg.goto(index.as_uri())
        yield pg, now
        b.close()


def _cells(pg, row: int) -> list[str]:
    return [c.strip() for c in pg.locator("#overview table tr").nth(row)
            .locator("td").all_inner_texts()]


def test_the_first_screen_says_which_version_is_best_and_what_changed(page):
    pg, results = page
    box = pg.locator("#overview table").bounding_box()
    assert box is not None and box["y"] + box["height"] <= 900, "the summary is below the fold"
    assert pg.locator(".banner").first.bounding_box()["y"] < 100  # the synthetic warning
    heads = pg.locator("#overview table tr").first.locator("th").all_inner_texts()
    tables = sorted(table_totals(results)["table"].unique())
    assert heads[1:1 + len(tables)] == [f"Table {t}" for t in tables]
    totals = table_totals(results).set_index(["version", "table"])["negatives"]
    overall = version_totals(results).set_index("version")["negatives"]
    for i, version in enumerate(overall.index, start=1):
        cells = _cells(pg, i)
        assert cells[0] == version
        for t, cell in zip(tables, cells[1:]):
            assert cell.split()[0] == str(totals[(version, t)])
        assert cells[1 + len(tables)].split()[0] == str(overall[version])
    # the change since the compared run: cassi-1.0's Table A lost two negatives
    a = tables.index("A")
    assert "(-2)" in _cells(pg, 1)[1 + a]
    change = _cells(pg, 1)[-1]
    assert change.startswith("▲ ") and "▼ 0 of 6 cells" in change and "sign test p =" in change
    best = _cells(pg, len(overall) + 1)
    assert best[0] == "best (fewest negatives)"
    assert best[1 + a] == "cassi-2.1"          # 3, 6 and 0 negatives
    assert best[1 + len(tables)] == "cassi-2.1"
    c = tables.index("C")
    assert "tie" in best[1 + c]                # Table C: no version earned a negative
    gate = pg.locator("#overview .gate")
    assert gate.inner_text().startswith("Gates: FAILED") and "1 failed" in gate.inner_text()


def test_the_details_fold_and_the_summary_links_open_them(page):
    pg, _ = page
    opened = "document.getElementById('table-A').closest('details').open"
    assert pg.locator("details:not([open]) #versions-compared").count() == 1
    pg.locator("details:has(#table-A) > summary").click()     # fold Table A
    assert not pg.evaluate(opened)
    pg.locator("#overview table tr").first.locator("a", has_text="Table A").click()
    pg.wait_for_function(opened)
    box = pg.locator("#table-A .wrap").bounding_box()
    assert box is not None and box["y"] < 900
