"""CASSI 1.0 (June 1998; thesis 4.1): initialisation, animation and jaw rotation.

The version is four stages run in order (see :class:`~cassi.versions.protocol.StagedVersion`):

1. :class:`JawStage` (4.1.3): initialisation rotates the chin and jaw from Parke's placement onto
   the head measures' gonion and gnathion, and the lower teeth from Parke's placement onto the
   first valid row's jaw pellets; animation rotates every Table 4.3 zone from the first row's jaw
   pellets onto each row's, the angle from the two jaw lines (Eqs. 4.1-4.3) and the point of
   rotation solved per frame (Eqs. 4.6-4.7). The lower lip is not in any zone (4.1.2).
2. :class:`LipFollowStage` (4.1.1-4.1.2): vertex 67 sits on UL and 49 on LL; the other vertices
   of each lip follow their lip's pellet (parameters 63-66 of Table 4.1). Versions 2.0 and 2.1
   replace this stage (:meth:`Cassi10.lip_stage`).
3. :class:`NoseClearanceStage` (4.1.1): the nose tip is raised when a high upper lip would leave
   no space below it.
4. :class:`TongueStage` (4.1.1): 289-292 sit on T1-T4 (parameters 55-62); the tip and the edge
   vertices follow their nearest pellet vertex ("adjusted accordingly"), the back stays anchored,
   and nothing keeps the tongue out of the teeth: the thesis's versions had no collision
   detection (6.2 lists it as future work), and its judges charged 1.0 tongues that poke through
   the front teeth. ``Cassi10(tongue="clamped")`` (:class:`TongueReading`) instead places the tip
   in front of T1 along T2 -> T1 behind the central incisors (:func:`place_tongue_tip`) and holds
   the edges inside the arch; the default is ``constants.TONGUE_READING``.

The palate comes with the face (``cassi.data.face.model.build_face(palate_mm=...)``); Table 4.2's
disabled parameters are listed in :mod:`cassi.versions.constants` and refused by
:func:`check_parameters`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import ClassVar

import numpy as np

from cassi.data.face import numbering as N
from cassi.data.face.model import jaw_pellet_sites
from cassi.common.errors import CassiInputError
from cassi.versions import constants as K
from cassi.versions.jaw import apply_zones, solve_jaw_motion
from cassi.versions.protocol import StagedVersion, Stage, TaskContext

__all__ = [
    "Cassi10",
    "JawStage",
    "LipFollowStage",
    "NoseClearanceStage",
    "TongueStage",
    "TongueReading",
    "check_parameters",
    "incisor_wall_x",
    "place_tongue_tip",
    "parameters_frame",
    "jaw_reference_vertices",
    "tongue_followers",
    "nose_tip_vertices",
]

_XZ = [0, 2]


def check_parameters(parameters: dict[int, float] | None) -> dict[int, float]:
    """Refuse parameters that CASSI disables (Table 4.2) or drives from the pellets (4, 55-66).

    Returns a plain ``{number: value}`` copy of the remaining Parke parameters.
    """
    out: dict[int, float] = {}
    for number, value in (parameters or {}).items():
        n = int(number)
        if n in K.DISABLED_PARAMETERS:
            raise CassiInputError(f"Parke parameter {n} is disabled in CASSI (thesis Table 4.2)")
        if n == K.JAW_PARAMETER or n in K.NEW_PARAMETERS:
            raise CassiInputError(f"parameter {n} is driven by the pellets in CASSI (thesis 4.1.2)")
        out[n] = float(value)
    return out


def jaw_reference_vertices(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parke (x, z) of the model's gnathion (point 1) and gonion (point 2).

    The thesis gives no vertex numbers for them; the face model names them
    (``cassi.data.face.numbering.GNATHION``, ``GONION``).
    """
    return _vertex_xz(vertices, N.GNATHION), _vertex_xz(vertices, N.GONION)


def _vertex_xz(vertices: np.ndarray, number) -> np.ndarray:
    """(x, z) of a vertex number, or the mean of a tuple of vertex numbers."""
    idx = np.atleast_1d(np.asarray(number, dtype=np.int64)) - 1
    return vertices[idx][:, _XZ].mean(axis=0)


