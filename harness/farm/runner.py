"""Run a batch plan: skip the jobs already done, execute the rest, derive the tables.

:class:`Scheduler` walks the :class:`~cassi.harness.farm.plan.BatchPlan`: it submits the geometry
jobs, and as each job finishes asks the plan what it unlocks (a geometry job its render
chunks, a view's last render chunk its image job). Its state is explicit: the jobs it knows,
their digests and records. The executor only sees ``(key, call_job, args)`` items. Once every
job has finished, :func:`collect` combines their rows, the ratings are derived, and the
tables are committed as one set (:mod:`.tableset`).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Iterable

import pandas as pd

from cassi.harness.farm import results as R
from cassi.harness.farm.results import ATTACHMENT_COLUMNS, RENDER_COLUMNS
from cassi.harness.farm.jobs import Job, Outcome, StageContext, StageFn, State, call_job, parent_inputs, store_outputs
from cassi.harness.farm.plan import BatchPlan, TaskSpec
from cassi.harness.farm.progress import JobRecord, Progress, Summary, write_job_log
from cassi.harness.farm.store import BlobRef, OutputStore, sha256_bytes
from cassi.harness.farm.tableset import write_table_set

__all__ = ["Pipeline", "RunResult", "Scheduler", "TaskSpec", "OutputWriteError", "run_batch",
           "Collected", "collect", "RENDER_COLUMNS", "RENDER_PREFIX", "ATTACHMENT_COLUMNS"]

#: Outputs named ``render-<frame>`` are images; they are listed in ``renders.parquet``.
RENDER_PREFIX = "render-"
STAGES = ("geometry", "render", "image")


class OutputWriteError(OSError):
    """The run's tables could not be written (full disk, read-only directory)."""


@dataclass(frozen=True)
class Pipeline:
    """The pluggable stages of a run.

    geometry : stage for geometry jobs (animate, geometric checks, pick the frames to render:
        ``meta["render_frames"]``, and those rendered only: ``meta["evidence_frames_by_view"]``).
    render : stage for render jobs (render ``job.frames`` of ``job.view``), or None for
        geometry-only runs.
    image : stage for image jobs (image checks over every rendered frame of a view: its inputs
        are the outputs of all the view's render chunks, never its evidence chunks), or None.
    ratings : the run's results table -> its ratings table (the one aggregation the run's
        ``ratings`` files and every report share), or None for a run without ratings.
    attachments : output names (of any stage) the run lists in ``attachments.parquet``.
    """

    geometry: StageFn
    render: StageFn | None = None
    image: StageFn | None = None
    ratings: Callable[[pd.DataFrame], pd.DataFrame] | None = None
    #: Output names listed in the run's attachments index (:data:`ATTACHMENT_COLUMNS`); a name
    #: ending in ``*`` is a prefix.
    attachments: tuple[str, ...] = ()

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


