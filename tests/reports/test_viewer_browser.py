"""The task viewer in a real browser: Debian's headless Chromium driven by Playwright, on a real
run (JW11 task 106, cassi-1.0 and cassi-2.1, front renders) and its report, opened from disk.

WebGL runs on Chromium's software rasteriser (SwiftShader) here; the golden screenshot allows
for what differs between CPUs (see :func:`test_front_view_matches_the_golden`).
"""
from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pandas as pd
import pytest

from testpaths import GOLDEN as GOLDEN_DIR
from cassi.harness.cli import main as cli_main
from cassi.harness.rubric import CHECKS
from cassi.renderer.compare import compare_images
from cassi.reports.report import write_report

pytestmark = [pytest.mark.browser, pytest.mark.render]

GOLDEN = GOLDEN_DIR / "viewer_front_jw11_106_1023.png"
REGEN = os.environ.get("CASSI_REGEN_VIEWER", "") not in ("", "0")
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run", "--disable-quic",
        # WebGL on SwiftShader, said explicitly: Chromium may stop falling back to it silently
        "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
#: Console messages that are not errors of the page: SwiftShader's performance notes.
BENIGN = re.compile(r"GL Driver Message|GPU stall")


def _chromium() -> str:
    for name in (os.environ.get("CHROMIUM", ""), "chromium", "chromium-browser"):
        if name and shutil.which(name):
            return shutil.which(name)
    pytest.skip("no Chromium installed (.ci/run installs Debian's chromium)")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    root = tmp_path_factory.mktemp("viewer")
    run = root / "run"
    assert cli_main(["run", "--subjects", "JW11", "--versions", "cassi-1.0", "cassi-2.1",
                     "--tasks", "106", "--views", "front", "--no-progress",
                     "--out", str(run)]) == 0
    write_report(run, root / "report")
    return run, root / "report"


@pytest.fixture(scope="module")
def browser():
    exe = _chromium()
    sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright for Python not installed")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe, args=ARGS)
        yield b
        b.close()


