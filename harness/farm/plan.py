"""The batch plan: which jobs a run has and what each one waits for, as plain data.

A batch is ``task files x versions`` geometry jobs. A geometry job decides which frames are
worth rendering, so its render jobs (``views x chunks``) are planned from its outputs
(:meth:`BatchPlan.render_jobs`), and a view's image job from its finished render chunks
(:meth:`BatchPlan.image_job`). Everything here is pure: no I/O, no executor, no state; the
scheduler (:mod:`.runner`) asks the plan what a finished job unlocks.

The dependency graph, per task file and version::

    geometry ──> render(view, chunk 0..n) ──> image(view)      for every view
             ├─> masks(view, chunk 0..k) ───┘                  (masks only: see masks_only)
             └─> evidence render(view, chunk 0..m)              (no image job reads them)
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


#: A masks-only job takes this many times a render job's frames: its frames cost a third of a
#: pictured frame's, and a job's own cost (inputs read, outputs hashed, a manifest fsynced:
#: about 10 ms) is spread over as much work.
MASKS_CHUNK_FACTOR = 4


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
    masks_only : frozenset of (subject, task, rep, view)
        Where the judged frames other than ``meta["render_frames"]`` (a video's grid whose
        video is not made) are rendered as masks only, for the image job, with no picture.
    judged : frozenset of (subject, task, rep, view), or None
        The views an image job follows (None: every view): a view no image check judges
        has none, which would only read its renders to find nothing to judge.
    """

    geometry: tuple[Job, ...]
    skipped: tuple[tuple[Job, str], ...]
    views: tuple[str, ...]
    chunk_size: int
    images: bool
    masks_only: frozenset = frozenset()
    judged: frozenset | None = None

    @classmethod
    def build(cls, tasks: Iterable[TaskSpec], versions: Iterable[str], views: Iterable[str], *,
              chunk_size: int, render: bool, images: bool, masks_only=(),
              judged=None) -> "BatchPlan":
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
                   bool(images and views), frozenset(masks_only) if images else frozenset(),
                   None if judged is None else frozenset(judged))

    def judges(self, render: Job) -> bool:
        """Whether an image job follows ``render``'s view (its judged chunks, not evidence)."""
        return self.images and not render.evidence and (
            self.judged is None
            or (render.subject, render.task, render.rep, render.view) in self.judged)

    @staticmethod
    def judged_frames(meta: Mapping, view: str) -> list[int]:
        """The frames ``view`` renders for its image job: ``meta["render_frames"]``, or the
        view's own list in ``meta["render_frames_by_view"]`` (the video grid's views)."""
        return list(meta.get("render_frames_by_view", {}).get(view, meta.get("render_frames", [])))

    @staticmethod
    def evidence_frames(meta: Mapping, view: str) -> list[int]:
        """The frames ``view`` renders for the report's links only
        (``meta["evidence_frames_by_view"]``) that it does not render for its image job."""
        judged = set(BatchPlan.judged_frames(meta, view))
        return sorted(int(f) for f in meta.get("evidence_frames_by_view", {}).get(view, [])
                      if int(f) not in judged)

    def render_jobs(self, geometry: Job, manifest: Mapping) -> dict[str, tuple[Job, ...]]:
        """The render chunks of :meth:`judged_frames` a finished geometry job unlocks, per
        view: together, the frames the view's image job judges. Where :attr:`masks_only`
        says so, those beyond ``meta["render_frames"]`` are chunks of masks only."""
        meta = manifest.get("meta", {})
        shown = {int(f) for f in meta.get("render_frames", [])}
        pictured, masks = {}, {}
        for view in self.views:
            judged = self.judged_frames(meta, view)
            if (geometry.subject, geometry.task, geometry.rep, view) in self.masks_only:
                pictured[view] = [f for f in judged if int(f) in shown]
                masks[view] = [f for f in judged if int(f) not in shown]
            else:
                pictured[view], masks[view] = judged, []
        pictured = self._chunks(geometry, manifest, pictured, evidence=False)
        masks = self._chunks(geometry, manifest, masks, evidence=False, pictures=False)
        return {view: pictured[view] + masks[view] for view in self.views}

    def evidence_jobs(self, geometry: Job, manifest: Mapping) -> dict[str, tuple[Job, ...]]:
        """The render chunks of :meth:`evidence_frames` a finished geometry job unlocks, per
        view (views without any left out): rendered and listed, never judged."""
        meta = manifest.get("meta", {})
        out = self._chunks(geometry, manifest,
                           {view: self.evidence_frames(meta, view) for view in self.views},
                           evidence=True)
        return {view: jobs for view, jobs in out.items() if jobs}

    def _chunks(self, geometry: Job, manifest: Mapping, frames: Mapping[str, list[int]], *,
                evidence: bool, pictures: bool = True) -> dict[str, tuple[Job, ...]]:
        """Per view, the render jobs of ``frames[view]`` in chunks (of masks only: larger)."""
        parent = outputs_digest([manifest])
        size = self.chunk_size if pictures else MASKS_CHUNK_FACTOR * self.chunk_size
        return {view: tuple(
            Job("render", *geometry.task_key, view, chunk, i, evidence=evidence,
                pictures=pictures, parents=(geometry.key,), parent_digest=parent,
                inputs=geometry.inputs, reads=geometry.reads)
            for i, chunk in enumerate(chunk_frames(frames[view], size)))
            for view in self.views}

    @staticmethod
    def image_job(renders: tuple[Job, ...], manifests: Iterable[Mapping]) -> Job:
        """A view's image job: every frame of its render chunks, after all of them."""
        first = renders[0]
        return Job("image", *first.task_key, first.view,
                   tuple(sorted(f for job in renders for f in job.frames)),
                   parents=tuple(job.key for job in renders),
                   parent_digest=outputs_digest(manifests), inputs=first.inputs,
                   reads=first.reads)

    @property
    def size(self) -> int:
        """Geometry jobs (runnable and skipped); render and image jobs follow from them."""
        return len(self.geometry) + len(self.skipped)
