"""The automated rubric: every criterion of the thesis's evaluation as one registered check.

The thesis's authors watched each animation and wrote down faults ("negatives"), one to three
per fault, and turned the count into a rating (thesis chapter 5, Table 5.2; restated in
``shared/spec/rubric.md``). Here every criterion of rubric.md's Tables A-E is a :class:`Check`
registered once in :data:`CHECKS` with what it measures, its unit, view and frames, its
thresholds and the negatives each earns, the reason for each threshold, and the negative's text
as the thesis writes it. ALL THRESHOLDS LIVE IN THIS FILE. Tables, reports and gates read the
registry; nothing else decides what a negative is.

Results are rows of the long results table (``cassi.harness.results.COLUMNS``): one whole-task
row (``frame == -1``) per check with the negatives, plus one evidence row at the worst frame
(negatives 0) so the farm can render the frame a check points at.

Tables (``Check.table``): ``A`` teeth/lips/tongue per subject (thesis Table 5.3), ``B`` face
shape at initialization (5.4), ``C`` lip placement across versions (5.5, summary 5.6), ``D``
maximum lip protrusion, task 118 (5.8), ``E`` jaw wagging, task 106 (5.9). Table C reuses the
lip rows of Table A (the thesis judged "the lip criteria of Table A, for each version") plus its
own checks and the comparison with the previous version (:func:`tabulate`).

Measures are in millimetres (converted from Parke units with the subject's jaw length,
thesis 4.1.1), degrees, or fractions of frames.
"""
from __future__ import annotations

import difflib
import functools
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from cassi.data.errors import CassiInputError

from . import rubric_geometry as G

__all__ = [
    "Check", "Measurement", "CHECKS", "TABLES", "RATINGS", "VERSION_ORDER", "MIN_FRAMES",
    "rate", "get_check", "checks_for", "registry_table", "summary_counts", "GeometryContext", "run_geometry_checks",
    "run_image_checks", "tabulate", "negatives_text",
]

#: Thesis Table 5.2: negatives -> rating (6 or more: UNACCEPTABLE).
RATINGS = ("EXCELLENT", "VERY GOOD", "GOOD", "FAIR", "POOR", "VERY POOR", "UNACCEPTABLE")

#: Rubric tables: letter -> (thesis table, title).
TABLES = {
    "A": ("5.3", "Teeth, lips and tongue, per subject"),
    "B": ("5.4", "Overall face shape at initialization"),
    "C": ("5.5", "Lip placement and movement across versions"),
    "D": ("5.8", "Maximum lip protrusion (task 118)"),
    "E": ("5.9", "Jaw wagging (task 106)"),
}

#: Versions in the order the thesis compares them (Table C: "compared with the previous version").
VERSION_ORDER = ("parke-1974", "cassi-1.0", "cassi-2.0", "cassi-2.1")

#: A fault "during the task" must last this many frames (3 x 6.866 ms ~ 20 ms) before it counts:
#: a single-frame graze is invisible at 146 frames per second, which is why sustained measures
#: take the MIN_FRAMES-th worst frame. One-frame jumps have their own check (corner_jump_switch).
MIN_FRAMES = 3

#: Lips are "open" for the image measures when the mouth opening covers at least this many pixels
#: in the front view (a sliver between touching lips is not an opening to judge centering in).
OPEN_MIN_PIXELS = 30
#: ... and is at least this many pixels tall somewhere. Added after the renders: Parke's neutral
#: lips part by 1.35 mm, a 1-pixel slit of ~40 pixels at the preview front view that passed the
#: area rule and had its glint of upper teeth judged as "centered high" (synthetic JW11 task 118).
OPEN_MIN_HEIGHT = 3
#: Centering (upper vs lower teeth inside the opening) is judged on frames open at least this
#: share of the task's widest opening. Added after the renders: Parke's face on synthetic JW11
#: task 118 showed the lower teeth more than the upper when open (share 0.32) but the median over
#: every open frame was 0.85 "centered high", carried by 3-pixel slits showing an upper edge only.
CENTERING_OPEN_SHARE = 0.5
#: The tongue "shows" when a connected patch of at least this many pixels of it lies inside the
#: lip opening. Tuned on renders: at the preview front view (1.3 mm per pixel) the tongue shows
#: through the 1-pixel gaps between the teeth as vertical slivers of 1-4 pixels, which the eye
#: does not read as the tongue; 6 px (~10 mm^2) is a visible patch.
TONGUE_MIN_PIXELS = 6


def rate(negatives: int) -> str:
    """The rating for a number of negatives (thesis Table 5.2).

    >>> rate(0), rate(3), rate(6), rate(11)
    ('EXCELLENT', 'FAIR', 'UNACCEPTABLE', 'UNACCEPTABLE')
    """
    n = int(negatives)
    if n < 0:
        raise CassiInputError(f"negatives must be >= 0, got {n}")
    return RATINGS[min(n, len(RATINGS) - 1)]


@dataclass(frozen=True)
class Measurement:
    """What a measure returns: the whole-task value, the worst frame and a detail text.

    ``series`` (optional, (F,)) is the per-frame value; ``negatives`` overrides the threshold
    grading for checks whose thesis rule is not a plain threshold (tongue: upper / lower / both).
    """

    value: float
    frame: int = -1
    detail: str = ""
    negatives: int | None = None
    frame_value: float | None = None


