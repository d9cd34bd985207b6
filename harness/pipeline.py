"""The CASSI stages: versions -> rubric geometric checks -> renderer -> image checks -> ratings.

Each stage is a module-level function ``stage(job, ctx, inputs) -> StageOutput`` run inside a
worker process (:func:`cassi.harness.jobs.execute_job`). Worker processes live for the whole run,
so the per-process caches below keep a corpus, a subject's profile and face, and one
:class:`~cassi.renderer.FaceRenderer` (one Mitsuba scene) per (subject, view, preset) across the
jobs the process runs, instead of rebuilding them per job.
"""
from __future__ import annotations

import inspect
import os
import tempfile
import threading
from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd

from cassi.data.errors import CassiInputError

from .jobs import Job, SkipJob, StageContext, StageOutput, npz_bytes, select_frames
from .runner import Pipeline

#: At most this many "extreme" frames per geometry job (the worst frame of the checks that
#: fired, most negatives first), so renders stay bounded on long tasks.
MAX_EXTREMES = 8

_lock = threading.Lock()
_corpora: dict[str, object] = {}
_profiles: dict[tuple[str, str], object] = {}
_faces: dict[tuple[str, str], object] = {}
_renderers: dict[tuple, object] = {}


def corpus_root(corpus: Path | str | None) -> Path:
    """``corpus``, or the embedded default (synthetic) corpus when None."""
    if corpus is not None:
        return Path(corpus)
    from cassi.data.synth import default_corpus  # noqa: PLC0415 - generated on first use

    return Path(default_corpus())


def get_corpus(corpus: Path | str | None):
    from cassi.data.corpus import Corpus  # noqa: PLC0415

    root = str(corpus_root(corpus))
    with _lock:
        if root not in _corpora:
            _corpora[root] = Corpus(root)
        return _corpora[root]


def get_profile(corpus, subject: str):
    from cassi.data.profile import preprocess  # noqa: PLC0415

    key = (str(corpus.root), subject)
    if key not in _profiles:
        _profiles[key] = preprocess(corpus, [subject])[subject]
    return _profiles[key]


def get_face(corpus, subject: str, profile):
    from cassi.data.face import build_face  # noqa: PLC0415

    key = (str(corpus.root), subject)
    if key not in _faces:
        _faces[key] = build_face(palate_mm=getattr(profile, "palate_mm", None),
                                 head_measures=getattr(profile, "head_measures", None))
    return _faces[key]


def get_renderer(corpus, subject: str, face, view: str, preset: str, variant: str | None):
    """The process's renderer for (subject, view, preset): its Mitsuba scene is loaded once."""
    from cassi.data.face import render_topology  # noqa: PLC0415
    from cassi.renderer.render import FaceRenderer  # noqa: PLC0415

    key = (str(corpus.root), subject, view, preset, variant)
    if key not in _renderers:
        topology = render_topology(face, half=(view == "half"))
        _renderers[key] = FaceRenderer(topology, view, preset, variant)
    return _renderers[key]


def cache_sizes() -> dict[str, int]:
    """How much each per-process cache holds (tests check renderer reuse)."""
    return {"corpora": len(_corpora), "profiles": len(_profiles), "faces": len(_faces),
            "renderers": len(_renderers)}


def _call(func, /, *args, **kwargs):
    """Call ``func`` with the keyword arguments its signature accepts."""
    try:
        params = inspect.signature(func).parameters
    except (TypeError, ValueError):
        return func(*args, **kwargs)
    if any(p.kind is p.VAR_KEYWORD for p in params.values()):
        return func(*args, **kwargs)
    return func(*args, **{k: v for k, v in kwargs.items() if k in params})


def extreme_frames(rows: pd.DataFrame, *, limit: int = MAX_EXTREMES) -> list[int]:
    """Frames the geometric checks point at: per check that earned negatives on some frame,
    its worst frame (largest |value| among the frames with the most negatives)."""
    if rows is None or not len(rows) or "frame" not in rows:
        return []
    per_frame = rows[(rows["frame"] >= 0) & (rows["negatives"].fillna(0) > 0)].copy()
    if per_frame.empty:
        return []
    per_frame["abs"] = pd.to_numeric(per_frame["value"], errors="coerce").abs().fillna(0)
    per_frame = per_frame.sort_values(["check", "negatives", "abs", "frame"],
                                      ascending=[True, False, False, True])
    worst = per_frame.groupby("check", sort=True).head(1)
    worst = worst.sort_values(["negatives", "abs", "check"], ascending=[False, False, True])
    return sorted({int(f) for f in worst["frame"].head(limit)})


def _usable_or_skip(subject_data, job: Job) -> None:
    try:
        u = subject_data.usability(job.task, job.rep)
    except CassiInputError as err:
        raise SkipJob(str(err)) from err
    if not u.usable:
        raise SkipJob("; ".join(u.reasons) or "task file not usable")


