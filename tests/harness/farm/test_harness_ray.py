"""The Ray executor on a real local cluster (one per module): same jobs, same results as the
local pool; a task whose worker dies is retried (at-least-once) without duplicate rows."""
from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cassi.harness.farm.executors import LocalExecutor, RayExecutor
from cassi.harness.farm.jobs import Job, StageContext, StageOutput, State, npz_bytes
from cassi.harness.evaluation.frames import select_frames
from cassi.harness.farm.runner import Pipeline, TaskSpec, run_batch
from cassi.harness.farm.store import OutputStore

ray = importlib.import_module("ray")
pytestmark = pytest.mark.ray


def geom(job: Job, ctx: StageContext, inputs) -> StageOutput:
    crash = ctx.option("crash_once")
    marker = Path(ctx.out_dir) / "crashed"
    if crash == job.key and not marker.exists():
        marker.write_text(str(os.getpid()))
        os._exit(5)
    v = np.arange(10) * (job.task + len(job.version)) % 7
    rows = pd.DataFrame({"frame": np.arange(10), "check": "gap", "table": "A", "component": "lips",
                         "value": v.astype(float), "unit": "mm", "negatives": (v > 5).astype(int)})
    return StageOutput(rows=rows, files={"v": (npz_bytes(v=v), ".npz")},
                       meta={"render_frames": select_frames(0, 9, stride=5)})


def render(job: Job, ctx: StageContext, inputs) -> StageOutput:
    rows = pd.DataFrame({"frame": list(job.frames), "check": "seen", "table": "A",
                         "component": "teeth", "value": [float(f) for f in job.frames]})
    return StageOutput(rows=rows, files={f"render-{f:06d}": (bytes([f]), ".bin") for f in job.frames})


def image(job: Job, ctx: StageContext, inputs) -> StageOutput:
    seen = sum(inputs[f"render-{f:06d}"][0] for f in job.frames)
    return StageOutput(rows=pd.DataFrame({"frame": [-1], "check": ["seen_all"], "table": ["A"],
                                          "component": ["teeth"], "value": [float(seen)]}))


PIPE = Pipeline(geometry=geom, render=render, image=image)
TASKS = [TaskSpec("S1", 1), TaskSpec("S1", 2), TaskSpec("S2", 3)]


@pytest.fixture(scope="module")
def cluster():
    from ray import cloudpickle  # Ray's own copy: it serializes task arguments

    # Ray workers cannot import this test module by name; ship its functions by value.
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, logging_level="ERROR")
    yield
    ray.shutdown()
    cloudpickle.unregister_pickle_by_value(sys.modules[__name__])


def _run(out, executor, options=()):
    ctx = StageContext(out_dir=out, stride=5, chunk_size=1, options=tuple(options))
    store = OutputStore(out)
    store.prepare()
    with store.lock(), executor:
        return run_batch(TASKS, ["a", "b"], ["front"], PIPE, ctx, executor, progress=False)


def test_ray_gives_the_local_pool_results(cluster, tmp_path):
    local = _run(tmp_path / "local", LocalExecutor(1))
    rayed = _run(tmp_path / "ray", RayExecutor(None, retries=1))
    assert rayed.summary.counts()["failed"] == 0
    assert rayed.summary.counts()["done"] == len(local.records) == 24  # 6 geometry + 6 x 2 render chunks + 6 image
    assert (tmp_path / "ray" / "results.csv").read_bytes() == \
        (tmp_path / "local" / "results.csv").read_bytes()
    renders = pd.read_parquet(tmp_path / "ray" / "renders.parquet")
    assert len(renders) == 12 and set(renders.frame) == {0, 5}
    assert ray.is_initialized()  # the executor leaves a cluster it did not start running


def test_ray_retries_a_dead_worker_without_duplicates(cluster, tmp_path):
    bad = "S1/002-1/b/geometry"
    ref = _run(tmp_path / "ref", RayExecutor(None))
    res = _run(tmp_path / "crash", RayExecutor(None, retries=1), options=(("crash_once", bad),))
    assert (tmp_path / "crash" / "crashed").exists()
    assert res.records[bad].state is State.DONE
    assert res.summary.counts()["failed"] == 0
    pd.testing.assert_frame_equal(res.results, ref.results)
    assert not res.results.duplicated(["subject", "task", "rep", "version", "view", "frame",
                                       "check", "component"]).any()


def test_ray_rerun_reuses_outputs(cluster, tmp_path):
    first = _run(tmp_path, RayExecutor(None))
    again = _run(tmp_path, RayExecutor(None))
    assert again.summary.counts()["cached"] == len(first.records)
    pd.testing.assert_frame_equal(again.results, first.results)