@dataclass(frozen=True)
class Check:
    """One rubric criterion.

    Attributes
    ----------
    name : str
        Unique registry key (the ``check`` column).
    table : str
        ``A`` .. ``E`` (:data:`TABLES`); ``thesis_table`` the thesis's table number.
    component : str
        teeth, lips, tongue, palate, jaw, face ...
    view : str
        Where the thesis judged it: front, side, half, top (the results' ``view`` column is
        ``geometry`` for geometric checks, the render view for image checks).
    unit : str
    frames : str
        Which frames it looks at.
    description : str
        What it measures.
    thresholds : tuple of float
        Values beyond which the fault counts, mildest first.
    negatives : tuple of int
        Negatives earned beyond each threshold (same length, non-decreasing).
    direction : {"higher", "lower"}
        ``higher``: larger values are worse (fires when value > threshold); ``lower``: smaller
        values are worse (fires when value < threshold).
    reason : str
        Why these threshold values.
    text : str
        The negative as the thesis writes it.
    kind : {"geometry", "image"}
    func : callable
        ``func(ctx) -> Measurement`` (geometry: a :class:`GeometryContext`; image: an
        :class:`cassi.harness.rubric_image.ImageContext`).
    tasks : tuple of int or None
        Only these tasks (118 for Table D, 106 for Table E); None = every task.
    counted : bool
        False for what the thesis measured but did not count (tongue through the palate) and
        for image cross-checks of a geometric check; such rows always carry 0 negatives.
    gate_tolerance : int
        Extra negatives (summed over subjects) the metric gate of ``cassi gate`` allows.
    """

    name: str
    table: str
    component: str
    view: str
    unit: str
    frames: str
    description: str
    thresholds: tuple[float, ...]
    negatives: tuple[int, ...]
    direction: str
    reason: str
    text: str
    kind: str
    func: Callable[[Any], Measurement] = field(repr=False, compare=False)
    tasks: tuple[int, ...] | None = None
    counted: bool = True
    gate_tolerance: int = 0

    def __post_init__(self):
        if self.table not in TABLES:
            raise ValueError(f"{self.name}: unknown table {self.table!r}")
        if len(self.thresholds) != len(self.negatives) or not self.thresholds:
            raise ValueError(f"{self.name}: one negatives count per threshold")
        if list(self.negatives) != sorted(self.negatives) or min(self.negatives) < 1:
            raise ValueError(f"{self.name}: negatives must be >= 1 and non-decreasing")
        step = np.diff(self.thresholds)
        if self.direction == "higher" and np.any(step <= 0) or \
           self.direction == "lower" and np.any(step >= 0):
            raise ValueError(f"{self.name}: thresholds must run from mild to severe")
        if self.kind not in ("geometry", "image"):
            raise ValueError(f"{self.name}: kind must be geometry or image")

    @property
    def thesis_table(self) -> str:
        return TABLES[self.table][0]

    @property
    def threshold(self) -> float:
        """The first (mildest) threshold: where the check starts to fire."""
        return float(self.thresholds[0])

    def applies_to(self, task: int | None) -> bool:
        return self.tasks is None or (task is not None and int(task) in self.tasks)

    def grade(self, value: float) -> int:
        """Negatives for a value by the thresholds (0 when not counted or not measurable)."""
        if value is None or not np.isfinite(value):
            return 0
        n = 0
        for t, k in zip(self.thresholds, self.negatives):
            if (value > t) if self.direction == "higher" else (value < t):
                n = k
        return n

    def fires(self, value: float) -> bool:
        return value is not None and np.isfinite(value) and (
            value > self.threshold if self.direction == "higher" else value < self.threshold)


# ----------------------------------------------------------------------------------------------
# Geometry context: the per-animation arrays and cached measures the check functions share
# ----------------------------------------------------------------------------------------------

class GeometryContext:
    """One animation's positions with its mouth parts, units and cached measures.

    Parameters
    ----------
    positions : float (F, V, 3)
        Parke units (``Animation.positions``).
    parts : rubric_geometry.MouthParts
    rest : float (V, 3)
        The face before initialization (``FaceModel.vertices``): the reference shape for
        cave-in, slope and clearance measures, so Parke's own profile never counts as a fault.
    mm_per_unit : float
        Millimetres per Parke unit.
    diagnostics : DataFrame or None
        ``Animation.diagnostics`` (``outer_abc_branch`` gives the ellipse switches).
    neutral : float (V, 3) or None
        Parke's neutral face (``build_face()``), the reference for an unusual jaw (Table B).
    task : int or None
    """

    def __init__(self, positions, parts: G.MouthParts, *, rest=None, mm_per_unit: float = 1.0,
                 diagnostics: pd.DataFrame | None = None, neutral=None, task: int | None = None):
        self.pos = np.asarray(positions, dtype=np.float64)
        if self.pos.ndim != 3 or self.pos.shape[2] != 3 or self.pos.shape[0] < 1:
            raise CassiInputError(f"positions must be (F, V, 3), got {self.pos.shape}")
        if not np.all(np.isfinite(self.pos)):
            raise CassiInputError("positions contain NaN or infinite values")
        need = max(int(np.max(np.atleast_1d(v))) for v in vars(parts).values()
                   if isinstance(v, (int, np.integer, np.ndarray)) and np.size(v))
        if need >= self.pos.shape[1]:
            raise CassiInputError(f"positions have {self.pos.shape[1]} vertices; the mouth parts "
                                  f"use vertex row {need}")
        self.parts = parts
        self.rest = self.pos[0] if rest is None else np.asarray(rest, dtype=np.float64)
        self.mm = float(mm_per_unit)
        self.diagnostics = diagnostics
        self.neutral = None if neutral is None else np.asarray(neutral, dtype=np.float64)
        self.task = task

    @property
    def F(self) -> int:
        return self.pos.shape[0]

    @functools.cached_property
    def tongue_teeth(self) -> dict[str, np.ndarray]:
        d = G.tongue_teeth_penetration(self.pos, self.parts, rest=self.rest)
        return {k: v * self.mm for k, v in d.items()}

    @functools.cached_property
    def gap(self) -> np.ndarray:
        return G.inner_lip_gap(self.pos, self.parts) * self.mm

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
        return G.max_protrusion_frame(self.pos, self.parts)

    @functools.cached_property
    def end_frames(self) -> np.ndarray:
        """The last 5 % of frames (at least MIN_FRAMES): "especially at its end" (Table 5.3)."""
        n = max(MIN_FRAMES, int(round(0.05 * self.F)))
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


def _m_sustained(series, *, worst="max", detail="") -> Measurement:
    v, f = sustained(series, worst=worst)
    return Measurement(v, f, detail, frame_value=float(np.asarray(series)[f]) if f >= 0 else None)


# ----------------------------------------------------------------------------------------------
# Geometric measures (ctx -> Measurement)
# ----------------------------------------------------------------------------------------------

def _end(ctx: GeometryContext, series: np.ndarray) -> Measurement:
    e = ctx.end_frames
    v = float(np.median(series[e]))
    f = int(e[np.argmax(series[e])])
    return Measurement(v, f, f"median over the last {len(e)} frames; largest during the task "
                             f"{np.max(series):.2f} at frame {int(np.argmax(series))}",
                       frame_value=float(series[f]))


def m_teeth_front_overlap(ctx):
    front, _ = G.teeth_overlap(ctx.pos, ctx.parts)
    return _end(ctx, front * ctx.mm)


def m_teeth_back_overlap(ctx):
    _, back = G.teeth_overlap(ctx.pos, ctx.parts)
    _, back0 = G.teeth_overlap(ctx.rest[None], ctx.parts)
    return _end(ctx, (back - back0[0]) * ctx.mm)


def _slope(ctx):
    return G.teeth_slope(ctx.pos, ctx.parts) - G.teeth_slope(ctx.rest[None], ctx.parts)[0]


def m_teeth_slope_up(ctx):
    return _end(ctx, _slope(ctx))


def m_teeth_slope_down(ctx):
    return _end(ctx, -_slope(ctx))


def m_teeth_apart(ctx):
    # the larger of the front gap and the back teeth's opening beyond rest: the half view shows
    # either (render review: CASSI 2.0's back teeth stand 5.5 mm apart while the incisors overlap)
    front = G.teeth_gap(ctx.pos, ctx.parts)
    _, back = G.teeth_overlap(ctx.pos, ctx.parts)
    _, back0 = G.teeth_overlap(ctx.rest[None], ctx.parts)
    return _end(ctx, np.maximum(front, -(back - back0[0])) * ctx.mm)


