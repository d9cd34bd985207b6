"""The CASSI stages: versions -> rubric geometric checks -> renderer -> image checks -> ratings.

Each stage is a module-level function ``stage(job, ctx, inputs) -> StageOutput`` run inside a
worker process (:func:`cassi.harness.farm.jobs.execute_job`), with the worker's caches
(:mod:`.caches`) and the frame policy (:mod:`.frames`).
"""
from __future__ import annotations

import io
import os
import platform
import re
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.harness import rubric
from cassi.harness.evaluation.caches import (get_corpus, get_face, get_neutral, get_profile,
                                             get_renderer, get_version_face)
from cassi.harness.evaluation.config import Catalog
from cassi.harness.evaluation.evalset import task_catalog
from cassi.harness.evaluation.frames import (DEFAULT_EXTREMES, evidence_frames,
                                             frames_to_render, image_views, viewer_frames, viewer_stride)
from cassi.harness.evaluation.viewerdata import viewer_blob
from cassi.harness.evaluation.withheld import withheld_sites
from cassi.harness.evaluation.inputs import (read_planned, verify_code, verify_profile,
                                             verify_subject_files)
from cassi.harness.farm.jobs import Job, SkipJob, StageContext, StageOutput, npz_bytes
from cassi.harness.farm.runner import Pipeline
from cassi.harness.rubric.frames import CHUNK_FRAMES, FileFrames
from cassi.harness.rubric.image import depth_read, is_read, read_box, read_pixels
from cassi.harness.rubric.measures import CRITERION_DIAGNOSTICS, DIAGNOSTICS_READ
from cassi.renderer.images import png_bytes
from cassi.renderer.views import PRESET_NAMES, VIEW_NAMES
from cassi.versions.registry import available_versions, get_version

#: A geometry job's temporary directory: ``cassi-geometry-<pid>-<host>-<random>``, so the next
#: worker on the host can tell (and remove) the ones a killed worker left behind.
TEMP_PREFIX = "cassi-geometry-"
_swept: set[str] = set()


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9.]", "_", platform.node()) or "host"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # another user's process
    return True


def remove_stale_temp_dirs(root: str | os.PathLike | None = None) -> list[Path]:
    """Remove this user's geometry temporary directories whose process (on this host) is gone
    (a worker killed with ``kill -9`` or by the OOM killer leaves its positions file behind:
    hundreds of MB for a long task). Returns what was removed."""
    root = Path(root or tempfile.gettempdir())
    removed = []
    pattern = re.compile(re.escape(TEMP_PREFIX) + r"(\d+)-" + re.escape(_host()) + r"-")
    for path in root.glob(TEMP_PREFIX + "*"):
        m = pattern.match(path.name)
        try:
            mine = path.is_dir() and not path.is_symlink() and path.stat().st_uid == os.getuid()
        except OSError:
            continue
        if m and mine and int(m[1]) != os.getpid() and not _pid_alive(int(m[1])):
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def geometry_temp_dir() -> tempfile.TemporaryDirectory:
    """A temporary directory for one geometry job, named after this process; the first call in
    a process removes those of dead processes first."""
    root = tempfile.gettempdir()
    if root not in _swept:
        remove_stale_temp_dirs(root)
        _swept.add(root)
    return tempfile.TemporaryDirectory(prefix=f"{TEMP_PREFIX}{os.getpid()}-{_host()}-")


def load_usable(subject_data, job: Job, data: bytes | None = None):
    """The job's recording, parsed once (from ``data``, its bytes as read, when given); SkipJob
    with the reason when it cannot be animated."""
    try:
        if data is None:
            rec = subject_data.load(job.task, job.rep, require_valid=False)
        else:
            rec = subject_data.read_task(subject_data.task_path(job.task, job.rep), data=data,
                                         task=job.task, rep=job.rep, require_valid=False)
        u = subject_data.usability(job.task, job.rep, recording=rec)
    except CassiInputError as err:
        raise SkipJob(str(err)) from err
    if not u.usable:
        raise SkipJob("; ".join(u.reasons) or "task file not usable")
    return rec


