"""Geometric measures: one function per check, ``m_<check>(ctx) -> Measurement``, over one
animation (:class:`GeometryContext`).

The pure geometry (penetrations, gaps, angles) is in :mod:`.geometry`; the windows and
thresholds these measures use are declared, with their reasons, in :mod:`.registry`.
Measures are in millimetres (converted from Parke units with the subject's jaw length, thesis
4.1.1), degrees, or fractions of frames.
"""
from __future__ import annotations

import functools

import numpy as np
import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.files import NOMINAL_PERIOD_US, rows_spanning

from cassi.harness.rubric import geometry as G
from cassi.harness.rubric.frames import ArrayFrames, Frames
from cassi.harness.rubric.model import Measurement
from cassi.harness.rubric.registry import (CHECKS, END_SHARE, JAW_NEAR_CLOSED_MM, JITTER_ORDER, JITTER_WINDOW_MS,
                       LIPS_BELOW_TEETH_MM, MIN_FAULT_MS, MIN_FRAMES, OFTEN_PERCENTILE, TEETH_HOLD_MS,
                       WIDE_OPEN_MM,
                       WIDE_OPEN_SHARE)

#: The ``Animation.diagnostics`` columns a measure reads (the geometry stage keeps only these of
#: a long task: a version may report 50 columns, about 400 bytes a frame).
DIAGNOSTICS_READ = ("lips_overlap", "ellipse")
#: CASSI 2.1's per-task criterion values (``cassi.versions.lips.LowLipsThicknessPolicy``), kept
#: for the whole-task ``criterion`` row of :func:`cassi.harness.rubric.run.run_geometry_checks`.
CRITERION_DIAGNOSTICS = ("low_lips_margin", "low_lips_inside_edge", "low_lips_reading")


