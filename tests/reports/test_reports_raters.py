"""`cassi agree` with several raters: Krippendorff's alpha against a reference computed here,
the run against each rater and the consensus, each check's precision and recall against the
ticked faults, the disagreements between raters linked to the viewer, old files unchanged."""
from __future__ import annotations

import json

import numpy as np
import pytest

from reports_fixtures import results_rows, write_run
from cassi.harness.cli import main
from cassi.harness.rubric import CHECKS, RATINGS

# JW11 under cassi-2.0, task 19: tongue_through_teeth 1 negative (Table A) and
# lower_lip_below_teeth 2 (the fixture's Table C); task 21 clean
NEGATIVES = {("cassi-2.0", "JW11", "tongue_through_teeth"): 1,
             ("cassi-2.0", "JW11", "lower_lip_below_teeth"): 2}
TONGUE = CHECKS["tongue_through_teeth"].text
LOWER_LIP = CHECKS["lower_lip_below_teeth"].text
HEADER = "subject,task,version,table,component,rating,rater,faults\n"
ALICE = HEADER + (f"JW11,19,cassi-2.0,A,,FAIR,alice,{TONGUE}\n"
                  "JW11,21,cassi-2.0,A,,EXCELLENT,alice,\n"
                  f"JW11,19,cassi-2.0,C,,GOOD,alice,{LOWER_LIP}\n")
OTHERS = HEADER + ("JW11,19,cassi-2.0,A,,POOR,bob,\n"
                   "JW11,19,cassi-2.0,A,,GOOD,carol,\n"
                   f"JW11,21,cassi-2.0,A,,VERY GOOD,bob,{TONGUE}\n")


def ordinal_alpha(units: list[list[int]], k: int = len(RATINGS)) -> float:
    """Krippendorff's ordinal alpha from its definition: the coincidence matrix o, the ordinal
    distance (sum of the marginals from c to k, less half of each end's)^2, and
    1 - (n - 1) * sum(o * d) / sum(n_c * n_k * d)."""
    o = np.zeros((k, k))
    for u in (u for u in units if len(u) > 1):
        for i, a in enumerate(u):
            for j, b in enumerate(u):
                if i != j:
                    o[a, b] += 1 / (len(u) - 1)
    n_c = o.sum(axis=1)
    d = np.array([[(n_c[min(a, b):max(a, b) + 1].sum() - (n_c[a] + n_c[b]) / 2) ** 2
                   for b in range(k)] for a in range(k)])
    return 1 - (n_c.sum() - 1) * (o * d).sum() / (np.outer(n_c, n_c) * d).sum()


@pytest.fixture
def files(tmp_path):
    run = write_run(tmp_path / "run", results_rows(NEGATIVES))
    a, b = tmp_path / "alice.csv", tmp_path / "others.csv"
    a.write_text(ALICE)
    b.write_text(OTHERS)
    return run, a, b


def test_several_raters(files, tmp_path, capsys):
    run, a, b = files
    out = tmp_path / "ag"
    assert main(["agree", str(run), "--ratings", str(a), str(b), "--out", str(out)]) == 0
    assert "Krippendorff's alpha (ordinal)" in capsys.readouterr().out
    r = json.loads((out / "agreement.json").read_text())
    assert r["rater_names"] == ["alice", "bob", "carol"]
    # units rated twice or more: task 19 Table A (FAIR, POOR, GOOD), task 21 (EXCELLENT, VERY GOOD)
    assert r["alpha"]["units"] == 2
    assert r["alpha"]["alpha"] == pytest.approx(ordinal_alpha([[3, 4, 2], [0, 1]]))
    assert {t["table"]: t["units"] for t in r["alpha"]["tables"]} == {"A": 2, "C": 0}
    assert [t["alpha"] for t in r["alpha"]["tables"] if t["table"] == "C"] == [None]
    per = {(g["rater"], g["table"]): g for g in r["raters"]}
    assert per[("alice", "A")]["n"] == 2 and per[("bob", "A")]["n"] == 2
    assert per[("carol", "A")]["n"] == 1
    # consensus: the median (FAIR of GOOD, FAIR, POOR; of EXCELLENT, VERY GOOD the milder)
    # against the run's VERY GOOD (task 19: the tongue's 1 negative) and EXCELLENT (task 21)
    cons = {c["table"]: c for c in r["consensus"]}
    assert list(cons) == ["A"] and cons["A"]["n"] == 2 and cons["A"]["exact"] == 0.5
    dis = r["rater_disagreements"]
    assert [(d["task"], d["spread"], d["consensus"]) for d in dis] == \
        [("19", 2, "FAIR"), ("21", 1, "EXCELLENT")]
    assert dis[0]["ratings"] == "alice: FAIR; bob: POOR; carol: GOOD"
    assert dis[0]["viewer"] == "viewer/JW11/019_1.html#a=cassi-2.0"
    checks = {c["check"]: c for c in r["checks"]}
    # tongue, Table A: 5 rater-cells, fired in the 3 of task 19, ticked by alice (19) and bob (21)
    t = checks["tongue_through_teeth"]
    assert (t["cells"], t["fired"], t["ticked"], t["both"]) == (5, 3, 2, 1)
    assert t["precision"] == pytest.approx(0.5) and t["recall"] == pytest.approx(1 / 3)
    lip = checks["lower_lip_below_teeth"]
    assert (lip["table"], lip["precision"], lip["recall"]) == ("C", 1.0, 1.0)
    md = (out / "agreement.md").read_text()
    assert "## Between the raters (alice, bob, carol)" in md and "viewer/JW11/019_1.html" in md


def test_a_rater_twice_on_a_unit_is_refused_across_files(files, tmp_path, capsys):
    run, a, b = files
    b.write_text(OTHERS + "JW11,19,cassi-2.0,A,,POOR,alice,\n")
    assert main(["agree", str(run), "--ratings", str(a), str(b)]) == 2
    assert "others.csv:5: duplicate of alice.csv:2" in capsys.readouterr().err


def test_an_unknown_fault_text_is_refused(files, capsys):
    run, a, _ = files
    a.write_text(HEADER + "JW11,19,cassi-2.0,A,,FAIR,alice,the nose glows\n")
    assert main(["agree", str(run), "--ratings", str(a)]) == 2
    assert "alice.csv:2: unknown fault 'the nose glows'" in capsys.readouterr().err


def test_one_rater_reports_no_alpha(files, tmp_path):
    run, a, _ = files
    assert main(["agree", str(run), "--ratings", str(a), "--out", str(tmp_path / "ag")]) == 0
    r = json.loads((tmp_path / "ag" / "agreement.json").read_text())
    assert r["alpha"] is None and r["raters"] == [] and r["rater_disagreements"] == []
    assert r["checks"]  # one rater's ticks still meet the checks


@pytest.mark.parametrize("version, problem", [
    ("MNPP", "looks like a blinded code: un-blind the file with --key"),
])
def test_a_code_without_its_key_is_refused(files, capsys, version, problem):
    run, a, _ = files
    a.write_text(HEADER + f"JW11,19,{version},A,,FAIR,alice,\n")
    assert main(["agree", str(run), "--ratings", str(a)]) == 2
    assert problem in capsys.readouterr().err