def geometry_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """Animate every frame, run the geometric checks, choose and keep the frames to render.

    Outputs: ``rows`` (the checks' rows, view ``"geometry"``), ``keyframes`` (npz: ``frames``
    int64 (K,) recording rows, ``positions`` float32 (K, V, 3) Parke units) and
    ``meta["render_frames"]``.
    """
    from cassi.harness import rubric  # noqa: PLC0415
    from cassi.versions.registry import get_version  # noqa: PLC0415

    corpus = get_corpus(ctx.corpus)
    subject = corpus.subject(job.subject)
    _usable_or_skip(subject, job)
    rec = subject.load(job.task, job.rep)
    try:
        profile = get_profile(corpus, job.subject)
    except CassiInputError as err:
        raise SkipJob(f"subject cannot be preprocessed: {err}") from err
    face = get_face(corpus, job.subject, profile)
    anim = get_version(job.version).animate(profile, face, rec)
    rows = _call(rubric.run_geometry_checks, anim, face, profile, recording=rec,
                 version=job.version, subject=job.subject)
    rows = pd.DataFrame(rows)
    frames = np.asarray(anim.frames, dtype=np.int64)
    if frames.size == 0:
        raise SkipJob("the version animated no frame")
    pick = select_frames(int(frames[0]), int(frames[-1]), stride=ctx.stride,
                         extremes=extreme_frames(rows))
    pick = [f for f in pick if f in set(frames.tolist())]
    idx = np.searchsorted(frames, pick)
    keyframes = npz_bytes(frames=np.asarray(pick, np.int64),
                          positions=np.asarray(anim.positions[idx], np.float32))
    log = [f"frames {frames[0]}..{frames[-1]} ({frames.size}); render {len(pick)}: {pick}"]
    log += [f"recording warning: {w}" for w in getattr(rec, "warnings", ())]
    return StageOutput(rows=rows, files={"keyframes": (keyframes, ".npz")},
                       meta={"render_frames": pick, "n_frames": int(frames.size)}, log=log)


def _png_bytes(rgb: np.ndarray, metadata: dict | None = None) -> bytes:
    from cassi.renderer.images import write_png  # noqa: PLC0415

    with tempfile.TemporaryDirectory(prefix="cassi-png-") as tmp:
        path = Path(tmp) / "frame.png"
        write_png(path, rgb, metadata=metadata)
        return path.read_bytes()


def render_stage(job: Job, ctx: StageContext, inputs: Mapping[str, bytes]) -> StageOutput:
    """Render ``job.frames`` of ``job.view`` and run the image checks on them.

    Outputs: ``rows`` (image checks, per frame), one PNG per frame named ``render-<frame>``.
    """
    import io  # noqa: PLC0415

    from cassi.harness import rubric  # noqa: PLC0415

    data = np.load(io.BytesIO(inputs["keyframes"]))
    all_frames = data["frames"].tolist()
    corpus = get_corpus(ctx.corpus)
    profile = get_profile(corpus, job.subject)
    face = get_face(corpus, job.subject, profile)
    renderer = get_renderer(corpus, job.subject, face, job.view, ctx.preset, ctx.variant)
    files, rendered = {}, []
    for f in job.frames:
        res = renderer.render(data["positions"][all_frames.index(f)])
        rendered.append((f, res))
        meta = {"subject": job.subject, "task": job.task, "rep": job.rep,
                "version": job.version, "frame": f}
        files[f"render-{f:06d}"] = (_png_bytes(res.rgb, meta), ".png")
    rows = _call(rubric.run_image_checks, rendered, view=job.view, face=face, profile=profile,
                 version=job.version, subject=job.subject)
    return StageOutput(rows=pd.DataFrame(rows), files=files,
                       log=[f"rendered {len(rendered)} frame(s) of {job.view}"])


def _rubric_attr(name: str):
    try:
        from cassi.harness import rubric  # noqa: PLC0415
    except ImportError:
        return None
    return getattr(rubric, name, None)


def cassi_pipeline(*, render: bool = True) -> Pipeline:
    """The real pipeline; ``render=False`` for geometry-only runs."""
    return Pipeline(geometry=geometry_stage, render=render_stage if render else None,
                    aggregate=_rubric_attr("aggregate"), rate=_rubric_attr("rate"))


def catalog(corpus):
    """The names a run may use on ``corpus`` (:class:`cassi.harness.config.Catalog`)."""
    from cassi.renderer.views import PRESET_NAMES, VIEW_NAMES  # noqa: PLC0415
    from cassi.versions.registry import available_versions  # noqa: PLC0415

    from .config import Catalog  # noqa: PLC0415
    from .evalset import task_catalog  # noqa: PLC0415

    return Catalog(subjects=tuple(corpus.subjects), tasks=task_catalog(corpus),
                   versions=tuple(available_versions()), views=tuple(VIEW_NAMES),
                   presets=tuple(PRESET_NAMES))


def worker_env() -> None:
    """Environment a worker needs before importing Mitsuba (LLVM for the llvm variants)."""
    llvm = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
    if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(llvm):
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm
