"""The job model: batch -> job (subject, task, rep, version, view, frames, chunk) -> frame.

Three kinds of job run the rubric on one task file and one version:

- a **geometry** job (view ``"geometry"``) animates every frame, runs the rubric's geometric
  checks on every frame and picks the frames to render (the first frame, the extreme frames the
  checks point at, and a stride);
- a **render** job (one per view and chunk of those frames) renders its frames and keeps their
  images and part masks;
- an **image** job (one per view) runs the image checks over all the rendered frames of the view,
  once every render chunk of it is done (the checks judge the whole task, e.g. "the tongue is
  barely visible" is a fraction of the open-mouth frames);
- an **evidence** render job (``Job.evidence``) renders the frames the report links to that
  the view's render chunks lack; no image job reads it.

The ratings are derived from the combined rows once every job has finished (:mod:`.runner`).
A job is a frozen, picklable value; its :meth:`Job.digest` names everything its outputs depend
on, so a stored output with the same digest can be reused instead of recomputed.

Stage functions are plain module-level callables ``stage(job, ctx, inputs) -> StageOutput`` so
that tests (and other farms) can plug in their own; :func:`execute_job` is what a worker
process runs around them: read the parent's outputs, call the stage, store the outputs
content-addressed, write the manifest last.
"""
from __future__ import annotations

import enum
from collections import abc
import hashlib
import io
import json
import os
import time
import traceback
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Callable, Mapping

import pandas as pd

from cassi.harness.farm import results as R
from cassi.harness.farm.store import OutputStore

GEOMETRY_VIEW = "geometry"


class State(str, enum.Enum):
    """Where a job is. PENDING -> RUNNING -> DONE | FAILED; CACHED and SKIPPED never run."""

    PENDING = "pending"
    RUNNING = "running"
    DONE = "done"          # ran now, outputs stored
    CACHED = "cached"      # outputs from an earlier run exist and verify; not rerun
    SKIPPED = "skipped"    # not runnable (unusable task file, missing geometry ...): reason given
    FAILED = "failed"      # raised, or its worker died more often than the retries allow

    @property
    def finished(self) -> bool:
        return self in (State.DONE, State.CACHED, State.SKIPPED, State.FAILED)


@dataclass(frozen=True)
class Job:
    """One unit of work.

    Attributes
    ----------
    stage : {"geometry", "render", "image"}
    subject, task, rep : the task file (``tpNNN.txy``; ``rep`` 1, or R for ``tpNNN_R.txy``)
    version : version name (``cassi-2.1`` ...)
    view : ``"geometry"`` for geometry jobs, else a render view (front, side, half, top)
    frames : tuple of int
        Recording rows to render (render jobs); empty for geometry jobs (every frame).
    chunk : int
        Index of this chunk among the view's render jobs for the task file.
    evidence : bool
        A render job of evidence frames only (the frames the report links to), which no image
        job judges; its chunks are counted apart from the judged ones.
    pictures : bool
        Whether a render job keeps a picture of each frame. False: masks only, for frames an
        image job judges and nobody looks at (``.../masks-NNN``, counted apart too).
    parents : tuple of str
        Keys of the jobs whose outputs this one reads (a render job's geometry job, an image
        job's render chunks).
    parent_digest : str
        Content hash of the parents' outputs, so a changed parent invalidates this job.
    inputs : str
        Digest of the corpus files the job reads (task file, subject files, profile), so a
        changed input invalidates exactly the jobs that read it.
    reads : tuple of (name, digest)
        Each input as planned (a file's name and SHA-256), for the stage to verify what it
        reads against: a file edited after planning fails the job instead of being stored
        under a digest that does not describe it.
    """

    stage: str
    subject: str
    task: int
    rep: int
    version: str
    view: str = GEOMETRY_VIEW
    frames: tuple[int, ...] = ()
    chunk: int = 0
    evidence: bool = False
    pictures: bool = True
    parents: tuple[str, ...] = ()
    parent_digest: str = ""
    inputs: str = ""
    reads: tuple[tuple[str, str], ...] = ()

    @property
    def key(self) -> str:
        """A readable, path-safe, unique name: ``JW11/019-1/cassi-2.1/geometry``,
        ``JW11/019-1/cassi-2.1/front/render-000``, ``JW11/019-1/cassi-2.1/front/evidence-000``,
        ``JW11/019-1/cassi-2.1/front/masks-000``,
        ``JW11/019-1/cassi-2.1/front/checks``."""
        head = f"{self.subject}/{self.task:03d}-{self.rep}/{self.version}"
        if self.stage == "geometry":
            return f"{head}/{GEOMETRY_VIEW}"
        if self.stage == "render":
            kind = "evidence" if self.evidence else "render" if self.pictures else "masks"
            return f"{head}/{self.view}/{kind}-{self.chunk:03d}"
        return f"{head}/{self.view}/checks"

    @property
    def task_key(self) -> tuple[str, int, int, str]:
        return (self.subject, self.task, self.rep, self.version)

    def planned(self, name: str) -> str | None:
        """The planned digest of input ``name`` (None when the job was planned without it)."""
        return dict(self.reads).get(name)

    def digest(self, salt: str = "") -> str:
        """SHA-256 of the job and ``salt`` (the run settings and code its outputs depend on)."""
        # asdict's fields, without its recursive copy of every tuple (a full set plans
        # 120,000 jobs): the same JSON, so the same digests
        job = {f: getattr(self, f) for f in _JOB_FIELDS}
        doc = json.dumps({"job": job, "salt": salt}, sort_keys=True, default=str)
        return hashlib.sha256(doc.encode()).hexdigest()


