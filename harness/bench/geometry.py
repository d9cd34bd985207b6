"""Geometry benchmark: frames per second of every registered version on one long task.

Registered as ``geometry`` in :data:`cassi.harness.bench.BENCHMARKS`. The task is generated here
(deterministic): JW45's first valid row of task 13 (thesis Figure 3.9) moved by jaw wagging, lip
protrusion and tongue motion at XRMB's 145.6 rows/s; the subject is JW45's published profile
(maxprotru.txt and lipthick.txt, thesis Figures 4.16 and 4.25). numpy's element-wise work runs
on one core, so the figure is a one-core figure.
"""
from __future__ import annotations

import time
import traceback

import numpy as np

from cassi.data.corpus.profile import SubjectProfile
from cassi.data.face.model import build_face
from cassi.data.synth.subjects import subject_figures
from cassi.data.xrmb.files import NOMINAL_PERIOD_US, TaskRecording
from cassi.versions.registry import available_versions, get_version

__all__ = ["bench_geometry", "long_task", "bench_profile", "bench_face"]

#: Frames of the long task (about 137 s of XRMB data for the full run).
FULL_FRAMES = 20_000
QUICK_FRAMES = 4_000  # --quick: a few seconds per version, enough to see a regression
#: JW45 task 13, 27464 us (thesis Figure 3.9), mm, PELLETS order.
_JW45_ROW = np.array([[15.757, 11.596], [12.175, -9.772], [-7.786, 5.158], [-27.477, 11.512],
                      [-42.758, 9.180], [-54.294, 0.829], [-0.699, -7.452], [-34.792, -9.862]])


def long_task(n_frames: int, *, seed: int = 0):
    """A deterministic :class:`~cassi.data.xrmb.files.TaskRecording` of ``n_frames`` rows."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames, dtype=np.float64)
    xy = np.broadcast_to(_JW45_ROW, (n_frames, 8, 2)).copy()
    theta = np.radians(10.0) * 0.5 * (1 - np.cos(2 * np.pi * t / 90.0))     # jaw wagging
    pivot = np.array([-75.0, 12.0])
    c, s = np.cos(theta), np.sin(theta)
    for p in (6, 7):
        rel = _JW45_ROW[p] - pivot
        xy[:, p, 0] = rel[0] * c + rel[1] * s + pivot[0]
        xy[:, p, 1] = rel[1] * c - rel[0] * s + pivot[1]
    xy[:, 1] += xy[:, 6] - _JW45_ROW[6]                                         # lower lip on the jaw
    xy[:, 0, 0] += 4.0 * np.sin(2 * np.pi * t / 300.0)                           # protrusion
    xy[:, 1, 0] += 3.0 * np.sin(2 * np.pi * t / 300.0)
    xy[:, 2:6] += 2.0 * np.sin(2 * np.pi * t[:, None, None] / 70.0) + rng.normal(0, .1, (n_frames, 4, 2))
    valid = np.ones((n_frames, 8), dtype=bool)
    valid[:3] = False                      # real files start with invalid rows
    xy[~valid] = np.nan
    return TaskRecording(path=None, subject="JW45", task=106, rep=1,
                         time_us=(np.arange(n_frames) * NOMINAL_PERIOD_US).astype(np.int64),
                         xy_mm=xy, valid=valid)


def bench_profile():
    """JW45's published profile (thesis Figures 4.16, 4.25), jaw length from Figure 3.9's row,
    and the synthetic corpus's JW45 pharynx outline (the thesis does not print a PHA.DAT; versions
    that place the tongue's back along it need one)."""
    d = float(np.hypot(*(_JW45_ROW[6] - _JW45_ROW[7])))
    return SubjectProfile(subject="JW45", jaw_length_mm=d, rest_ul=0.462957, rest_ll=0.355955,
                          max_ul=0.692150, max_ll=0.564495, min_ul=0.010773, min_ll=0.008101,
                          lipthick=0.619474,
                          pharynx_mm=subject_figures("JW45").pharynx_outline())


def bench_face():
    """The neutral face model (``cassi.data.face.model.build_face()``) at the bench profile's
    scale (its jaw length), as the versions animate it."""
    return build_face(jaw_length_mm=bench_profile().jaw_length_mm)


def bench_geometry(quick: bool = False, *, face=None, frames: int | None = None,
                   versions: list[str] | None = None) -> dict:
    """Frames per second of every registered version on one long task.

    Parameters
    ----------
    quick : bool
        A shorter task and fewer repeats.
    face : FaceModel, optional
        Default: the neutral face model.
    frames : int, optional
        Rows of the task (default 20,000; 4,000 when quick).
    versions : list of str, optional
        Default: every registered version.

    Returns
    -------
    dict
        ``geometry_frames_per_s``: {version: frames/s (best of the repeats)}; ``frames``,
        ``vertices``, ``repeats``, ``seconds`` {version: best wall time}; ``errors``
        {version: message} for a version that failed.
    """
    n = int(frames or (QUICK_FRAMES if quick else FULL_FRAMES))
    repeats = 2 if quick else 3
    rec, profile = long_task(n), bench_profile()
    face = bench_face() if face is None else face
    fps: dict[str, float] = {}
    seconds: dict[str, float] = {}
    errors: dict[str, str] = {}
    for name in (versions or available_versions()):
        try:
            version = get_version(name)
            version.animate(profile, face, long_task(64))            # warm up imports, caches
            best = np.inf
            for _ in range(repeats):
                t0 = time.perf_counter()
                anim = version.animate(profile, face, rec)
                best = min(best, time.perf_counter() - t0)
            fps[name] = round(anim.n_frames / best, 1)
            seconds[name] = round(best, 4)
        except Exception as err:  # noqa: BLE001 - one failing version must not hide the others
            errors[name] = f"{type(err).__name__}: {err} | " + " / ".join(
                traceback.format_exc().splitlines()[-3:])
    return {"geometry_frames_per_s": fps, "frames": int(n - 3), "vertices": int(len(face.vertices)),
            "repeats": repeats, "seconds": seconds, "errors": errors, "goal_frames_per_s": 20_000}
