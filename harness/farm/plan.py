"""The batch plan: which jobs a run has and what each one waits for, as plain data.

A batch is ``task files x versions`` geometry jobs. A geometry job decides which frames are
worth rendering, so its render jobs (``views x chunks``) are planned from its outputs
(:meth:`BatchPlan.render_jobs`), and a view's image job from its finished render chunks
(:meth:`BatchPlan.image_job`). Everything here is pure: no I/O, no executor, no state; the
scheduler (:mod:`.runner`) asks the plan what a finished job unlocks.

The dependency graph, per task file and version::

    geometry ──> render(view, chunk 0..n) ──> image(view)      for every view
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import Iterable, Mapping

from cassi.harness.farm.jobs import GEOMETRY_VIEW, Job, chunk_frames


@dataclass(frozen=True)
class TaskSpec:
    """A task file of the batch.

    ``usable`` False makes its jobs SKIPPED with ``reason``. ``inputs`` is the digest of every
    file its jobs read (the task file, the subject's files and profile); it is part of each
    job's identity, so a changed input recomputes exactly the jobs that read it. ``reads``
    names each of those files (and any derived input) with its digest as planned, so a worker
    can refuse bytes that changed after planning.
    """

    subject: str
    task: int
    rep: int = 1
    usable: bool = True
    reason: str = ""
    inputs: str = ""
    reads: tuple[tuple[str, str], ...] = ()


def outputs_digest(manifests: Iterable[Mapping]) -> str:
    """One digest of the outputs of some finished jobs (their blob hashes)."""
    doc = json.dumps([{n: r.sha256 for n, r in sorted(m["outputs"].items())} for m in manifests])
    return hashlib.sha256(doc.encode()).hexdigest()


@dataclass(frozen=True)
class BatchPlan:
    """Every job a batch can run and what each depends on.

    Attributes
    ----------
    geometry : tuple of Job
        One geometry job per usable task file and version (the roots of the graph).
    skipped : tuple of (Job, str)
        Geometry jobs of unusable task files, with the reason.
    views : tuple of str
        Render views (empty for a geometry-only run).
    chunk_size : int
        Frames per render job.
    images : bool
        Whether each view's renders are followed by an image job.
    """

    geometry: tuple[Job, ...]
    skipped: tuple[tuple[Job, str], ...]
    views: tuple[str, ...]
    chunk_size: int
    images: bool

    @classmethod
    def build(cls, tasks: Iterable[TaskSpec], versions: Iterable[str], views: Iterable[str], *,
              chunk_size: int, render: bool, images: bool) -> "BatchPlan":
        versions = list(versions)
        geometry, skipped = [], []
        for spec in tasks:
            for version in versions:
                job = Job("geometry", spec.subject, spec.task, spec.rep, version,
                          inputs=spec.inputs, reads=spec.reads)
                if spec.usable:
                    geometry.append(job)
                else:
                    skipped.append((job, spec.reason or "task file not usable"))
        views = tuple(v for v in views if v != GEOMETRY_VIEW) if render else ()
        return cls(tuple(geometry), tuple(skipped), views, max(1, int(chunk_size)),
                   bool(images and views))

    def render_jobs(self, geometry: Job, manifest: Mapping) -> dict[str, tuple[Job, ...]]:
        """The render chunks a finished geometry job unlocks, per view.

        The geometry stage names its frames in ``meta["render_frames"]``; a view may have its
        own list in ``meta["render_frames_by_view"]`` (the front view's animation frames).
        """
        meta = manifest.get("meta", {})
        parent = outputs_digest([manifest])
        out = {}
        for view in self.views:
            frames = meta.get("render_frames_by_view", {}).get(view, meta.get("render_frames", []))
            out[view] = tuple(
                Job("render", *geometry.task_key, view, chunk, i, parents=(geometry.key,),
                    parent_digest=parent, inputs=geometry.inputs,
                    reads=geometry.reads)
                for i, chunk in enumerate(chunk_frames(frames, self.chunk_size)))
        return out

    @staticmethod
    def image_job(renders: tuple[Job, ...], manifests: Iterable[Mapping]) -> Job:
        """A view's image job: every frame of its render chunks, after all of them."""
        first = renders[0]
        return Job("image", *first.task_key, first.view,
                   tuple(f for job in renders for f in job.frames),
                   parents=tuple(job.key for job in renders),
                   parent_digest=outputs_digest(manifests), inputs=first.inputs,
                   reads=first.reads)

    @property
    def size(self) -> int:
        """Geometry jobs (runnable and skipped); render and image jobs follow from them."""
        return len(self.geometry) + len(self.skipped)
