"""Kinematic statistics of XRMB recordings: how a corpus moves (``cassi corpus stats``).

Arrays in, numbers out. Every figure is computed from the rows where the pellets concerned are
valid, from each file's first valid row on (thesis 3.2.5: the rows before it are the tracker
starting up). Coordinates are the XRMB head frame (thesis 3.2.3): millimetres, x forward, y up,
origin at the tip of the upper central incisors, so a y is a height relative to the incisor tip.

Per pellet (:data:`PELLET_COLUMNS`):

- ``speed_p50``, ``speed_p90``, ``speed_p99`` (mm/s): percentiles of the speed between
  consecutive valid rows (distance over the rows' own time difference), pooled over files;
- ``x_range``, ``y_range`` (mm): the extent (max - min) of the pellet in one file, median over
  files;
- ``d2_rms_um`` (micrometres): root mean square of the second difference
  ``p[t+1] - 2 p[t] + p[t-1]`` per coordinate, over triples of consecutive valid rows, pooled:
  acceleration times the squared row period plus tracking noise. At rest it is the noise (real
  JW45, thesis Figure 3.9: 1-7 um); in speech the movement adds to it (an acceleration of
  1000 mm/s^2 is 47 um at 145.6 Hz). It is a figure per row, kept so because its rest part is
  the tracker's noise per sample: at another rate the movement part scales with the squared
  period (at 500 Hz, 1000 mm/s^2 is 4 um), so compare it only between recordings of one rate.
  The speeds divide by the rows' own time differences and are the same at any rate.

Whole-recording figures (:data:`SCALARS`):

- ``jaw_distance_mean``, ``jaw_distance_median`` (mm) and ``jaw_distance_sd`` (mm): the MNI-MNM
  distance, mean and median over all valid rows, and its within-file standard deviation (root
  mean of the per-file variances): the jaw is rigid, so the SD is tracking noise;
- ``mni_y_p95``, ``mni_y_median``, ``mni_y_p05`` (mm): height of the lower incisor pellet MNI
  relative to the upper incisor tip over all valid rows: near the closed jaw, typical, and wide
  open (the jaw opening);
- ``lip_mid_first``, ``lip_mid_mean``, ``lip_mid_median``, ``lip_mid_p05`` (mm): height of the
  midpoint of the UL and LL pellets relative to the incisor tip, at the first valid row (mean
  over files), and the mean, median and 5th percentile over all valid rows (where speech takes
  it);
- ``ul_ll_first``, ``ul_ll_median``, ``ul_ll_p01``, ``ul_ll_p001`` (mm): the UL-LL distance at
  the first valid row (mean over files; thesis Figure 4.25 divides it by the jaw length), and its
  median, 1st and 0.1th percentile over all rows (the lips pressed together);
- ``ul_back_wide_jaw`` (mm): how far the upper lip sits back when the jaw is open wide: the UL
  x median over all rows minus its median over the rows where the jaw is open wider than in 99 %
  of them (MNI y below its 1st percentile); > 0: the lip is drawn back.

A frame set (:mod:`cassi.data.xrmb.frames`: frames without times, not necessarily consecutive)
gives the distributions only (:func:`frame_set_stats`): the figures that need consecutive rows
(speeds, second differences), whole files (ranges, within-file SD) or a first row are undefined.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.data.corpus.disk import Corpus
from cassi.data.xrmb.files import PELLETS, read_txy
from cassi.data.xrmb.frames import is_frame_set, read_frames

__all__ = ["PELLET_COLUMNS", "SCALARS", "KinematicStats", "compare", "corpus_stats",
           "frame_set_stats", "recording_stats", "summarise"]

PELLET_COLUMNS = ("speed_p50", "speed_p90", "speed_p99", "x_range", "y_range", "d2_rms_um")
SCALARS = ("jaw_distance_mean", "jaw_distance_median", "jaw_distance_sd", "mni_y_p95",
           "mni_y_median", "mni_y_p05", "lip_mid_first", "lip_mid_mean", "lip_mid_median",
           "lip_mid_p05", "ul_ll_first", "ul_ll_median", "ul_ll_p01", "ul_ll_p001",
           "ul_back_wide_jaw")
#: Units of every figure, for tables and JSON.
UNITS = {"speed_p50": "mm/s", "speed_p90": "mm/s", "speed_p99": "mm/s", "x_range": "mm",
         "y_range": "mm", "d2_rms_um": "um", **{k: "mm" for k in SCALARS}}
_UL, _LL, _MNI, _MNM = (PELLETS.index(p) for p in ("UL", "LL", "MNI", "MNM"))


@dataclass
class _Samples:
    """What one or more recordings contribute; merged before the figures are taken."""

    speeds: list[list[np.ndarray]] = field(default_factory=lambda: [[] for _ in PELLETS])
    ranges: list[list[tuple[float, float]]] = field(default_factory=lambda: [[] for _ in PELLETS])
    d2_sq: np.ndarray = field(default_factory=lambda: np.zeros(len(PELLETS)))
    d2_n: np.ndarray = field(default_factory=lambda: np.zeros(len(PELLETS), np.int64))
    jaw: list[np.ndarray] = field(default_factory=list)
    jaw_var: list[float] = field(default_factory=list)
    mni_y: list[np.ndarray] = field(default_factory=list)
    lip_mid: list[np.ndarray] = field(default_factory=list)
    ul_ll: list[np.ndarray] = field(default_factory=list)
    ul_x_mni_y: list[np.ndarray] = field(default_factory=list)  # (n, 2) where both are valid
    lip_mid_first: list[float] = field(default_factory=list)
    ul_ll_first: list[float] = field(default_factory=list)
    files: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class KinematicStats:
    """Statistics of a set of recordings.

    Attributes
    ----------
    pellets : DataFrame
        Index :data:`~cassi.data.xrmb.files.PELLETS`, columns :data:`PELLET_COLUMNS` (NaN where a
        pellet has too few valid rows).
    scalars : dict
        :data:`SCALARS` -> float (NaN when undefined).
    n_files : int
    label : str
        What was measured (a path), for tables.
    n_frames : int
        Frames measured in a frame set; 0 for task files.
    """

    pellets: pd.DataFrame
    scalars: dict[str, float]
    n_files: int
    label: str = ""
    n_frames: int = 0

    def as_dict(self) -> dict:
        """JSON-ready: ``{"label", "n_files", "n_frames", "units", "pellets": {UL: {...}},
        "scalars"}``."""
        def num(v):
            return None if v is None or not math.isfinite(v) else round(float(v), 6)
        return {"label": self.label, "n_files": self.n_files, "n_frames": self.n_frames,
                "units": UNITS,
                "pellets": {p: {c: num(self.pellets.at[p, c]) for c in PELLET_COLUMNS}
                            for p in self.pellets.index},
                "scalars": {k: num(v) for k, v in self.scalars.items()}}


def _add(s: _Samples, time_us: np.ndarray, xy_mm: np.ndarray, valid: np.ndarray,
         label: str) -> None:
    """Add one recording from its first valid row on; raises CassiInputError without one."""
    all_ok = valid.all(axis=1)
    rows = np.flatnonzero(all_ok)
    if rows.size == 0:
        raise CassiInputError("no row has all eight pellets valid", path=label or None)
    i0 = int(rows[0])
    t = time_us[i0:].astype(np.float64) * 1e-6
    xy, ok = xy_mm[i0:], valid[i0:]
    dt = np.diff(t)
    for p in range(len(PELLETS)):
        q, m = xy[:, p], ok[:, p]
        pair = m[1:] & m[:-1]
        v = np.hypot(*(q[1:] - q[:-1]).T) / dt
        s.speeds[p].append(v[pair])
        if m.any():
            good = q[m]
            s.ranges[p].append((float(np.ptp(good[:, 0])), float(np.ptp(good[:, 1]))))
        trip = m[2:] & m[1:-1] & m[:-2]
        d2 = (q[2:] - 2.0 * q[1:-1] + q[:-2])[trip]
        s.d2_sq[p] += float(np.square(d2).sum())
        s.d2_n[p] += d2.size
    d = _add_distributions(s, xy, ok)
    if d.size > 1:
        s.jaw_var.append(float(np.var(d)))
    s.lip_mid_first.append(0.5 * float(xy[0, _UL, 1] + xy[0, _LL, 1]))
    s.ul_ll_first.append(float(np.hypot(*(xy[0, _UL] - xy[0, _LL]))))
    s.files.append(label)


def _add_distributions(s: _Samples, xy: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Add the rows' jaw distance, MNI height, lip midpoint and UL-LL distance (each where its
    pellets are valid); return the jaw distances."""
    jaw_ok = ok[:, _MNI] & ok[:, _MNM]
    d = np.hypot(*(xy[jaw_ok, _MNI] - xy[jaw_ok, _MNM]).T)
    s.jaw.append(d)
    s.mni_y.append(xy[ok[:, _MNI], _MNI, 1])
    lips_ok = ok[:, _UL] & ok[:, _LL]
    s.lip_mid.append(0.5 * (xy[lips_ok, _UL, 1] + xy[lips_ok, _LL, 1]))
    s.ul_ll.append(np.hypot(*(xy[lips_ok, _UL] - xy[lips_ok, _LL]).T))
    both = ok[:, _UL] & ok[:, _MNI]
    s.ul_x_mni_y.append(np.stack([xy[both, _UL, 0], xy[both, _MNI, 1]], axis=1))
    return d