class GeometryContext:
    """One animation's positions with its mouth parts, units and cached measures.

    Parameters
    ----------
    positions : float (F, V, 3) or frames.Frames
        Parke units (``Animation.positions``), or a source that gives them a chunk of frames
        at a time (:mod:`.frames`): every measure reads per-frame series through
        :meth:`series` and single frames through :meth:`frame`, so memory holds one chunk.
    parts : geometry.MouthParts
    rest : float (V, 3)
        The face before initialization (``FaceModel.vertices``): the reference shape for
        cave-in, slope and clearance measures, so Parke's own profile never counts as a fault.
    mm_per_unit : float
        Millimetres per Parke unit.
    diagnostics : DataFrame or None
        ``Animation.diagnostics`` (``ellipse`` gives the switches between horizontal and
        vertical ellipse; ``lips_overlap`` the crossings a version handles).
    neutral : float (V, 3) or None
        Parke's neutral face (``build_face()``), the reference for an unusual jaw (Table B).
    task : int or None
    period_us : float
        The recording's sample period (:func:`~cassi.data.xrmb.files.recording_period_us`):
        the windows stated in ms (registry) become this recording's rows.
    """

    def __init__(self, positions, parts: G.MouthParts, *, rest=None, mm_per_unit: float = 1.0,
                 diagnostics: pd.DataFrame | None = None, neutral=None, task: int | None = None,
                 period_us: float = NOMINAL_PERIOD_US):
        self.frames = positions if isinstance(positions, Frames) else ArrayFrames(positions)
        if self.frames.n_frames < 1:
            raise CassiInputError("positions must be (F, V, 3) with at least one frame")
        finite = self.frames.series(lambda p: np.isfinite(p).all(axis=(1, 2)))
        if not finite.all():
            raise CassiInputError("positions contain NaN or infinite values")
        need = max(int(np.max(np.atleast_1d(v))) for v in vars(parts).values()
                   if isinstance(v, (int, np.integer, np.ndarray)) and np.size(v))
        if need >= self.frames.n_vertices:
            raise CassiInputError(f"positions have {self.frames.n_vertices} vertices; the mouth "
                                  f"parts use vertex row {need}")
        self.parts = parts
        self.rest = self.frame(0) if rest is None else np.asarray(rest, dtype=np.float64)
        self.mm = float(mm_per_unit)
        self.diagnostics = diagnostics
        self.neutral = None if neutral is None else np.asarray(neutral, dtype=np.float64)
        self.task = task
        # the registry's windows in this recording's rows (XRMB: 3, 15 and 9)
        self.min_frames = rows_spanning(MIN_FAULT_MS * 1000, period_us)
        self.teeth_hold_frames = rows_spanning(TEETH_HOLD_MS * 1000, period_us)
        self.jitter_window = rows_spanning(JITTER_WINDOW_MS * 1000, period_us, odd=True)

    @property
    def F(self) -> int:
        return self.frames.n_frames

    def series(self, fn, *args, halo: int = 0, **kwargs):
        """``fn(positions, *args)`` over every frame (see :meth:`frames.Frames.series`)."""
        return self.frames.series(fn, *args, halo=halo, **kwargs)

    def frame(self, i: int) -> np.ndarray:
        """float64 (V, 3): frame ``i``."""
        return self.frames.frame(i)

    @functools.cached_property
    def tongue(self) -> dict[str, np.ndarray]:
        """mm per frame: the tongue through the upper and the lower front teeth and the palate
        (:func:`geometry.tongue_penetrations`: the tongue sampled once for the three)."""
        d = self.series(G.tongue_penetrations, self.parts, rest=self.rest)
        return {k: v * self.mm for k, v in d.items()}

    @functools.cached_property
    def gap(self) -> np.ndarray:
        return self.series(G.inner_lip_gap, self.parts) * self.mm

    @functools.cached_property
    def handled_overlap(self) -> np.ndarray:
        """bool (F,): frames where the version reports it placed crossing lips itself (CASSI
        2.0's rule, thesis 4.2.2: inner outlines at equal distances from the centerline);
        diagnostics column ``lips_overlap``. All False when the version does not say."""
        d = self.diagnostics
        if d is None or "lips_overlap" not in d or len(d) != self.F:
            return np.zeros(self.F, bool)
        return d["lips_overlap"].fillna(False).to_numpy().astype(bool)

    @functools.cached_property
    def max_protrusion(self) -> int:
        return int(np.argmax(self.series(G.protrusion_sum, self.parts)))

    @functools.cached_property
    def jaw_near_closed(self) -> np.ndarray:
        """bool (F,): the jaw point (258) within JAW_NEAR_CLOSED_MM of its most closed (highest)
        position in the task."""
        jp = self.parts.jaw_point
        z = self.series(lambda p: p[:, jp, 2]) * self.mm
        return z >= z.max() - JAW_NEAR_CLOSED_MM

    @functools.cached_property
    def end_frames(self) -> np.ndarray:
        """The last END_SHARE of frames (at least MIN_FRAMES): "especially at its end" (Table 5.3)."""
        n = max(self.min_frames, int(round(END_SHARE * self.F)))
        return np.arange(max(0, self.F - n), self.F)



def sustained(series: np.ndarray, *, worst: str = "max", k: int = MIN_FRAMES) -> tuple[float, int]:
    """The k-th worst value of a per-frame series and the frame of the worst one.

    A fault "during the task" counts when it lasts :data:`MIN_FRAMES` frames; shorter series
    use their mildest frame.
    """
    s = np.asarray(series, dtype=np.float64)
    if s.size == 0:
        return float("nan"), -1
    order = np.argsort(-s if worst == "max" else s, kind="stable")
    k = min(k, s.size)
    return float(s[order[k - 1]]), int(order[0])


def _m_sustained(ctx, series, *, worst="max", detail="") -> Measurement:
    v, f = sustained(series, worst=worst, k=ctx.min_frames)
    return Measurement(v, f, detail, frame_value=float(np.asarray(series)[f]) if f >= 0 else None)


# ----------------------------------------------------------------------------------------------
# Geometric measures (ctx -> Measurement)
# ----------------------------------------------------------------------------------------------

