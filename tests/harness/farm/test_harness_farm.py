"""The farm machinery with small real stages of its own: caching, resume after kill -9,
crashing workers, retries without duplicate rows, skipped inputs, the run lock.

The stages below are real (they compute rows and files from the job and write through the
store); they stand in for the CASSI pipeline so that these tests check the machinery alone.
"""
from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cassi.common.errors import CassiInputError
from cassi.harness.farm import results as R
from cassi.harness.farm.executors import LocalExecutor
from cassi.harness.farm.jobs import Job, SkipJob, StageContext, StageOutput, State, npz_bytes
from cassi.harness.evaluation.frames import select_frames
from cassi.harness.farm.plan import BatchPlan
from cassi.harness.farm.runner import Pipeline, Scheduler, TaskSpec, collect, run_batch
from cassi.harness.farm.store import OutputStore
from cassi.harness.rubric import ratings_table

TESTS = Path(__file__).resolve().parent
N_FRAMES = 30


def _marker(ctx: StageContext, name: str) -> Path:
    return Path(ctx.out_dir) / f"marker-{name}"


def geom_stage(job: Job, ctx: StageContext, inputs) -> StageOutput:
    """Per-frame 'lip gap' from the job's numbers; picks the largest as an extreme frame."""
    time.sleep(float(os.environ.get("FARM_TEST_SLEEP", 0)))
    if job.task == 99:
        raise SkipJob("task 99 has no valid row")
    crash_once = ctx.option("crash_once")
    if crash_once == job.key and not _marker(ctx, "crashed").exists():
        _marker(ctx, "crashed").write_text("x")
        os._exit(3)
    if ctx.option("crash_always") == job.key:
        os._exit(4)
    if ctx.option("raise_on") == job.key:
        raise RuntimeError("planted failure")
    seed = job.task * 31 + job.rep * 7 + sum(map(ord, job.subject + job.version))
    gap = (np.arange(N_FRAMES) * seed % 17).astype(float)
    rows = [dict(frame=f, check="lip_gap", table="A", component="lips", value=g, unit="mm",
                 threshold=12.0, negatives=int(g > 12)) for f, g in enumerate(gap)]
    rows.append(dict(frame=-1, check="lip_gap", table="A", component="lips",
                     value=float(gap.max()), unit="mm", threshold=12.0,
                     negatives=int(gap.max() > 12) + int(gap.max() > 15)))
    positions = np.stack([gap, gap * 2, -gap], axis=1).astype(np.float32)
    return StageOutput(rows=pd.DataFrame(rows), files={"positions": (npz_bytes(p=positions), ".npz")},
                       meta={"render_frames": select_frames(0, N_FRAMES - 1, stride=ctx.stride,
                                                            extremes=[int(gap.argmax())])},
                       log=[f"max gap {gap.max()}"])


def render_stage(job: Job, ctx: StageContext, inputs) -> StageOutput:
    """'Renders' a tiny image per frame from the parent's positions; one image check row each."""
    time.sleep(float(os.environ.get("FARM_TEST_SLEEP", 0)))
    pos = np.load(io.BytesIO(inputs["positions"]))["p"]
    files = {}
    for f in job.frames:
        img = np.full((4, 4), pos[f].sum() + len(job.view), dtype=np.float32)
        files[f"render-{f:06d}"] = (npz_bytes(img=img), ".npz")
    return StageOutput(files=files)


def image_stage(job: Job, ctx: StageContext, inputs) -> StageOutput:
    """A whole-view check over every rendered frame of the view (all render chunks)."""
    means = [float(np.load(io.BytesIO(inputs[f"render-{f:06d}"]))["img"].mean()) for f in job.frames]
    worst = int(np.argmax(means))
    return StageOutput(rows=pd.DataFrame([
        dict(frame=-1, check="teeth_visible", table="A", component="teeth", value=max(means),
             unit="px", threshold=20.0, negatives=int(max(means) > 20)),
        dict(frame=job.frames[worst], check="teeth_visible", table="A", component="teeth",
             value=means[worst], unit="px", threshold=20.0, negatives=0, detail="evidence")]))


