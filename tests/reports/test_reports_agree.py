"""`cassi agree` and the report's agreement section: levels, statistics, every kind of bad
ratings file (exit 2 naming the line), evidence links."""
from __future__ import annotations

import json

import pandas as pd
import pytest

from reports_fixtures import results_rows, write_run
from cassi.harness.cli import main
from cassi.harness.rubric import level_ratings
from cassi.reports.report import write_report

HEADER = "subject,task,version,table,component,rating\n"
# JW11 under cassi-2.0: lips 2 negatives and tongue 1 in task 19, nothing in task 21
NEGATIVES = {("cassi-2.0", "JW11", "lip_gap_start"): 2, ("cassi-2.0", "JW11", "tongue_through_teeth"): 1}
GOOD = HEADER + (
    "JW11,,cassi-2.0,A,lips,GOOD\n"             # line 2: the subject's lips: 2 -> GOOD
    "JW11,,cassi-2.0,A,,GOOD\n"                 # line 3: the whole table: 2 + 1 -> FAIR
    "JW11,19,cassi-2.0,A,tongue,VERY GOOD\n"    # line 4: one file's tongue: 1 -> VERY GOOD
    "JW11,21,cassi-2.0,A,,EXCELLENT\n"          # line 5: a clean file, whole table
    "JW11,19,cassi-2.0,A,,POOR\n"               # line 6: task 19, whole table: 3 -> FAIR
    "JW12,,cassi-2.0,A,lips,excellent\n"        # line 7: any case
    "\n"
    "JW11,,cassi-1.0,A,lips,EXCELLENT\n")       # line 9 (a blank line is skipped)


@pytest.fixture
def run(tmp_path):
    return write_run(tmp_path / "run", results_rows(NEGATIVES))


def test_levels_blank_task_and_blank_component(run):
    lv = level_ratings(results_rows(NEGATIVES)).set_index(
        ["version", "table", "subject", "file", "component"])["rating"]
    assert lv[("cassi-2.0", "A", "JW11", "", "lips")] == "GOOD"
    assert lv[("cassi-2.0", "A", "JW11", "", "")] == "FAIR"
    assert lv[("cassi-2.0", "A", "JW11", "19", "")] == "FAIR"
    assert lv[("cassi-2.0", "A", "JW11", "21", "")] == "EXCELLENT"
    assert lv[("cassi-2.0", "A", "JW11", "19", "tongue")] == "VERY GOOD"


def test_agree_on_a_good_file(run, tmp_path, capsys):
    ratings = tmp_path / "ratings.csv"
    ratings.write_text(GOOD)
    assert main(["agree", str(run), "--ratings", str(ratings), "--out", str(tmp_path / "ag")]) == 0
    assert "not real speakers" in capsys.readouterr().out
    result = json.loads((tmp_path / "ag" / "agreement.json").read_text())
    groups = {(g["table"], g["version"]): g for g in result["groups"]}
    g = groups[("A", "cassi-2.0")]
    assert g["n"] == 6 and g["exact"] == pytest.approx(4 / 6) and g["within_one"] == 1.0
    # people GOOD, GOOD, VERY GOOD, EXCELLENT, POOR, EXCELLENT; the run GOOD, FAIR, VERY GOOD,
    # EXCELLENT, FAIR, EXCELLENT: the GOOD/FAIR cell of the confusion counts once
    assert g["confusion"][2][3] == 1 and g["confusion"][4][3] == 1
    assert groups[("A", "cassi-1.0")]["kappa"] is None        # one rating throughout: undefined
    dis = pd.read_csv(tmp_path / "ag" / "agreement.csv", keep_default_na=False)
    assert list(dis["line"]) == [3, 6]
    assert list(dis["steps"]) == [1, -1] and list(dis["run"]) == ["FAIR", "FAIR"]
    assert list(dis["evidence"]) == ["subjects/JW11.html#cassi-2.0-table-A"] * 2
    md = (tmp_path / "ag" / "agreement.md").read_text()
    assert "Synthetic corpus" in md and "2000 resamples" in md


