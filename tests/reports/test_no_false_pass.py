"""No false pass, round three: a version that animates no frame, gates and goldens that trust a
blob's name, a run that evaluated nothing.

Each test reproduces one way a run, a gate, a golden or a night passed what it never saw."""
from __future__ import annotations

import dataclasses
import datetime as dt
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cassi.common.errors import CassiInputError
from cassi.data.synth.corpus import make_corpus
from cassi.data.xrmb.files import PELLETS, read_txy, write_txy
from cassi.harness.cli import main
from cassi.harness.evaluation import stages
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.nightly import nightly
from cassi.harness.evaluation.run import run
from cassi.harness.farm.jobs import SkipJob, State
from cassi.reports.gates import GOLDEN_MARK, MismatchedBaseline, gate, update_golden
from cassi.reports.nightly import review_night

from reports_fixtures import image, results_rows, write_run

GEOMETRY = dict(subjects=("JW45",), tasks=(2,), views=("geometry",), workers=1)
#: The version that animates nothing in the tests of item 1 (x1 of the issue).
EMPTY = "cassi-1.0"
KEY = ("JW11", 19, "cassi-2.0", "front", 0)
KEY2 = ("JW11", 19, "cassi-2.0", "front", 5)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW45"])


# -- 1. a version that animates no frame -----------------------------------------------------
class _NoFrames:
    """A version whose ``animate_chunks`` yields nothing (the rest is the real version's)."""

    def __init__(self, version):
        self._version, self.name = version, version.name

    def animate_chunks(self, *args, **kwargs):
        return iter(())

    def __getattr__(self, name):
        return getattr(self._version, name)


def geometry_animating_nothing(job, ctx, inputs):
    """The real geometry stage, with EMPTY animating no frame (in this worker process)."""
    real = stages.get_version
    stages.get_version = lambda name: _NoFrames(real(name)) if name == EMPTY else real(name)
    try:
        return stages.geometry_stage(job, ctx, inputs)
    finally:
        stages.get_version = real


def test_a_version_that_animates_no_frame_of_a_usable_file_fails_its_job(corpus, tmp_path,
                                                                          capsys):
    cfg = RunConfig(out=tmp_path / "run", corpus=corpus, versions=(EMPTY, "cassi-2.1"),
                    **GEOMETRY)
    good = tmp_path / "good"
    assert run(cfg.replace(out=good), progress=False).ok
    pipeline = dataclasses.replace(stages.cassi_pipeline(render=False),
                                   geometry=geometry_animating_nothing)
    result = run(cfg, progress=False, pipeline=pipeline)
    empty = result.records[f"JW45/002-1/{EMPTY}/geometry"]
    assert empty.state is State.FAILED, empty                # not skipped: the file was usable
    assert f"{EMPTY} animated no frame of a usable task file" in empty.reason
    assert result.records["JW45/002-1/cassi-2.1/geometry"].state is State.DONE
    assert not result.ok                                      # cassi run exits 1
    assert main(["gate", str(cfg.out), "--baseline", str(good)]) == 2
    assert f"JW45/002-1/{EMPTY}/geometry" in capsys.readouterr().err
    assert main(["golden", str(cfg.out), "--golden", str(tmp_path / "golden")]) == 2
    assert "animated no frame" in capsys.readouterr().err


def _checks_run(root: Path, versions=("cassi-1.0", "cassi-2.0", "cassi-2.1"), **kw) -> Path:
    """A run whose versions other than ``versions`` were skipped, as x1 was before it failed."""
    results = results_rows({})
    results = results[results["version"].isin(versions)].reset_index(drop=True)
    skipped = {f"{s}/{t:03d}-1/{v}/geometry": "the version animated no frame"
               for s in ("JW11", "JW12") for t in (19, 21)
               for v in {"cassi-1.0", "cassi-2.0", "cassi-2.1"} - set(versions)}
    return write_run(root, results, summary={"failed": {}, "skipped": skipped}, **kw)


def test_a_gate_refuses_a_side_lacking_checks_the_other_has(tmp_path, capsys):
    base = _checks_run(tmp_path / "base")
    lacking = _checks_run(tmp_path / "run", versions=("cassi-2.0", "cassi-2.1"))
    for a, b, side in ((lacking, base, "baseline"), (base, lacking, "run")):
        with pytest.raises(MismatchedBaseline, match=rf"checks differ \(only in the {side}: "
                                                     r"JW11/019-1/cassi-1\.0/geometry \(3 checks"):
            gate(a, b)
    assert main(["gate", str(lacking), "--baseline", str(base)]) == 2
    err = capsys.readouterr().err
    assert "JW12/021-1/cassi-1.0/geometry" in err and "--common-only" in err
    assert not (lacking / "gate.md").exists()
    # said so: compared on what both have
    passed, results = gate(lacking, base, common_only=True)
    assert passed and {r.version for r in results if r.gate == "metric"} == {"cassi-2.0",
                                                                              "cassi-2.1"}
    assert "checks differ" in (lacking / "gate.md").read_text()


