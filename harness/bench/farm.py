"""The farm benchmarks: ``farm_preview`` and ``farm`` in :data:`cassi.harness.bench.BENCHMARKS`.

- ``farm_preview``: preview frames per second end to end in the farm (one worker, one core:
  render jobs reading their keyframes, rendering, encoding the PNG in memory, storing PNG and
  masks), per view and the mean over the four views (``farm_preview_frames_per_s``, goal >= 60
  with llvm), beside a bare Mitsuba frame (vertex upload + the one ``mi.render``) of the same
  subject's scene in the same run; the same two per CPU second as well
  (``farm_preview_cpu_frames_per_s``: the rate of a worker with a core to itself, which the
  wall-clock rate on a machine shared with other work understates);
- ``farm``: the same batch run with 1 and 2 local worker processes side by side
  (``farm_speedup_2_workers``, goal >= 1.6) and through a local Ray cluster (its overhead
  against the 2-worker local pool).

A job's wall and CPU seconds are what its worker measured and returned with its outcome
(:attr:`~cassi.harness.evaluation.run.progress.JobRecord.seconds`, ``cpu_seconds``). Pool and cluster start-up
are timed separately from the batch, so jobs per second describe the steady state that a long
batch sees.
"""
from __future__ import annotations

import io
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from cassi.renderer.views import VIEW_NAMES

from cassi.harness.evaluation.config import RunConfig
from cassi.harness.farm.executors import LocalExecutor, RayExecutor
from cassi.harness.farm.workers import thread_env, worker_env
from cassi.harness.evaluation.run import plan
from cassi.harness.farm.jobs import Job, StageContext, StageOutput, State
from cassi.harness.evaluation.caches import (get_corpus, get_face, get_profile, get_renderer,
                                             warm_worker)
from cassi.harness.evaluation.stages import cassi_pipeline
from cassi.harness.farm.runner import Pipeline, TaskSpec, run_batch
from cassi.harness.farm.store import OutputStore
from cassi.harness.bench.render import bare_frame

SPEEDUP_GOAL = 1.6  # the goal for 2 local workers over 1 on the same batch
FARM_PREVIEW_GOAL = 60.0  # frames/s of one worker on one core, the goal with llvm


# -- a CPU-bound stage, used only when the CASSI pipeline cannot run -------------------------
def cpu_stage(job: Job, ctx: StageContext, inputs) -> StageOutput:
    """About ``ctx.option("work")`` seconds of single-threaded numpy work on one core."""
    rng = np.random.default_rng(job.task * 1000 + job.rep)
    x = rng.standard_normal(200_000)
    t_end = time.perf_counter() + float(ctx.option("work", 0.2))
    n = 0
    while time.perf_counter() < t_end:
        x = np.sort(np.sin(x) * 1.0001)
        n += 1
    rows = [{"frame": -1, "check": "cpu_work", "table": "bench", "component": "farm",
             "value": float(x[: 10].sum()), "unit": "1", "negatives": 0}]
    return StageOutput(rows=pd.DataFrame(rows), meta={"render_frames": [], "iterations": n})


def _noop() -> int:
    return os.getpid()


def _workload(quick: bool, kind: str = "auto"):
    """The batch to time: the real pipeline (geometry and renders of the default corpus) when
    it can be planned, else the CPU-bound stage; with a description of which."""
    why = "asked for the cpu-bound stage"
    try:
        if kind == "cpu":
            raise LookupError(why)
        views = ("front",) if quick else ("front", "half")
        cfg = RunConfig(subjects=("JW11",), versions=("cassi-2.1",) if quick else None,
                        views=views, stride=0 if quick else 200)
        corpus, tasks, versions, views = plan(cfg)
        tasks = [t for t in tasks if t.usable]
        if not tasks:
            raise RuntimeError("the default corpus gave no usable task file")
        return {"kind": "cassi pipeline (default corpus JW11, geometry + renders + image checks)",
                "tasks": tasks, "versions": versions, "views": list(views),
                "pipeline": cassi_pipeline(render=True),
                "warm": (warm_worker, (str(corpus.root), "JW11", tuple(views), "preview", None, 1)),
                "ctx": dict(corpus=Path(corpus.root), stride=cfg.stride, chunk_size=4,
                            preset="preview", synthetic=True)}, None
    except LookupError:
        pass
    except Exception as err:  # noqa: BLE001 - fall back, and say why
        why = f"{type(err).__name__}: {err}"
    n = 8 if quick else 16
    return {"kind": f"cpu-bound test stage (~0.2 s/job): {why}",
            "tasks": [TaskSpec("BENCH", i + 1) for i in range(n)], "versions": ["bench"],
            "views": [], "pipeline": Pipeline(geometry=cpu_stage), "warm": (None, ()),
            "ctx": dict(options=(("work", 0.1 if quick else 0.2),))}, why