class Scheduler:
    """Runs one :class:`BatchPlan` on an executor, reusing outputs that verify.

    State: ``jobs`` (key -> Job) and ``digests`` of every job planned so far, ``records``
    (key -> JobRecord) of what happened to each, and ``chunks`` (render key -> the view's
    sibling chunks) to know when a view's renders are all finished.
    """

    def __init__(self, plan: BatchPlan, pipeline: Pipeline, ctx: StageContext, executor, *,
                 progress: bool = True):
        self.plan, self.pipeline, self.ctx, self.executor = plan, pipeline, ctx, executor
        self.store = OutputStore(ctx.out_dir, cache=ctx.cache_dir)
        self.jobs: dict[str, Job] = {}
        self.digests: dict[str, str] = {}
        self.records: dict[str, JobRecord] = {}
        self.chunks: dict[str, tuple[Job, ...]] = {}
        #: key -> the manifest that verified when a render job finished (DONE or CACHED), kept
        #: until its view's image job is planned from it
        self.verified: dict[str, dict] = {}
        #: what the tables need of every finished job, taken as it finishes (:class:`Collected`)
        self.collected = Collected(pipeline.attachments)
        self.bars = Progress(STAGES, enabled=progress)

    # -- the loop ----------------------------------------------------------------------------
    def run(self) -> dict[str, JobRecord]:
        try:
            for job, reason in self.plan.skipped:
                self._skip(job, reason)
            for job in self.plan.geometry:
                self._schedule(job)
            while self.executor.pending():
                for fin in self.executor.wait(timeout=1.0):
                    self._finished(fin.key, fin.value, fin.ok, fin.error, fin.attempts)
        finally:
            self.bars.close()
        return self.records

    def manifest(self, key: str) -> dict | None:
        """The verified manifest of a finished render job (DONE or CACHED) whose image job is
        not planned yet, else None: the one that verified when it finished (a DONE job whose
        outputs did not verify is FAILED). A full set's manifests are not all held at once:
        each job's rows and index entries are taken as it finishes (:attr:`collected`)."""
        return self.verified.get(key)

    def _verified(self, job: Job, manifest: dict) -> None:
        self.collected.add(job, manifest)
        if job.stage == "render" and self.plan.judges(job):
            self.verified[job.key] = manifest

    # -- transitions ---------------------------------------------------------------------------
    def _record(self, job: Job, state: State, reason: str = "", **kw) -> JobRecord:
        rec = self.records.setdefault(job.key, JobRecord(job.key, job.stage))
        rec.state, rec.reason = state, reason
        for k, v in kw.items():
            setattr(rec, k, v)
        return rec

    def _schedule(self, job: Job) -> None:
        """CACHED if its outputs verify, else submitted."""
        self.jobs[job.key] = job
        digest = self.digests[job.key] = job.digest(self.ctx.salt(job.version))
        self.bars.planned(job.stage)
        manifest = self.store.verified(job.key, digest)
        if manifest is not None:
            self._verified(job, manifest)
            self._record(job, State.CACHED)
            self.bars.finished(job.stage, State.CACHED)
            self._unlock(job, manifest)
            return
        args = (self.pipeline.stage(job.stage), job, self.ctx, digest)
        if self.ctx.ship:
            shipped = parent_inputs(self.store, job)
            if shipped is None:
                self._skip(job, "a parent job has no outputs")
                return
            args += (dict(shipped),)  # bytes: they travel to a node that cannot read our store
        self._record(job, State.RUNNING)
        self.executor.submit(job.key, call_job, *args)

    def _skip(self, job: Job, reason: str) -> None:
        self.jobs[job.key] = job
        write_job_log(self.store, self._record(job, State.SKIPPED, reason))

    def _finished(self, key: str, outcome: Outcome | None, ok: bool, error: str,
                  attempts: int) -> None:
        job = self.jobs[key]
        if not ok or outcome is None:
            rec = self._record(job, State.FAILED,
                               error.strip().splitlines()[0] if error else "failed",
                               attempts=attempts, log=error.splitlines())
        else:
            rec = self._record(job, outcome.state, outcome.reason, attempts=attempts,
                               seconds=outcome.seconds, cpu_seconds=outcome.cpu_seconds,
                               log=outcome.log)
            if outcome.blobs is not None and rec.state is State.DONE:
                # Outputs shipped back by a worker that does not share our filesystem.
                store_outputs(self.store, key, self.digests[key], outcome.blobs, outcome.meta)
        manifest = None
        if rec.state is State.DONE:
            manifest = self.store.verified(key, self.digests[key])
            if manifest is None:
                self._record(job, State.FAILED, "outputs missing or corrupt after the job finished")
            else:
                self._verified(job, manifest)
        write_job_log(self.store, rec)
        self.bars.finished(job.stage, rec.state)
        self._unlock(job, manifest)

    def _unlock(self, job: Job, manifest: dict | None) -> None:
        """Schedule what a finished job makes runnable."""
        if job.stage == "geometry" and manifest is not None:
            for chunks in self.plan.render_jobs(job, manifest).values():
                for chunk in chunks:
                    if self.plan.judges(chunk):
                        self.chunks[chunk.key] = chunks
                for chunk in chunks:
                    self._schedule(chunk)
            for chunks in self.plan.evidence_jobs(job, manifest).values():
                for chunk in chunks:  # rendered for the report only: no image job waits on them
                    self._schedule(chunk)
        elif job.stage == "render" and self.plan.judges(job):
            siblings = self.chunks[job.key]
            if not all(self.records.get(s.key, JobRecord(s.key, "render")).state.finished
                       for s in siblings):
                return
            manifests = [self.verified.pop(s.key, None) for s in siblings]
            for s in siblings:
                self.chunks.pop(s.key, None)
            image = self.plan.image_job(siblings, [m for m in manifests if m is not None])
            bad = [s.key for s, m in zip(siblings, manifests) if m is None]
            if bad:
                self._skip(image, f"render job(s) not done: {', '.join(bad)}")
            else:
                self._schedule(image)


def _attached(name: str, attachments) -> bool:
    """Whether output ``name`` is one of ``attachments`` (an entry ending in ``*`` is a
    prefix: ``masks-*``)."""
    return any(name == a or (a.endswith("*") and name.startswith(a[:-1])) for a in attachments)


#: The store's memo of combined results tables (:meth:`OutputStore.memo`), by their jobs' rows.
COMBINED_MEMO = "combined-results"


def _combined(store: OutputStore, rows: list[tuple[str, BlobRef]]) -> pd.DataFrame:
    """:func:`results.combine` of the jobs' stored rows (``(job key, rows blob)``, sorted by
    key); a table combined before from the very same blobs is read from the store's memo
    instead of 1,400 small tables (a night whose jobs are all reused)."""
    key = sha256_bytes("".join(f"{k}\0{ref.sha256}\n" for k, ref in rows).encode())
    data = store.memo(COMBINED_MEMO, key)
    if data is not None:
        return R.from_parquet_bytes(data)
    table = R.combine(R.from_parquet_bytes(store.get(ref)) for _, ref in rows)
    store.remember(COMBINED_MEMO, key, R.to_parquet_bytes(table), ".parquet")
    return table