@dataclass
class JawStage:
    """Jaw rotation of 4.1.3 with Table 4.3's zones (initialisation and animation phases)."""

    zones: tuple = K.CASSI10_ZONES
    teeth_vertices: tuple[int, ...] = K.TEETH_VERTICES
    name: str = "jaw"

    def initialise(self, ctx: TaskContext) -> None:
        teeth_set = set(self.teeth_vertices)
        teeth = tuple(z for z in self.zones if set(z.vertices) <= teeth_set)
        others = tuple(z for z in self.zones if not set(z.vertices) <= teeth_set)
        # Teeth: Parke's placement -> the first valid row's jaw pellets.
        mani, manm = jaw_pellet_sites(ctx.neutral)
        motion = solve_jaw_motion(mani, manm, ctx.pellet("MNI")[:1], ctx.pellet("MNM")[:1])
        ctx.start[:] = apply_zones(ctx.start, motion, teeth)[0]
        ctx.state["init_teeth_theta"] = float(motion.theta[0])
        # Chin and jaw: Parke's placement -> the head measures (when the subject has them).
        hm = getattr(ctx.profile, "head_measures", None)
        if hm is None:      # the face model carries them too (build_face(head_measures=...))
            hm = getattr(ctx.face, "head_measures", None)
        if hm is not None and others:
            gnathion, gonion = jaw_reference_vertices(ctx.neutral)
            target1 = ctx.mapping.to_parke(np.asarray(hm.gnathion_mm, dtype=np.float64))[None]
            target2 = ctx.mapping.to_parke(np.asarray(hm.gonion_mm, dtype=np.float64))[None]
            motion = solve_jaw_motion(gnathion, gonion, target1, target2)
            ctx.start[:] = apply_zones(ctx.start, motion, others)[0]
            ctx.state["init_jaw_theta"] = float(motion.theta[0])
        else:
            ctx.state["init_jaw_theta"] = float("nan")

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        # Animation phase: the first valid row's jaw line -> each row's jaw line.
        mni, mnm = ctx.pellet("MNI"), ctx.pellet("MNM")
        motion = solve_jaw_motion(ctx.first_pellet("MNI"), ctx.first_pellet("MNM"), mni, mnm)
        apply_zones(ctx.start, motion, self.zones, out=positions)
        ctx.state["jaw_motion"] = motion
        ctx.diagnostics["jaw_angle_rad"] = motion.theta
        ctx.diagnostics["jaw_angle_deg"] = motion.degrees
        ctx.diagnostics["jaw_point_x"] = motion.point[:, 0]
        ctx.diagnostics["jaw_point_z"] = motion.point[:, 1]
        ctx.diagnostics["param_4"] = motion.degrees  # parameter 4 now follows the jaw pellets
        # The initialisation's two rotations (constant per task), so a report can show how far
        # the subject's teeth and jaw were turned from Parke's placement.
        n = ctx.n_frames
        ctx.diagnostics["init_teeth_angle_deg"] = np.full(n, np.degrees(ctx.state.get(
            "init_teeth_theta", np.nan)))
        ctx.diagnostics["init_jaw_angle_deg"] = np.full(n, np.degrees(ctx.state.get(
            "init_jaw_theta", np.nan)))