PIPE = Pipeline(geometry=geom_stage, render=render_stage, image=image_stage, ratings=ratings_table)
TASKS = [TaskSpec("JW11", 19), TaskSpec("JW11", 21), TaskSpec("JW12", 2), TaskSpec("JW12", 5)]


def _run(out: Path, *, workers=1, tasks=TASKS, options=(), versions=("v1", "v2"),
         views=("front", "half"), retries=1):
    ctx = StageContext(out_dir=out, stride=10, chunk_size=2, options=tuple(options))
    store = OutputStore(out)
    store.prepare()
    with store.lock():
        store.remove_partials()
        with LocalExecutor(workers, retries=retries) as ex:
            return run_batch(tasks, versions, views, PIPE, ctx, ex, progress=False)


def _drive(out: str, workers: int, sleep: float) -> None:
    """Entry point for the kill -9 test's child process (slowed so that it can be killed
    mid-batch; the delay is not a run setting, so the rerun can reuse its outputs)."""
    os.environ["FARM_TEST_SLEEP"] = str(sleep)
    _run(Path(out), workers=workers)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("reference")
    res = _run(out, workers=2)
    return out, res


def test_batch_runs_and_tables_are_consistent(reference):
    out, res = reference
    c = res.summary.counts()
    # 4 files x 2 versions geometry jobs; renders: frames {0,10,20,argmax} in chunks of 2, 2 views
    assert c["failed"] == 0 and c["skipped"] == 0
    assert c["done"] == len(res.records) > 8
    df = R.read_results(out / "results.parquet")
    assert list(df.columns) == list(R.COLUMNS)
    assert not df.duplicated(list(R.KEY)).any()
    csv = pd.read_csv(out / "results.csv")
    assert len(csv) == len(df)
    assert set(df["view"]) == {"geometry", "front", "half"}
    # every render frame was picked by the geometry stage (first, stride, extreme)
    geo = df[(df.view == "geometry") & (df.subject == "JW11") & (df.task == 19) & (df.version == "v1")
             & (df.frame >= 0)]
    extreme = int(geo.loc[geo.value.idxmax(), "frame"])
    renders = pd.read_parquet(out / "renders.parquet")
    front = renders[(renders.view == "front") & (renders.subject == "JW11") & (renders.task == 19)
                    & (renders.version == "v1")]
    assert set(front.frame) == {0, 10, 20, extreme}
    assert all((out / p).is_file() for p in renders.path)
    # one image job per view saw every frame of its render chunks
    checks = df[(df.view == "front") & (df.subject == "JW11") & (df.task == 19) & (df.version == "v1")]
    assert list(checks.frame) == [-1, int(checks.frame.max())] and checks.frame.max() in set(front.frame)
    rt = pd.read_parquet(out / "ratings.parquet")
    # the rubric's one aggregation: per version, table, subject and component (only frame -1
    # rows count); Table A's lip rows are judged again in Table C
    assert len(rt) == 2 * 2 * 3 and set(rt.component) == {"lips", "teeth"}
    assert set(zip(rt.table, rt.component)) == {("A", "lips"), ("A", "teeth"), ("C", "lips")}
    pd.testing.assert_frame_equal(rt, ratings_table(pd.read_parquet(out / "results.parquet")))
    assert set(rt["rating"]) <= {"EXCELLENT", "VERY GOOD", "GOOD", "FAIR"}
    assert (out / "logs" / "JW11" / "019-1" / "v1" / "geometry.log").is_file()