class NoFrameAnimated(RuntimeError):
    """A version animated no frame of a usable task file: the version failed (the job fails),
    the file was not unusable (which would skip it)."""


def geometry_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """Animate every frame (and again with T2, then T3, withheld: Table G's leave-one-out
    tongue), run the geometric checks, choose and keep the frames to render.

    Outputs: ``rows`` (the checks' rows, view ``"geometry"``), ``keyframes`` (npz: ``frames``
    int64 (K,) recording rows, ``positions`` float32 (K, V, 3) Parke units), ``viewer`` (the
    report's task viewer data, :mod:`cassi.harness.evaluation.viewerdata`) and
    ``meta["render_frames"]`` (and ``"render_frames_by_view"``, ``"evidence_frames_by_view"``).
    """
    corpus = get_corpus(ctx.corpus)
    verify_code(ctx, job.version)
    subject = corpus.subject(job.subject)
    verify_subject_files(job, subject)
    # The bytes parsed are the bytes verified: the file is read once.
    data = read_planned(job, corpus, subject.task_path(job.task, job.rep))
    rec = load_usable(subject, job, data)
    try:
        profile = get_profile(corpus, job.subject)
    except CassiInputError as err:
        raise SkipJob(f"subject cannot be preprocessed: {err}") from err
    verify_profile(job, profile)
    version = get_version(job.version)
    with geometry_temp_dir() as tmp:
        anim, face, rows = checked_animation(version, corpus, job.subject, profile, rec,
                                             task=job.task, rep=job.rep, tmp=Path(tmp))
        out = _geometry_output(job, ctx, rec, anim, rows)
        out.files["viewer"] = (_viewer_output(rec, anim, face, profile, out.rows), ".npz")
        return out


def checked_animation(version, corpus, subject: str, profile, rec, *, task: int, rep: int,
                      tmp: Path, version_face_of=get_version_face):
    """Animate ``rec`` into ``tmp`` (and again with T2, then T3, withheld: Table G's
    leave-one-out tongue) and run the geometric checks: (animation, the face the version
    animated, the checks' rows). ``version_face_of`` gives that face (the worker's cache by
    default; :func:`cassi.harness.evaluation.sensitivity` builds it afresh under a setting)."""
    face = get_face(corpus, subject, profile)
    anim = animate_to_file(version, profile, face, rec, tmp)
    withheld = withheld_sites(version, profile, face, rec)           # leave-one-out tongue
    face = version_face_of(corpus, subject, profile, version)       # what it animated
    rows = rubric.run_geometry_checks(anim, face, profile, task=task, subject=subject, rep=rep,
                                      neutral=get_neutral(), recording=rec, withheld=withheld)
    return anim, face, pd.DataFrame(rows)


@dataclass(frozen=True)
class StreamedAnimation:
    """An :class:`~cassi.versions.protocol.Animation` whose positions stay in a file
    (:class:`~cassi.harness.rubric.frames.FileFrames`), read back a chunk at a time."""

    version: str
    frames: np.ndarray
    time_us: np.ndarray
    positions: object
    diagnostics: pd.DataFrame


def animate_to_file(version, profile, face, rec, tmp: Path) -> StreamedAnimation:
    """Animate ``rec`` a chunk of frames at a time into a positions file under ``tmp``, so a
    worker's memory does not grow with the task's positions (about 6.8 KB a frame for the
    570-vertex face); of the diagnostics, only the columns the rubric reads are kept. A version
    without ``animate_chunks`` (the protocol only asks for ``animate``) is animated at once and
    its positions written out."""
    kept = ("frame", "time_us", *DIAGNOSTICS_READ, *CRITERION_DIAGNOSTICS)

    chunks = (version.animate_chunks(profile, face, rec, frames=CHUNK_FRAMES)
              if hasattr(version, "animate_chunks") else iter([version.animate(profile, face, rec)]))
    store, frames, times, diags, name = None, [], [], [], getattr(version, "name", "")
    for anim in chunks:
        if store is None:
            store = FileFrames(tmp / "positions.f32", anim.positions.shape[1])
        store.append(anim.positions)
        frames.append(np.asarray(anim.frames, np.int64))
        times.append(np.asarray(anim.time_us, np.int64))
        diags.append(anim.diagnostics.filter(items=kept))
        name = anim.version
    if store is None or not sum(f.size for f in frames):
        raise NoFrameAnimated(f"{name or 'the version'} animated no frame of a usable task file")
    return StreamedAnimation(name, np.concatenate(frames), np.concatenate(times), store,
                             pd.concat(diags, ignore_index=True))