_JOB_FIELDS = tuple(f.name for f in fields(Job))


@dataclass(frozen=True)
class StageContext:
    """Run settings every stage sees (picklable; sent to worker processes).

    ``provenance`` names the code the outputs come from (package version, a digest of the
    installed cassi code and of the rubric registry, the packages that shape results),
    ``version_provenance`` each version's own code: part of every job's digest, so new code or
    a changed threshold recomputes. ``cache_dir`` is a store shared between runs (a nightly
    directory's nights): jobs whose digest it holds are reused from it. ``ship`` makes workers take their
    inputs from the job and hand their outputs back instead of using ``out_dir`` (a cluster
    whose nodes do not share the driver's filesystem).
    """

    out_dir: Path
    corpus: Path | None = None
    stride: int = 25
    chunk_size: int = 16
    preset: str = "preview"
    variant: str | None = None
    synthetic: bool = False
    options: tuple[tuple[str, object], ...] = ()
    provenance: str = ""
    version_provenance: tuple[tuple[str, str], ...] = ()
    ship: bool = False
    cache_dir: Path | None = None

    def salt(self, version: str | None = None) -> str:
        """The settings that change a job's outputs (not out_dir or cache_dir, which only say
        where they go): the shared ``provenance`` and ``version``'s own code
        (``version_provenance``), so a change to one version's code leaves the others' jobs."""
        return json.dumps({"corpus": str(self.corpus), "stride": self.stride,
                           "chunk": self.chunk_size, "preset": self.preset,
                           "variant": self.variant, "synthetic": self.synthetic,
                           "options": [list(o) for o in self.options],
                           "provenance": self.provenance,
                           "version": dict(self.version_provenance).get(version, "")},
                          sort_keys=True)

    def option(self, name: str, default=None):
        return dict(self.options).get(name, default)


@dataclass
class StageOutput:
    """What a stage returns: result rows, extra files (name -> (bytes, suffix)), metadata.

    ``meta`` is stored in the manifest (JSON); a geometry stage puts the frames to render there
    under ``"render_frames"``.
    """

    rows: pd.DataFrame | None = None
    files: dict[str, tuple[bytes, str]] = field(default_factory=dict)
    meta: dict = field(default_factory=dict)
    log: list[str] = field(default_factory=list)


class SkipJob(Exception):
    """Raised by a stage when its input is unusable: the job is SKIPPED with this reason."""


StageFn = Callable[[Job, StageContext, Mapping[str, bytes]], StageOutput]


@dataclass
class Outcome:
    """What a worker reports back for one job.

    Small when the worker wrote its outputs into the shared store; with ``ctx.ship`` the
    outputs travel back in ``blobs`` (name -> (bytes, suffix)) for the driver to store.
    """

    key: str
    state: State
    seconds: float = 0.0
    reason: str = ""
    meta: dict = field(default_factory=dict)
    log: list[str] = field(default_factory=list)
    blobs: dict[str, tuple[bytes, str]] | None = None
    #: CPU time of the worker process over the job (``seconds`` is its wall time).
    cpu_seconds: float = 0.0


def rows_to_bytes(rows: pd.DataFrame) -> bytes:
    """Parquet bytes of rows already normalised by :func:`results.normalize`."""
    return R.to_parquet_bytes(rows)


def npz_bytes(*, compressed: bool = False, **arrays) -> bytes:
    """Deterministic ``.npz`` bytes (no timestamps: ``np.savez`` writes fixed zip dates);
    ``compressed``: deflated, for arrays that are mostly background (part masks, depth)."""
    import numpy as np  # noqa: PLC0415

    buf = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buf, **arrays)
    return buf.getvalue()


