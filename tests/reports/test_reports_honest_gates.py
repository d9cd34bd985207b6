"""Results that cannot lie: a gate refuses an incomplete side, a comparison of nothing, tables
under another run's run.json and runs of other corpus files; identical renders pass unread.

Each test reproduces one way a gate, a report or a night gave a wrong answer."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pandas as pd
import pytest

from cassi.data.synth.corpus import make_corpus
from cassi.harness.cli import main
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.nights import previous_night
from cassi.harness.evaluation.run import run
from cassi.harness.farm import store
from cassi.harness.farm.tableset import TableSetError
from cassi.reports import gates
from cassi.reports.gates import (IncompleteRun, MismatchedBaseline, NothingCompared, gate,
                                 update_golden)
from cassi.reports.runio import load_run

from reports_fixtures import image, results_rows, write_run

VERSIONS = ["cassi-1.0", "cassi-2.0", "cassi-2.1"]
KEY = ("JW11", 19, "cassi-2.0", "front", 0)


def _run(root: Path, tasks, *, failed=None, digests=None, drop=None, images=None) -> Path:
    """A run of ``tasks`` [(subject, task)]; ``digests[(subject, task)]`` its input digests,
    ``drop`` a (subject, task, version) whose results are gone without a job record."""
    results = results_rows({})
    keep = set(tasks)
    results = results[[(s, t) in keep for s, t in zip(results.subject, results.task)]]
    if drop:
        results = results[[(s, t, v) != drop for s, t, v in
                           zip(results.subject, results.task, results.version)]]
    rows = [[s, t, 1, True, ""] + ([digests[(s, t)]] if digests else []) for s, t in tasks]
    meta = {"tasks_resolved": rows, "versions_resolved": VERSIONS, "views_resolved": ["front"],
            "preset": "preview"}
    return write_run(root, results.reset_index(drop=True), meta=meta, images=images,
                     summary={"failed": failed or {}, "skipped": {}})


# -- 1. a failed side ------------------------------------------------------------------------
@pytest.mark.parametrize("job", ["JW11/019-1/cassi-2.0/front/checks",
                                 "JW11/019-1/cassi-2.0/geometry"])
def test_a_baseline_with_a_failed_job_is_refused_naming_it(tmp_path, capsys, job):
    healthy = _run(tmp_path / "run", [("JW11", 19)])
    base = _run(tmp_path / "base", [("JW11", 19)], failed={job: "boom"})
    with pytest.raises(IncompleteRun, match=f"baseline has failed .*{job} failed: boom"):
        gate(healthy, base)
    assert main(["gate", str(healthy), "--baseline", str(base)]) == 2
    err = capsys.readouterr().err
    assert job in err and str(base) in err and "PASSED" not in err
    assert not (healthy / "gate.md").exists()  # no report that blames or clears the run


def test_a_baseline_missing_results_without_a_record_is_refused(tmp_path):
    healthy = _run(tmp_path / "run", [("JW11", 19)])
    base = _run(tmp_path / "base", [("JW11", 19)], drop=("JW11", 19, "cassi-2.0"))
    with pytest.raises(IncompleteRun, match="JW11/019-1/cassi-2.0: no results and no job record"):
        gate(healthy, base)
    with pytest.raises(IncompleteRun, match="the run lacks jobs"):
        gate(base, healthy)


def test_a_run_with_a_failed_job_exits_2_naming_it_and_gate_md_lists_it(tmp_path, capsys):
    base = _run(tmp_path / "base", [("JW11", 19)])
    bad = _run(tmp_path / "bad", [("JW11", 19)],
               failed={"JW11/019-1/cassi-2.0/geometry": "boom"})
    assert main(["gate", str(bad), "--baseline", str(base)]) == 2
    assert "JW11/019-1/cassi-2.0/geometry" in capsys.readouterr().err
    assert "job failed: boom" in (bad / "gate.md").read_text()


def test_golden_refuses_a_run_with_a_failed_job(tmp_path, capsys):
    bad = _run(tmp_path / "bad", [("JW11", 19)], images={KEY: image(1)},
               failed={"JW11/019-1/cassi-2.1/front/checks": "boom"})
    with pytest.raises(IncompleteRun, match="cannot be the golden baseline"):
        update_golden(bad, tmp_path / "golden")
    assert main(["golden", str(bad), "--golden", str(tmp_path / "golden")]) == 2
    assert "front/checks failed: boom" in capsys.readouterr().err
    assert not (tmp_path / "golden").exists()


def test_the_night_after_a_failed_night_compares_with_the_newest_complete_one(tmp_path):
    runs = tmp_path / "runs"
    _run(runs / "2026-01-01", [("JW11", 19)])
    _run(runs / "2026-01-02", [("JW11", 19)], failed={"JW11/019-1/cassi-2.0/geometry": "boom"})
    assert previous_night(runs, "2026-01-03") == runs / "2026-01-01"
    _run(runs / "2026-01-03", [("JW11", 19)])
    assert previous_night(runs, "2026-01-04") == runs / "2026-01-03"
    assert previous_night(runs, "2026-01-01") is None
    # a night whose tables do not verify (here: under another run.json) is passed over too
    meta = json.loads((runs / "2026-01-03" / "run.json").read_text())
    (runs / "2026-01-03" / "run.json").write_text(json.dumps({**meta, "preset": "final"}))
    assert previous_night(runs, "2026-01-04") == runs / "2026-01-01"


# -- 2. nothing compared ---------------------------------------------------------------------
def test_nothing_in_common_is_not_a_pass(tmp_path, capsys):
    a = _run(tmp_path / "a", [("JW11", 19)])
    b = _run(tmp_path / "b", [("JW12", 21)])
    with pytest.raises(NothingCompared, match="nothing was compared .*--common-only"):
        gate(a, b, common_only=True)
    assert main(["gate", str(a), "--baseline", str(b), "--common-only"]) == 2
    assert "a gate that compares nothing is not a pass" in capsys.readouterr().err


def test_an_empty_corpus_is_refused_before_a_0_job_run(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["run", "--corpus", str(empty), "--out", str(tmp_path / "out"),
                 "--no-progress"]) == 2
    assert "nothing to run" in capsys.readouterr().err
    assert not (tmp_path / "out" / "tables.json").exists()


# -- 3. old tables under a new run.json ------------------------------------------------------
def test_tables_under_another_runs_config_are_refused(tmp_path, capsys):
    root = _run(tmp_path / "run", [("JW11", 19)])
    meta = json.loads((root / "run.json").read_text())
    # what the run adds once the tables are written keeps them valid
    (root / "run.json").write_text(json.dumps({**meta, "summary": {"jobs": 3},
                                               "finished": "2026-01-01T00:00:00Z"}))
    assert load_run(root).results.shape[0]
    # a rerun with other versions into the same directory, killed before its tables
    (root / "run.json").write_text(json.dumps({**meta, "versions_resolved": ["cassi-2.1"],
                                               "started": "2026-02-02T00:00:00Z"}))
    with pytest.raises(TableSetError, match="run.json does not describe these tables"):
        load_run(root)
    assert main(["report", str(root), "--out", str(tmp_path / "report")]) == 2
    assert main(["gate", str(root), "--baseline", str(root)]) == 2
    assert "does not describe these tables" in capsys.readouterr().err


# -- 4. the corpus each run read ------------------------------------------------------------
def test_runs_of_other_corpus_files_are_refused_or_compared_on_the_same_files(tmp_path):
    tasks = [("JW11", 19), ("JW11", 21)]
    same = {t: "a" * 64 for t in tasks}
    a = _run(tmp_path / "a", tasks, digests=same)
    b = _run(tmp_path / "b", tasks, digests={**same, ("JW11", 21): "b" * 64})
    with pytest.raises(MismatchedBaseline, match=r"corpus files differ for 1 task file\(s\) "
                                                 r"\(JW11/21/1\)"):
        gate(a, b)
    passed, results = gate(a, b, common_only=True)
    assert passed and {r.subject for r in results if r.gate == "metric"} == {"all"}
    assert "corpus files differ" in (a / "gate.md").read_text()
    assert gate(a, _run(tmp_path / "a2", tasks, digests=same))[0]
    # a run that does not record them: said, not silently passed over
    old = _run(tmp_path / "old", tasks)
    assert gate(a, old)[0]
    assert "corpus files were not compared: the baseline" in (a / "gate.md").read_text()


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW45"])


def test_a_run_records_its_input_digests_and_its_tables_survive_its_last_write(corpus, tmp_path):
    out = tmp_path / "out"
    run(RunConfig(out=out, corpus=corpus, subjects=("JW45",), tasks=(2,), versions=("cassi-1.0",),
                  views=("geometry",), workers=1), progress=False)
    meta = json.loads((out / "run.json").read_text())
    assert "finished" in meta and len(meta["tasks_resolved"][0][5]) == 64
    assert gate(out, out)[0]


# -- 5. report to an unwritable directory ---------------------------------------------------
def test_report_to_an_unwritable_out_exits_2_like_run(tmp_path, capsys):
    root = _run(tmp_path / "run", [("JW11", 19)])
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["report", str(root), "--out", str(blocker / "report")]) == 2
    err = capsys.readouterr().err
    assert "report directory is not writable" in err and str(blocker / "report") in err


# -- identical renders ----------------------------------------------------------------------
def test_an_identical_render_passes_without_being_decoded(tmp_path, monkeypatch):
    a = write_run(tmp_path / "a", results_rows({}), images={KEY: image(1)})
    b = tmp_path / "b"
    shutil.copytree(a, b)
    golden = tmp_path / "golden"
    update_golden(a, golden)

    def no_decoding(*_):
        raise AssertionError("an identical render was decoded")

    monkeypatch.setattr(gates, "read_rgb8", no_decoding)
    for baseline in (b, golden):
        passed, results = gate(a, baseline)
        image_gate = [r for r in results if r.gate == "image"]
        assert passed and [r.status for r in image_gate] == ["pass"]
        assert "the same bytes" in image_gate[0].reason
    # an unequal render still goes through the comparison rule (the decoder)
    c = write_run(tmp_path / "c", results_rows({}), images={KEY: image(2)})
    with pytest.raises(AssertionError, match="decoded"):
        gate(c, golden)


def test_renders_named_by_the_same_digest_pass_undecoded_and_each_hashed_once(corpus, tmp_path,
                                                                            monkeypatch):
    """Night against night: both renders are store blobs named by their SHA-256; the gate
    verifies each file's bytes against its name once (a name alone is no proof: a write into
    a linked blob keeps it) and decodes none of them."""
    cfg = RunConfig(out=tmp_path / "a", corpus=corpus, subjects=("JW45",), tasks=(2,),
                    versions=("cassi-1.0",), views=("front",), stride=0, extremes=1, workers=1)
    run(cfg, progress=False)
    run(cfg.replace(out=tmp_path / "b"), progress=False)
    paths = pd.read_parquet(tmp_path / "a" / "renders.parquet")["path"]
    assert len(paths) and all(len(Path(p).stem) == 64 for p in paths)  # content-addressed

    def no_decoding(*_):
        raise AssertionError("a render named by its digest was decoded")

    hashed, real = [], store.sha256_file
    monkeypatch.setattr(gates, "read_rgb8", no_decoding)
    monkeypatch.setattr(store, "sha256_file", lambda p: hashed.append(Path(p).resolve()) or real(p))
    # the gate as a process of its own (`cassi gate`): the runs above verified these blobs in
    # this process, which a night's gate trusts while each file's identity is unchanged
    monkeypatch.setattr(store, "_HASHED", {})
    passed, results = gate(tmp_path / "a", tmp_path / "b")
    image_gates = [r for r in results if r.gate == "image"]
    assert passed and image_gates and {r.status for r in image_gates} == {"pass"}
    assert len(hashed) == len(set(hashed)) == 2 * len(paths)   # a's and b's, once each
    hashed.clear()
    assert gate(tmp_path / "a", tmp_path / "b")[0] and not hashed  # unchanged: not read again