def _teeth(ctx: GeometryContext, series: np.ndarray, *, closed_only: bool = False) -> Measurement:
    """A teeth fault "during the task, especially at its end" (thesis Table 5.3).

    The end is the median over the last frames (:attr:`GeometryContext.end_frames`); during the
    task a fault counts when it shows in TEETH_HOLD_FRAMES frames (a posture the eye catches,
    not a passing phase of the jaw) -- with ``closed_only`` only frames with the jaw near closed
    (:attr:`GeometryContext.jaw_near_closed`) count. The larger of the two is the value.
    """
    e = ctx.end_frames
    end = float(np.median(series[e]))
    during = np.flatnonzero(ctx.jaw_near_closed) if closed_only else np.arange(ctx.F)
    hold = ctx.teeth_hold_frames
    held, hf = sustained(series[during], k=hold)
    hf = int(during[hf]) if hf >= 0 else hf
    if not np.isfinite(held) or end >= held or len(during) < hold:
        f = int(e[np.argmax(series[e])])
        return Measurement(end, f, f"at the end: median over the last {len(e)} frames; held "
                                   f"during the task {held:.2f}", frame_value=float(series[f]))
    where = " with the jaw near closed" if closed_only else ""
    return Measurement(held, hf, f"during the task: in {hold} frames{where}; at the "
                                 f"end {end:.2f}", frame_value=float(series[hf]))


def m_teeth_front_overlap(ctx):
    front, _ = ctx.series(G.teeth_overlap, ctx.parts)
    return _teeth(ctx, front * ctx.mm)


def m_teeth_back_overlap(ctx):
    _, back = ctx.series(G.teeth_overlap, ctx.parts)
    _, back0 = G.teeth_overlap(ctx.rest[None], ctx.parts)
    return _teeth(ctx, (back - back0[0]) * ctx.mm)


def _slope(ctx):
    return ctx.series(G.teeth_slope, ctx.parts) - G.teeth_slope(ctx.rest[None], ctx.parts)[0]


def m_teeth_slope_up(ctx):
    return _teeth(ctx, _slope(ctx), closed_only=True)


def m_teeth_slope_down(ctx):
    return _teeth(ctx, -_slope(ctx), closed_only=True)


def m_teeth_apart(ctx):
    # the larger of the front gap and the back teeth's opening beyond rest: the half view shows
    # either (render review: CASSI 2.0's back teeth stand 5.5 mm apart while the incisors overlap)
    front = ctx.series(G.teeth_gap, ctx.parts)
    _, back = ctx.series(G.teeth_overlap, ctx.parts)
    _, back0 = G.teeth_overlap(ctx.rest[None], ctx.parts)
    return _teeth(ctx, np.maximum(front, -(back - back0[0])) * ctx.mm, closed_only=True)


def m_lips_never_touch(ctx):
    g = ctx.gap
    f = int(np.argmin(g))
    return Measurement(float(g[f]), f, "smallest gap between the lips' edges (61-58) in the task",
                       frame_value=float(g[f]))


def _at_ends(values, ctx, what: str):
    """The worse (larger) of a per-frame value at the first and the last frame: the two frames
    the judges examined for lip contact (thesis 5.3.1)."""
    f = 0 if values[0] >= values[-1] else ctx.F - 1
    return Measurement(float(values[f]), f, f"{what} at the first frame ({values[0]:.2f} mm) and the "
                                            f"last ({values[-1]:.2f} mm), the larger",
                       frame_value=float(values[f]))


def m_lips_apart_ends(ctx):
    return _at_ends(ctx.gap, ctx, "gap between the lips' edges")


def m_lips_pressed(ctx):
    return _at_ends(-ctx.gap, ctx, "how far the lips' edges cross")


def m_lips_overlap(ctx):
    cross = np.where(ctx.handled_overlap, np.minimum(-ctx.gap, 0.0), -ctx.gap)
    return _m_sustained(ctx, cross, detail="how far the lower lip's edge rises above the upper's, in "
                                      "frames where the version does not handle the overlap")


