"""``cassi bench``: the registered benchmarks in one JSON document.

- ``geometry``: :func:`cassi.versions.bench.bench_geometry` (owned by the versions package);
- ``render``: :func:`cassi.renderer.bench.bench_render` (owned by the renderer package);
- ``geometry_memory`` and ``image_memory``: peak RSS of one worker on a 100,000-row task
  (:mod:`.bench_memory`, ``geometry_peak_rss_mb``, ``image_peak_rss_mb``);
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

A benchmark whose package is missing or fails is reported as ``{"error": ...}``, never
replaced by made-up numbers. Pool and cluster start-up are timed separately from the batch, so
jobs per second describe the steady state that a long batch sees.
"""
from __future__ import annotations

import importlib
import os
import platform
import re
import shutil
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np
import pandas as pd

from cassi.harness.farm.executors import LocalExecutor, RayExecutor, thread_env
from cassi.harness.farm.jobs import Job, StageContext, StageOutput
from cassi.harness.farm.runner import Pipeline, TaskSpec, run_batch

SPEEDUP_GOAL = 1.6


def _registered(module: str, func: str, quick: bool) -> dict:
    try:
        fn = getattr(importlib.import_module(module), func)
    except (ImportError, AttributeError) as err:
        return {"error": f"{module}.{func} not available: {type(err).__name__}: {err}"}
    try:
        out = fn(quick)
    except Exception as err:  # noqa: BLE001 - one failing benchmark must not hide the others
        return {"error": f"{type(err).__name__}: {err}",
                "traceback": traceback.format_exc().splitlines()[-6:]}
    return out if isinstance(out, dict) else {"result": out}


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
    its packages are present, else the CPU-bound stage; with a description of which."""
    why = "asked for the cpu-bound stage"
    try:
        if kind == "cpu":
            raise LookupError(why)
        from cassi.harness.evaluation.config import RunConfig  # noqa: PLC0415
        from cassi.harness.evaluation.run import plan  # noqa: PLC0415
        from cassi.harness.evaluation.pipeline import cassi_pipeline, warm_worker  # noqa: PLC0415

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


def _job_times(rec) -> tuple[float, float] | None:
    """(wall, cpu) seconds of a job as its worker logged them (first log line), or None."""
    m = re.match(r"wall ([\d.]+) s, cpu ([\d.]+) s", rec.log[0]) if rec.log else None
    return (float(m.group(1)), float(m.group(2))) if m else None


def _time_batch(work: dict, executor, n_workers: int, tmp: Path, name: str) -> dict:
    """Start ``executor``, wait until each of its workers has run the warm-up, time the batch."""
    t0 = time.perf_counter()
    executor.start()
    # One trivial item per worker: a worker runs its set-up (the warm-up) before its first item,
    # so when these come back every worker is warm. (Ray: concurrent warm-up tasks.)
    init, initargs = work["warm"]
    for i in range(n_workers):
        if isinstance(executor, RayExecutor) and init is not None:
            executor.submit(f"warm{i}", init, *initargs)
        else:
            executor.submit(f"warm{i}", _noop)
    while executor.pending():
        for fin in executor.wait(timeout=1.0):
            if not fin.ok:
                raise RuntimeError(f"warm-up failed: {fin.error}")
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
    wall_sum = cpu_sum = 0.0
    for rec in res.records.values():
        times = _job_times(rec)
        if times:
            wall_sum += times[0]
            cpu_sum += times[1]
    return {"jobs": jobs, "jobs_by_stage": by_stage, "failed": c["failed"],
            "failure_reasons": failures, "skipped": c["skipped"], "seconds": round(wall, 3),
            "jobs_per_s": round(jobs / wall, 3) if wall else None,
            "startup_s": round(startup, 3),
            # CPU time / wall time of the jobs: well below 1 means they waited for a core
            # (another load on the machine), so the timing says little about the farm.
            "job_cpu_share": round(cpu_sum / wall_sum, 3) if wall_sum else None}


def bench_farm(quick: bool = False, *, workload: str = "auto", ray: bool = True,
               repeats: int = 2) -> dict:
    """Jobs per second with 1 and 2 local workers, and with Ray, on the same batch.

    The 1- and 2-worker runs alternate ``repeats`` times and the best of each counts (on a
    shared machine the other load only ever slows a run down); every run is listed under
    ``runs``. ``workload="cpu"`` times the CPU-bound stage instead of the CASSI pipeline
    (tests); ``ray=False`` leaves Ray out.
    """
    use_ray = ray
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
            import ray  # noqa: PLC0415

            from cassi.harness.evaluation.pipeline import worker_env  # noqa: PLC0415

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


FARM_PREVIEW_GOAL = 60.0


def bench_farm_preview(quick: bool = False, *, subject: str = "JW11", task: int = 118,
                       version: str = "cassi-2.1") -> dict:
    """Preview frames per second end to end in the farm, one worker, per view.

    One task file is animated by one version; its render jobs render every ``stride``-th frame
    (quick: ~40 per view, else ~300) in all four views with the farm's own chunking. The time
    of a view is the sum of its render jobs' wall times as the worker measured them (inputs
    read, frames rendered and encoded, outputs stored), so geometry and image checks do not
    count. In the same run and process kind (one core), a bare Mitsuba frame of the same scene:
    :func:`cassi.renderer.bench.bare_frame` on the same keyframes.
    """
    import io  # noqa: PLC0415

    from cassi.renderer.bench import bare_frame  # noqa: PLC0415
    from cassi.renderer.views import VIEW_NAMES  # noqa: PLC0415

    from cassi.harness.evaluation.config import RunConfig  # noqa: PLC0415
    from cassi.harness.evaluation.run import plan  # noqa: PLC0415
    from cassi.harness.evaluation.pipeline import (cassi_pipeline, get_corpus, get_face, get_profile,  # noqa: PLC0415
                           get_renderer, warm_worker, worker_env)
    from cassi.harness.farm.store import OutputStore  # noqa: PLC0415

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
            ex.submit("warm", _noop)
            while ex.pending():
                ex.wait(timeout=1.0)
            res = run_batch(tasks, versions, views, cassi_pipeline(render=True), ctx, ex,
                            progress=False)
        renders = pd.read_parquet(ctx.out_dir / "renders.parquet")
        seconds: dict[str, float] = {}
        cpu: dict[str, float] = {}
        for key, rec in res.records.items():
            if rec.stage == "render" and rec.state.value == "done":
                view = key.split("/")[3]
                seconds[view] = seconds.get(view, 0.0) + rec.seconds
                cpu[view] = cpu.get(view, 0.0) + (_job_times(rec) or (0.0, 0.0))[1]
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


def _variant() -> str:
    try:
        from cassi.renderer.variant import choose_variant  # noqa: PLC0415

        return choose_variant()
    except Exception as err:  # noqa: BLE001
        return f"error: {type(err).__name__}: {err}"


#: Figures copied to the top of the document, under the keys the issues name.
HEADLINE = {"geometry": ("geometry_frames_per_s",),
            "geometry_memory": ("geometry_peak_rss_mb",),
            "image_memory": ("image_peak_rss_mb",),
            "render": ("render_per_s", "render_pipeline_efficiency",
                       "render_pipeline_efficiency_vs_own_pass", "render_rss_growth_mb",
                       "bare_mi_render_frames_per_s"),
            "farm_preview": ("farm_preview_frames_per_s", "farm_preview_cpu_frames_per_s")}


def headline(benchmarks: dict) -> dict:
    """The headline figures of the benchmark entries that produced them (errors have none)."""
    out = {}
    for name, keys in HEADLINE.items():
        entry = benchmarks.get(name)
        for key in keys:
            if isinstance(entry, dict) and key in entry:
                out[key] = entry[key]
    return out


#: The benchmarks of ``cassi bench``, in the order they run (``--only`` picks some): the module
#: and function of each registered one; ``farm`` is this module's :func:`bench_farm`.
BENCHMARKS = {"geometry": ("cassi.versions.bench", "bench_geometry"),
              "render": ("cassi.renderer.bench", "bench_render"),
              "geometry_memory": ("cassi.harness.bench_memory", "bench_geometry_memory"),
              "image_memory": ("cassi.harness.bench_memory", "bench_image_memory"),
              "farm_preview": ("cassi.harness.bench", "bench_farm_preview"),
              "farm": None}


def run_benchmarks(*, quick: bool = False, only=None) -> dict:
    """Every benchmark (or those named in ``only``); the document ``cassi bench`` writes."""
    chosen = tuple(BENCHMARKS if only is None else (n for n in BENCHMARKS if n in set(only)))
    report = {"quick": quick, "cpu_count": os.cpu_count(),
              "cpus_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
              "python": platform.python_version(), "machine": platform.machine(),
              "variant": _variant(), "benchmarks": {}, "only": list(chosen)}
    for name in chosen:
        if BENCHMARKS[name] is not None:
            report["benchmarks"][name] = _registered(*BENCHMARKS[name], quick)
    if "farm" in chosen:
        try:
            farm = bench_farm(quick, repeats=1 if quick else 2)  # --quick: under a minute in all
        except Exception as err:  # noqa: BLE001
            farm = {"error": f"{type(err).__name__}: {err}",
                    "traceback": traceback.format_exc().splitlines()[-6:]}
        report["benchmarks"]["farm"] = farm
        if "speedup_2_workers" in farm:
            report["farm_speedup_2_workers"] = farm["speedup_2_workers"]
        if "ray_overhead_vs_local" in farm:
            report["ray_overhead_vs_local"] = farm["ray_overhead_vs_local"]
    report.update(headline(report["benchmarks"]))
    return report