def _warm_up(executor, n_workers: int, init=None, initargs=()) -> None:
    """Return once each of ``executor``'s workers has run its set-up.

    One trivial item per worker: a worker runs its set-up (the warm-up) before its first item,
    so when these come back every worker is warm. (Ray: concurrent warm-up tasks.)
    """
    for i in range(n_workers):
        if isinstance(executor, RayExecutor) and init is not None:
            executor.submit(f"warm{i}", init, *initargs)
        else:
            executor.submit(f"warm{i}", _noop)
    while executor.pending():
        for fin in executor.wait(timeout=1.0):
            if not fin.ok:
                raise RuntimeError(f"warm-up failed: {fin.error}")


def _time_batch(work: dict, executor, n_workers: int, tmp: Path, name: str) -> dict:
    """Start ``executor``, wait until each of its workers has run the warm-up, time the batch."""
    t0 = time.perf_counter()
    executor.start()
    _warm_up(executor, n_workers, *work["warm"])
    startup = time.perf_counter() - t0
    ctx = StageContext(out_dir=tmp / name, **work["ctx"])
    t1 = time.perf_counter()
    res = run_batch(work["tasks"], work["versions"], work["views"], work["pipeline"], ctx,
                    executor, progress=False)
    wall = time.perf_counter() - t1
    c = res.summary.counts()
    jobs = c["done"]
    by_stage = {}
    for rec in res.records.values():
        by_stage[rec.stage] = by_stage.get(rec.stage, 0) + 1
    failures = sorted({r.reason for r in res.summary.failed})[:3]
    ran = [rec for rec in res.records.values() if rec.state is State.DONE]  # not cached ones
    wall_sum = sum(rec.seconds for rec in ran)
    cpu_sum = sum(rec.cpu_seconds for rec in ran)
    return {"jobs": jobs, "jobs_by_stage": by_stage, "failed": c["failed"],
            "failure_reasons": failures, "skipped": c["skipped"], "seconds": round(wall, 3),
            "jobs_per_s": round(jobs / wall, 3) if wall else None,
            "startup_s": round(startup, 3),
            # CPU time / wall time of the jobs: well below 1 means they waited for a core
            # (another load on the machine), so the timing says little about the farm.
            "job_cpu_share": round(cpu_sum / wall_sum, 3) if wall_sum else None}