def m_lips_too_large_moving(ctx):
    crossing = ctx.gap < 0
    n = int(crossing.sum())
    if n == 0:
        return Measurement(float("nan"), -1, "the lips never cross")
    area = ctx.series(_outer_area, ctx.parts) / _outer_area(ctx.rest[None], ctx.parts)[0]
    idx = np.flatnonzero(crossing)
    v = float(np.percentile(area[idx], OFTEN_PERCENTILE))
    f = int(idx[np.argmax(area[idx])])
    handled = int(np.sum(ctx.handled_overlap & crossing))
    return Measurement(v, f, f"front-view lip area over the rest face's, {OFTEN_PERCENTILE}th percentile over the "
                             f"{n} frames where the lips cross ({handled} handled by the version)",
                       frame_value=float(area[f]))


def m_lower_lip_below_teeth(ctx):
    below = ctx.series(G.lower_lip_below_teeth, ctx.parts) * ctx.mm
    frac = float(np.mean(below > LIPS_BELOW_TEETH_MM))
    f = int(np.argmax(below))
    return Measurement(frac, f, f"lower lip edge (58) more than {LIPS_BELOW_TEETH_MM} mm below the "
                                f"lower gum line (258); deepest {below[f]:.2f} mm",
                       frame_value=float(below[f]))


def m_lips_through_teeth(ctx):
    d = ctx.series(G.lip_teeth_penetration, ctx.parts, rest=ctx.rest) * ctx.mm
    return _m_sustained(ctx, d, detail="lip vertices behind the front surface of the front teeth")


def m_lower_lip_protrudes(ctx):
    d = ctx.series(G.protrusion_difference, ctx.parts) * ctx.mm
    v = float(np.percentile(d, OFTEN_PERCENTILE))
    f = int(np.argmax(d))
    return Measurement(v, f, f"{OFTEN_PERCENTILE}th percentile over frames of x(49) - x(67)",
                       frame_value=float(d[f]))


def m_tongue_teeth(ctx):
    up, lo = ctx.tongue["upper"], ctx.tongue["lower"]
    du, fu = sustained(up, k=ctx.min_frames)
    dl, fl = sustained(lo, k=ctx.min_frames)
    c = CHECKS["tongue_through_teeth"]
    through = int(du > c.thresholds[0]) + int(dl > c.thresholds[0])
    # thesis Table 5.3: one front set 1, both 2, very noticeably through both 3
    neg = 3 if through == 2 and min(du, dl) > c.thresholds[-1] else through
    f = fu if du >= dl else fl
    return Measurement(max(du, dl), f, f"upper {du:.2f} mm, lower {dl:.2f} mm", negatives=neg,
                       frame_value=float(max(up[f], lo[f])))


def m_tongue_palate(ctx):
    d = ctx.tongue["palate"]
    return _m_sustained(ctx, d, detail="tongue above the palatal surface (not counted by the thesis)")


def m_tongue_back_v(ctx):
    t = ctx.parts.tongue
    if len(t) < 6:
        return Measurement(float("nan"), -1, "no tongue centre line")
    # centre line tip, T1-T4, back (numbering.TONGUE_CENTRE): the angle at T4 between T3 and
    # the anchored back vertex
    ang = ctx.series(G.profile_angle, t[3], t[4], t[5])
    return _m_sustained(ctx, ang, worst="min", detail="side-view angle T3-T4-back of the tongue "
                                                 "(not counted by the thesis)")


def m_palate_below_incisor(ctx):
    d = G.palate_below_incisor(ctx.frame(0), ctx.parts) * ctx.mm
    return Measurement(d, 0, "lowest palate vertex below vertex 226 at initialization", frame_value=d)


#: Table B's figures without Parke's neutral face to take them over.
_NO_NEUTRAL = Measurement(float("nan"), -1, "no neutral face to compare with")


def _has_neutral(ctx, *also: int) -> bool:
    """Whether Table B has Parke's neutral face to compare with: a jaw of at least three
    vertices, and the jaw's and ``also``'s vertices in it."""
    jaw = ctx.parts.jaw
    return (ctx.neutral is not None and len(jaw) >= 3
            and ctx.neutral.shape[0] > max((int(jaw.max()), *also)))


