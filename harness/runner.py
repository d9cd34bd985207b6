"""Run a batch: plan jobs, skip the ones already done, execute the rest, derive the tables.

The run loop is executor-agnostic: it submits ``(key, call_job, (stage, job, ctx, digest))``
items and reacts to finished ones. Render jobs of a task file are planned as soon as its
geometry job finishes (or is found already done), so renders overlap with other geometry; a
view's image job as soon as all its render chunks are done. A batch is
``tasks x versions`` geometry jobs, each fanning out to ``views x chunks`` render jobs and
``views`` image jobs; the ratings stage then runs here, in the main process.
"""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable

import pandas as pd

from cassi.data.atomic import atomic_write_text

from . import results as R
from .jobs import GEOMETRY_VIEW, Job, Outcome, StageContext, StageFn, State, call_job, chunk_frames
from .progress import JobRecord, Progress, Summary, write_job_log
from .store import OutputStore

#: Outputs named ``render-<frame>`` are images; they are listed in ``renders.parquet``.
RENDER_PREFIX = "render-"
RENDER_COLUMNS = ("subject", "task", "rep", "version", "view", "frame", "path")


class OutputWriteError(OSError):
    """The run's tables could not be written (full disk, read-only directory)."""


@dataclass(frozen=True)
class TaskSpec:
    """A task file of the batch; ``usable`` False makes its jobs SKIPPED with ``reason``."""

    subject: str
    task: int
    rep: int = 1
    usable: bool = True
    reason: str = ""


@dataclass(frozen=True)
class Pipeline:
    """The pluggable stages of a run.

    geometry : stage for geometry jobs (animate, geometric checks, pick the frames to render:
        ``meta["render_frames"]``).
    render : stage for render jobs (render ``job.frames`` of ``job.view``), or None for
        geometry-only runs.
    image : stage for image jobs (image checks over every rendered frame of a view: its inputs
        are the outputs of all the view's render chunks), or None.
    aggregate : rows of the whole run -> extra rows, or None.
    rate : negatives -> rating words (thesis Table 5.2), or None for the rubric's.
    """

    geometry: StageFn
    render: StageFn | None = None
    image: StageFn | None = None
    aggregate: Callable[[pd.DataFrame], pd.DataFrame] | None = None
    rate: Callable[[int], str] | None = None

    def stage(self, name: str) -> StageFn:
        return {"geometry": self.geometry, "render": self.render, "image": self.image}[name]


@dataclass
class RunResult:
    summary: Summary
    results: pd.DataFrame
    ratings: pd.DataFrame
    records: dict[str, JobRecord] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.summary.failed


def _outputs_digest(manifests: list[dict]) -> str:
    doc = json.dumps([{n: r.sha256 for n, r in sorted(m["outputs"].items())} for m in manifests])
    return hashlib.sha256(doc.encode()).hexdigest()


STAGES = ("geometry", "render", "image")


