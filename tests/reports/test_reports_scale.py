"""A report that scales to a full set (issue 44): subject pages lead with a summary of what
fired and group their fault cards per check, folded when large; long tables are embedded as
data and drawn when opened; past 100 task files the viewer pages carry the renders of fired
checks' frames only, and say so."""
from __future__ import annotations

import re

import pandas as pd
import pytest

from browsers import chromium
from reports_fixtures import image, write_run
from cassi.harness.farm.results import normalize
from cassi.harness.rubric import file_verdicts
from cassi.harness.evaluation.frames import ALL_RENDERS_UP_TO
from cassi.reports.report import (GROUP_OPEN_UP_TO, LAZY_ROWS, _image_store,
                                  _renders_rule, _viewer_images, write_report)
from cassi.reports.runio import load_run

TASKS = 110
CHECKS = [("A", "lips", "lip_gap_start"), ("A", "tongue", "tongue_through_teeth"),
          ("C", "lips", "lower_lip_below_teeth")]


def _rows(tasks=TASKS, silent_frames=False):
    """cassi-1.0's lip gap fires in every task file (one large group), cassi-2.0's tongue in
    two (a small one); a criterion row per task file and version."""
    rows = []
    for version in ("cassi-1.0", "cassi-2.0"):
        for task in range(1, tasks + 1):
            for table, component, check in CHECKS:
                neg = int((version, check) == ("cassi-1.0", "lip_gap_start")
                          or ((version, check) == ("cassi-2.0", "tongue_through_teeth")
                              and task <= 2))
                row = dict(subject="JW11", task=task, rep=1, version=version, view="geometry",
                           frame=-1, check=check, table=table, component=component,
                           value=float(neg), unit="mm", threshold=0.5, negatives=neg,
                           detail="", synthetic=True)
                rows.append(row)
                if neg:
                    rows.append({**row, "frame": 7})
                elif silent_frames:
                    rows.append({**row, "frame": 3})
            rows.append(dict(subject="JW11", task=task, rep=1, version=version,
                             view="criterion", frame=-1, check="low_lips_margin", table=None,
                             component=None, value=0.5, unit="mm", threshold=0.0, negatives=0,
                             detail="margin", synthetic=True))
    return normalize(rows)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    root = tmp_path_factory.mktemp("scale")
    images = {("JW11", t, "cassi-1.0", "front", 7): image(t) for t in range(1, 13)}
    images.update({("JW11", t, "cassi-2.0", "front", 7): image(100 + t) for t in (1, 2)})
    run = write_run(root / "run", _rows(), images=images)
    index = write_report(run, root / "report")
    return index, (index.parent / "subjects" / "JW11.html")


def _section(page: str, anchor: str) -> str:
    start = page.index(f'id="{anchor}"')
    end = page.find("<h3 id=", start + 1)
    return page[start:end if end > 0 else len(page)]


def test_subject_page_summarises_and_groups_its_fault_cards(report):
    index, subject = report
    page, html = subject.read_text(), index.read_text()
    summary = page[page.index('id="summary"'):page.index('id="filter"')]
    assert re.search(r'lip_gap_start</td>.*?<a href="#cassi-1.0-table-A--lip_gap_start">'
                     rf'{TASKS} files</a>', summary, re.S)
    assert '<a href="#cassi-2.0-table-A--tongue_through_teeth">2 files</a>' in summary
    # a group of more than GROUP_OPEN_UP_TO cards starts folded, a small one open
    big = re.search(r'<details class="check" id="cassi-1.0-table-A--lip_gap_start"[^>]*>', page)
    small = re.search(r'<details class="check" id="cassi-2.0-table-A--tongue_through_teeth"[^>]*>',
                      page)
    assert big and " open" not in big.group(0) and TASKS > GROUP_OPEN_UP_TO
    assert small and small.group(0).endswith(" open>")
    assert _section(page, "cassi-1.0-table-A").count('class="fired"') >= TASKS
    # every anchor the index and the page itself link to exists
    ids = set(re.findall(r'id="([^"]+)"', page))
    links = re.findall(r'href="subjects/JW11\.html#([^"]+)"', html)
    assert "cassi-1.0-table-A" in links
    assert set(links) <= ids
    assert set(re.findall(r'href="#([^"]+)"', page)) <= ids
    assert (index.parent / "static" / "report.js").is_file()
    assert '<script src="../static/report.js"></script>' in page