def test_a_gate_refuses_a_side_lacking_renders_the_other_has(tmp_path):
    base = write_run(tmp_path / "base", results_rows({}), images={KEY: image(1), KEY2: image(2)})
    golden = tmp_path / "golden"
    update_golden(base, golden)
    lacking = write_run(tmp_path / "run", results_rows({}), images={KEY: image(1)})
    for baseline in (base, golden):
        with pytest.raises(MismatchedBaseline, match=r"renders differ \(only in the baseline: "
                                                     r"JW11/019-1/cassi-2\.0/front \(frame 5\)\)"):
            gate(lacking, baseline)
        passed, results = gate(lacking, baseline, common_only=True)
        assert passed and [r.status for r in results if r.gate == "image"] == ["pass"]
        assert "renders differ" in (lacking / "gate.md").read_text()


# -- 2. gates and goldens trust blob names ---------------------------------------------------
def _blobs(root: Path) -> list[Path]:
    return sorted((root / "objects").glob("*/*"))


def test_a_blob_changed_in_the_store_fails_the_gate_and_makes_no_golden(corpus, tmp_path,
                                                                         capsys):
    store = tmp_path / "store"
    cfg = RunConfig(out=tmp_path / "a", corpus=corpus, cache=store, subjects=("JW45",),
                    tasks=(2,), versions=("cassi-1.0",), views=("front",), stride=0,
                    extremes=1, workers=1)
    run(cfg, progress=False)
    run(cfg.replace(out=tmp_path / "b"), progress=False)
    # the store's blobs and their links are read-only: a write into one run's copy would be
    # a write into every run's
    for root in (store, tmp_path / "a", tmp_path / "b"):
        assert _blobs(root) and not any(p.stat().st_mode & 0o222 for p in _blobs(root))
    assert main(["gate", str(tmp_path / "a"), "--baseline", str(tmp_path / "b")]) == 0
    # one byte of a render flipped in the store (by someone with the rights to)
    blob = store / pd.read_parquet(tmp_path / "a" / "renders.parquet")["path"].iloc[0]
    blob.chmod(0o644)
    data = bytearray(blob.read_bytes())
    data[len(data) // 2] ^= 0xFF
    blob.write_bytes(bytes(data))
    passed, results = gate(tmp_path / "a", tmp_path / "b")
    bad = [r for r in results if r.status == "fail"]
    assert not passed and len(bad) == 1 and bad[0].gate == "image"
    assert "is corrupt: its bytes hash to" in bad[0].reason
    golden = tmp_path / "golden"
    assert main(["golden", str(tmp_path / "a"), "--golden", str(golden)]) == 2
    assert "is corrupt" in capsys.readouterr().err
    assert not (golden / GOLDEN_MARK).exists() and not list(golden.rglob("*.png*"))


def test_golden_decodes_what_it_writes(tmp_path, capsys):
    cut = write_run(tmp_path / "run", results_rows({}), images={KEY: image(1), KEY2: image(2)})
    render = sorted((cut / "objects").glob("*.png"))[1]
    render.write_bytes(render.read_bytes()[:-40])  # a render cut short
    golden = tmp_path / "golden"
    assert main(["golden", str(cut), "--golden", str(golden)]) == 2
    err = capsys.readouterr().err
    assert "the render does not decode" in err and render.name in err
    assert not list(golden.rglob("*.png*"))      # neither image written, no temporary left


# -- 5. a run that evaluated nothing ---------------------------------------------------------
def test_a_run_whose_only_task_file_is_unusable_is_an_error(corpus, tmp_path, capsys):
    data = tmp_path / "c"
    shutil.copytree(corpus, data)
    path = data / "JW45" / "tp002.txy"
    rec = read_txy(path, require_valid=False)
    valid, xy = rec.valid.copy(), rec.xy_mm.copy()
    valid[:, PELLETS.index("MNM")] = False                      # MNM lost: never all eight
    xy[~valid] = np.nan
    write_txy(path, dataclasses.replace(rec, valid=valid, xy_mm=xy))
    out = tmp_path / "out"
    assert main(["run", "--corpus", str(data), "--subjects", "JW45", "--tasks", "2",
                 "--versions", "cassi-1.0", "--views", "geometry", "--out", str(out),
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "nothing to evaluate: no task file of the run is usable (JW45/002-1: " in err
    assert not (out / "tables.json").exists()
    # the night inherits it: no baseline recorded
    with pytest.raises(CassiInputError, match="nothing to evaluate"):
        nightly(tmp_path / "nightly", review=review_night, corpus=data,
                config=RunConfig(versions=("cassi-1.0",), **GEOMETRY),
                today=dt.date(2026, 12, 1), progress=False)
    assert not (tmp_path / "nightly" / "latest.txt").exists()


def geometry_skipping(job, ctx, inputs):
    """A geometry stage that finds every job's input unusable in the worker."""
    raise SkipJob("subject cannot be preprocessed: no palate")


def test_a_run_whose_every_job_is_skipped_is_an_error_and_no_golden(corpus, tmp_path, capsys):
    out = tmp_path / "out"
    pipeline = dataclasses.replace(stages.cassi_pipeline(render=False), geometry=geometry_skipping)
    with pytest.raises(CassiInputError, match=r"the run evaluated nothing: every job was skipped "
                                              r"\(JW45/002-1/cassi-1\.0/geometry: subject cannot"):
        run(RunConfig(out=out, corpus=corpus, versions=("cassi-1.0",), **GEOMETRY),
            progress=False, pipeline=pipeline)
    assert main(["golden", str(out), "--golden", str(tmp_path / "golden")]) == 2
    assert "the run evaluated nothing (0 result rows; every job skipped" in capsys.readouterr().err
    assert not (tmp_path / "golden" / GOLDEN_MARK).exists()