class Collected:
    """What the run's tables need of each finished job, taken as the job finishes so that no
    manifest is held for the whole run: its rows blob and its entries in the render and
    attachment indexes (column lists, each row tagged with its job's key, so that the tables
    come out in job-key order, as from every manifest read at the end)."""

    def __init__(self, attachments=()):
        self.attachments = tuple(attachments)
        self.rows: list[tuple[str, BlobRef]] = []
        # column lists, not a dict a row: a full set's 120,000 index rows
        self.renders = {c: [] for c in (*RENDER_COLUMNS, "_key")}
        self.attached = {c: [] for c in (*ATTACHMENT_COLUMNS, "_key")}

    def add(self, job: Job, manifest: dict) -> None:
        outputs = manifest["outputs"]
        if "rows" in outputs:
            self.rows.append((job.key, outputs["rows"]))
        for name, ref in outputs.items():
            if name.startswith(RENDER_PREFIX) and name[len(RENDER_PREFIX):].isdigit():
                _index_row(self.renders, job, frame=int(name[len(RENDER_PREFIX):]),
                           path=ref.relpath, _key=job.key)
            elif _attached(name, self.attachments):
                _index_row(self.attached, job, name=name, path=ref.relpath, _key=job.key)

    def ordered(self) -> tuple[list[tuple[str, BlobRef]], dict[str, list], dict[str, list]]:
        """The rows blobs, the render index and the attachment index, in job-key order."""
        def by_key(columns: dict[str, list]) -> dict[str, list]:
            keys = columns["_key"]
            order = sorted(range(len(keys)), key=keys.__getitem__)  # stable: a job's own order
            return {c: [v[i] for i in order] for c, v in columns.items() if c != "_key"}
        return sorted(self.rows, key=lambda r: r[0]), by_key(self.renders), by_key(self.attached)


def collect(scheduler: Scheduler) -> tuple[pd.DataFrame, dict[str, list], dict[str, list]]:
    """The combined stored rows of every finished job, the render index and the attachment
    index entries (the outputs named in the pipeline's ``attachments``), each index as column
    lists in job-key order: what the scheduler collected as its jobs finished."""
    rows, renders, attached = scheduler.collected.ordered()
    return _combined(scheduler.store, rows), renders, attached


def _index_row(columns: dict[str, list], job, **values) -> None:
    """Append one row of a job's output to an index held as column lists: ``values`` for the
    output's own columns, the job's attributes for the rest."""
    for c, column in columns.items():
        column.append(values[c] if c in values else getattr(job, c))


def _index_frame(columns: dict[str, list], names) -> pd.DataFrame:
    """An index's column lists as a table (an empty index: no rows, the named columns, as a
    list of row dicts made it)."""
    if not columns[names[0]]:
        return pd.DataFrame([], columns=list(names))
    return pd.DataFrame({c: columns[c] for c in names})


def run_batch(tasks: Iterable[TaskSpec], versions: Iterable[str], views: Iterable[str],
              pipeline: Pipeline, ctx: StageContext, executor, *, progress: bool = True,
              extra_meta: dict | None = None, masks_only=(), judged=None) -> RunResult:
    """Plan and run every job of ``tasks x versions`` (and their renders and image checks),
    then write the run's tables as one set.

    The caller prepares ``ctx.out_dir`` (:meth:`OutputStore.prepare`) and holds its lock.
    ``masks_only``, ``judged``: :attr:`BatchPlan.masks_only`, :attr:`BatchPlan.judged`.
    Writes ``results``, ``ratings``, ``renders`` and ``attachments`` (``.parquet`` + ``.csv``),
    ``summary.json`` and ``tables.json`` there.
    """
    t0 = time.perf_counter()
    plan = BatchPlan.build(tasks, versions, views, chunk_size=ctx.chunk_size,
                           render=pipeline.render is not None,
                           images=pipeline.image is not None, masks_only=masks_only,
                           judged=judged)
    scheduler = Scheduler(plan, pipeline, ctx, executor, progress=progress)
    records = scheduler.run()
    table, renders, attached = collect(scheduler)
    scheduler.store.save_stamps()
    rated = pipeline.ratings(table) if pipeline.ratings is not None else R.empty_ratings()
    summary = Summary(records, time.perf_counter() - t0,
                      worker_crashes=getattr(executor, "crashes", 0),
                      reused=len(scheduler.store.reused))
    render_index = _index_frame(renders, RENDER_COLUMNS).sort_values(
        ["subject", "task", "rep", "version", "view", "frame"], kind="mergesort")
    try:
        write_table_set(scheduler.store.root,
                        {"results": table, "ratings": rated, "renders": render_index,
                         "attachments": _index_frame(attached, ATTACHMENT_COLUMNS)},
                        {**summary.to_dict(), **(extra_meta or {})})
    except OSError as err:
        # A full disk or a directory gone read-only: every finished job's outputs are intact
        # (atomic writes), so the same command finishes the tables once the cause is fixed.
        raise OutputWriteError(err.errno, f"cannot write the run's tables ({err.filename or scheduler.store.root}): "
                               f"{err.strerror or err}; finished job outputs are kept, rerun "
                               f"the same command to finish") from err
    return RunResult(summary, table, rated, records)