@pytest.mark.parametrize("line, problem", [
    ("JW11,,cassi-2.0,A,lips,SPLENDID", "unknown rating 'SPLENDID'"),
    ("JW99,,cassi-2.0,A,lips,GOOD", "unknown subject 'JW99'"),
    ("JW11,,cassi-9.9,A,lips,GOOD", "unknown version 'cassi-9.9'"),
    ("JW11,,cassi-2.0,H,lips,GOOD", "unknown table 'H'"),
    ("JW11,,cassi-2.0,B,,GOOD", "the run has no Table B for JW11, cassi-2.0"),
    ("JW11,118,cassi-2.0,A,lips,GOOD", "no task file 118"),
    ("JW11,,cassi-2.0,A,nose,GOOD", "unknown component 'nose'"),
    ("JW11,,cassi-2.0,A,lips,", "no rating"),
    ("JW11,19,cassi-2.0,A,tongue,POOR", "duplicate of line 4"),
    ("JW11,\u00b2,cassi-2.0,A,lips,GOOD", "is not a task number"),   # a digit int() refuses
    ("JW11,,cassi-1.0,A,tongue,GOOD,POOR", "7 fields, the header has 6"),
    ("JW11,,cassi-1.0,A,tongue,GOOD,,x", "8 fields, the header has 6"),
    ("JW11,,cassi-1.0,A,GOOD", "5 fields, the header has 6"),
    ('JW11,,cassi-1.0,A,tongue,"GOOD', "malformed CSV: unexpected end of data"),
])
def test_bad_lines_exit_2_naming_the_file_and_line(run, tmp_path, capsys, line, problem):
    ratings = tmp_path / "bad.csv"
    ratings.write_text(GOOD + line + "\n")
    assert main(["agree", str(run), "--ratings", str(ratings)]) == 2
    err = capsys.readouterr().err
    assert f"{ratings}:10: " in err and problem in err, err
    assert not (run / "agreement.json").exists()


def test_bad_header_and_empty_file(run, tmp_path, capsys):
    ratings = tmp_path / "bad.csv"
    ratings.write_text("subject,version,table,rating\nJW11,cassi-2.0,A,GOOD\n")
    assert main(["agree", str(run), "--ratings", str(ratings)]) == 2
    assert f"{ratings}:1: the header lacks column(s) task, component" in capsys.readouterr().err
    ratings.write_text(HEADER)
    assert main(["agree", str(run), "--ratings", str(ratings)]) == 2
    assert f"{ratings}:1: no ratings" in capsys.readouterr().err


def test_a_file_that_agrees_throughout(run, tmp_path, capsys):
    """No disagreement at all is a result, not a crash; a form feed inside a line does not
    shift the lines named."""
    ratings = tmp_path / "ok.csv"
    ratings.write_text(HEADER + "JW11,,cassi-2.0,A,lips,GOOD\n")
    assert main(["agree", str(run), "--ratings", str(ratings), "--out", str(tmp_path / "ag")]) == 0
    assert "0 disagreement(s)" in capsys.readouterr().out
    assert json.loads((tmp_path / "ag" / "agreement.json").read_text())["disagreements"] == []
    ratings.write_text(HEADER + "JW11,,cassi-2.0,A,lips,GOOD\f\n" + "JW11,,cassi-2.0,A,lips,GOOD\n")
    assert main(["agree", str(run), "--ratings", str(ratings)]) == 2
    assert f"{ratings}:3: duplicate of line 2" in capsys.readouterr().err
    ratings.write_text("subject,task,version,table,component,rating,rating\nJW11,,cassi-2.0,A,lips,GOOD,POOR\n")
    assert main(["agree", str(run), "--ratings", str(ratings)]) == 2
    assert f"{ratings}:1: the header names column(s) rating more than once" in capsys.readouterr().err


def test_report_with_ratings_has_the_section_and_links_to_the_evidence(run, tmp_path):
    ratings = tmp_path / "<i>ratings.csv"        # what the user named reaches the page escaped
    ratings.write_text(GOOD + "JW11,,cassi-2.1,C,,excellent\n")
    index = write_report(run, tmp_path / "report", ratings=ratings)
    html = index.read_text()
    assert "<i>ratings" not in html and "&lt;i&gt;ratings.csv" in html
    section = html[html.index('id="agreement"'):html.index("<h2", html.index('id="agreement"') + 5)]
    assert "describe the software, not real speakers" in section
    assert "<td>A</td><td>cassi-2.0</td><td>6</td>" in section
    href = "subjects/JW11.html#cassi-2.0-table-A"
    assert section.count(f'<a href="{href}">evidence</a>') == 2
    assert 'id="cassi-2.0-table-A"' in (index.parent / "subjects" / "JW11.html").read_text()
    assert (index.parent / "agreement.csv").is_file()
    # the command takes the same option; a bad file writes no report
    ratings.write_text(HEADER + "<script>,,cassi-2.0,A,,GOOD\n")
    assert main(["report", str(run), "--ratings", str(ratings), "--out", str(tmp_path / "r2")]) == 2
    assert not (tmp_path / "r2" / "index.html").exists()


def test_blank_cells_beyond_the_header_are_a_spreadsheets_trailing_commas(run, tmp_path, capsys):
    ratings = tmp_path / "export.csv"
    for header in (HEADER, HEADER.replace("\n", ",,\n")):    # unnamed columns or none
        ratings.write_text(header + "JW11,,cassi-2.0,A,lips,GOOD,,\n"
                           + "JW12,,cassi-2.0,A,lips,EXCELLENT, ,\n")
        assert main(["agree", str(run), "--ratings", str(ratings),
                     "--out", str(tmp_path / "ag")]) == 0
        assert "0 disagreement(s)" in capsys.readouterr().out