def test_no_manifest_is_held_after_the_run_and_the_indexes_come_in_job_key_order(tmp_path):
    """Each job's rows and index entries are taken as it finishes (2 workers: out of order);
    the indexes equal those read from every manifest at the end, in job-key order."""
    ctx = StageContext(out_dir=tmp_path, stride=10, chunk_size=2)
    store = OutputStore(tmp_path)
    store.prepare()
    pipe = Pipeline(geometry=geom_stage, render=render_stage, image=image_stage,
                    attachments=("positions",))
    plan = BatchPlan.build(TASKS, ("v1", "v2"), ("front", "half"), chunk_size=2, render=True,
                           images=True)
    with LocalExecutor(2) as ex:
        scheduler = Scheduler(plan, pipe, ctx, ex, progress=False)
        scheduler.run()
    assert scheduler.verified == {} and scheduler.chunks == {}
    _, renders, attached = collect(scheduler)
    want_renders, want_attached, finished = [], [], []
    for key in sorted(scheduler.records):
        manifest = store.verified(key, scheduler.digests[key])
        job = scheduler.jobs[key]
        for name, ref in manifest["outputs"].items():
            if name.startswith("render-"):
                want_renders.append((key, int(name[7:]), ref.relpath))
            elif name == "positions":
                want_attached.append((key, ref.relpath))
        finished.append(key)
    assert len(finished) == len(scheduler.records) > 20
    assert list(zip(renders["frame"], renders["path"])) == [(f, p) for _, f, p in want_renders]
    assert attached["path"] == [p for _, p in want_attached] and len(want_attached) == 8


def test_rerun_skips_everything_and_gives_identical_tables(reference, tmp_path):
    out, first = reference
    before = (out / "results.csv").read_bytes()
    res = _run(out, workers=1)
    c = res.summary.counts()
    assert c["cached"] == len(first.records) and c["done"] == 0
    assert (out / "results.csv").read_bytes() == before


def test_corrupt_output_is_recomputed(reference, tmp_path):
    out, first = reference
    blobs = sorted((out / "objects").rglob("*.npz"))
    blobs[0].chmod(0o644)  # blobs are read-only: this is damage done on purpose
    blobs[0].write_bytes(b"garbage")
    res = _run(out, workers=1)
    assert res.summary.counts()["done"] >= 1
    assert res.summary.counts()["failed"] == 0
    pd.testing.assert_frame_equal(res.results, first.results)