class Page:
    """A page with its console errors and every URL it asked for."""

    def __init__(self, browser, url: str, *, width: int = 1100, height: int = 900):
        self.page = browser.new_page(viewport={"width": width, "height": height})
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page.on("console", lambda m: self.errors.append(m.text)
                     if m.type == "error" and not BENIGN.search(m.text) else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.goto(url)

    def ready(self):
        self.page.wait_for_selector("#status[data-ready='1']", timeout=30000)
        return self

    def frame(self) -> int:
        return int(self.page.text_content("#frame"))

    def pixels(self) -> np.ndarray:
        return np.asarray(iio.imread(self.page.locator("#three canvas").screenshot()))[..., :3]


def _viewer_url(report: Path, fragment: str = "") -> str:
    return (report / "viewer" / "JW11" / "106_1.html").as_uri() + fragment


def test_viewer_loads_with_no_console_error_and_no_remote_resource(report, browser):
    _, rep = report
    p = Page(browser, _viewer_url(rep)).ready()
    assert p.errors == []
    assert p.requests and all(u.startswith(("file://", "data:", "blob:")) for u in p.requests), \
        [u for u in p.requests if not u.startswith(("file://", "data:", "blob:"))]
    assert p.page.text_content("#status") == "ready"
    p.page.close()


def test_play_advances_the_frame_and_changes_the_canvas(report, browser):
    _, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=600&a=cassi-1.0")).ready()
    before, shot = p.frame(), p.pixels()
    assert before == 600
    p.page.select_option("#speed", "1")
    p.page.click("#play")
    p.page.wait_for_function("Number(document.getElementById('frame').textContent) > 640",
                             timeout=20000)
    p.page.click("#play")  # pause
    after = p.frame()
    assert after > before
    played = p.pixels()
    # The canvas shows the frame it names: the same as the viewer opened at that frame (how far
    # play got under load varies, and so does how much the face moved since frame 600).
    q = Page(browser, _viewer_url(rep, f"#frame={after}&a=cassi-1.0")).ready()
    assert q.frame() == after
    same = np.abs(played.astype(int) - q.pixels().astype(int)).max(axis=-1) > 24
    changed = np.abs(played.astype(int) - shot.astype(int)).max(axis=-1) > 24
    assert same.sum() < 20 and changed.sum() > 5 * max(same.sum(), 10), \
        "the canvas did not follow the frame while playing"
    assert p.errors == [] and q.errors == []
    q.page.close()
    p.page.close()


def test_a_negative_in_the_subject_page_opens_the_viewer_at_its_first_frame(report, browser):
    run, rep = report
    p = Page(browser, (rep / "subjects" / "JW11.html").as_uri())
    link = p.page.locator("a.viewer").first
    href = link.get_attribute("href")
    check = re.search(r"check=([^&]+)", href).group(1)
    version = re.search(r"a=([^&]+)", href).group(1)
    link.click()
    p.ready()
    res = pd.read_parquet(run / "results.parquet")
    ev = res[(res["check"] == check) & (res["version"] == version) & (res["frame"] >= 0)
             & (res["task"] == 106)]
    assert p.frame() == int(ev["frame"].min())
    hl = p.page.locator("#events li.hl")
    assert hl.count() == 1 and hl.get_attribute("data-check") == check
    assert p.page.input_value("#va") == version
    # it opens in the view the check is judged from
    view = CHECKS[check].view
    assert p.page.evaluate("window.cassiViewer.state.view") == view
    assert p.page.get_attribute(f"button[data-view='{view}']", "class") == "on"
    assert p.errors == []
    p.page.close()


def test_the_address_names_the_view_it_opens_in(report, browser):
    _, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=1023&a=cassi-1.0&view=side")).ready()
    side = p.page.evaluate("window.cassiViewer.camera()")
    p.page.click("button[data-view='front']")
    front = p.page.evaluate("window.cassiViewer.camera()")
    assert side["position"] != front["position"]
    p.page.click("button[data-view='side']")
    assert p.page.evaluate("window.cassiViewer.camera()")["position"] == side["position"]
    # a view the viewer does not have is ignored: the default front view opens
    q = Page(browser, _viewer_url(rep, "#frame=1023&a=cassi-1.0&view=%3Cx%3E")).ready()
    assert q.page.evaluate("window.cassiViewer.state.view") == "front"
    assert p.errors == [] and q.errors == []
    q.page.close()
    p.page.close()


def test_a_fault_in_the_thesis_tables_opens_the_viewer(report, browser):
    _, rep = report
    p = Page(browser, (rep / "index.html").as_uri())
    link = p.page.locator("a.fault").first
    frame = int(re.search(r"frame=(\d+)", link.get_attribute("href")).group(1))
    link.click()
    p.ready()
    assert p.frame() == frame
    p.page.close()


def test_a_b_shows_two_versions_at_the_same_frame(report, browser):
    _, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=1023&a=cassi-1.0&b=cassi-2.1")).ready()
    assert p.page.text_content("#labelA") == "A: cassi-1.0"
    assert p.page.text_content("#labelB") == "B: cassi-2.1"
    img = p.pixels().astype(int)
    bg = np.array([0xf4, 0xf4, 0xf4])
    w = img.shape[1] // 2
    for half in (img[:, :w], img[:, w:]):
        assert (np.abs(half - bg).max(axis=-1) > 30).mean() > 0.1, "a viewport shows no face"
    assert p.frame() == 1023
    # both faces are set from the same recording row, and they differ (two versions)
    state = p.page.evaluate("window.cassiViewer.state.row")
    assert state == 1023
    assert np.abs(img[:, :w] - img[:, w:2 * w]).max(axis=-1).mean() > 0.5
    # overlaid: one viewport, B as wireframe, still one frame
    p.page.select_option("#mode", "overlay")
    p.page.wait_for_function("document.getElementById('labelB').style.display === 'none'")
    assert "B: cassi-2.1, wireframe" in p.page.text_content("#labelA")
    assert p.frame() == 1023 and p.errors == []
    p.page.close()


def test_front_view_matches_the_golden(report, browser):
    """The front view of cassi-1.0 at frame 1023 against a golden screenshot, by the project's
    one image rule (:func:`cassi.renderer.compare.compare_images`: at most 0.5% of the pixels
    more than one 8-bit level apart). WebGL runs on SwiftShader here, whose JIT may round the
    last bit differently on another CPU, as Dr.Jit's does; geometry, camera or colour errors
    change whole regions. The rule must also tell a wrong frame: frame 644 (the jaw at its widest
    in this task) fails it."""
    _, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=1023&a=cassi-1.0"), width=1100, height=900).ready()
    img = p.pixels()
    if REGEN:
        iio.imwrite(GOLDEN, img)
    if not GOLDEN.is_file():
        pytest.fail(f"no golden {GOLDEN.name}: record it with CASSI_REGEN_VIEWER=1")
    gold = np.asarray(iio.imread(GOLDEN))[..., :3]
    same = compare_images(img, gold)
    assert same.passed, same.reason
    p.page.evaluate("window.cassiViewer.go(644)")
    moved = compare_images(p.pixels(), gold)
    assert not moved.passed, moved.reason
    p.page.close()


def _carried(report: Path, version: str, view: str) -> list[int]:
    """The frames whose ``view`` render of ``version`` the report carries for JW11 task 106."""
    text = (report / "viewer" / "JW11" / "106_1.js").read_text()
    data = json.loads(text[text.index("{"):text.rindex("}") + 1])
    return sorted(r["frame"] for r in data["version_data"][version]["renders"]
                  if r["view"] == view)


def test_the_render_panel_follows_the_view(report, browser):
    run, rep = report
    frame = _carried(rep, "cassi-1.0", "front")[-1]
    p = Page(browser, _viewer_url(rep, f"#frame={frame}&a=cassi-1.0&view=side")).ready()
    assert "no Mitsuba render of frame" in p.page.text_content("#renders")
    assert "(side view)" in p.page.text_content("#renders")
    p.page.click("button[data-view='front']")
    assert p.page.text_content("#renders .meta") == \
        f"cassi-1.0: Mitsuba render, front view, frame {frame}"
    assert p.page.locator("#renders img").count() >= 1
    # the WebP copy decodes in the browser at the render's size
    assert p.page.evaluate("document.querySelector('#renders img').naturalWidth") == \
        iio.imread(run / pd.read_parquet(run / "renders.parquet")["path"].iloc[0]).shape[1]
    p.page.click("button[data-view='top']")
    assert "(top view)" in p.page.text_content("#renders")
    assert p.page.locator("#renders img").count() == 0 and p.errors == []
    p.page.close()


def _hash(p: Page) -> dict:
    return dict(x.split("=", 1) for x in p.page.evaluate("location.hash").lstrip("#").split("&"))


def test_the_address_follows_the_state_and_the_state_the_address(report, browser):
    _, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=1023&a=cassi-1.0")).ready()
    p.page.click("#next")
    assert _hash(p)["frame"] == str(p.frame()) != "1023"
    p.page.click("button[data-view='side']")
    p.page.select_option("#vb", "cassi-2.1")
    p.page.wait_for_function("location.hash.includes('b=cassi-2.1')")
    assert _hash(p) == {"frame": str(p.frame()), "a": "cassi-1.0", "b": "cassi-2.1",
                        "view": "side"}
    # an address typed or pasted over the open page is followed
    p.page.evaluate("location.hash = '#frame=700&a=cassi-2.1&view=top'")
    p.page.wait_for_function("document.getElementById('frame').textContent === '700'")
    assert p.page.evaluate("window.cassiViewer.state.view") == "top"
    assert p.page.input_value("#va") == "cassi-2.1"
    assert p.page.get_attribute("button[data-view='top']", "class") == "on"
    assert p.errors == []
    p.page.close()


def test_the_page_fits_1024_and_the_opened_event_shows_above_the_fold(report, browser):
    run, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=1023&a=cassi-1.0"), width=1024, height=768).ready()
    width = p.page.evaluate("document.documentElement.scrollWidth")
    assert width <= 1024, f"the page scrolls sideways: {width} px wide"
    tl = p.page.locator("#timeline").bounding_box()
    assert tl["x"] >= 0 and tl["x"] + tl["width"] <= 1024
    assert p.errors == []
    p.page.close()
    res = pd.read_parquet(run / "results.parquet")
    mine = res[(res["task"] == 106) & (res["version"] == "cassi-1.0") & res["table"].notna()]
    fired = set(mine[(mine["frame"] == -1) & (mine["negatives"] > 0)]["check"])
    ev = mine[(mine["frame"] >= 0) & mine["check"].isin(fired)].sort_values(["frame", "check"])
    check, frame = ev.iloc[0]["check"], int(ev.iloc[0]["frame"])
    q = Page(browser, _viewer_url(rep, f"#frame={frame}&a=cassi-1.0&check={check}"),
             width=1400, height=900).ready()
    shown = q.page.locator(f".hl[data-check='{check}']").first.bounding_box()
    assert shown is not None and shown["y"] + shown["height"] <= 900, \
        f"the opened event is below the fold: {shown}"
    assert q.errors == []
    q.page.close()


def test_the_frame_steps_say_they_step_to_the_next_kept_frame(report, browser):
    _, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=1000&a=cassi-1.0")).ready()
    for button in ("#prev", "#next"):
        assert "kept frame" in p.page.text_content(button)
        assert "every 4th recording row" in p.page.get_attribute(button, "title")
    kept = p.page.evaluate("Array.from(window.cassiViewer.state.a.frames)")
    p.page.click("#next")
    assert p.frame() == min(f for f in kept if f > 1000)
    p.page.close()


def test_a_lost_webgl_context_is_restored_and_drawn(report, browser):
    _, rep = report
    p = Page(browser, _viewer_url(rep, "#frame=1023&a=cassi-1.0")).ready()
    before = p.pixels()
    p.page.evaluate("""() => new Promise((done) => {
        const gl = window.cassiViewer.three().renderer.getContext();
        const ext = gl.getExtension('WEBGL_lose_context');
        const cv = gl.canvas;
        cv.addEventListener('webglcontextlost', () => setTimeout(() => ext.restoreContext(), 50),
                            { once: true });
        cv.addEventListener('webglcontextrestored', () => setTimeout(done, 300), { once: true });
        ext.loseContext();
    })""")
    p.page.wait_for_timeout(300)
    after = p.pixels()
    assert compare_images(after, before).passed, "the canvas is not drawn again after a restore"
    assert p.page.text_content("#status") == "ready"
    p.page.close()


@pytest.fixture(scope="module")
def report19(tmp_path_factory):
    """JW11 task 19, where cassi-1.0's Table A cell names three faults."""
    root = tmp_path_factory.mktemp("viewer19")
    assert cli_main(["run", "--subjects", "JW11", "--versions", "cassi-1.0", "--tasks", "19",
                     "--views", "front", "--no-progress", "--out", str(root / "run")]) == 0
    write_report(root / "run", root / "report")
    return root / "run", root / "report"


def test_each_fault_a_table_cell_names_opens_its_own_frame(report19, browser):
    run, rep = report19
    p = Page(browser, (rep / "index.html").as_uri())
    cells = [c for c in p.page.locator("td").all() if c.locator("a.fault").count() >= 2]
    assert cells, "no table cell names several faults in this run"
    links = cells[0].locator("a.fault")
    hrefs = [links.nth(i).get_attribute("href") for i in range(links.count())]
    checks = [re.search(r"check=([^&]+)", h).group(1) for h in hrefs]
    assert len(set(checks)) == len(checks), hrefs
    # each link's text is its own check's, and the second opens on its own event
    for i, check in enumerate(checks):
        assert CHECKS[check].text in links.nth(i).text_content()
    frame = int(re.search(r"frame=(\d+)", hrefs[1]).group(1))
    links.nth(1).click()
    p.ready()
    assert p.frame() == frame
    assert p.page.locator("#events li.hl").get_attribute("data-check") == checks[1]
    assert p.errors == []
    p.page.close()
