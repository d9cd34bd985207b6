"""The CASSI stages: versions -> rubric geometric checks -> renderer -> image checks -> ratings.

Each stage is a module-level function ``stage(job, ctx, inputs) -> StageOutput`` run inside a
worker process (:func:`cassi.harness.jobs.execute_job`). Worker processes live for the whole run,
so the per-process caches below keep a corpus, a subject's profile and face, and one
:class:`~cassi.renderer.FaceRenderer` (one Mitsuba scene) per (subject, view, preset) across the
jobs the process runs, instead of rebuilding them per job.
"""
from __future__ import annotations

import os
import platform
import tempfile
import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd

from cassi.common.errors import CassiInputError

from .jobs import Job, SkipJob, StageContext, StageOutput, npz_bytes, select_frames
from .runner import Pipeline

#: At most this many "extreme" frames per geometry job (the worst frame of the checks that
#: fired, most negatives first), so renders stay bounded on long tasks.
MAX_EXTREMES = 8
#: The views a task file's video shows side by side; with ``animate_stride`` each of them is
#: rendered at that stride (views a run leaves out are not rendered).
VIDEO_VIEWS = ("front", "side", "half", "top")
#: Tasks whose versions are compared side by side (front view) in the nightly report.
COMPARED_TASKS = (106, 118)
COMPARISON_VIEW = "front"


def image_views(task: int) -> set[str]:
    """The views the task's image checks judge (the front view): the only views whose masks are
    kept, and the views every version renders on the video grid, so that the image checks
    judge every version on the same frames."""
    from cassi.harness.rubric import checks_for  # noqa: PLC0415

    return {c.view for c in checks_for(kind="image", task=task)}


_lock = threading.Lock()
_corpora: dict[str, object] = {}
_profiles: dict[tuple[str, str], object] = {}
_faces: dict = {}
#: Renderers (Mitsuba scenes) a worker keeps, least recently used dropped first: each holds
#: about 6 MB, and a night's worker meets every subject, view and face (measured: 120 scenes,
#: 1.03 GB). Sixteen cover a task file's four views for a few faces at once.
RENDERERS_KEPT = 16
_renderers: OrderedDict[tuple, object] = OrderedDict()


def corpus_root(corpus: Path | str | None) -> Path:
    """``corpus``, or the embedded default (synthetic) corpus when None."""
    if corpus is not None:
        return Path(corpus)
    from cassi.data.synth.corpus import default_corpus  # noqa: PLC0415 - generated on first use

    return Path(default_corpus())


def get_corpus(corpus: Path | str | None):
    """This process's :class:`~cassi.data.corpus.disk.Corpus` for ``corpus`` (cached).

    A cluster worker reads the corpus from the path the run declares: when it cannot see it,
    the error says so (outputs travel back to the driver, but the corpus is storage the
    cluster must share).
    """
    from cassi.data.corpus.disk import Corpus  # noqa: PLC0415

    root = str(corpus_root(corpus))
    if not os.path.isdir(root):
        raise CassiInputError(
            f"the corpus directory is not visible in this process (host {platform.node()}, "
            f"pid {os.getpid()}): every node of a cluster must see the corpus at the same path",
            path=root)
    with _lock:
        if root not in _corpora:
            _corpora[root] = Corpus(root)
        return _corpora[root]


def get_profile(corpus, subject: str):
    from cassi.data.corpus.profile import preprocess  # noqa: PLC0415

    key = (str(corpus.root), subject)
    if key not in _profiles:
        _profiles[key] = preprocess(corpus, [subject])[subject]
    return _profiles[key]


def get_face(corpus, subject: str, profile):
    from cassi.versions.mapping import subject_face  # noqa: PLC0415

    key = (str(corpus.root), subject)
    if key not in _faces:
        # jaw_length_mm scales the palate by p/d like the pellets (thesis 4.1.1).
        _faces[key] = subject_face(palate_mm=getattr(profile, "palate_mm", None),
                                   head_measures=getattr(profile, "head_measures", None),
                                   jaw_length_mm=getattr(profile, "jaw_length_mm", None))
    return _faces[key]


def get_version_face(corpus, subject: str, profile, version):
    """The face ``version`` animates for ``subject`` (cached): the shared face, or the one the
    version derives from it (:func:`cassi.versions.protocol.version_face`)."""
    from cassi.versions.protocol import version_face  # noqa: PLC0415

    face = get_face(corpus, subject, profile)
    if getattr(version, "animated_face", None) is None:
        return face
    key = (str(corpus.root), subject, getattr(version, "name", repr(version)))
    if key not in _faces:
        _faces[key] = version_face(version, face)
    return _faces[key]