def _hull_area(p: np.ndarray) -> float:
    """Area of the convex hull of side-view points (N, 2); NaN when they are collinear."""
    from scipy.spatial import ConvexHull  # noqa: PLC0415 - only Table B needs it

    try:
        return float(ConvexHull(p).volume)
    except Exception:  # degenerate (collinear) points: no area to compare
        return float("nan")


def _jaw_squareness(v: np.ndarray, jaw: np.ndarray) -> float:
    """Extent of the jaw (14-43) seen from the side: hull area over its bounding box."""
    p = v[jaw][:, [0, 2]]
    box = float(np.ptp(p[:, 0]) * np.ptp(p[:, 1]))
    return _hull_area(p) / box if box > 0 else float("nan")


def m_jaw_square(ctx):
    """Squareness of the jaw alone: the version's initial jaw rotation is no shape change."""
    jaw = ctx.parts.jaw
    if not _has_neutral(ctx):
        return _NO_NEUTRAL
    # align the jaw to the neutral one (rotation and translation in the side view, Kabsch)
    a = ctx.frame(0)[jaw][:, [0, 2]]
    b = ctx.neutral[jaw][:, [0, 2]]
    ac, bc = a - a.mean(0), b - b.mean(0)
    u, _, vt = np.linalg.svd(ac.T @ bc)
    d = np.sign(np.linalg.det(u @ vt))
    rot = u @ np.diag([1.0, d]) @ vt
    aligned = np.zeros((len(jaw), 3))
    aligned[:, [0, 2]] = ac @ rot + b.mean(0)
    full = ctx.neutral.copy()
    full[jaw] = aligned
    r = _jaw_squareness(full, jaw) / _jaw_squareness(ctx.neutral, jaw)
    return Measurement(float(r), 0, "jaw squareness (hull area / bounding box) at "
                       "initialization over Parke's neutral face",
                       frame_value=float(r))


def _jaw_reach(v: np.ndarray, jaw: np.ndarray, tip: int) -> float:
    """How far the jaw (14-43) reaches below the tip of the upper front teeth (226), side view."""
    return float(v[tip, 2] - v[jaw, 2].min())


def _lower_face_area(v: np.ndarray, jaw: np.ndarray, tip: int) -> float:
    """Side-view area of the hull of the jaw (14-43) and the upper front teeth's tip (226)."""
    return _hull_area(v[np.append(jaw, tip)][:, [0, 2]])


def _lower_face_ratio(ctx, figure, what: str) -> Measurement:
    """A figure of the lower face, the head fixed, where the version put the jaw, over Parke's
    neutral face: CASSI 1.0's initialisation turns Parke's jaw onto the head measures (4.1.3),
    and a jaw turned down or pushed forward reads, beside the head, as a longer or larger
    lower face."""
    jaw, tip = ctx.parts.jaw, ctx.parts.upper_incisor_tip
    if not _has_neutral(ctx, tip):
        return _NO_NEUTRAL
    r = figure(ctx.frame(0), jaw, tip) / figure(ctx.neutral, jaw, tip)
    return Measurement(float(r), 0, f"{what} at initialization over Parke's neutral face",
                       frame_value=float(r))


def m_jaw_long(ctx):
    return _lower_face_ratio(ctx, _jaw_reach,
                             "lowest point of the jaw below the upper incisor tip (226)")


def m_jaw_large(ctx):
    return _lower_face_ratio(ctx, _lower_face_area,
                             "side-view area of the lower face (hull of the jaw and 226)")


def m_no_rounding(ctx):
    f = ctx.max_protrusion
    r = G.lip_rounding_at(ctx.frame(0), ctx.frame(f), ctx.parts)
    return Measurement(r, f, "lip-corner half-width at maximum protrusion over at the start",
                       frame_value=r)


def m_lips_from_chin(ctx):
    p = ctx.parts
    f = ctx.max_protrusion
    at, first = ctx.frame(f), ctx.frame(0)
    d = (at[p.ll_outer, 0] - at[p.chin, 0]) - (first[p.ll_outer, 0] - first[p.chin, 0])
    return Measurement(float(d * ctx.mm), f, "x(49) - x(chin) at maximum protrusion, beyond the "
                                             "first frame",
                       frame_value=float(d * ctx.mm))