def _geometry_output(job: Job, ctx: StageContext, rec, anim: StreamedAnimation,
                     rows: pd.DataFrame) -> StageOutput:
    """Pick the frames to render from the checks' rows and keep their positions.

    ``render_frames`` (``render_frames_by_view`` where a view has its own) are rendered and
    judged by the view's image checks; ``evidence_frames_by_view`` are rendered for the
    report's links only (:func:`~cassi.harness.evaluation.frames.evidence_frames`)."""
    frames = np.asarray(anim.frames, dtype=np.int64)
    step = int(ctx.option("animate_stride", 0) or 0)
    pick, by_view = frames_to_render(
        frames, rows, task=job.task, version=job.version, stride=ctx.stride,
        extremes=ctx.option("extremes", DEFAULT_EXTREMES), animate_stride=step,
        video_versions=ctx.option("video_versions"))
    evidence = evidence_frames(rows, frames)
    meta = {"render_frames": pick, "n_frames": int(frames.size)}
    if by_view:
        meta["render_frames_by_view"] = by_view
    if evidence:
        meta["evidence_frames_by_view"] = evidence
    keep = sorted(set(pick).union(*by_view.values(), *evidence.values()))
    idx = np.searchsorted(frames, keep)
    keyframes = npz_bytes(frames=np.asarray(keep, np.int64), positions=anim.positions.take(idx))
    log = [f"frames {frames[0]}..{frames[-1]} ({frames.size}); render {len(pick)}: {pick}"]
    video = set().union(*by_view.values()) - set(pick)
    if video:
        log.append(f"video frames (every {step}th row, {', '.join(by_view)}): {len(video)} more")
    if evidence:
        log.append("evidence frames (rendered, not judged): " +
                   "; ".join(f"{view} {f}" for view, f in evidence.items()))
    log += [f"recording warning: {w}" for w in getattr(rec, "warnings", ())]
    return StageOutput(rows=rows, files={"keyframes": (keyframes, ".npz")}, meta=meta, log=log)


def _viewer_output(rec, anim: StreamedAnimation, face, profile, rows: pd.DataFrame) -> bytes:
    """The report's task viewer data (:mod:`.viewerdata`) at :func:`viewer_frames`."""
    stride = viewer_stride(rec.period_us)
    keep = viewer_frames(anim.frames, rows, stride=stride)
    idx = np.searchsorted(anim.frames, keep)
    xy = np.asarray(rec.xy_mm)[keep]
    return viewer_blob(face, anim.positions.take(idx), np.asarray(keep, np.int64),
                       np.asarray(anim.time_us)[idx], xy, np.asarray(rec.valid, bool)[keep],
                       profile.jaw_length_mm)


def _png_bytes(srgb: np.ndarray, metadata: dict | None = None) -> bytes:
    """The frame's sRGB PNG (uint8 (H, W, 3)), encoded in memory (no temporary file per frame)."""
    return png_bytes(srgb, metadata=metadata, linear=False)