def test_long_tables_are_embedded_and_short_ones_stay_html(report):
    index, subject = report
    page, html = subject.read_text(), index.read_text()
    lazy = _section(page, "cassi-2.0-table-A")   # 218 silent checks
    assert 'class="lazy-rows"' in lazy and "more than 200" in lazy and "<td>lip_gap_start" not in lazy
    plain = _section(page, "cassi-1.0-table-A")  # 110
    assert 'class="lazy-rows"' not in plain and plain.count("<td>tongue_through_teeth</td>") == TASKS
    crit = html[html.index('id="low-lips-criterion"'):]
    assert 2 * TASKS > LAZY_ROWS and 'class="lazy-rows"' in crit and "<td>cassi-2.1</td>" not in crit
    assert '<script src="static/report.js"></script>' in html


def test_past_the_limit_the_viewer_carries_fired_frames_only(tmp_path):
    small, big = _rows(tasks=3, silent_frames=True), _rows(tasks=ALL_RENDERS_UP_TO + 1,
                                                           silent_frames=True)
    images = {("JW11", 1, "cassi-1.0", "front", f): image(f) for f in (0, 3, 7)}
    for name, rows in (("small", small), ("big", big)):
        run = load_run(write_run(tmp_path / name, rows, images=images))
        fired, note = _renders_rule(run, file_verdicts(run.results))
        out = tmp_path / f"{name}-report"
        shown = _viewer_images(run, out, _image_store(out, None), None, fired, note)
        frames = {i["frame"] for i in shown("JW11", 1, 1, "cassi-1.0")}
        if name == "small":
            assert (fired, note, frames) == (None, None, {0, 3, 7})
        else:
            assert frames == {0, 7} and shown.note == note
            assert f"{ALL_RENDERS_UP_TO + 1} task files" in note and "silent" in note



@pytest.mark.browser
def test_folded_cards_load_no_image_until_opened_and_filters_work(report):
    exe = chromium()
    sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright not installed")
    _, subject = report
    page = subject.read_text()
    big = re.search(r'id="cassi-1.0-table-A--lip_gap_start".*?</details>', page, re.S).group(0)
    hidden = {s.rsplit("/", 1)[1] for s in re.findall(r'<img src="([^"]+)"', big)}
    assert len(hidden) == 12
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe, args=["--no-sandbox"])
        pg = b.new_page(viewport={"width": 1400, "height": 900})
        asked = []
        pg.on("request", lambda r: asked.append(r.url.rsplit("/", 1)[1]))
        pg.goto(subject.as_uri())
        pg.wait_for_timeout(500)
        pg.mouse.wheel(0, 20000)   # scroll through the page: folded cards stay unloaded
        pg.wait_for_timeout(500)
        assert not hidden & set(asked)
        pg.locator("[id='cassi-1.0-table-A--lip_gap_start'] > summary").click()
        pg.locator("[id='cassi-1.0-table-A--lip_gap_start'] img").first.scroll_into_view_if_needed()
        pg.wait_for_timeout(500)
        assert hidden & set(asked)
        # the filters: one version, then one task
        pg.select_option("#filter select[name=version]", "cassi-2.0")
        assert pg.locator("[id='cassi-1.0']").is_hidden()
        assert pg.locator("#shown").inner_text().startswith("2 of ")
        pg.fill("#filter input[name=task]", "2")
        assert pg.locator("#shown").inner_text().startswith("1 of ")
        # a long silent table is drawn when opened
        silent = pg.locator("section.version[data-version='cassi-2.0'] "
                            "section.table[data-table='A'] details.silent")
        pg.locator("#filter button[type=reset]").click()
        silent.locator("summary").click()
        silent.locator("tr").nth(2 * TASKS - 2).wait_for(timeout=5000)  # drawn on "toggle"
        assert silent.locator("tr").count() == 1 + 2 * TASKS - 2
        assert silent.locator("tr").nth(1).locator("td").nth(1).inner_text() in (
            "lip_gap_start", "tongue_through_teeth")
        # a link to a folded group opens it
        pg.goto(subject.as_uri() + "#cassi-1.0-table-A--lip_gap_start")
        pg.reload()
        assert pg.locator("[id='cassi-1.0-table-A--lip_gap_start']").get_attribute("open") is not None
        b.close()