class ParentOutputs(abc.Mapping):
    """The outputs of a job's parents by name, each read from the store when asked for, so a
    stage that reads one mask at a time never holds every parent blob at once."""

    def __init__(self, store: OutputStore, refs: dict):
        self._store, self._refs = store, refs

    def __getitem__(self, name: str) -> bytes:
        return self._store.get(self._refs[name])

    def __iter__(self):
        return iter(self._refs)

    def __len__(self) -> int:
        return len(self._refs)


def parent_inputs(store: OutputStore, job: Job) -> ParentOutputs | None:
    """The outputs of ``job``'s parents by name (read lazily), or None when a parent has none.

    Each parent's ``rows`` are left out when there are several parents: they are already in
    the results, and their names would clash.
    """
    refs: dict = {}
    for key in job.parents:
        parent = store.read_manifest(key)
        if parent is None:
            return None
        for name, ref in parent["outputs"].items():
            if name == "rows" and len(job.parents) > 1:
                continue
            refs[name] = ref
    return ParentOutputs(store, refs)


def store_outputs(store: OutputStore, key: str, digest: str,
                  blobs: Mapping[str, tuple[bytes, str]], meta: Mapping) -> None:
    """Store a job's blobs, then its manifest (last: a manifest never names a missing blob)."""
    refs = {name: store.put(data, suffix) for name, (data, suffix) in blobs.items()}
    store.write_manifest(key, digest, refs, meta)


def execute_job(stage: StageFn, job: Job, ctx: StageContext, digest: str,
                shipped: Mapping[str, bytes] | None = None) -> Outcome:
    """Run ``stage`` for ``job`` in this (worker) process.

    With the shared store (default) the parents' outputs are read from ``ctx.out_dir`` and the
    job's outputs written there; with ``ctx.ship`` they come as ``shipped`` and go back in the
    outcome. Idempotent either way: the same job writes the same blobs and manifest.
    Exceptions other than :class:`SkipJob` propagate (the executor reports them).
    """
    t0, c0 = time.perf_counter(), time.process_time()
    store = None if ctx.ship else OutputStore(ctx.out_dir, cache=ctx.cache_dir)
    inputs = dict(shipped or {}) if ctx.ship else parent_inputs(store, job)
    if inputs is None:
        return Outcome(job.key, State.SKIPPED, reason="a parent job has no outputs")
    try:
        out = stage(job, ctx, inputs)
    except SkipJob as why:
        return Outcome(job.key, State.SKIPPED, time.perf_counter() - t0, reason=str(why))
    blobs: dict[str, tuple[bytes, str]] = {}
    if out.rows is not None:
        rows = R.normalize(out.rows, subject=job.subject, task=job.task, rep=job.rep,
                           version=job.version, view=job.view, synthetic=ctx.synthetic)
        blobs["rows"] = (rows_to_bytes(rows), ".parquet")
    blobs.update(out.files)
    if store is not None:
        store_outputs(store, job.key, digest, blobs, out.meta)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    # CPU time beside wall time: a job whose CPU time is far below its wall time waited for a
    # core (an oversubscribed machine), which is what to look at when workers do not scale.
    log = [f"wall {wall:.3f} s, cpu {cpu:.3f} s (pid {os.getpid()})", *out.log]
    return Outcome(job.key, State.DONE, wall, meta=out.meta, log=log,
                   blobs=blobs if store is None else None, cpu_seconds=cpu)


def call_job(stage: StageFn, job: Job, ctx: StageContext, digest: str,
             shipped: Mapping[str, bytes] | None = None) -> Outcome:
    """:func:`execute_job`, with a Python exception turned into a FAILED outcome (with its
    traceback) instead of propagating; a process crash still ends the worker."""
    t0 = time.perf_counter()
    try:
        return execute_job(stage, job, ctx, digest, shipped)
    except Exception as err:  # noqa: BLE001 - reported per job; the batch goes on
        return Outcome(job.key, State.FAILED, time.perf_counter() - t0,
                       reason=f"{type(err).__name__}: {err}",
                       log=traceback.format_exc().splitlines())


def chunk_frames(frames: list[int] | tuple[int, ...], size: int) -> list[tuple[int, ...]]:
    """Split sorted frame numbers into chunks of at most ``size``."""
    frames = sorted(set(int(f) for f in frames))
    size = max(1, int(size))
    return [tuple(frames[i:i + size]) for i in range(0, len(frames), size)]