def m_lips_never_touch(ctx):
    g = ctx.gap
    f = int(np.argmin(g))
    return Measurement(float(g[f]), f, "smallest gap between the lips' edges (61-58) in the task",
                       frame_value=float(g[f]))


def m_lips_apart_start(ctx):
    return Measurement(float(ctx.gap[0]), 0, "gap between the lips' edges at the first frame",
                       frame_value=float(ctx.gap[0]))


def m_lips_pressed(ctx):
    return Measurement(float(-ctx.gap[0]), 0, "how far the lips' edges cross at the first frame",
                       frame_value=float(-ctx.gap[0]))


def m_lips_overlap(ctx):
    cross = np.where(ctx.handled_overlap, np.minimum(-ctx.gap, 0.0), -ctx.gap)
    return _m_sustained(cross, detail="how far the lower lip's edge rises above the upper's, in "
                                      "frames where the version does not handle the overlap")


def m_lips_too_large_moving(ctx):
    crossing = ctx.gap < 0
    n = int(crossing.sum())
    if n == 0:
        return Measurement(float("nan"), -1, "the lips never cross")
    area = _outer_area(ctx.pos, ctx.parts) / _outer_area(ctx.rest[None], ctx.parts)[0]
    idx = np.flatnonzero(crossing)
    v = float(np.percentile(area[idx], 90))
    f = int(idx[np.argmax(area[idx])])
    handled = int(np.sum(ctx.handled_overlap & crossing))
    return Measurement(v, f, f"front-view lip area over the rest face's, 90th percentile over the "
                             f"{n} frames where the lips cross ({handled} handled by the version)",
                       frame_value=float(area[f]))


def m_lips_centered_low(ctx):
    below = G.lower_lip_below_teeth(ctx.pos, ctx.parts) * ctx.mm
    frac = float(np.mean(below > 0.5))
    f = int(np.argmax(below))
    return Measurement(frac, f, f"lower lip edge (58) more than 0.5 mm below the lower gum line "
                                f"(258); deepest {below[f]:.2f} mm", frame_value=float(below[f]))


def m_lips_through_teeth(ctx):
    d = G.lip_teeth_penetration(ctx.pos, ctx.parts, rest=ctx.rest) * ctx.mm
    return _m_sustained(d, detail="lip vertices behind the front surface of the front teeth")


def m_lower_lip_protrudes(ctx):
    d = G.protrusion_difference(ctx.pos, ctx.parts) * ctx.mm
    v = float(np.percentile(d, 90))
    f = int(np.argmax(d))
    return Measurement(v, f, "90th percentile over frames of x(49) - x(67)", frame_value=float(d[f]))


def m_tongue_teeth(ctx):
    up, lo = ctx.tongue_teeth["upper"], ctx.tongue_teeth["lower"]
    du, fu = sustained(up)
    dl, fl = sustained(lo)
    c = CHECKS["tongue_through_teeth"]
    through = int(du > c.thresholds[0]) + int(dl > c.thresholds[0])
    # thesis Table 5.3: one front set 1, both 2, very noticeably through both 3
    neg = 3 if through == 2 and min(du, dl) > c.thresholds[-1] else through
    f = fu if du >= dl else fl
    return Measurement(max(du, dl), f, f"upper {du:.2f} mm, lower {dl:.2f} mm", negatives=neg,
                       frame_value=float(max(up[f], lo[f])))


def m_tongue_palate(ctx):
    d = G.tongue_palate_penetration(ctx.pos, ctx.parts) * ctx.mm
    return _m_sustained(d, detail="tongue above the palatal surface (not counted by the thesis)")


def m_tongue_back_v(ctx):
    t = ctx.parts.tongue
    if len(t) < 6:
        return Measurement(float("nan"), -1, "no tongue centre line")
    # centre line tip, T1-T4, back (numbering.TONGUE_CENTRE): the angle at T4 between T3 and
    # the anchored back vertex
    ang = G.profile_angle(ctx.pos, t[3], t[4], t[5])
    return _m_sustained(ang, worst="min", detail="side-view angle T3-T4-back of the tongue "
                                                 "(not counted by the thesis)")


def m_palate_below_incisor(ctx):
    d = G.palate_below_incisor(ctx.pos[0], ctx.parts) * ctx.mm
    return Measurement(d, 0, "lowest palate vertex below vertex 226 at initialization", frame_value=d)


def _jaw_shape(v: np.ndarray, jaw: np.ndarray) -> tuple[float, float, float]:
    """Length (x extent), side-view hull area and extent (area / box) of the jaw (14-43)."""
    from scipy.spatial import ConvexHull  # noqa: PLC0415 - only Table B needs it

    p = v[jaw][:, [0, 2]]
    length = float(np.ptp(p[:, 0]))
    try:
        area = float(ConvexHull(p).volume)
    except Exception:  # degenerate (collinear) jaw: no area to compare
        return length, float("nan"), float("nan")
    box = float(np.ptp(p[:, 0]) * np.ptp(p[:, 1]))
    return length, area, area / box if box > 0 else float("nan")


def _jaw_ratio(ctx, i: int, what: str) -> Measurement:
    jaw = ctx.parts.jaw
    if ctx.neutral is None or len(jaw) < 3 or ctx.neutral.shape[0] <= jaw.max():
        return Measurement(float("nan"), -1, "no neutral face to compare with")
    # the version's initial jaw rotation is no shape change: align the jaw to the neutral one
    # (rotation and translation in the side view, Kabsch) before measuring
    a = ctx.pos[0][jaw][:, [0, 2]]
    b = ctx.neutral[jaw][:, [0, 2]]
    ac, bc = a - a.mean(0), b - b.mean(0)
    u, _, vt = np.linalg.svd(ac.T @ bc)
    d = np.sign(np.linalg.det(u @ vt))
    rot = u @ np.diag([1.0, d]) @ vt
    aligned = np.zeros((len(jaw), 3))
    aligned[:, [0, 2]] = ac @ rot + b.mean(0)
    full = ctx.neutral.copy()
    full[jaw] = aligned
    r = _jaw_shape(full, jaw)[i] / _jaw_shape(ctx.neutral, jaw)[i]
    return Measurement(float(r), 0, f"jaw {what} at initialization over Parke's neutral face",
                       frame_value=float(r))


def m_jaw_long(ctx):
    return _jaw_ratio(ctx, 0, "length (vertices 14-43, x extent)")


def m_jaw_large(ctx):
    return _jaw_ratio(ctx, 1, "side-view area")


def m_jaw_square(ctx):
    return _jaw_ratio(ctx, 2, "squareness (hull area / bounding box)")


def m_no_rounding(ctx):
    r, f = G.lip_rounding(ctx.pos, ctx.parts)
    return Measurement(r, f, "lip-corner half-width at maximum protrusion over at the start",
                       frame_value=r)