def run_batch(tasks: Iterable[TaskSpec], versions: Iterable[str], views: Iterable[str],
              pipeline: Pipeline, ctx: StageContext, executor, *, progress: bool = True,
              extra_meta: dict | None = None) -> RunResult:
    """Run every (task file x version) geometry job, every (view x chunk) render job and every
    view's image job; then derive the results and ratings tables.

    The caller prepares ``ctx.out_dir`` (:meth:`OutputStore.prepare`) and holds its lock.
    Writes ``results``, ``ratings`` and ``renders`` (``.parquet`` + ``.csv``) and
    ``summary.json`` there.
    """
    t0 = time.perf_counter()
    store = OutputStore(ctx.out_dir)
    salt = ctx.salt()
    views = [v for v in views if v != GEOMETRY_VIEW] if pipeline.render is not None else []
    versions = list(versions)
    records: dict[str, JobRecord] = {}
    jobs: dict[str, Job] = {}
    digests: dict[str, str] = {}
    groups: dict[tuple, list[str]] = {}      # (task key, view) -> render chunk keys
    group_of: dict[str, tuple] = {}
    bars = Progress(STAGES, enabled=progress)

    def record(job: Job, state: State, reason: str = "", **kw) -> JobRecord:
        rec = records.setdefault(job.key, JobRecord(job.key, job.stage))
        rec.state, rec.reason = state, reason
        for k, v in kw.items():
            setattr(rec, k, v)
        return rec

    def schedule(job: Job) -> None:
        """Mark CACHED if its outputs verify, else submit it."""
        jobs[job.key] = job
        digest = digests[job.key] = job.digest(salt)
        bars.planned(job.stage)
        manifest = store.verified(job.key, digest)
        if manifest is not None:
            record(job, State.CACHED)
            bars.finished(job.stage, State.CACHED)
            after(job, manifest)
            return
        record(job, State.RUNNING)
        executor.submit(job.key, call_job, pipeline.stage(job.stage), job, ctx, digest)

    def skip(job: Job, reason: str) -> None:
        jobs[job.key] = job
        rec = record(job, State.SKIPPED, reason)
        write_job_log(store, rec)

    def after(job: Job, manifest: dict | None) -> None:
        """Plan what a finished job unlocks."""
        if job.stage == "geometry" and manifest is not None:
            meta = manifest.get("meta", {})
            parent_digest = _outputs_digest([manifest])
            for view in views:
                # A view may have frames of its own (the front view's animation frames).
                frames = meta.get("render_frames_by_view", {}).get(view, meta.get("render_frames", []))
                chunks = chunk_frames(frames, ctx.chunk_size)
                group = (job.task_key, view)
                groups[group] = [Job("render", *job.task_key, view, c, i).key
                                 for i, c in enumerate(chunks)]
                for key in groups[group]:
                    group_of[key] = group
                for i, chunk in enumerate(chunks):
                    schedule(Job("render", *job.task_key, view, chunk, i, parents=(job.key,),
                                 parent_digest=parent_digest))
        elif job.stage == "render" and pipeline.image is not None:
            group = group_of[job.key]
            keys = groups[group]
            if not all(k in records and records[k].state.finished for k in keys):
                return
            (subject, task, rep, version), view = group
            image = Job("image", subject, task, rep, version, view,
                        tuple(f for k in keys for f in jobs[k].frames), parents=tuple(keys))
            bad = [k for k in keys if records[k].state not in (State.DONE, State.CACHED)]
            if bad:
                skip(image, f"render job(s) not done: {', '.join(bad)}")
                return
            manifests = [store.verified(k, digests[k]) for k in keys]
            if any(m is None for m in manifests):
                skip(image, "render outputs missing or corrupt")
                return
            schedule(Job("image", subject, task, rep, version, view, image.frames,
                         parents=tuple(keys), parent_digest=_outputs_digest(manifests)))

    def finish(key: str, outcome: Outcome | None, ok: bool, error: str, attempts: int) -> None:
        job = jobs[key]
        if not ok or outcome is None:
            rec = record(job, State.FAILED, error.strip().splitlines()[0] if error else "failed",
                         attempts=attempts, log=error.splitlines())
        else:
            rec = record(job, outcome.state, outcome.reason, attempts=attempts,
                         seconds=outcome.seconds, log=outcome.log)
        manifest = None
        if rec.state is State.DONE:
            manifest = store.verified(job.key, digests[job.key])
            if manifest is None:
                record(job, State.FAILED, "outputs missing or corrupt after the job finished")
        write_job_log(store, rec)
        bars.finished(job.stage, rec.state)
        after(job, manifest)

    try:
        executor.start()
        for spec in tasks:
            for version in versions:
                job = Job("geometry", spec.subject, spec.task, spec.rep, version)
                if not spec.usable:
                    skip(job, spec.reason or "task file not usable")
                    continue
                schedule(job)
        while executor.pending():
            for fin in executor.wait(timeout=1.0):
                finish(fin.key, fin.value, fin.ok, fin.error, fin.attempts)
    finally:
        bars.close()
    # The ratings stage: the rows of every finished job, combined, aggregated and rated.
    frames, renders = [], []
    for key, rec in sorted(records.items()):
        if rec.state in (State.DONE, State.CACHED):
            manifest = store.verified(key, digests[key])
            if manifest is None:
                continue
            if "rows" in manifest["outputs"]:
                frames.append(R.from_parquet_bytes(store.get(manifest["outputs"]["rows"])))
            job = jobs[key]
            for name, ref in manifest["outputs"].items():
                if name.startswith(RENDER_PREFIX) and name[len(RENDER_PREFIX):].isdigit():
                    renders.append({"subject": job.subject, "task": job.task, "rep": job.rep,
                                    "version": job.version, "view": job.view,
                                    "frame": int(name[len(RENDER_PREFIX):]), "path": ref.relpath})
    table = R.combine(frames)
    if pipeline.aggregate is not None and len(table):
        table = R.combine([table, pipeline.aggregate(table)])
    rated = R.ratings(table, pipeline.rate)
    summary = Summary(records, time.perf_counter() - t0,
                      worker_crashes=getattr(executor, "crashes", 0))
    try:
        R.write_table(table, store.root / "results.parquet")
        R.write_table(rated, store.root / "ratings.parquet")
        R.write_table(pd.DataFrame(renders, columns=list(RENDER_COLUMNS)).sort_values(
            ["subject", "task", "rep", "version", "view", "frame"], kind="mergesort"),
            store.root / "renders.parquet")
        atomic_write_text(store.root / "summary.json",
                          json.dumps({**summary.to_dict(), **(extra_meta or {})}, indent=1,
                                     sort_keys=True, default=str))
    except OSError as err:
        # A full disk or a directory gone read-only: every finished job's outputs are intact
        # (atomic writes), so the same command finishes the tables once the cause is fixed.
        raise OutputWriteError(err.errno, f"cannot write the run's tables in {store.root}: "
                               f"{err.strerror or err}; finished job outputs are kept, rerun "
                               f"the same command to finish") from err
    return RunResult(summary, table, rated, records)
