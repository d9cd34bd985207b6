"""Every link of the report opens on a rendered frame: a real run (JW11 task 19, two versions,
three views) that renders no frame of its own beyond the first (``--stride 0 --extremes 0``),
so every render at a linked frame is an evidence frame; the image checks judge only the frames
rendered for them."""
from __future__ import annotations

import html
import json
import re
import urllib.parse
from pathlib import Path

import pandas as pd
import pytest

from cassi.harness.cli import main as cli_main
from cassi.harness.evaluation.frames import linked_frames
from cassi.reports.report import write_report

pytestmark = pytest.mark.render

LINK = re.compile(r'href="((?:\.\./)?viewer/([^/"]+)/(\d+)_(\d+)\.html#[^"]*)"')


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    root = tmp_path_factory.mktemp("links")
    run = root / "run"
    assert cli_main(["run", "--subjects", "JW11", "--tasks", "19", "--versions", "cassi-1.0",
                     "parke-1974", "--views", "front", "side", "half", "--stride", "0",
                     "--extremes", "0", "--no-progress", "--out", str(run)]) == 0
    write_report(run, root / "report")
    return run, root / "report"


def _links(report: Path) -> list[dict]:
    """Every viewer link of the thesis tables and the subject pages, as the page opens it."""
    out = []
    for page in [report / "index.html", *sorted((report / "subjects").glob("*.html"))]:
        for href, subject, task, rep in LINK.findall(page.read_text()):
            frag = urllib.parse.parse_qs(html.unescape(href).split("#", 1)[1])
            out.append({"page": page.name, "subject": subject, "task": int(task),
                        "rep": int(rep), **{k: v[0] for k, v in frag.items()}})
    return out


def _viewer_renders(report: Path, subject: str, task: int, rep: int) -> dict:
    text = (report / "viewer" / subject / f"{task:03d}_{rep}.js").read_text()
    data = json.loads(text[text.index("{"):text.rindex("}") + 1])
    return {v: {(r["frame"], r["view"]) for r in d["renders"]}
            for v, d in data["version_data"].items()}


def test_every_link_of_the_report_opens_on_its_render(report):
    run, rep = report
    links = _links(rep)
    results = pd.read_parquet(run / "results.parquet")
    assert {l["page"] for l in links} == {"index.html", "JW11.html"}
    # the links are the linked frames, each in the view its check is judged from
    assert {(l["a"], l["check"], int(l["frame"])) for l in links} == \
        {(v, c, f) for (_, _, _, v, c), f in linked_frames(results).items()}
    assert {l["view"] for l in links} >= {"front", "side", "half"}
    renders = pd.read_parquet(run / "renders.parquet")
    have = set(zip(renders["version"], renders["view"], renders["frame"]))
    shown = _viewer_renders(rep, "JW11", 19, 1)
    for link in links:
        frame = int(link["frame"])
        assert (link["a"], link["view"], frame) in have, link
        assert (frame, link["view"]) in shown[link["a"]], link  # the viewer's render panel
    # the subject page shows the frame pointed at, not the nearest one rendered
    page = (rep / "subjects" / "JW11.html").read_text()
    pointed = re.findall(r"frame pointed at: (\d+) \(nearest rendered: (\d+)\)", page)
    assert pointed and all(a == b for a, b in pointed)


def _rendered_by(run: Path, kind: str) -> dict[tuple, set[int]]:
    """(version, view) -> the frames its ``kind`` (render, evidence) jobs rendered."""
    out: dict[tuple, set[int]] = {}
    for path in (run / "jobs").glob(f"JW11/019-1/*/*/{kind}-*.json"):
        names = json.loads(path.read_text())["outputs"]
        out.setdefault((path.parent.parent.name, path.parent.name), set()).update(
            int(n.split("-")[1]) for n in names if n.startswith("render-"))
    return out


def test_the_image_checks_judge_only_the_frames_rendered_for_them(report):
    run, _ = report
    judged, evidence = _rendered_by(run, "render"), _rendered_by(run, "evidence")
    assert {view for _, view in evidence} == {"front", "side", "half"}
    assert all(not (judged[k] & evidence[k]) for k in evidence)  # nothing rendered twice
    att = pd.read_parquet(run / "attachments.parquet")
    masks = att[att["name"].str.startswith("masks-")]
    # masks (what the image checks read) for the frames of the render jobs only
    assert set(masks["view"]) == {"front"}
    for version in ("cassi-1.0", "parke-1974"):
        mine = masks[masks["version"] == version]
        assert {int(n.split("-")[1]) for n in mine["name"]} == judged[(version, "front")]
    results = pd.read_parquet(run / "results.parquet")
    rows = results[(results["view"] == "front") & (results["frame"] >= 0)]
    assert len(rows) and all(int(f) in judged[(v, "front")]
                             for v, f in zip(rows["version"], rows["frame"]))