def _ul_back_wide_jaw(ul_x_mni_y: np.ndarray) -> float:
    """UL x median over all rows minus over the rows with MNI y below its 1st percentile."""
    if ul_x_mni_y.shape[0] < 100:  # a 1st percentile needs rows
        return float("nan")
    ul_x, mni_y = ul_x_mni_y[:, 0], ul_x_mni_y[:, 1]
    wide = mni_y < np.percentile(mni_y, 1)
    return float(np.median(ul_x) - np.median(ul_x[wide]))


def _figures(s: _Samples, label: str, n_frames: int = 0) -> KinematicStats:
    nan = float("nan")
    rows = []
    for p in range(len(PELLETS)):
        v = np.concatenate(s.speeds[p]) if s.speeds[p] else np.empty(0)
        pct = np.percentile(v, [50, 90, 99]) if v.size else [nan] * 3
        rng = np.array(s.ranges[p]) if s.ranges[p] else np.full((1, 2), nan)
        d2 = math.sqrt(s.d2_sq[p] / s.d2_n[p]) * 1000.0 if s.d2_n[p] else nan
        rows.append([*map(float, pct), float(np.median(rng[:, 0])), float(np.median(rng[:, 1])),
                     d2])
    table = pd.DataFrame(rows, index=list(PELLETS), columns=list(PELLET_COLUMNS))

    def cat(parts):
        return np.concatenate(parts) if parts else np.empty(0)

    jaw, mid, dist, mni_y = cat(s.jaw), cat(s.lip_mid), cat(s.ul_ll), cat(s.mni_y)

    def stat(fn, a, *args):
        return float(fn(a, *args)) if a.size else nan

    scalars = {
        "jaw_distance_mean": stat(np.mean, jaw),
        "jaw_distance_median": stat(np.median, jaw),
        "jaw_distance_sd": math.sqrt(float(np.mean(s.jaw_var))) if s.jaw_var else nan,
        "mni_y_p95": stat(np.percentile, mni_y, 95),
        "mni_y_median": stat(np.median, mni_y),
        "mni_y_p05": stat(np.percentile, mni_y, 5),
        "lip_mid_first": stat(np.mean, np.array(s.lip_mid_first)),
        "lip_mid_mean": stat(np.mean, mid),
        "lip_mid_median": stat(np.median, mid),
        "lip_mid_p05": stat(np.percentile, mid, 5),
        "ul_ll_first": stat(np.mean, np.array(s.ul_ll_first)),
        "ul_ll_median": stat(np.median, dist),
        "ul_ll_p01": stat(np.percentile, dist, 1),
        "ul_ll_p001": stat(np.percentile, dist, 0.1),
        "ul_back_wide_jaw": _ul_back_wide_jaw(cat(s.ul_x_mni_y)),
    }
    return KinematicStats(table, scalars, len(s.files), label, n_frames)