def _weights() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Index arrays and (UL, LL) weights of every lip vertex: (indices, w_ul, w_ll)."""
    upper = np.asarray(K.UPPER_LIP_VERTICES) - 1
    lower = np.asarray(K.LOWER_LIP_VERTICES) - 1
    corners = np.asarray(K.LIP_CORNER_VERTICES) - 1
    idx = np.concatenate([upper, lower, corners])
    w_ul = np.concatenate([np.ones(len(upper)), np.zeros(len(lower)),
                           np.full(len(corners), K.CORNER_WEIGHTS["UL"])])
    w_ll = np.concatenate([np.zeros(len(upper)), np.ones(len(lower)),
                           np.full(len(corners), K.CORNER_WEIGHTS["LL"])])
    return idx, w_ul, w_ll


@dataclass
class LipFollowStage:
    """CASSI 1.0's lips: 67 on UL and 49 on LL; each lip's other vertices move with its pellet.

    Lip widths never change (no rounding in 1.0); parameters 63-66 are the pellets' displacements
    from the first valid row.
    """

    name: str = "lips"

    def initialise(self, ctx: TaskContext) -> None:
        idx, w_ul, w_ll = _weights()
        d_ul = ctx.pellet("UL")[0] - ctx.start[K.V_UL - 1, _XZ]
        d_ll = ctx.pellet("LL")[0] - ctx.start[K.V_LL - 1, _XZ]
        ctx.start[np.ix_(idx, _XZ)] += w_ul[:, None] * d_ul + w_ll[:, None] * d_ll

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        idx, w_ul, w_ll = _weights()
        d_ul, d_ll = ctx.displacement("UL"), ctx.displacement("LL")
        delta = w_ul[None, :, None] * d_ul[:, None, :] + w_ll[None, :, None] * d_ll[:, None, :]
        for axis_out, axis_in in ((0, 0), (2, 1)):
            positions[:, idx, axis_out] = ctx.start[idx, axis_out] + delta[..., axis_in]
        parameters_frame(ctx, {63: ("UL", 0), 64: ("UL", 1), 65: ("LL", 0), 66: ("LL", 1)})


def parameters_frame(ctx: TaskContext, spec: dict[int, tuple[str, int]]) -> None:
    """Table 4.1's parameters as diagnostics columns: displacement from the first valid row."""
    for number, (pellet, axis) in spec.items():
        ctx.diagnostics[f"param_{number}"] = ctx.displacement(pellet)[:, axis]


def nose_tip_vertices(vertices: np.ndarray | None = None) -> np.ndarray:
    """1-based numbers of the nose-tip vertices the clearance rule raises (the face model's
    ``NOSE_TIP``: the tip and its underside above the upper lip)."""
    return np.asarray(K.NOSE_TIP_VERTICES, dtype=np.int64)


@dataclass
class NoseClearanceStage:
    """Keep a space between the top of the upper lip and the nose tip (4.1.1)."""

    # read when built, not when imported (cassi.versions.ranges sets it for a while)
    min_gap_mm: float = field(default_factory=lambda: K.NOSE_LIP_MIN_GAP_MM)
    name: str = "nose"

    def _setup(self, ctx: TaskContext) -> tuple[np.ndarray, np.ndarray, float]:
        if "nose_tip" not in ctx.state:
            tip = nose_tip_vertices(ctx.neutral) - 1
            upper = np.asarray(K.UPPER_LIP_VERTICES) - 1
            neutral_gap = ctx.neutral[tip, 2].min() - ctx.neutral[upper, 2].max()
            # Never demand more space than Parke's neutral face has, so a neutral lip never
            # moves the nose.
            want = self.min_gap_mm * ctx.mapping.scale
            ctx.state["nose_tip"] = (tip, upper, float(min(want, max(neutral_gap, 0.0))))
        return ctx.state["nose_tip"]

    def initialise(self, ctx: TaskContext) -> None:
        tip, upper, gap = self._setup(ctx)
        raise_by = max(0.0, gap - (ctx.start[tip, 2].min() - ctx.start[upper, 2].max()))
        ctx.start[tip, 2] += raise_by
        ctx.state["init_nose_raise"] = raise_by

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        tip, upper, gap = self._setup(ctx)
        have = positions[:, tip, 2].min(axis=1) - positions[:, upper, 2].max(axis=1)
        # Relative to the initialised nose: raise only by what this frame's lip needs beyond it.
        raise_by = np.maximum(0.0, gap - have)
        positions[:, tip, 2] += raise_by[:, None]
        ctx.diagnostics["nose_raise"] = raise_by


def tongue_followers(vertices: np.ndarray | None = None) -> dict[int, int | None]:
    """For each non-pellet tongue vertex, the pellet vertex it follows (None: anchored); see
    :data:`cassi.versions.constants.TONGUE_FOLLOW`."""
    return dict(K.TONGUE_FOLLOW)