def _cave(ctx, a, m, b, what):
    c = ctx.series(G.concavity, a, m, b) - G.concavity(ctx.rest[None], a, m, b)[0]
    return _m_sustained(ctx, c * ctx.mm, detail=f"{what} behind the chord of its neighbours, beyond rest")


def m_above_lip_cave(ctx):
    p = ctx.parts
    return _cave(ctx, p.subnasale, p.above_lip[0], p.ul_outer, "point above the upper lip (71)")


def m_below_lip_cave(ctx):
    p = ctx.parts
    return _cave(ctx, p.ll_outer, p.below_lip[0], p.chin, "point under the lower lip (41)")


def m_chin_cave(ctx):
    """The chin behind the chord of its neighbours: a hollow where the chin bulges. Not beyond
    rest: a chin flatter than Parke's but still convex reads as a smaller chin, not a cave."""
    p = ctx.parts
    c = ctx.series(G.concavity, p.below_lip[0], p.chin, p.chin_low)
    return _m_sustained(ctx, c * ctx.mm, detail="chin (24) behind the chord 41 - underside of the chin")


def m_lips_into_nose(ctx):
    c = ctx.series(G.lip_nose_clearance, ctx.parts, ctx.rest)
    return _m_sustained(ctx, c, worst="min", detail="distance 67 - nose base over its rest value")


def _outer_area(pos, p):
    left = np.concatenate([p.upper_outer, [p.corner], p.lower_outer[::-1]])
    half = pos[:, left][:, :, [1, 2]].copy()
    half[..., 0] = np.abs(half[..., 0])
    mirror = half[:, ::-1].copy()
    mirror[..., 0] *= -1
    area, _ = G.polygon_extent(np.concatenate([half, mirror[:, 1:-1]], axis=1))
    return area


def m_lips_too_big(ctx):
    f = ctx.max_protrusion
    r = float(_outer_area(ctx.frame(f)[None], ctx.parts)[0] / _outer_area(ctx.rest[None], ctx.parts)[0])
    return Measurement(r, f, "front-view area inside the outer lip outline at maximum protrusion "
                             "over at rest", frame_value=r)


def m_lower_lip_protrudes_start(ctx):
    d = float(G.protrusion_difference(ctx.frame(0)[None], ctx.parts)[0] * ctx.mm)
    return Measurement(d, 0, "x(49) - x(67) at the first frame", frame_value=d)


def m_upper_protrudes_more(ctx):
    f = ctx.max_protrusion
    d = float(-G.protrusion_difference(ctx.frame(f)[None], ctx.parts)[0] * ctx.mm)
    return Measurement(d, f, "x(67) - x(49) at maximum protrusion", frame_value=d)


def m_upper_lip_sharp(ctx):
    p = ctx.parts
    f = ctx.max_protrusion
    a = G.profile_angle(ctx.frame(f)[None], p.above_lip[0], p.ul_outer, p.upper_inner[0])[0]
    a0 = G.profile_angle(ctx.rest[None], p.above_lip[0], p.ul_outer, p.upper_inner[0])[0]
    return Measurement(float(a0 - a), f, f"profile angle 71-67-61 {a:.0f} deg at maximum "
                                         f"protrusion, {a0:.0f} deg at rest", frame_value=float(a0 - a))


def _derived_lip_points(p: G.MouthParts) -> np.ndarray:
    # the lip vertices the versions compute (not the UL/LL pellets themselves, whose jitter is
    # the data's): the outlines beside the centerline and the corners
    return np.concatenate([p.upper_outer[1:], p.lower_outer[1:], p.upper_inner[1:],
                           p.lower_inner[1:], [p.corner, p.inner_corner]])


def _jitter(ctx, points):
    # the excess over the largest shake of the jaw and the lip pellets (the data's own jitter)
    p = ctx.parts
    ref = np.asarray([p.jaw_point, p.ul_outer, p.ll_outer])
    window = ctx.jitter_window
    if ctx.F < window:
        return np.zeros(ctx.F)
    return ctx.series(G.excess_jitter, points, ref, window=window, order=JITTER_ORDER,
                      halo=window) * ctx.mm