def get_neutral():
    """Vertices of the neutral face (no subject palate): the rubric's Table B reference."""
    from cassi.data.face.model import build_face  # noqa: PLC0415

    if "neutral" not in _faces:
        _faces["neutral"] = np.asarray(build_face().vertices)
    return _faces["neutral"]


def get_renderer(corpus, subject: str, face, view: str, preset: str, variant: str | None):
    """The process's renderer for (subject, view, preset): its Mitsuba scene is loaded once."""
    from cassi.data.face.topology import render_topology  # noqa: PLC0415
    from cassi.renderer.render import FaceRenderer  # noqa: PLC0415

    # A version may animate a face of its own (more vertices, other polygons: see
    # cassi.versions.protocol.version_face): that face gets a scene of its own.
    key = (str(corpus.root), subject, view, preset, variant, face.vertex_count,
           hash(face.polygons))
    if key in _renderers:
        _renderers.move_to_end(key)
        return _renderers[key]
    topology = render_topology(face, half=(view == "half"))
    _renderers[key] = renderer = FaceRenderer(topology, view, preset, variant)
    while len(_renderers) > RENDERERS_KEPT:
        _renderers.popitem(last=False)
    return renderer


def cache_sizes() -> dict[str, int]:
    """How much each per-process cache holds (tests check renderer reuse)."""
    return {"corpora": len(_corpora), "profiles": len(_profiles), "faces": len(_faces),
            "renderers": len(_renderers)}


def extreme_frames(rows: pd.DataFrame, *, limit: int = MAX_EXTREMES) -> list[int]:
    """Frames the geometric checks point at.

    The rubric gives each check a whole-task row (``frame == -1``, with the negatives) and an
    evidence row at the check's worst frame. The worst frames of the checks that earned
    negatives come first (most negatives first), then those of the other checks, up to
    ``limit`` frames.
    """
    if rows is None or not len(rows) or "frame" not in rows:
        return []
    rows = rows.copy()
    rows["negatives"] = pd.to_numeric(rows["negatives"], errors="coerce").fillna(0)
    fired = rows[rows["frame"] == -1].groupby("check")["negatives"].max()
    # Evidence rows only: the fidelity traces (view "trace") are per-frame data, not a fault.
    traces = rows["view"] == "trace" if "view" in rows else False
    evidence = rows[(rows["frame"] >= 0) & ~traces].copy()
    if evidence.empty:
        return []
    evidence["fired"] = evidence["check"].map(fired).fillna(0)
    evidence = evidence.sort_values(["fired", "check", "frame"], ascending=[False, True, True])
    picked: list[int] = []
    for f in evidence["frame"]:
        if int(f) not in picked:
            picked.append(int(f))
        if len(picked) >= limit:
            break
    return sorted(picked)