def bench_farm(quick: bool = False, *, workload: str = "auto", ray: bool = True,
               repeats: int | None = None) -> dict:
    """Jobs per second with 1 and 2 local workers, and with Ray, on the same batch.

    The 1- and 2-worker runs alternate ``repeats`` times and the best of each counts (on a
    shared machine the other load only ever slows a run down; default 2, quick 1: under a minute
    in all); every run is listed under ``runs``. ``workload="cpu"`` times the CPU-bound stage instead of the CASSI pipeline
    (tests); ``ray=False`` leaves Ray out.
    """
    use_ray = ray
    repeats = (1 if quick else 2) if repeats is None else repeats
    work, fallback_reason = _workload(quick, workload)
    out: dict = {"workload": work["kind"], "versions": work["versions"], "views": work["views"],
                 "task_files": len(work["tasks"]), "threads_per_worker": 1}
    if fallback_reason and workload != "cpu":
        out["pipeline_unavailable"] = fallback_reason
    tmp = Path(tempfile.mkdtemp(prefix="cassi-bench-"))
    init, initargs = work["warm"]
    try:
        runs = {1: [], 2: []}
        for rep in range(max(1, int(repeats))):
            for n in (1, 2):
                with LocalExecutor(n, initializer=init, initargs=initargs,
                                   env=thread_env(1)) as ex:
                    runs[n].append(_time_batch(work, ex, n, tmp, f"local{n}-{rep}"))
        for n in (1, 2):
            out[f"local_{n}"] = max(runs[n], key=lambda r: (not r["failed"], r["jobs_per_s"] or 0))
        out["runs"] = {f"local_{n}": [(r["jobs_per_s"], r["job_cpu_share"]) for r in runs[n]]
                       for n in (1, 2)}
        a, b = out["local_1"]["jobs_per_s"], out["local_2"]["jobs_per_s"]
        same = (out["local_1"]["jobs"] == out["local_2"]["jobs"]
                and not out["local_1"]["failed"] and not out["local_2"]["failed"])
        # A speed-up only means something when both runs did the same, complete work.
        out["speedup_2_workers"] = round(b / a, 3) if a and b and same else None
        if not same:
            out["speedup_invalid"] = "the 1- and 2-worker runs did not complete the same jobs"
        out["speedup_goal"] = SPEEDUP_GOAL
        if not use_ray:
            return out
        try:
            import ray  # noqa: PLC0415 - optional dependency (cassi-farm[ray])

            owned = not ray.is_initialized()
            ex = RayExecutor(None, num_cpus=2, initializer=worker_env, initargs=(1,))
            try:
                out["ray_2"] = _time_batch(work, ex, 2, tmp, "ray")
            finally:
                ex.close()
                if owned and ray.is_initialized():
                    ray.shutdown()
            r, l2 = out["ray_2"]["jobs_per_s"], out["local_2"]["jobs_per_s"]
            if r and l2 and out["ray_2"]["jobs"] == out["local_2"]["jobs"] \
                    and not out["ray_2"]["failed"] and not out["local_2"]["failed"]:
                out["ray_overhead_vs_local"] = round(l2 / r - 1.0, 3)  # extra time fraction
                out["ray_overhead_ms_per_job"] = round(1000 * (1 / r - 1 / l2), 1)
        except Exception as err:  # noqa: BLE001
            out["ray_2"] = {"error": f"{type(err).__name__}: {err}"}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out