def test_kill_9_then_rerun_is_identical(reference, tmp_path):
    ref_out, _ = reference
    out = tmp_path / "killed"
    code = (f"import sys; sys.path.insert(0, {str(TESTS)!r}); import test_harness_farm as t; "
            f"t._drive({str(out)!r}, 2, 0.15)")
    proc = subprocess.Popen([sys.executable, "-c", code], start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 60
    try:
        while time.time() < deadline:
            if len(list((out / "jobs").rglob("*.json"))) >= 6 if (out / "jobs").exists() else False:
                break
            if proc.poll() is not None:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the batch finished before it could be killed"
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the run and its workers, as a machine crash would
        proc.wait()
    assert not (out / "results.parquet").exists()
    res = _run(out, workers=2)
    c = res.summary.counts()
    assert c["cached"] >= 6 and c["done"] >= 1 and c["failed"] == 0
    assert (out / "results.csv").read_bytes() == (ref_out / "results.csv").read_bytes()
    pd.testing.assert_frame_equal(R.read_results(out / "results.parquet"),
                                  R.read_results(ref_out / "results.parquet"))
    assert not [p for p in out.rglob(".*") if ".tmp" in p.name]


def test_worker_crash_is_retried_and_nothing_else_lost(reference, tmp_path):
    ref_out, first = reference
    out = tmp_path / "crash"
    res = _run(out, workers=2, options=(("crash_once", "JW11/021-1/v2/geometry"),))
    assert (out / "marker-crashed").exists()
    assert res.summary.worker_crashes == 1
    assert res.summary.counts()["failed"] == 0
    assert res.records["JW11/021-1/v2/geometry"].attempts == 2
    assert (out / "results.csv").read_bytes() == (ref_out / "results.csv").read_bytes()


def test_worker_crashing_every_time_fails_only_that_job(reference, tmp_path):
    _, first = reference
    out = tmp_path / "crash-always"
    bad = "JW12/002-1/v1/geometry"
    res = _run(out, workers=2, options=(("crash_always", bad),), retries=1)
    assert not res.ok
    assert [r.key for r in res.summary.failed] == [bad]
    assert "worker process died" in res.records[bad].reason
    assert "FAILED " + bad in res.summary.text()
    expected = first.results[~((first.results.subject == "JW12") & (first.results.task == 2)
                               & (first.results.version == "v1"))].reset_index(drop=True)
    pd.testing.assert_frame_equal(res.results, expected)


def test_exception_fails_job_with_traceback_in_log(tmp_path):
    bad = "JW11/019-1/v1/geometry"
    res = _run(tmp_path, tasks=TASKS[:1], versions=("v1",), views=(),
               options=(("raise_on", bad),))
    assert res.records[bad].state is State.FAILED
    assert "planted failure" in res.records[bad].reason
    log = (tmp_path / "logs" / f"{bad}.log").read_text()
    assert "Traceback" in log and "RuntimeError" in log


def test_unusable_inputs_become_skipped_jobs_with_reasons(tmp_path):
    tasks = [TaskSpec("JW11", 19), TaskSpec("JW11", 7, usable=False, reason="file has no valid row"),
             TaskSpec("JW11", 99)]
    res = _run(tmp_path, tasks=tasks, versions=("v1",), views=("front",))
    s = res.summary
    assert s.counts()["skipped"] == 2 and s.counts()["failed"] == 0
    text = s.text()
    assert "file has no valid row" in text and "task 99 has no valid row" in text
    assert set(res.results["task"]) == {19}


def test_lock_stops_a_second_run(tmp_path):
    store = OutputStore(tmp_path)
    store.prepare()
    with store.lock():
        with pytest.raises(CassiInputError, match="another cassi run"):
            with OutputStore(tmp_path).lock():
                pass
    with OutputStore(tmp_path).lock():  # released again
        pass


def test_unwritable_out_dir_is_a_clear_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(CassiInputError, match="not writable"):
        OutputStore(blocker / "out").prepare()


def test_an_unusable_cache_is_named_as_the_cache(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(CassiInputError, match="cache directory") as info:
        OutputStore(tmp_path / "out", cache=blocker / "cache").prepare()
    assert str(blocker) in str(info.value.path)
    with pytest.raises(CassiInputError, match="output directory exists and is not a directory"):
        OutputStore(blocker).prepare()


def test_results_normalize_folds_extra_columns_into_detail():
    df = R.normalize([{"check": "x", "value": 1, "where": "UL"}], subject="S", task=1, rep=1)
    assert df.loc[0, "detail"] == "where=UL"
    assert df.loc[0, "frame"] == -1 and df.loc[0, "negatives"] == 0
    assert list(df.columns) == list(R.COLUMNS)


def test_tables_that_cannot_be_written_keep_finished_outputs(tmp_path):
    from cassi.harness.farm.runner import OutputWriteError

    (tmp_path / "results.parquet").mkdir()  # the table's name is taken: its write must fail
    with pytest.raises(OutputWriteError, match="finished job outputs are kept"):
        _run(tmp_path, tasks=TASKS[:1], versions=("v1",), views=())
    (tmp_path / "results.parquet").rmdir()
    res = _run(tmp_path, tasks=TASKS[:1], versions=("v1",), views=())
    assert res.summary.counts()["cached"] == 1 and (tmp_path / "results.parquet").is_file()


def test_a_jobs_digest_is_the_json_of_all_its_fields():
    """Job.digest is the SHA-256 of every field as dataclasses.asdict gives them (tuples
    nested included): stores written before keep their digests."""
    import dataclasses
    import hashlib
    import json

    job = Job(stage="render", subject="JW11", task=19, rep=2, version="cassi-2.1", view="front",
              frames=tuple(range(0, 2000, 24)), chunk=3, evidence=True, parents=("a", "b"),
              parent_digest="p", inputs="i", reads=(("keyframes", "ab"), ("x", "cd")))
    doc = json.dumps({"job": dataclasses.asdict(job), "salt": "s"}, sort_keys=True, default=str)
    assert job.digest("s") == hashlib.sha256(doc.encode()).hexdigest()
    assert job.digest("s") != dataclasses.replace(job, frames=job.frames[:-1]).digest("s")