def m_lips_from_chin(ctx):
    p = ctx.parts
    f = ctx.max_protrusion
    d = (ctx.pos[f, p.ll_outer, 0] - ctx.pos[f, p.chin, 0]) - (ctx.pos[0, p.ll_outer, 0] - ctx.pos[0, p.chin, 0])
    return Measurement(float(d * ctx.mm), f, "x(49) - x(chin) at maximum protrusion, beyond the "
                                             "first frame",
                       frame_value=float(d * ctx.mm))


def _cave(ctx, a, m, b, what):
    c = G.concavity(ctx.pos, a, m, b) - G.concavity(ctx.rest[None], a, m, b)[0]
    return _m_sustained(c * ctx.mm, detail=f"{what} behind the chord of its neighbours, beyond rest")


def m_above_lip_cave(ctx):
    p = ctx.parts
    return _cave(ctx, p.subnasale, p.above_lip[0], p.ul_outer, "point above the upper lip (71)")


def m_below_lip_cave(ctx):
    p = ctx.parts
    return _cave(ctx, p.ll_outer, p.below_lip[0], p.chin, "point under the lower lip (41)")


def m_chin_cave(ctx):
    p = ctx.parts
    return _cave(ctx, p.below_lip[0], p.chin, p.chin_low, "chin")


def m_lips_into_nose(ctx):
    c = G.lip_nose_clearance(ctx.pos, ctx.parts, ctx.rest)
    return _m_sustained(c, worst="min", detail="distance 67 - nose base over its rest value")


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
    r = float(_outer_area(ctx.pos[f:f + 1], ctx.parts)[0] / _outer_area(ctx.rest[None], ctx.parts)[0])
    return Measurement(r, f, "front-view area inside the outer lip outline at maximum protrusion "
                             "over at rest", frame_value=r)


def m_lower_lip_protrudes_start(ctx):
    d = float(G.protrusion_difference(ctx.pos[:1], ctx.parts)[0] * ctx.mm)
    return Measurement(d, 0, "x(49) - x(67) at the first frame", frame_value=d)


def m_upper_protrudes_more(ctx):
    f = ctx.max_protrusion
    d = float(-G.protrusion_difference(ctx.pos[f:f + 1], ctx.parts)[0] * ctx.mm)
    return Measurement(d, f, "x(67) - x(49) at maximum protrusion", frame_value=d)


def m_upper_lip_sharp(ctx):
    p = ctx.parts
    f = ctx.max_protrusion
    a = G.profile_angle(ctx.pos[f:f + 1], p.above_lip[0], p.ul_outer, p.upper_inner[0])[0]
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
    return G.excess_jitter(ctx.pos, points, ref) * ctx.mm


def m_lip_jitter(ctx):
    j = _jitter(ctx, _derived_lip_points(ctx.parts))
    return _m_sustained(j, detail="lip acceleration beyond the jaw's and the lip pellets'")


def m_corner_jump(ctx):
    p = ctx.parts
    branch = None
    if ctx.diagnostics is not None and "outer_abc_branch" in ctx.diagnostics:
        branch = ctx.diagnostics["outer_abc_branch"].to_numpy()
    jump, sw = G.switch_jumps(ctx.pos, p, branch)
    jump = jump * ctx.mm
    jit = _jitter(ctx, np.asarray([p.corner, p.inner_corner]))
    jv, jf = sustained(jit)
    sv = float(jump.max()) if len(sw) else 0.0
    if sv >= jv:
        f = int(np.argmax(jump))
        return Measurement(sv, f, f"largest corner jump at one of {len(sw)} ellipse switches",
                           frame_value=sv)
    return Measurement(jv, jf, f"corner jitter beyond the jaw's ({len(sw)} ellipse switches, "
                               f"largest jump {sv:.2f} mm)", frame_value=float(jit[jf]))


def m_lip_shape(ctx):
    poly = G.opening_polygon(ctx.pos, ctx.parts)
    area, extent = G.polygon_extent(poly)
    height = ctx.gap
    wide = height >= max(3.0, 0.7 * float(height.max()))
    if not np.any(wide):
        return Measurement(float("nan"), -1, "the lips never open wide (> 3 mm)")
    idx = np.flatnonzero(wide)
    v = float(np.median(extent[idx]))
    f = int(idx[np.argmin(extent[idx])])
    return Measurement(v, f, f"median over {len(idx)} wide-open frames of the opening's "
                             "area / bounding box (ellipse 0.79, diamond 0.5)",
                       frame_value=float(extent[f]))


def m_lower_lip_through_lower_teeth(ctx):
    d = G.lip_teeth_penetration(ctx.pos, ctx.parts, rest=ctx.rest, which="lower") * ctx.mm
    return _m_sustained(d, detail="lower lip behind the front surface of the lower front teeth")


def m_corners_misplaced(ctx):
    d = G.corner_misplacement(ctx.pos, ctx.parts) * ctx.mm
    return _m_sustained(d, detail="corner 70 outside the band of 69 and 51")


# ----------------------------------------------------------------------------------------------
# The registry
# ----------------------------------------------------------------------------------------------

def _image(name):
    """Deferred image measure (rubric_image imports this module)."""
    def f(ctx):
        from . import rubric_image  # noqa: PLC0415
        return getattr(rubric_image, name)(ctx)
    f.__name__ = name
    return f