def incisor_wall_x(vertices: np.ndarray, z: np.ndarray) -> np.ndarray:
    """x of the front-most wall the tongue tip must stay behind, at height ``z``.

    Parameters
    ----------
    vertices : float (F, V, 3) or (V, 3)
        Positions (Parke units) with the teeth already placed for each frame.
    z : float (F,) or scalar
        Height of the tip per frame.

    Returns
    -------
    float (F,)
        The smaller of the lower and the upper central incisor's x at ``z`` along their centre-line
        edge (:data:`~cassi.versions.constants.TONGUE_TIP_INCISOR_EDGES`), each edge extended
        vertically beyond its ends (a tip above a lowered lower incisor still stays behind it).
    """
    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim == 2:
        v = v[None]
    z = np.broadcast_to(np.asarray(z, dtype=np.float64), (v.shape[0],))
    walls = []
    for tip, gum in K.TONGUE_TIP_INCISOR_EDGES:
        a, b = v[:, tip - 1], v[:, gum - 1]
        dz = b[:, 2] - a[:, 2]
        t = np.clip((z - a[:, 2]) / np.where(np.abs(dz) > 1e-12, dz, 1.0), 0.0, 1.0)
        walls.append(a[:, 0] + t * (b[:, 0] - a[:, 0]))
    return np.minimum(*walls)