def m_lip_jitter(ctx):
    j = _jitter(ctx, _derived_lip_points(ctx.parts))
    return _m_sustained(ctx, j, detail="lip acceleration beyond the jaw's and the lip pellets'")


def m_corner_jump(ctx):
    p = ctx.parts
    # the switch between a horizontal and a vertical ellipse (the `ellipse` diagnostic), not any
    # change of OUTER_ABC_CALC branch: leaving the band near c_rest is no switch of shape
    switch = None
    if ctx.diagnostics is not None and "ellipse" in ctx.diagnostics:
        switch = ctx.diagnostics["ellipse"].astype(str).to_numpy()
    jump, sw = G.switch_jumps_from(ctx.series(G.corner_step_excess, p, halo=1), switch)
    jump = jump * ctx.mm
    jit = _jitter(ctx, np.asarray([p.corner, p.inner_corner]))
    jv, jf = sustained(jit, k=ctx.min_frames)
    sv = float(jump.max()) if len(sw) else 0.0
    if sv >= jv:
        f = int(np.argmax(jump))
        return Measurement(sv, f, f"largest corner jump at one of {len(sw)} ellipse switches",
                           frame_value=sv)
    return Measurement(jv, jf, f"corner jitter beyond the jaw's ({len(sw)} ellipse switches, "
                               f"largest jump {sv:.2f} mm)", frame_value=float(jit[jf]))


def _wide_open(ctx) -> np.ndarray:
    """Frames (indices) where the lips are open wide (WIDE_OPEN_SHARE of the task's widest, at
    least WIDE_OPEN_MM): Table E's shapes are judged "especially when opened wide"."""
    height = ctx.gap
    return np.flatnonzero(height >= max(WIDE_OPEN_MM, WIDE_OPEN_SHARE * float(height.max())))


def m_lip_shape(ctx):
    area, extent = ctx.series(lambda pos: G.polygon_extent(G.opening_polygon(pos, ctx.parts)))
    idx = _wide_open(ctx)
    if not idx.size:
        return Measurement(float("nan"), -1, f"the lips never open wide (> {WIDE_OPEN_MM} mm)")
    v = float(np.median(extent[idx]))
    f = int(idx[np.argmin(extent[idx])])
    return Measurement(v, f, f"median over {len(idx)} wide-open frames of the opening's "
                             "area / bounding box (ellipse 0.79, diamond 0.5)",
                       frame_value=float(extent[f]))


def _sharpest_side_turn(pos, parts):
    # the opening outline's smallest interior angle away from its two corners (287 and its
    # mirror image), where a mouth is pointed: a kink on the lips' edges is the fault
    poly = G.opening_polygon(pos, parts)
    nu, n_half = len(parts.upper_inner), len(parts.upper_inner) + 1 + len(parts.lower_inner)
    corners = [nu, n_half + (n_half - 1 - nu) - 1]
    a = G.outline_angles(poly)
    return np.delete(a, corners, axis=1).min(axis=1)


def m_lip_outline_angular(ctx):
    idx = _wide_open(ctx)
    if not idx.size:
        return Measurement(float("nan"), -1, f"the lips never open wide (> {WIDE_OPEN_MM} mm)")
    turn = ctx.series(_sharpest_side_turn, ctx.parts)
    v = float(np.median(turn[idx]))
    f = int(idx[np.argmin(turn[idx])])
    return Measurement(v, f, f"median over {len(idx)} wide-open frames of the opening outline's "
                             "sharpest angle away from the corners (straight on 180, hexagon 120)",
                       frame_value=float(turn[f]))


def m_lower_lip_through_lower_teeth(ctx):
    d = ctx.series(G.lip_teeth_penetration, ctx.parts, rest=ctx.rest, which="lower") * ctx.mm
    return _m_sustained(ctx, d, detail="lower lip behind the front surface of the lower front teeth")


def m_corners_misplaced(ctx):
    d = ctx.series(G.corner_misplacement, ctx.parts) * ctx.mm
    return _m_sustained(ctx, d, detail="corner 70 outside the band of 69 and 51")