def render_budget(rows_of, tasks, versions, views, *, stride: int, extremes: int,
                  animate_stride: int, video_versions=None) -> int:
    """At most how many frames a run renders (said before any work starts).

    ``rows_of`` maps ``(subject, task, rep)`` to the task file's rows
    (:attr:`cassi.harness.inputs.CheckedInputs.rows`: the files are not read again). Per
    usable task file of R rows, version and view: the first frame, every ``stride``-th row and
    up to ``extremes`` check frames; plus every ``animate_stride``-th row where
    :func:`geometry_stage` renders video frames (overlaps counted twice: an upper bound).
    """
    total = 0
    for t in tasks:
        if not t.usable:
            continue
        rows = rows_of[(t.subject, t.task, t.rep)]
        base = 1 + (rows // stride if stride > 0 else 0) + max(0, extremes)
        video = rows // animate_stride + 1 if animate_stride > 0 else 0
        judged = image_views(t.task)
        for version in versions:
            for view in views:
                shows = (video_versions is None or version in video_versions
                         or view in judged
                         or (t.task in COMPARED_TASKS and view == COMPARISON_VIEW))
                total += base + (video if shows else 0)
    return total


def load_usable(subject_data, job: Job):
    """The job's recording, parsed once; SkipJob with the reason when it cannot be animated."""
    try:
        rec = subject_data.load(job.task, job.rep, require_valid=False)
        u = subject_data.usability(job.task, job.rep, recording=rec)
    except CassiInputError as err:
        raise SkipJob(str(err)) from err
    if not u.usable:
        raise SkipJob("; ".join(u.reasons) or "task file not usable")
    return rec


def geometry_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """Animate every frame, run the geometric checks, choose and keep the frames to render.

    Outputs: ``rows`` (the checks' rows, view ``"geometry"``), ``keyframes`` (npz: ``frames``
    int64 (K,) recording rows, ``positions`` float32 (K, V, 3) Parke units) and
    ``meta["render_frames"]``.
    """
    from cassi.harness import rubric  # noqa: PLC0415
    from cassi.versions.registry import get_version  # noqa: PLC0415

    corpus = get_corpus(ctx.corpus)
    rec = load_usable(corpus.subject(job.subject), job)
    try:
        profile = get_profile(corpus, job.subject)
    except CassiInputError as err:
        raise SkipJob(f"subject cannot be preprocessed: {err}") from err
    version = get_version(job.version)
    face = get_face(corpus, job.subject, profile)
    with tempfile.TemporaryDirectory(prefix="cassi-geometry-") as tmp:
        anim = animate_to_file(version, profile, face, rec, Path(tmp))
        face = get_version_face(corpus, job.subject, profile, version)  # what it animated
        rows = rubric.run_geometry_checks(anim, face, profile, task=job.task, subject=job.subject,
                                          rep=job.rep, neutral=get_neutral(), recording=rec)
        return _geometry_output(job, ctx, rec, anim, pd.DataFrame(rows))


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
    from cassi.harness.rubric.frames import CHUNK_FRAMES, FileFrames  # noqa: PLC0415
    from cassi.harness.rubric.measures import DIAGNOSTICS_READ  # noqa: PLC0415

    kept = ("frame", "time_us", *DIAGNOSTICS_READ)

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
    if store is None:
        raise SkipJob("the version animated no frame")
    return StreamedAnimation(name, np.concatenate(frames), np.concatenate(times), store,
                             pd.concat(diags, ignore_index=True))


def _geometry_output(job: Job, ctx: StageContext, rec, anim: StreamedAnimation,
                     rows: pd.DataFrame) -> StageOutput:
    """Pick the frames to render from the checks' rows and keep their positions."""
    frames = np.asarray(anim.frames, dtype=np.int64)
    if frames.size == 0:
        raise SkipJob("the version animated no frame")
    pick = select_frames(int(frames[0]), int(frames[-1]), stride=ctx.stride,
                         extremes=extreme_frames(rows, limit=ctx.option("extremes", MAX_EXTREMES)))
    animated = set(frames.tolist())
    pick = [f for f in pick if f in animated]
    meta = {"render_frames": pick, "n_frames": int(frames.size)}
    # Every task file is also shown as a video (four views side by side, cassi.reports.media):
    # the video versions get every `animate_stride`-th frame in every view, the others in the
    # views the image checks judge (else those checks would judge the video versions on every
    # grid frame and the others on a first frame and an extreme or two) and in the front view
    # of tasks 106 and 118 (the version comparisons); the same frames for every version, so
    # videos of a task compare frame for frame.
    step = int(ctx.option("animate_stride", 0) or 0)
    video_versions = ctx.option("video_versions")
    if step > 0:
        grid = {f for f in select_frames(int(frames[0]), int(frames[-1]), stride=step)
                if f in animated}
        if video_versions is None or job.version in video_versions:
            views = VIDEO_VIEWS
        else:
            views = tuple(v for v in VIDEO_VIEWS if v in image_views(job.task)
                          or (job.task in COMPARED_TASKS and v == COMPARISON_VIEW))
        if views:
            meta["render_frames_by_view"] = {view: sorted(set(pick) | grid) for view in views}
    keep = sorted(set(pick).union(*meta.get("render_frames_by_view", {}).values()))
    idx = np.searchsorted(frames, keep)
    keyframes = npz_bytes(frames=np.asarray(keep, np.int64), positions=anim.positions.take(idx))
    log = [f"frames {frames[0]}..{frames[-1]} ({frames.size}); render {len(pick)}: {pick}"]
    if len(keep) > len(pick):
        log.append(f"video frames (every {step}th row, {', '.join(views)}): "
                   f"{len(keep) - len(pick)} more")
    log += [f"recording warning: {w}" for w in getattr(rec, "warnings", ())]
    return StageOutput(rows=rows, files={"keyframes": (keyframes, ".npz")}, meta=meta, log=log)


def _png_bytes(srgb: np.ndarray, metadata: dict | None = None) -> bytes:
    """The frame's sRGB PNG (uint8 (H, W, 3)), encoded in memory (no temporary file per frame)."""
    from cassi.renderer.images import png_bytes  # noqa: PLC0415

    return png_bytes(srgb, metadata=metadata, linear=False)


class StoredFrame:
    """A rendered frame as the image checks need it, rebuilt from a render job's outputs."""

    def __init__(self, mask: np.ndarray, depth: np.ndarray, part_names: tuple[str, ...]):
        self.mask, self.depth, self.part_names = mask, depth, part_names


def render_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """Render ``job.frames`` of ``job.view``.

    Outputs: one PNG per frame (``render-<frame>``) and, in the views the task's image checks
    judge, ``masks-<frame>`` (npz: ``mask`` uint8 (H, W) part ids, ``depth`` float32 (H, W)
    Parke units, ``part_names``). Nothing else reads masks, and a night's masks of every view
    were 6.9 GB written and hashed.
    """
    import io  # noqa: PLC0415

    from cassi.versions.registry import get_version  # noqa: PLC0415

    judged = job.view in image_views(job.task)

    data = np.load(io.BytesIO(inputs["keyframes"]))
    all_frames = data["frames"].tolist()
    positions = data["positions"]  # read once: each data[...] access decodes the array again
    corpus = get_corpus(ctx.corpus)
    profile = get_profile(corpus, job.subject)
    face = get_version_face(corpus, job.subject, profile, get_version(job.version))
    renderer = get_renderer(corpus, job.subject, face, job.view, ctx.preset, ctx.variant)
    files = {}
    seconds = 0.0
    for f in job.frames:
        res = renderer.render(positions[all_frames.index(f)])
        seconds += float(getattr(res, "render_s", 0.0))
        meta = {"subject": job.subject, "task": job.task, "rep": job.rep,
                "version": job.version, "view": job.view, "frame": f,
                "synthetic": ctx.synthetic}
        files[f"render-{f:06d}"] = (_png_bytes(res.srgb8(), {**res.metadata(), **meta}), ".png")
        if not judged:
            continue
        mask = np.asarray(res.mask)
        if mask.max(initial=0) > 255:
            raise ValueError("more than 255 parts: masks are stored as uint8")
        files[f"masks-{f:06d}"] = (npz_bytes(mask=mask.astype(np.uint8),
                                             depth=np.asarray(res.depth, np.float32),
                                             part_names=np.asarray(res.part_names, dtype=str)),
                                   ".npz")
    return StageOutput(files=files, meta={"render_s": round(seconds, 3)},
                       log=[f"rendered {len(job.frames)} frame(s) of {job.view} "
                            f"({ctx.preset}, {renderer.variant}) in {seconds:.2f} s"])


def image_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """The rubric's image checks over every rendered frame of ``job.view`` (all chunks)."""
    import io  # noqa: PLC0415

    from cassi.harness import rubric  # noqa: PLC0415

    def frames():  # one frame's masks at a time: the checks keep a few numbers per frame
        for f in job.frames:
            d = np.load(io.BytesIO(inputs[f"masks-{f:06d}"]))
            yield int(f), StoredFrame(d["mask"].astype(np.int32), d["depth"],
                                      tuple(str(n) for n in d["part_names"]))

    rows = rubric.run_image_checks({job.view: frames()}, task=job.task, subject=job.subject,
                                   rep=job.rep, version=job.version)
    return StageOutput(rows=pd.DataFrame(rows),
                       log=[f"image checks on {len(job.frames)} frame(s): {len(rows)} row(s)"])


def cassi_pipeline(*, render: bool = True) -> Pipeline:
    """The real pipeline; ``render=False`` for geometry-only runs."""
    from cassi.harness.rubric import ratings_table  # noqa: PLC0415

    return Pipeline(geometry=geometry_stage, render=render_stage if render else None,
                    image=image_stage if render else None, ratings=ratings_table)


def catalog(corpus):
    """The names a run may use on ``corpus`` (:class:`cassi.harness.config.Catalog`)."""
    from cassi.renderer.views import PRESET_NAMES, VIEW_NAMES  # noqa: PLC0415
    from cassi.versions.registry import available_versions  # noqa: PLC0415

    from .config import Catalog  # noqa: PLC0415
    from .evalset import task_catalog  # noqa: PLC0415

    return Catalog(subjects=tuple(corpus.subjects), tasks=task_catalog(corpus),
                   versions=tuple(available_versions()), views=tuple(VIEW_NAMES),
                   presets=tuple(PRESET_NAMES))


def worker_env(threads: int | None = 1) -> None:
    """Set up a worker process: ``threads`` CPU threads for its native libraries.

    A farm worker is one core by default: the farm scales by processes, and a renderer that
    spread over every core in each of N workers would only make them fight (Dr.Jit's LLVM
    backend otherwise starts a thread per core in every process). None leaves the defaults.
    """
    if threads is None:
        return
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, str(threads))
    try:
        import drjit  # noqa: PLC0415

        drjit.set_thread_count(int(threads))
    except (ImportError, AttributeError, RuntimeError):
        pass


def warm_worker(corpus: str | None, subject: str, views=(), preset: str = "preview",
                variant: str | None = None, threads: int | None = 1) -> None:
    """:func:`worker_env`, then fill this process's caches for ``subject`` (corpus, profile,
    face, one renderer per view, its kernels compiled by one render), so that timings after it
    describe the steady state (``cassi bench``)."""
    worker_env(threads)
    c = get_corpus(corpus)
    profile = get_profile(c, subject)
    face = get_face(c, subject, profile)
    get_neutral()
    for view in views:
        get_renderer(c, subject, face, view, preset, variant).render(np.asarray(face.vertices))