_ALL: list[Check] = [
    # ---------------- Table A (thesis 5.3): teeth ----------------
    Check("teeth_front_overlap", "A", "teeth", "half", "mm", "end of the task",
          "vertical overlap of the upper over the lower front teeth (z of the lower incisor tip "
          "minus z of 226)", (3.5,), (1,), "higher",
          "the reference is 'a very slight overlap'; an adult overbite of 2-3 mm looks normal, so "
          "only more than 3.5 mm counts", "front teeth overlap top to bottom", "geometry",
          m_teeth_front_overlap),
    Check("teeth_back_overlap", "A", "teeth", "half", "mm", "end of the task",
          "vertical overlap of the back teeth (lower molar top minus upper molar bottom), beyond "
          "Parke's rest face", (1.5,), (1,), "higher",
          "Parke's face is the reference alignment; 1.5 mm more overlap than it is visible in the "
          "half-face view at its scale", "back teeth overlap top to bottom", "geometry",
          m_teeth_back_overlap),
    Check("teeth_slope_up", "A", "teeth", "half", "deg", "end of the task",
          "angle of the lower occlusal line (lower molar -> lower incisor tip) above the upper "
          "one, beyond Parke's rest face", (5.0, 25.0), (1, 3), "higher",
          "was 8 deg; 5 deg after the renders: CASSI 2.0 on synthetic JW11 task 19 ends at 7 deg "
          "and the half view plainly shows the lower row rising toward the front against the "
          "horizontal upper row (Parke's 0 deg reads level). The thesis gives a 'very steep "
          "slope' three negatives: 25 deg", "lower teeth slant upward toward the front",
          "geometry", m_teeth_slope_up),
    Check("teeth_slope_down", "A", "teeth", "half", "deg", "end of the task",
          "angle of the lower occlusal line below the upper one, beyond rest", (5.0,), (1,),
          "higher", "as teeth_slope_up (5 deg)", "lower teeth slant downward toward the front", "geometry",
          m_teeth_slope_down),
    Check("teeth_too_far_apart", "A", "teeth", "half", "mm", "end of the task",
          "vertical gap between the upper (226) and lower front teeth tips, or between the back "
          "teeth beyond Parke's rest face, whichever is larger", (5.0,), (1,), "higher",
          "at the end of a task the jaw is near rest, where the incisors nearly meet; a gap over "
          "5 mm (about a fingertip's thickness) is clearly open", "upper and lower teeth too far apart",
          "geometry", m_teeth_apart),
    # ---------------- Table A: lips ----------------
    Check("lips_never_touch", "A", "lips", "front", "mm", "all frames",
          "smallest gap between the lips' edges (61 above 58) over the task", (1.5, 4.0), (1, 2),
          "higher", "lips that touch have ~0 gap. Was 1 mm; raised to 1.5 mm after the renders: "
          "Parke's neutral face parts the lips by 1.35 mm and its front render reads as lips "
          "lightly touching (a dark seam with a glint of teeth). 4 mm is the thesis's 'large "
          "separation' (two negatives)",
          "lips too far apart, never touching", "geometry", m_lips_never_touch),
    Check("lips_apart_at_start", "A", "lips", "front", "mm", "first frame",
          "gap between the lips' edges at the first frame", (1.5,), (1,), "higher",
          "desirable: the lips lightly touch at the start; 1.5 mm as lips_never_touch (Parke's "
          "1.35 mm still reads as touching on the render)",
          "lips separated at the start", "geometry", m_lips_apart_start),
    Check("lips_pressed", "A", "lips", "front", "mm", "first frame",
          "how far the lips' edges cross at the first frame (tightly pressed)", (2.0,), (1,),
          "higher", "lightly touching lips meet at 0. Was 0.5 mm; 2 mm after the renders: CASSI "
          "2.0's 0.8 mm crossing at the start (synthetic JW12 task 5) renders as lips lightly "
          "closed, not pressed",
          "lips too close together, tightly pressed", "geometry", m_lips_pressed),
    Check("lips_centered_low", "A", "lips", "front", "fraction", "all frames",
          "fraction of frames with the lower lip's edge (58) more than 0.5 mm below the lower gum "
          "line (258)", (0.10, 0.50), (1, 2), "higher",
          "'often' = at least a tenth of the task; 'the usual state' (two negatives) = half",
          "centered low: the lower lip goes below the bottom of the lower front teeth", "geometry",
          m_lips_centered_low),
    Check("lips_centered_high", "A", "lips", "front", "fraction", "frames with the lips open",
          "share of the teeth pixels inside the lip opening that are upper teeth (median over open "
          "frames)", (0.80,), (1,), "higher",
          "well centered = similar portions; speakers normally show more upper than lower teeth, "
          "so only 4:1 or more counts as 'much of the upper and little of the lower'",
          "centered high: much of the upper teeth and little of the lower teeth show", "image",
          _image("m_centered_high")),
    Check("lips_through_teeth", "A", "lips", "side", "mm", "all frames (sustained 3)",
          "depth of lip vertices behind the front surface of the front teeth", (0.5,), (1,),
          "higher", "0.5 mm is beyond the teeth's shading: the lip visibly sinks in",
          "lips pass through the surface of the teeth", "geometry", m_lips_through_teeth),
    Check("lower_lip_protrudes", "A", "lips", "side", "mm", "all frames (90th percentile)",
          "x(49) - x(67): lower lip forward of the upper", (1.0, 3.0), (1, 2), "higher",
          "upper lip is normally at or ahead of the lower; 1 mm ahead shows in profile, 3 mm is "
          "'marked' (two negatives)", "lower lip protrudes farther than the upper lip", "geometry",
          m_lower_lip_protrudes),
    Check("lips_overlap", "A", "lips", "front", "mm", "all frames (sustained 3)",
          "how far the lower lip's edge rises above the upper lip's edge (the lips cross)",
          (0.5,), (1,), "higher", "crossing by 0.5 mm shows as one lip through the other",
          "the lips overlap during the task", "geometry", m_lips_overlap),
    # ---------------- Table A: tongue ----------------
    Check("tongue_through_teeth", "A", "tongue", "front", "mm", "all frames (sustained 3)",
          "depth of tongue vertices and edges forward of the back surface of the upper and of the "
          "lower front teeth", (0.5, 2.0), (1, 3), "higher",
          "0.5 mm through one set: one negative; through both: two; both by more than 2 mm ('very "
          "noticeably'): three (graded by m_tongue_teeth)",
          "tongue pokes through the front teeth", "geometry", m_tongue_teeth),
    Check("tongue_hidden", "A", "tongue", "front", "fraction", "frames with the lips open",
          "fraction of open-lip front-view frames in which any tongue pixel shows", (0.10,), (1,),
          "lower", "barely visible = seen in fewer than one open frame in ten",
          "tongue barely visible from the front (hidden by the teeth)", "image",
          _image("m_tongue_visible")),
    Check("tongue_in_front_of_teeth", "A", "tongue", "front", "px", "all rendered frames",
          "tongue pixels nearer the camera than the front teeth (image cross-check of "
          "tongue_through_teeth)", (5.0,), (1,), "higher",
          "5 pixels rules out antialiasing at the teeth's edge; counted by the geometric check",
          "tongue shows in front of the teeth", "image", _image("m_tongue_in_front"),
          counted=False),
    Check("tongue_through_palate", "A", "tongue", "half", "mm", "all frames (sustained 3)",
          "height of tongue vertices and edges above the palatal surface", (0.5,), (1,), "higher",
          "measured but, as in the thesis, not counted (most subjects pass the alveolar ridge)",
          "tongue passes through the palatal outline", "geometry", m_tongue_palate, counted=False),
    Check("tongue_back_v", "A", "tongue", "half", "deg", "all frames (sustained 3)",
          "angle at T4 between T3 and the anchored back of the tongue (the V at the back)",
          (120.0,), (1,), "lower",
          "measured but, as in the thesis, not counted; a bend sharper than 120 deg reads as a V",
          "V shape at the back of the tongue (anchored back points)", "geometry", m_tongue_back_v,
          counted=False),
    # ---------------- Table B (thesis 5.4) ----------------
    Check("palate_below_incisor", "B", "palate", "half", "mm", "initialization",
          "how far the palatal outline reaches below the tip of the upper front teeth (226)",
          (0.25, 2.0), (1, 2), "higher",
          "any reach below the tip shows (0.25 mm rules out round-off); over 2 mm is 'very "
          "noticeable' (two negatives)", "palatal outline extends below the tip of the upper front "
          "teeth", "geometry", m_palate_below_incisor),
    Check("jaw_long", "B", "jaw", "side", "ratio", "initialization",
          "jaw length (vertices 14-43, x extent) over Parke's neutral face", (1.15,), (1,), "higher",
          "15 % longer than Parke's average face reads as 'very long'", "unusual jaw: very long",
          "geometry", m_jaw_long),
    Check("jaw_square", "B", "jaw", "side", "ratio", "initialization",
          "jaw squareness (side-view hull area / box) over Parke's neutral", (1.10,), (1,), "higher",
          "a square jaw fills its box; 10 % fuller than Parke's is visibly squarer",
          "unusual jaw: very square", "geometry", m_jaw_square),
    Check("jaw_large", "B", "jaw", "side", "ratio", "initialization",
          "jaw side-view area over Parke's neutral face", (1.25,), (1,), "higher",
          "a quarter larger than Parke's reads as 'too large seen from the side'",
          "unusual jaw: too large seen from the side", "geometry", m_jaw_large),
    # ---------------- Table C (thesis 5.5) ----------------
    Check("lips_too_large_moving", "C", "lips", "front", "ratio", "frames where the lips cross",
          "front-view area inside the outer lip outline over the rest face's, in the frames where "
          "the lips overlap (90th percentile)", (1.5,), (1,), "higher",
          "the thesis saw overlapping lips look too large; half again the rest face's lip area "
          "reads so. Not the crossing depth: on renders a 12 mm crossing the version handles "
          "(CASSI 2.0, synthetic JW11 task 5 frame 459) looks like closed lips, not large ones",
          "lips appear too large when moving (overlapping)", "geometry", m_lips_too_large_moving),
    Check("lower_lip_too_large", "C", "lips", "front", "fraction", "frames with the lips open",
          "fraction of open-lip front-view frames in which the lower teeth show", (0.25,), (1,),
          "lower", "'bottom teeth rarely seen' = in fewer than a quarter of the open frames",
          "the lower lip too large (bottom teeth rarely seen)", "image",
          _image("m_lower_teeth_seen")),
    # ---------------- Table D (thesis 5.8), task 118 ----------------
    Check("no_lip_rounding", "D", "lips", "front", "ratio", "maximum protrusion",
          "lip-corner half-width at maximum protrusion over at the start", (0.95,), (3,), "higher",
          "rounding draws the corners in; less than 5 % narrowing is no rounding (three negatives)",
          "no lip rounding", "geometry", m_no_rounding, tasks=(118,)),
    Check("lips_stick_out", "D", "lips", "side", "mm", "maximum protrusion",
          "x(49) - x(chin) at maximum protrusion beyond its value at the first frame", (8.0,),
          (1,), "higher",
          "real maximum protrusion moves the lips 5-8 mm. Was 10 mm; 8 mm after the renders: "
          "CASSI 2.1 on synthetic JW11 task 118 at 8.5 mm shows a beak of lips far ahead of the "
          "chin in the side view. "
          "Measured from the first frame, not Parke's rest face: the initial placement is the "
          "data's (survey: against the rest face every CASSI version fired at 12.4 mm)",
          "lips stick out too much from the chin at maximum protrusion", "geometry",
          m_lips_from_chin, tasks=(118,)),
    Check("above_lip_cave_in", "D", "face", "side", "mm", "all frames (sustained 3)",
          "vertex 71 behind the chord nose base - 67, beyond rest", (1.0,), (1,), "higher",
          "1 mm of new hollow above the lip casts a visible shadow", "points above the lip cave in",
          "geometry", m_above_lip_cave, tasks=(118,)),
    Check("lips_into_nose", "D", "lips", "side", "ratio", "all frames (sustained 3)",
          "distance from the upper lip's edge (67) to the nose base over its rest value",
          (0.5, 0.2), (1, 2), "lower",
          "half the rest distance squeezes the skin between them; a fifth is 'marked' (two)",
          "lips run into the nose at maximum protrusion", "geometry", m_lips_into_nose,
          tasks=(118,)),
    Check("lips_too_big", "D", "lips", "front", "ratio", "maximum protrusion",
          "front-view area inside the outer lip outline at maximum protrusion over at rest",
          (1.5,), (1,), "higher", "rounded lips shrink; half again as large is 'too big'",
          "lips too big at maximum protrusion", "geometry", m_lips_too_big, tasks=(118,)),
    Check("lips_centering_118", "D", "lips", "front", "fraction", "frames with the lips open",
          "distance of the upper-teeth share inside the lip opening from an even split",
          (0.30,), (1,), "higher",
          "an even split is 0; 0.3 means a 4:1 split either way (centered too high or too low)",
          "lips centered too high or too low", "image", _image("m_centering_offset"),
          tasks=(118,)),
    Check("lower_lip_protrudes_start", "D", "lips", "side", "mm", "first frame",
          "x(49) - x(67) at the first frame", (1.0,), (1,), "higher", "as lower_lip_protrudes",
          "the lower lip protrudes in the initial position", "geometry",
          m_lower_lip_protrudes_start, tasks=(118,)),
    Check("upper_protrudes_more", "D", "lips", "side", "mm", "maximum protrusion",
          "x(67) - x(49) at maximum protrusion", (4.0,), (1,), "higher",
          "the upper lip normally leads by 1-2 mm; more than 4 mm is marked",
          "the top lip protrudes more than the bottom at maximum protrusion", "geometry",
          m_upper_protrudes_more, tasks=(118,)),
    Check("upper_lip_sharp", "D", "lips", "side", "deg", "maximum protrusion",
          "how much sharper the side-profile angle 71-67-61 at the upper lip's edge is at maximum "
          "protrusion than on the rest face", (10.0,), (1,), "higher",
          "relative to the rest face because Parke's own profile turns sharply there (108 deg on "
          "the generated face; an absolute 110 deg limit fired on every version, survey). Was 40 deg; "
          "10 deg after the renders: CASSI 2.1 on synthetic JW11 task 118 turns 12.5 deg sharper "
          "and its side view shows the upper lip as a pointed wedge",
          "the upper lip has a sharp profile", "geometry", m_upper_lip_sharp, tasks=(118,)),
    Check("lip_jitter", "D", "lips", "front", "mm", "all frames (sustained 3)",
          "frame-to-frame shake (distance from a 9-frame quadratic fit) of the computed lip "
          "vertices beyond the jaw's and the lip pellets'", (0.5,), (1,), "higher",
          "jitter the jaw shows equally comes from the data; 0.5 mm of shake beyond it is visible. "
          "Was the second difference: that fired on fast but smooth rounding movements (CASSI 2.0, "
          "synthetic JW16 task 118, frames 127/536/912: 71 % of files); the fit ignores them", "the lips jitter more than the jaw", "geometry", m_lip_jitter,
          tasks=(118,)),
    # ---------------- Table E (thesis 5.9), task 106 ----------------
    Check("lip_shape_triangular", "E", "lips", "front", "ratio", "wide-open frames",
          "area / bounding box of the lip opening (inner outline) when open wide", (0.62,), (1,),
          "lower", "an ellipse fills 0.79 of its box, a diamond or triangle 0.5; 0.62 is half way",
          "lips very triangular or diamond-shaped when opened wide", "geometry", m_lip_shape,
          tasks=(106,)),
    Check("lip_shape_image", "E", "lips", "front", "ratio", "wide-open frames",
          "area / bounding box of the rendered mouth opening (regionprops extent), cross-check",
          (0.62,), (1,), "lower", "as lip_shape_triangular; counted there",
          "lips very triangular or diamond-shaped when opened wide", "image",
          _image("m_opening_extent"), tasks=(106,), counted=False),
    Check("lower_lip_through_teeth", "E", "lips", "front", "mm", "all frames (sustained 3)",
          "depth of lower-lip vertices behind the front surface of the lower front teeth",
          (0.5,), (1,), "higher", "as lips_through_teeth",
          "the lower lip passes through the bottom set of teeth", "geometry",
          m_lower_lip_through_lower_teeth, tasks=(106,)),
    Check("below_lip_cave_in", "E", "face", "side", "mm", "all frames (sustained 3)",
          "vertex 41 behind the chord 49 - chin, beyond rest", (1.0,), (1,), "higher",
          "1 mm of new hollow under the lip casts a visible shadow",
          "points under the lip cave in, making unusual shapes and shadows", "geometry",
          m_below_lip_cave, tasks=(106,)),
    Check("corners_misplaced", "E", "lips", "side", "mm", "all frames (sustained 3)",
          "distance of the corner (70) outside the band between 69 and 51", (1.0,), (1,), "higher",
          "a corner 1 mm above, below or ahead of its neighbours kinks the outline",
          "the lip corners badly placed relative to the other lip points", "geometry",
          m_corners_misplaced, tasks=(106,)),
    Check("chin_cave_in", "E", "jaw", "side", "mm", "all frames (sustained 3)",
          "chin vertex behind the chord 41 - underside of the chin, beyond rest", (1.0,), (1,),
          "higher", "1 mm of new hollow in the chin shows in profile",
          "the chin or lower jaw caves in", "geometry", m_chin_cave, tasks=(106,)),
    Check("corner_jump_switch", "E", "lips", "side", "mm", "ellipse switches; all frames",
          "largest lip-corner step beyond the jaw's at a switch between horizontal and vertical "
          "ellipse, or the corners' sustained jitter beyond the jaw's", (1.0,), (1,), "higher",
          "a 1 mm jump in one frame (7 ms) is a visible pop",
          "the lip corners jitter, or a large frame jump at the ellipse switch", "geometry",
          m_corner_jump, tasks=(106,)),
]

