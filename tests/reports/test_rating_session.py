"""`cassi rate`: a blinded session on a real run (JW11 tasks 19 and 106, cassi-1.0 and cassi-2.1,
geometry only): no version name in what the rater gets, the key apart and right (each code's
animation is its version's), the seeded shuffle, the tables' faults; its export un-blinded by
`cassi agree --key` and refused without it."""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest

from cassi.harness.cli import main
from cassi.harness.evaluation.viewerdata import read_viewer_blob
from cassi.harness.rubric import CHECKS
from cassi.reports.agree import read_human_ratings, read_key
from cassi.reports.runio import load_run
from cassi.reports.viewer import version_payload

VERSIONS = ("cassi-1.0", "cassi-2.1")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    root = tmp_path_factory.mktemp("rate") / "run"
    assert main(["run", "--subjects", "JW11", "--versions", *VERSIONS, "--tasks", "19", "106",
                 "--views", "geometry", "--no-progress", "--out", str(root)]) == 0
    return root


def _session(path: Path) -> dict:
    text = (path / "session" / "session.js").read_text()
    return json.loads(text.removeprefix("window.CASSI_SESSION = ").rstrip().rstrip(";"))


def _viewer(path: Path) -> dict:
    text = path.read_text()
    return json.loads(text.removeprefix("window.CASSI_VIEWER = ").rstrip().rstrip(";"))


def test_the_session_names_no_version_and_the_key_is_apart(run, tmp_path):
    assert main(["rate", str(run), "--out", str(tmp_path / "s"), "--seed", "3"]) == 0
    files = [p for p in (tmp_path / "s" / "session").rglob("*") if p.is_file()]
    assert any(p.suffix == ".html" for p in files) and len(files) > 6
    names = set(load_run(run).versions) | set(VERSIONS)
    for p in files:
        data = p.read_bytes()
        for name in names:
            assert name.encode() not in data, f"{p} names {name}"
    key = json.loads((tmp_path / "s" / "key.json").read_text())
    assert key["seed"] == 3 and sorted({c["version"] for c in key["codes"].values()}) == \
        sorted(VERSIONS)


def test_each_code_plays_its_versions_animation(run, tmp_path):
    main(["rate", str(run), "--out", str(tmp_path / "s"), "--seed", "3"])
    key = json.loads((tmp_path / "s" / "key.json").read_text())
    att = load_run(run).attachments
    for code, c in key["codes"].items():
        page = _viewer(tmp_path / "s" / "session" / "cells" / f"{code}.js")
        assert page["versions"] == [code] and page["subject"] == c["subject"]
        shown = page["version_data"][code]
        assert shown["events"] == [] and shown["renders"] == []
        for version in VERSIONS:
            row = att[(att["task"] == c["task"]) & (att["version"] == version)].iloc[0]
            truth = version_payload(read_viewer_blob(Path(row["path"]).read_bytes()), [], [])
            assert (truth["dq"]["b64"] == shown["dq"]["b64"]) == (version == c["version"])


def test_the_seed_decides_the_order_and_the_codes(run, tmp_path):
    for name, seed in (("a", "5"), ("b", "5"), ("c", "6")):
        assert main(["rate", str(run), "--out", str(tmp_path / name), "--seed", seed]) == 0
    a, b, c = (_session(tmp_path / n) for n in "abc")
    assert a == b
    assert [x["id"] for x in a["cells"]] != [x["id"] for x in c["cells"]]
    cells = [(x["file"], json.loads((tmp_path / "a" / "key.json").read_text())["codes"]
              [x["code"]]["version"], x["table"]) for x in a["cells"]]
    # every (task file, version, table) the run judged, once, not in the sorted order
    assert sorted(cells) == sorted(set(cells)) and cells != sorted(cells)
    assert {(f, t) for f, _, t in cells} == {("19", "A"), ("19", "B"), ("19", "C"), ("106", "E")}


def test_tables_sample_and_faults(run, tmp_path, capsys):
    assert main(["rate", str(run), "--out", str(tmp_path / "s"), "--tables", "a,E",
                 "--sample", "3", "--seed", "1"]) == 0
    s = _session(tmp_path / "s")
    assert len(s["cells"]) == 3 and {c["table"] for c in s["cells"]} <= {"A", "E"}
    for cell in s["cells"]:
        texts = {c.text for c in CHECKS.values() if c.table == cell["table"] and c.counted}
        assert cell["faults"] and set(cell["faults"]) <= texts
    assert main(["rate", str(run), "--out", str(tmp_path / "t"), "--tables", "A,Q"]) == 2
    assert "unknown table(s) Q" in capsys.readouterr().err
    assert main(["rate", str(run), "--out", str(tmp_path / "s"), "--seed", "1"]) == 2
    assert "a new session goes into a new directory" in capsys.readouterr().err


def test_an_export_is_unblinded_by_its_key_only(run, tmp_path, capsys):
    main(["rate", str(run), "--out", str(tmp_path / "s"), "--seed", "8"])
    main(["rate", str(run), "--out", str(tmp_path / "other"), "--seed", "9"])
    s = _session(tmp_path / "s")
    key = json.loads((tmp_path / "s" / "key.json").read_text())
    lines = [",".join(s["columns"])]
    words = ["GOOD", "POOR", "EXCELLENT"]
    for cell, word in zip(s["cells"], words):
        fields = [cell["subject"], cell["file"], cell["code"], cell["table"], "", word, "dora",
                  cell["faults"][0], "", s["session"]]
        out = io.StringIO()
        csv.writer(out, lineterminator="").writerow(fields)
        lines.append(out.getvalue())
    export = tmp_path / "export.csv"
    export.write_text("\n".join(lines) + "\n")
    assert main(["agree", str(run), "--ratings", str(export), "--out", str(tmp_path / "x")]) == 2
    assert "export.csv:2: blinded ratings (session " in capsys.readouterr().err
    assert main(["agree", str(run), "--ratings", str(export), "--key",
                 str(tmp_path / "other" / "key.json"), "--out", str(tmp_path / "x")]) == 2
    assert "is not the key's" in capsys.readouterr().err
    assert main(["agree", str(run), "--ratings", str(export), "--key",
                 str(tmp_path / "s" / "key.json"), "--out", str(tmp_path / "ag")]) == 0
    r = json.loads((tmp_path / "ag" / "agreement.json").read_text())
    assert sum(g["n"] for g in r["groups"]) == 3
    rows = read_human_ratings(export, load_run(run), key=read_key(tmp_path / "s" / "key.json"))
    assert list(zip(rows["task"], rows["version"], rows["table"], rows["human"], rows["rater"])) \
        == [(c["file"], key["codes"][c["code"]]["version"], c["table"], w, "dora")
            for c, w in zip(s["cells"], words)]
    assert [f[0] for f in rows["faults"]] == [c["faults"][0] for c in s["cells"][:3]]
    # a line whose task is not its code's
    cell = s["cells"][0]
    other = "106" if cell["file"] == "19" else "19"
    table = "E" if other == "106" else "A"
    export.write_text(lines[0] + "\n" + ",".join([cell["subject"], other, cell["code"], table, "",
                                                  "GOOD", "dora", "", "", s["session"]]) + "\n")
    assert main(["agree", str(run), "--ratings", str(export), "--key",
                 str(tmp_path / "s" / "key.json")]) == 2
    assert f"code {cell['code']} is task file {cell['file']} in the key" in capsys.readouterr().err