def place_tongue_tip(t1: np.ndarray, t2: np.ndarray, vertices: np.ndarray, scale: float
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Tip (x, z) in front of T1 along T2 -> T1, kept behind the incisors (4.1.1).

    Parameters
    ----------
    t1, t2 : float (F, 2)
        T1 and T2 (Parke x, z) per frame.
    vertices : float (F, V, 3)
        Positions with the teeth placed.
    scale : float
        Parke units per subject mm (p / d).

    Returns
    -------
    tip : float (F, 2)
    ahead_mm : float (F,)
        How far in front of T1 the tip was placed (subject mm).
    """
    t1 = np.asarray(t1, dtype=np.float64)
    u = t1 - np.asarray(t2, dtype=np.float64)
    n = np.hypot(u[:, 0], u[:, 1])
    u = np.where(n[:, None] > 1e-9, u / np.where(n > 1e-9, n, 1.0)[:, None], [1.0, 0.0])
    ahead = np.full(len(t1), K.TONGUE_TIP_AHEAD_MM * scale)
    low = K.TONGUE_TIP_MIN_AHEAD_MM * scale
    # Shorten the step until the tip is clear of the incisor wall at the tip's own height (the
    # wall is nearly vertical, so two passes settle it).
    for _ in range(3):
        tip = t1 + ahead[:, None] * u
        room = incisor_wall_x(vertices, tip[:, 1]) - K.TONGUE_TIP_TEETH_CLEARANCE_MM * scale
        over = (tip[:, 0] > room) & (u[:, 0] > 1e-9)
        want = np.where(u[:, 0] > 1e-9, (room - t1[:, 0]) / np.where(u[:, 0] > 1e-9, u[:, 0], 1.0),
                        ahead)
        ahead = np.where(over, np.clip(want, low, ahead), ahead)
    tip = t1 + ahead[:, None] * u
    return tip, ahead / scale


def _arch_segments() -> np.ndarray:
    """(S, 2) vertex rows of the biting-line segments of both tooth sets (0-based)."""
    segs = []
    for k in range(N.TEETH_PER_SET):
        lo = N.lower_tooth(k)
        up = N.upper_tooth(k)
        segs += [(lo[0] - 1, lo[1] - 1), (up[3] - 1, up[2] - 1)]
    return np.asarray(segs, dtype=np.int64)


def arch_wall_x(vertices: np.ndarray, y: np.ndarray) -> np.ndarray:
    """x of the front-facing teeth (biting line of both sets) at lateral offset ``y``.

    Parameters
    ----------
    vertices : float (F, V, 3)
    y : float (E,)
        |y| of the points to bound.

    Returns
    -------
    float (F, E)
        The smallest x of the front-facing segments spanning each y; +inf where none does.
    """
    v = np.asarray(vertices, dtype=np.float64)
    seg = _arch_segments()
    a, b = v[:, seg[:, 0]], v[:, seg[:, 1]]                    # (F, S, 3)
    dx, dy = b[..., 0] - a[..., 0], np.abs(b[..., 1]) - np.abs(a[..., 1])
    length = np.hypot(dx, dy)
    front = np.abs(dy) >= K.TONGUE_ARCH_FRONT_NX * np.where(length > 0, length, np.inf)
    ya, yb = np.abs(a[..., 1])[:, None], np.abs(b[..., 1])[:, None]     # (F, 1, S)
    yy = np.abs(np.asarray(y, dtype=np.float64))[None, :, None]         # (1, E, 1)
    lo, hi = np.minimum(ya, yb), np.maximum(ya, yb)
    span = (yy >= lo) & (yy <= hi) & front[:, None, :]
    t = (yy - ya) / np.where(np.abs(yb - ya) > 1e-12, yb - ya, 1.0)
    x = a[..., 0][:, None] + t * dx[:, None]
    return np.where(span, x, np.inf).min(axis=-1)


class TongueReading(str, Enum):
    """How CASSI 1.0's tongue (2.0's and 2.1's too) meets the teeth.

    TEXT: 4.1.1 as written, the tip and edges following their pellets with nothing keeping them
    out of the teeth (the thesis's versions had no collision detection, 6.2): the default, see
    ``constants.TONGUE_READING``.
    CLAMPED: the tip placed in front of T1 along T2 -> T1 and held behind the central incisors,
    the edges held inside the arch (a collision rule, CASSI 3.0's kind of fix).
    """

    TEXT = "text"
    CLAMPED = "clamped"


@dataclass
class TongueStage:
    """289-292 on T1-T4; the other vertices follow them, the back anchored (4.1.1, parameters
    55-62); with ``reading`` CLAMPED the tip sits ahead of T1 behind the teeth and the edges
    inside the arch."""

    name: str = "tongue"
    reading: TongueReading = TongueReading(K.TONGUE_READING)
    #: The pellets between two others, which a leave-one-out animation may withhold.
    predicts: ClassVar[tuple[str, ...]] = ("T2", "T3")

    def predict_withheld(self, ctx: TaskContext, name: str) -> np.ndarray:
        """Where CASSI 1.0's tongue puts a withheld T2 or T3 (Parke (x, z), (F, 2)): its vertex
        moves with the mean of its two neighbours' offsets from their neutral vertices.

        CHOSEN (the thesis has no rule for a pellet missing throughout; a missing value is held,
        3.2.5): 1.0 moves each tongue vertex without a pellet with the pellet beside it
        (:data:`~cassi.versions.constants.TONGUE_FOLLOW`), keeping Parke's shape between them;
        a centre vertex between two pellets follows both, equally."""
        names = ("T1", "T2", "T3", "T4")
        i = names.index(name)
        before, after = names[i - 1], names[i + 1]
        if {before, after} & set(ctx.withheld):
            raise CassiInputError(f"cannot predict {name} with {before} or {after} withheld too")
        centre = K.V_TONGUE_PELLETS
        n = ctx.neutral[:, _XZ]
        offset = 0.5 * ((ctx.pellet(before) - n[centre[i - 1] - 1])
                        + (ctx.pellet(after) - n[centre[i + 1] - 1]))
        return n[centre[i] - 1] + offset

    def _clamped(self) -> bool:
        return TongueReading(self.reading) is TongueReading.CLAMPED

    def _setup(self, ctx: TaskContext):
        if "tongue_plan" not in ctx.state:
            follow = tongue_followers(ctx.neutral)
            centre = np.asarray(K.V_TONGUE_PELLETS) - 1
            # Clamped, the tip and the edge vertex beside it are placed by place_tongue_tip;
            # every other moving vertex takes column j of the (F, 4, 2) pellet displacements.
            tip_pair = {N.TONGUE_TIP, N.TONGUE_EDGE[0]} if self._clamped() else set()
            movers = [v for v, lead in follow.items() if lead is not None and v not in tip_pair]
            idx = np.concatenate([centre, np.asarray(movers, dtype=np.int64) - 1])
            col = np.concatenate([np.arange(4), [K.V_TONGUE_PELLETS.index(follow[v])
                                                 for v in movers]]).astype(np.int64)
            # The edge beside the tip keeps its neutral offset from the tip.
            side = ctx.neutral[N.TONGUE_EDGE[0] - 1, _XZ] - ctx.neutral[N.TONGUE_TIP - 1, _XZ]
            ctx.state["tongue_plan"] = (idx, col, side)
        return ctx.state["tongue_plan"]

    def _tip(self, ctx: TaskContext, out: np.ndarray, t1: np.ndarray, t2: np.ndarray,
             vertices: np.ndarray) -> np.ndarray:
        _, _, side = self._setup(ctx)
        tip, ahead = place_tongue_tip(t1, t2, vertices, ctx.mapping.scale)
        out[..., N.TONGUE_TIP - 1, 0] = tip[:, 0].reshape(out.shape[:-2])
        out[..., N.TONGUE_TIP - 1, 2] = tip[:, 1].reshape(out.shape[:-2])
        out[..., N.TONGUE_EDGE[0] - 1, 0] = (tip[:, 0] + side[0]).reshape(out.shape[:-2])
        out[..., N.TONGUE_EDGE[0] - 1, 2] = (tip[:, 1] + side[1]).reshape(out.shape[:-2])
        return ahead

    def _inside_arch(self, ctx: TaskContext, out: np.ndarray) -> None:
        """Hold every moving edge vertex behind the front of the teeth's arch (4.1.1)."""
        edges = np.asarray([v for v in N.TONGUE_EDGE if tongue_followers()[v] is not None]) - 1
        view = out if out.ndim == 3 else out[None]
        wall = arch_wall_x(view, view[0, edges, 1] if out.ndim == 2 else out[0, edges, 1])
        room = wall - K.TONGUE_TIP_TEETH_CLEARANCE_MM * ctx.mapping.scale
        view[:, edges, 0] = np.minimum(view[:, edges, 0], room)

    def initialise(self, ctx: TaskContext) -> None:
        idx, col, _ = self._setup(ctx)
        centre = np.asarray(K.V_TONGUE_PELLETS) - 1
        first = np.stack([ctx.pellet(p)[0] for p in ("T1", "T2", "T3", "T4")])   # (4, 2)
        delta = first - ctx.start[centre][:, _XZ]
        ctx.start[np.ix_(idx, _XZ)] += delta[col]
        if self._clamped():
            self._tip(ctx, ctx.start, first[None, 0], first[None, 1], ctx.start)
            self._inside_arch(ctx, ctx.start)

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        idx, col, _ = self._setup(ctx)
        d = np.stack([ctx.displacement(p) for p in ("T1", "T2", "T3", "T4")], axis=1)  # (F,4,2)
        positions[:, idx, 0] = ctx.start[idx, 0] + d[:, col, 0]
        positions[:, idx, 2] = ctx.start[idx, 2] + d[:, col, 1]
        if self._clamped():
            ahead = self._tip(ctx, positions, ctx.pellet("T1"), ctx.pellet("T2"), positions)
            self._inside_arch(ctx, positions)
        else:
            tip = positions[:, N.TONGUE_TIP - 1, _XZ] - positions[:, N.T1 - 1, _XZ]
            ahead = np.hypot(tip[:, 0], tip[:, 1]) / ctx.mapping.scale
        ctx.diagnostics["tongue_tip_ahead_mm"] = ahead
        parameters_frame(ctx, {55: ("T1", 0), 56: ("T1", 1), 57: ("T2", 0), 58: ("T2", 1),
                               59: ("T3", 0), 60: ("T3", 1), 61: ("T4", 0), 62: ("T4", 1)})


class Cassi10(StagedVersion):
    """CASSI 1.0 (thesis 4.1). Subclasses change the lips by overriding :meth:`lip_stage`.

    Parameters
    ----------
    tongue : TongueReading or str, optional
        How the tongue meets the teeth (default :attr:`tongue`, ``constants.TONGUE_READING``).
    """

    name = "cassi-1.0"
    #: The tongue's reading: TEXT by default (the thesis's versions had no collision detection).
    tongue: TongueReading = TongueReading(K.TONGUE_READING)

    def __init__(self, *, tongue: TongueReading | str | None = None):
        if tongue is not None:
            self.tongue = TongueReading(tongue)

    def jaw_stage(self) -> Stage:
        return JawStage()

    def lip_stage(self) -> Stage:
        return LipFollowStage()

    def stages(self) -> list[Stage]:
        return [self.jaw_stage(), self.lip_stage(), NoseClearanceStage(),
                TongueStage(reading=self.tongue)]