class StoredFrame:
    """A rendered frame as the image checks need it, rebuilt from a render job's outputs: the
    crop of the frame that holds what they read (``mask``, ``depth``) at ``origin`` (row,
    column) of a frame of ``shape`` (H, W)."""

    def __init__(self, mask: np.ndarray, depth: np.ndarray, part_names: tuple[str, ...],
                 origin: tuple[int, int] = (0, 0), shape: tuple[int, int] | None = None):
        self.mask, self.depth, self.part_names = mask, depth, part_names
        self.origin = (int(origin[0]), int(origin[1]))
        self.shape = tuple(int(n) for n in (shape if shape is not None else mask.shape))

    def full(self) -> "StoredFrame":
        """The whole frame: background (part 0, depth inf) outside the crop."""
        if self.shape == tuple(self.mask.shape):
            return self
        (r, c), (h, w) = self.origin, self.mask.shape
        mask = np.zeros(self.shape, self.mask.dtype)
        depth = np.full(self.shape, np.inf, np.float32)
        mask[r:r + h, c:c + w], depth[r:r + h, c:c + w] = self.mask, self.depth
        return StoredFrame(mask, depth, self.part_names, (0, 0), self.shape)


#: The ``masks-<frame>`` blob's format, a run option and so part of every job's digest: a store
#: written in another format recomputes instead of being read as this one. 1: mask and the
#: whole depth image (53 of a front frame's 55 KB deflated). 2: depth only where the image
#: measures read it (:func:`cassi.harness.rubric.image.depth_read`: teeth and tongue), exact
#: float32 there and inf elsewhere, as for background (about 2 KB a frame). 3: only the crop
#: that holds the parts the measures read (:func:`cassi.harness.rubric.image.read_box`), with
#: its place in the frame: the same values for every measure, and a sixth of format 2's
#: encoding and the image checks' work.
MASKS_FORMAT = 3
#: The masks outputs' name prefix (``masks-<frame:06d>``), listed as run attachments.
MASKS_OUTPUT = "masks-"


def masks_blob(mask: np.ndarray, depth: np.ndarray, part_names, *, origin=(0, 0),
               shape=None) -> bytes:
    """A frame's ``masks-<frame>`` blob: npz, deflated, of the crop :func:`read_box` of
    ``mask`` (part ids, a frame of ``shape``, or the part of one at ``origin``): ``mask`` uint8
    part ids, ``depth`` float32 Parke units where :func:`depth_read` (inf elsewhere),
    ``part_names``, ``origin`` (row, column in the frame) and ``shape`` (the frame's H, W)."""
    mask = np.asarray(mask)
    if mask.max(initial=0) > 255:
        raise ValueError("more than 255 parts: masks are stored as uint8")
    shape = tuple(mask.shape) if shape is None else tuple(shape)
    (h, w), seen = mask.shape, read_pixels(mask, part_names)
    edges = [e for e, cut in ((seen[0], origin[0] > 0), (seen[:, 0], origin[1] > 0),
                              (seen[-1], origin[0] + h < shape[0]),
                              (seen[:, -1], origin[1] + w < shape[1])) if cut] if seen.size else []
    if any(e.any() for e in edges):
        # what the measures read, and the ring around it, must lie in the rendered region
        raise ValueError(f"the rendered region {h}x{w} at {tuple(origin)} of a {shape} frame "
                         "cuts the parts the image measures read")
    r0, r1, c0, c1 = read_box(seen)
    mask = mask[r0:r1, c0:c1]
    kept = np.where(depth_read(mask, part_names), np.asarray(depth, np.float32)[r0:r1, c0:c1],
                    np.float32(np.inf))
    return npz_bytes(mask=mask.astype(np.uint8), depth=kept,
                     part_names=np.asarray(part_names, dtype=str),
                     origin=np.asarray([origin[0] + r0, origin[1] + c0], np.int32),
                     shape=np.asarray(shape, np.int32), compressed=True)


def read_masks_blob(data: bytes) -> StoredFrame:
    """A ``masks-<frame>`` blob (:func:`masks_blob`) as the image checks read it: the crop
    (:meth:`StoredFrame.full` for the whole frame)."""
    d = np.load(io.BytesIO(data))
    names = tuple(str(n) for n in d["part_names"])
    if "origin" not in d:  # format 2: the whole frame
        return StoredFrame(d["mask"].astype(np.int32), d["depth"], names)
    return StoredFrame(d["mask"].astype(np.int32), d["depth"], names,
                       tuple(d["origin"].tolist()), tuple(d["shape"].tolist()))