def summarise(time_us, xy_mm, valid=None, *, label: str = "") -> KinematicStats:
    """Statistics of one recording given as arrays.

    Parameters
    ----------
    time_us : (F,) sample times, microseconds, strictly increasing.
    xy_mm : (F, 8, 2) pellets in :data:`~cassi.data.xrmb.files.PELLETS` order, mm.
    valid : bool (F, 8), optional; default: where ``xy_mm`` is finite.
    label : what the arrays are (names the source in errors and tables).

    Raises
    ------
    CassiInputError : wrong shapes, or no row with all eight pellets valid.
    """
    t = np.asarray(time_us)
    xy = np.asarray(xy_mm, dtype=np.float64)
    if xy.ndim != 3 or xy.shape[1:] != (len(PELLETS), 2) or t.shape != xy.shape[:1]:
        raise CassiInputError(f"expected time (F,) and pellets (F, 8, 2), got {t.shape} and "
                              f"{xy.shape}", path=label or None)
    ok = np.isfinite(xy).all(axis=2) if valid is None else np.asarray(valid, bool)
    if ok.shape != xy.shape[:2]:
        raise CassiInputError(f"valid must be (F, 8), got {ok.shape}", path=label or None)
    if t.size > 1 and not (np.diff(t) > 0).all():
        raise CassiInputError("sample times must increase", path=label or None)
    s = _Samples()
    _add(s, t, xy, ok, label)
    return _figures(s, label)