def bench_farm_preview(quick: bool = False, *, subject: str = "JW11", task: int = 118,
                       version: str = "cassi-2.1") -> dict:
    """Preview frames per second end to end in the farm, one worker, per view.

    One task file is animated by one version; its render jobs render every ``stride``-th frame
    (quick: ~40 per view, else ~300) in all four views with the farm's own chunking. The time
    of a view is the sum of its render jobs' wall times as the worker measured them (inputs
    read, frames rendered and encoded, outputs stored), so geometry and image checks do not
    count. In the same run and process kind (one core), a bare Mitsuba frame of the same scene:
    :func:`cassi.harness.bench.render.bare_frame` on the same keyframes.
    """
    cfg = RunConfig(subjects=(subject,), tasks=(task,), versions=(version,), views=VIEW_NAMES)
    corpus, tasks, versions, views = plan(cfg)
    tasks = [t for t in tasks if t.usable][:1]
    if not tasks:
        return {"error": f"{subject} task {task} is not usable in the default corpus"}
    n_rows = len(corpus.subject(subject).load(task, tasks[0].rep).time_us)
    stride = max(1, n_rows // (40 if quick else 300))
    tmp = Path(tempfile.mkdtemp(prefix="cassi-bench-preview-"))
    out: dict = {"subject": subject, "task": task, "version": version, "stride": stride,
                 "threads_per_worker": 1, "goal": FARM_PREVIEW_GOAL}
    try:
        ctx = StageContext(out_dir=tmp / "run", corpus=Path(corpus.root), stride=stride,
                           chunk_size=RunConfig().chunk, preset="preview", synthetic=True,
                           options=(("extremes", 0),))
        OutputStore(ctx.out_dir).prepare()
        init = (warm_worker, (str(corpus.root), subject, tuple(views), "preview", None, 1))
        with LocalExecutor(1, initializer=init[0], initargs=init[1], env=thread_env(1)) as ex:
            _warm_up(ex, 1)
            res = run_batch(tasks, versions, views, cassi_pipeline(render=True), ctx, ex,
                            progress=False)
        renders = pd.read_parquet(ctx.out_dir / "renders.parquet")
        seconds: dict[str, float] = {}
        cpu: dict[str, float] = {}
        for key, rec in res.records.items():
            if rec.stage == "render" and rec.state is State.DONE:
                view = key.split("/")[3]
                seconds[view] = seconds.get(view, 0.0) + rec.seconds
                cpu[view] = cpu.get(view, 0.0) + rec.cpu_seconds
        per_view = {}
        for view in views:
            n = int((renders["view"] == view).sum())
            if n and seconds.get(view):
                per_view[view] = {"frames": n, "seconds": round(seconds[view], 3),
                                  "frames_per_s": round(n / seconds[view], 2),
                                  "cpu_seconds": round(cpu.get(view, 0.0), 3)}
                if cpu.get(view):
                    per_view[view]["cpu_frames_per_s"] = round(n / cpu[view], 2)
        out["by_view"] = per_view
        if len(per_view) == len(views):
            out["farm_preview_frames_per_s"] = round(
                float(np.mean([v["frames_per_s"] for v in per_view.values()])), 2)
            if all("cpu_frames_per_s" in v for v in per_view.values()):
                # What a worker with a core to itself would reach: on a shared machine the
                # wall-clock rate above also counts the time other processes held the core.
                out["farm_preview_cpu_frames_per_s"] = round(
                    float(np.mean([v["cpu_frames_per_s"] for v in per_view.values()])), 2)
        else:
            out["error"] = f"render jobs failed: {sorted(res.summary.to_dict()['failed'].items())[:2]}"

        # The bare Mitsuba frame on the same keyframes, one core, in this process.
        worker_env(1)
        c = get_corpus(corpus.root)
        profile = get_profile(c, subject)
        face = get_face(c, subject, profile)
        geo = [k for k in res.records if k.endswith("/geometry")][0]
        keyframes = OutputStore(ctx.out_dir).get(
            OutputStore(ctx.out_dir).read_manifest(geo)["outputs"]["keyframes"])
        positions = np.load(io.BytesIO(keyframes))["positions"]
        bare, bare_cpu = {}, {}
        for view in views:
            r = get_renderer(c, subject, face, view, "preview", None)
            bare_frame(r, positions[0])
            t0, c0 = time.perf_counter(), time.process_time()
            for pos in positions:
                bare_frame(r, pos)
            bare[view] = round(len(positions) / (time.perf_counter() - t0), 2)
            bare_cpu[view] = round(len(positions) / max(1e-9, time.process_time() - c0), 2)
        out["bare_mi_render_frames_per_s"] = bare
        out["bare_mi_render_mean_frames_per_s"] = round(float(np.mean(list(bare.values()))), 2)
        out["bare_mi_render_cpu_frames_per_s"] = bare_cpu
        out["bare_mi_render_mean_cpu_frames_per_s"] = round(float(np.mean(list(bare_cpu.values()))), 2)
        if "farm_preview_frames_per_s" in out:
            out["farm_efficiency_vs_bare"] = round(
                out["farm_preview_frames_per_s"] / out["bare_mi_render_mean_frames_per_s"], 3)
        if "farm_preview_cpu_frames_per_s" in out:
            out["farm_cpu_efficiency_vs_bare"] = round(
                out["farm_preview_cpu_frames_per_s"] / out["bare_mi_render_mean_cpu_frames_per_s"], 3)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out