#: The registry: check name -> :class:`Check`, in rubric order.
CHECKS: dict[str, Check] = {}
for _c in _ALL:
    if _c.name in CHECKS:
        raise RuntimeError(f"check {_c.name} registered twice")
    CHECKS[_c.name] = _c
del _c


def get_check(name: str) -> Check:
    """The registered check ``name``; an unknown name says which names are close."""
    try:
        return CHECKS[name]
    except KeyError:
        close = difflib.get_close_matches(name, CHECKS, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise CassiInputError(f"unknown rubric check {name!r}{hint}") from None


def registry_table() -> pd.DataFrame:
    """The registry as a table (one row per check): what reports and docs print."""
    return pd.DataFrame([dict(check=c.name, table=c.table, thesis_table=c.thesis_table,
                              component=c.component, view=c.view, kind=c.kind, unit=c.unit,
                              frames=c.frames, thresholds=list(c.thresholds),
                              negatives=list(c.negatives), direction=c.direction,
                              counted=c.counted, tasks=None if c.tasks is None else list(c.tasks),
                              text=c.text, description=c.description, reason=c.reason)
                         for c in CHECKS.values()])


def checks_for(*, kind: str | None = None, table: str | None = None,
               task: int | None = None) -> list[Check]:
    """Registered checks filtered by kind, table and task (a task selects D/E checks)."""
    return [c for c in CHECKS.values()
            if (kind is None or c.kind == kind) and (table is None or c.table == table)
            and (task is None or c.applies_to(task))]


# ----------------------------------------------------------------------------------------------
# Running checks
# ----------------------------------------------------------------------------------------------

def _rows(check: Check, m: Measurement, view: str, ids: dict) -> list[dict]:
    neg = m.negatives if m.negatives is not None else check.grade(m.value)
    detail = m.detail
    if not check.counted:
        if check.fires(m.value):
            detail = f"fired (not counted); {detail}"
        neg = 0
    if m.frame >= 0:
        detail = f"{detail}; worst frame {m.frame}" if detail else f"worst frame {m.frame}"
    base = dict(ids, view=view, check=check.name, table=check.table, component=check.component,
                unit=check.unit, threshold=check.threshold)
    rows = [dict(base, frame=-1, value=m.value, negatives=int(neg), detail=detail)]
    if m.frame >= 0 and m.frame_value is not None:
        rows.append(dict(base, frame=int(m.frame), value=m.frame_value, negatives=0,
                         detail="evidence: the worst frame"))
    return rows


def _frame_numbers(anim, n: int) -> np.ndarray:
    frames = getattr(anim, "frames", None)
    return np.asarray(frames) if frames is not None and len(frames) == n else np.arange(n)


def run_geometry_checks(anim, face, profile=None, *, task: int, subject: str | None = None,
                        rep: int = 1, parts: G.MouthParts | None = None,
                        mm_per_unit: float | None = None, neutral=None,
                        checks: Iterable[str] | None = None) -> pd.DataFrame:
    """Run every geometric check that applies to ``task`` on one animation.

    Parameters
    ----------
    anim : cassi.versions.protocol.Animation
        ``positions`` float32 (F, V, 3) Parke units, ``diagnostics``, ``frames``, ``version``.
    face : cassi.data.face.FaceModel
        The face the version animated (its ``vertices`` are the rest shape).
    profile : cassi.data.profile.SubjectProfile or None
        Gives the subject and the jaw length (mm per Parke unit).
    task : int
        Task number (118 and 106 add Tables D and E).
    parts, mm_per_unit, neutral : optional
        Overrides (tests); by default from the face, the profile and ``build_face()``.
    checks : iterable of str, optional
        Only these checks.

    Returns
    -------
    DataFrame
        Results-table rows (``frame`` are recording rows; -1 = whole task), view ``geometry``.
    """
    pos = np.asarray(anim.positions)
    rest = np.asarray(face.vertices, dtype=np.float64) if face is not None else None
    if parts is None:
        if face is None:
            raise CassiInputError("run_geometry_checks needs a face or explicit parts")
        parts = G.mouth_parts(face)
    if mm_per_unit is None:
        jaw = getattr(profile, "jaw_length_mm", None) if profile is not None else None
        mm_per_unit = G.mm_per_unit(rest if rest is not None else pos[0], jaw,
                                    mani=parts.jaw_point)
    if neutral is None and face is not None:
        try:
            from cassi.data.face import build_face  # noqa: PLC0415 - Table B reference only
            neutral = build_face().vertices
        except Exception:  # the face module not present: the jaw checks report "not measurable"
            neutral = None
    ctx = GeometryContext(pos, parts, rest=rest, mm_per_unit=mm_per_unit,
                          diagnostics=getattr(anim, "diagnostics", None), neutral=neutral, task=task)
    ids = dict(subject=subject or getattr(profile, "subject", None), task=int(task), rep=int(rep),
               version=getattr(anim, "version", None))
    wanted = None if checks is None else {get_check(c).name for c in checks}
    frame_no = _frame_numbers(anim, pos.shape[0])
    rows: list[dict] = []
    for c in checks_for(kind="geometry", task=task):
        if wanted is not None and c.name not in wanted:
            continue
        m = c.func(ctx)
        if m.frame >= 0:
            m = Measurement(m.value, int(frame_no[m.frame]), m.detail, m.negatives, m.frame_value)
        rows.extend(_rows(c, m, "geometry", ids))
    return _frame(rows)


def _frame(rows: list[dict]) -> pd.DataFrame:
    cols = ["subject", "task", "rep", "version", "view", "frame", "check", "table", "component",
            "value", "unit", "threshold", "negatives", "detail"]
    df = pd.DataFrame(rows, columns=cols)
    df["negatives"] = df["negatives"].astype("int64")
    df["frame"] = df["frame"].astype("int64")
    df["value"] = df["value"].astype("float64")
    return df


def run_image_checks(results_by_view: Mapping[str, Any], *, task: int, subject: str | None = None,
                     rep: int = 1, version: str | None = None,
                     checks: Iterable[str] | None = None) -> pd.DataFrame:
    """Run the image checks that apply to ``task`` on rendered frames.

    Parameters
    ----------
    results_by_view : mapping view -> frames
        Frames as a mapping ``frame -> RenderResult`` or a sequence of ``(frame, RenderResult)``;
        a RenderResult has ``mask`` int (H, W) part ids, ``part_names`` and ``depth``.
    task : int

    Returns
    -------
    DataFrame of results-table rows (view = the render view each check judges).
    """
    from . import rubric_image as I  # noqa: PLC0415 - image side imports this module

    ids = dict(subject=subject, task=int(task), rep=int(rep), version=version)
    wanted = None if checks is None else {get_check(c).name for c in checks}
    rows: list[dict] = []
    contexts: dict[str, Any] = {}  # one mask analysis per view, shared by its checks
    for c in checks_for(kind="image", task=task):
        if wanted is not None and c.name not in wanted:
            continue
        frames = results_by_view.get(c.view) if hasattr(results_by_view, "get") else None
        if not frames:
            continue
        if c.view not in contexts:
            contexts[c.view] = I.ImageContext.of(frames)
        rows.extend(_rows(c, c.func(contexts[c.view]), c.view, ids))
    return _frame(rows)


# ----------------------------------------------------------------------------------------------
# Tables
# ----------------------------------------------------------------------------------------------

def negatives_text(rows: pd.DataFrame) -> str:
    """The negatives of some result rows as the thesis lists them: ``- text`` (``--`` for two)."""
    out = []
    for _, r in rows.iterrows():
        n = int(r["negatives"])
        if n <= 0:
            continue
        c = CHECKS.get(str(r["check"]))
        text = c.text if c is not None else str(r["check"])
        out.append(f"{'-' * n} {text}")
    return "; ".join(out)


def tabulate(results: pd.DataFrame, *, version_order: Sequence[str] = VERSION_ORDER) -> pd.DataFrame:
    """Per rubric table, subject, version and component: negatives, rating, negatives as text.

    Only whole-task rows (``frame == -1``) count, and each check once per subject and version
    (the most negatives any of the subject's task files earned). Table C is built from the lip
    rows of Table A
    plus Table C's own checks, per subject and version; a version whose lip negatives exceed the
    previous version's (in ``version_order``) earns one more negative ("looks worse"), as the
    thesis compared versions (rubric.md Table C).

    Returns
    -------
    DataFrame with columns table, thesis_table, subject, version, component, negatives, rating,
    text (per component) -- plus one ``component == "all"`` row per table/subject/version.
    """
    cols = ["table", "thesis_table", "subject", "version", "component", "negatives", "rating",
            "text"]
    if results is None or len(results) == 0:
        return pd.DataFrame(columns=cols)
    df = results[results["frame"] == -1].copy()
    df = df[df["table"].notna()]
    df["subject"] = df["subject"].astype("object").fillna("")
    df["version"] = df["version"].astype("object").fillna("")
    lip_a = df[(df["table"] == "A") & (df["component"] == "lips")].copy()
    lip_a["table"] = "C"
    df = pd.concat([df, lip_a], ignore_index=True)
    # a fault is noted once per subject and version, however many of its task files show it
    # (the thesis judged each subject from its files together): the most negatives any file earned
    df = (df.groupby(["table", "subject", "version", "component", "check"], sort=True)
            ["negatives"].max().reset_index())
    out = []
    for (table, subject, version), g in df.groupby(["table", "subject", "version"], sort=True):
        for comp, gc in g.groupby("component", sort=True):
            n = int(gc["negatives"].sum())
            out.append(dict(table=table, thesis_table=TABLES[table][0], subject=subject,
                            version=version, component=comp, negatives=n, rating=rate(n),
                            text=negatives_text(gc)))
        n = int(g["negatives"].sum())
        out.append(dict(table=table, thesis_table=TABLES[table][0], subject=subject,
                        version=version, component="all", negatives=n, rating=rate(n),
                        text=negatives_text(g)))
    tab = pd.DataFrame(out, columns=cols)
    # Table C: "a version that looks worse than the previous one earns an extra negative"
    order = {v: i for i, v in enumerate(version_order)}
    c_all = tab[(tab["table"] == "C") & (tab["component"] == "all")]
    for subject, g in c_all.groupby("subject"):
        g = g[g["version"].isin(order)].sort_values("version", key=lambda s: s.map(order))
        prev = None
        for idx, r in g.iterrows():
            if prev is not None and r["negatives"] > prev:
                tab.loc[idx, "negatives"] = r["negatives"] + 1
                tab.loc[idx, "rating"] = rate(r["negatives"] + 1)
                tab.loc[idx, "text"] = "; ".join(t for t in (r["text"], "- looks worse than the "
                                                             "previous version") if t)
            prev = r["negatives"]  # compare raw counts, not the already-penalised one
    return tab.reset_index(drop=True)


def summary_counts(tab: pd.DataFrame, table: str = "C") -> pd.DataFrame:
    """Count of ratings per version (thesis Table 5.6) from :func:`tabulate` output."""
    t = tab[(tab["table"] == table) & (tab["component"] == "all")]
    counts = t.groupby(["version", "rating"]).size().unstack(fill_value=0)
    return counts.reindex(columns=[r for r in RATINGS if r in counts.columns], fill_value=0)