def frame_set_stats(frames_mm, *, label: str = "") -> KinematicStats:
    """The distributions of a frame set (frames without times, :mod:`cassi.data.xrmb.frames`).

    Parameters
    ----------
    frames_mm : (F, 8, 2) pellets in :data:`~cassi.data.xrmb.files.PELLETS` order, mm; NaN where
        a value is bad (each figure uses the frames where its pellets are valid).
    label : what the frames are (names the source in errors and tables).

    Returns
    -------
    KinematicStats with ``n_files`` 0 and ``n_frames`` F: the jaw distance's mean and median,
    MNI heights, lip midpoints and UL-LL distances; every other figure NaN.
    """
    xy = np.asarray(frames_mm, dtype=np.float64)
    if xy.ndim != 3 or xy.shape[1:] != (len(PELLETS), 2):
        raise CassiInputError(f"expected frames (F, 8, 2), got {xy.shape}", path=label or None)
    s = _Samples()
    _add_distributions(s, xy, np.isfinite(xy).all(axis=2))
    return _figures(s, label, n_frames=xy.shape[0])


def recording_stats(recs, *, label: str = "") -> KinematicStats:
    """Statistics pooled over :class:`~cassi.data.xrmb.files.TaskRecording` objects.

    Raises CassiInputError when there is no recording or one has no valid row.
    """
    s = _Samples()
    for rec in recs:
        _add(s, rec.time_us, rec.xy_mm, rec.valid, str(rec.path) if rec.path else rec.subject)
    if not s.files:
        raise CassiInputError("no task file to measure", path=label or None)
    return _figures(s, label)


def _selected(path: Path, tasks: set[int] | None):
    """Recordings under ``path`` (corpus, subject directory or task file) worth measuring.

    In a directory: every task file with a valid row whose task is not listed in its subject's
    Mis.dat (logged mistracking would be measured as movement); pellets lost without a log are
    masked row by row. ``tasks`` restricts the task numbers.
    """
    if not path.exists():
        raise CassiInputError("not found", path=path)
    if path.is_file():
        if not path.name.lower().endswith(".txy"):
            raise CassiInputError("expected a corpus directory, a subject directory, a "
                                  "*.txy task file or a frame set (.npy, .mat)", path=path)
        yield read_txy(path)
        return
    corpus = Corpus(path)
    if corpus.problems:
        raise CassiInputError(corpus.problems[0])
    if not corpus.subjects:
        raise CassiInputError("no subject directory with task files", path=path)
    for name in corpus.subjects:
        subj = corpus.subject(name)
        listed = subj.mistracked_tasks
        for task, rep in subj.tasks():
            if (tasks is not None and task not in tasks) or task in listed:
                continue
            rec = subj.load(task, rep, require_valid=False)
            if rec.first_valid_index is not None:
                yield rec


def corpus_stats(path, *, tasks=None) -> KinematicStats:
    """Statistics of a corpus, a subject directory, one task file or a frame set.

    Parameters
    ----------
    path : path-like
        A frame set is a ``.npy`` or ``.mat`` file (:func:`frame_set_stats`).
    tasks : iterable of int, optional
        Only these task numbers (e.g. ``[105]`` for the "sa sa sa" repetitions); a frame set has
        none.

    Raises
    ------
    CassiInputError : a malformed file (``file:line: reason``), nothing to measure, tasks asked
        of a frame set.
    """
    p = Path(path)
    if is_frame_set(p):
        if tasks is not None:
            raise CassiInputError("a frame set has no task numbers: leave out --tasks", path=p)
        return frame_set_stats(read_frames(p), label=str(p))
    keep = None if tasks is None else {int(t) for t in tasks}
    return recording_stats(_selected(p, keep), label=str(p))


def compare(a: KinematicStats, b: KinematicStats) -> pd.DataFrame:
    """Side by side: one row per figure (``pellet``, ``figure``, ``unit``, ``a``, ``b``,
    ``ratio`` = a / b, NaN where b is 0 or either is undefined)."""
    rows = []
    for p in PELLETS:
        for c in PELLET_COLUMNS:
            rows.append((p, c, a.pellets.at[p, c], b.pellets.at[p, c]))
    for k in SCALARS:
        rows.append(("", k, a.scalars[k], b.scalars[k]))
    df = pd.DataFrame(rows, columns=["pellet", "figure", "a", "b"])
    df.insert(2, "unit", [UNITS[c] for c in df["figure"]])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = df["a"].to_numpy(float) / df["b"].to_numpy(float)
    df["ratio"] = np.where(np.isfinite(ratio), ratio, np.nan)
    return df