def render_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """Render ``job.frames`` of ``job.view``.

    Outputs: one PNG per frame (``render-<frame>``; none for a job of masks only,
    ``job.pictures`` False) and, for the frames the task's image checks judge (their views,
    not an evidence job's frames), ``masks-<frame>`` (:func:`masks_blob`). Nothing else reads
    masks, and a night's masks of every view were 6.9 GB written and hashed. A job of masks
    only traces the rays of the region that holds what the image measures read
    (:meth:`~cassi.renderer.render.FaceRenderer.render_region`): the same masks, at a third of
    a pictured frame's cost.
    """
    judged = not job.evidence and job.view in image_views(job.task)

    data = np.load(io.BytesIO(inputs["keyframes"]))
    all_frames = data["frames"].tolist()
    positions = data["positions"]  # read once: each data[...] access decodes the array again
    corpus = get_corpus(ctx.corpus)
    verify_code(ctx, job.version)
    profile = get_profile(corpus, job.subject)
    verify_profile(job, profile)
    face = get_version_face(corpus, job.subject, profile, get_version(job.version))
    renderer = get_renderer(corpus, job.subject, face, job.view, ctx.preset, ctx.variant)
    files = {}
    t0 = time.perf_counter()
    seconds = 0.0
    for f in job.frames:
        if not job.pictures:
            if not judged:
                raise ValueError(f"{job.key}: masks only of frames no image check judges")
            mask, depth, origin = renderer.render_region(positions[all_frames.index(f)], is_read)
            files[f"{MASKS_OUTPUT}{f:06d}"] = (masks_blob(
                mask, depth, renderer.part_names, origin=origin,
                shape=(renderer.preset.height, renderer.preset.width)), ".npz")
            continue
        res = renderer.render(positions[all_frames.index(f)])
        seconds += float(getattr(res, "render_s", 0.0))
        meta = {"subject": job.subject, "task": job.task, "rep": job.rep,
                "version": job.version, "view": job.view, "frame": f,
                "synthetic": ctx.synthetic}
        files[f"render-{f:06d}"] = (_png_bytes(res.srgb8(), {**res.metadata(), **meta}), ".png")
        if not judged:
            continue
        files[f"{MASKS_OUTPUT}{f:06d}"] = (masks_blob(res.mask, res.depth, res.part_names), ".npz")
    if not job.pictures:
        seconds = time.perf_counter() - t0
    what = "frame(s)" if job.pictures else "frame(s), masks only,"
    return StageOutput(files=files, meta={"render_s": round(seconds, 3)},
                       log=[f"rendered {len(job.frames)} {what} of {job.view} "
                            f"({ctx.preset}, {renderer.variant}) in {seconds:.2f} s"])


def image_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """The rubric's image checks over every rendered frame of ``job.view`` (all its render
    chunks; its evidence chunks are not among ``job.frames``)."""

    def frames():  # one frame's masks at a time: the checks keep a few numbers per frame
        for f in job.frames:
            yield int(f), read_masks_blob(inputs[f"masks-{f:06d}"])

    verify_code(ctx, job.version)
    rows = rubric.run_image_checks({job.view: frames()}, task=job.task, subject=job.subject,
                                   rep=job.rep, version=job.version)
    return StageOutput(rows=pd.DataFrame(rows),
                       log=[f"image checks on {len(job.frames)} frame(s): {len(rows)} row(s)"])


def cassi_pipeline(*, render: bool = True) -> Pipeline:
    """The real pipeline; ``render=False`` for geometry-only runs."""
    return Pipeline(geometry=geometry_stage, render=render_stage if render else None,
                    image=image_stage if render else None, ratings=rubric.ratings_table,
                    attachments=("viewer", f"{MASKS_OUTPUT}*"))


def catalog(corpus):
    """The names a run may use on ``corpus`` (:class:`cassi.harness.evaluation.config.Catalog`)."""
    return Catalog(subjects=tuple(corpus.subjects), tasks=task_catalog(corpus),
                   versions=tuple(available_versions()), views=tuple(VIEW_NAMES),
                   presets=tuple(PRESET_NAMES))


