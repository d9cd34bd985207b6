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
4. :class:`TongueStage` (4.1.1): 289-292 sit on T1-T4 (parameters 55-62); the tip follows T1, the
   edge vertices their nearest centre vertex, the back stays anchored.

The palate comes with the face (``cassi.data.face.build_face(palate_mm=...)``); Table 4.2's
disabled parameters are listed in :mod:`cassi.versions.constants` and refused by
:func:`check_parameters`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.data import numbering as N
from cassi.data.errors import CassiInputError
from cassi.versions import constants as K
from cassi.versions.jaw import apply_zones, solve_jaw_motion
from cassi.versions.protocol import StagedVersion, Stage, TaskContext

__all__ = [
    "Cassi10",
    "JawStage",
    "LipFollowStage",
    "NoseClearanceStage",
    "TongueStage",
    "check_parameters",
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
    (``cassi.data.numbering.GNATHION``, ``GONION``).
    """
    return _vertex_xz(vertices, N.GNATHION), _vertex_xz(vertices, N.GONION)


def _vertex_xz(vertices: np.ndarray, number) -> np.ndarray:
    """(x, z) of a vertex number, or the mean of a tuple of vertex numbers."""
    idx = np.atleast_1d(np.asarray(number, dtype=np.int64)) - 1
    return vertices[idx][:, _XZ].mean(axis=0)


def _mandible_points(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Model (x, z) of the MANi site (258) and the MANm site (midpoint of 281 and 286)."""
    return _vertex_xz(vertices, K.V_MANI), _vertex_xz(vertices, K.V_MANM_PAIR)


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
        mani, manm = _mandible_points(ctx.neutral)
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
        motion = solve_jaw_motion(mni[0], mnm[0], mni, mnm)
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
        _parameters(ctx, {63: ("UL", 0), 64: ("UL", 1), 65: ("LL", 0), 66: ("LL", 1)})


def _parameters(ctx: TaskContext, spec: dict[int, tuple[str, int]]) -> None:
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

    min_gap_mm: float = K.NOSE_LIP_MIN_GAP_MM
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


@dataclass
class TongueStage:
    """289-292 on T1-T4; tip, edges follow; back anchored (4.1.1, parameters 55-62)."""

    name: str = "tongue"

    def _setup(self, ctx: TaskContext):
        if "tongue_plan" not in ctx.state:
            follow = tongue_followers(ctx.neutral)
            centre = np.asarray(K.V_TONGUE_PELLETS) - 1
            # Column j of the (F, 4, 2) pellet displacements drives each moving vertex.
            movers = [v for v, lead in follow.items() if lead is not None]
            idx = np.concatenate([centre, np.asarray(movers, dtype=np.int64) - 1])
            col = np.concatenate([np.arange(4), [K.V_TONGUE_PELLETS.index(follow[v])
                                                 for v in movers]]).astype(np.int64)
            ctx.state["tongue_plan"] = (idx, col)
        return ctx.state["tongue_plan"]

    def initialise(self, ctx: TaskContext) -> None:
        idx, col = self._setup(ctx)
        centre = np.asarray(K.V_TONGUE_PELLETS) - 1
        first = np.stack([ctx.pellet(p)[0] for p in ("T1", "T2", "T3", "T4")])   # (4, 2)
        delta = first - ctx.start[centre][:, _XZ]
        ctx.start[np.ix_(idx, _XZ)] += delta[col]

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        idx, col = self._setup(ctx)
        d = np.stack([ctx.displacement(p) for p in ("T1", "T2", "T3", "T4")], axis=1)  # (F,4,2)
        positions[:, idx, 0] = ctx.start[idx, 0] + d[:, col, 0]
        positions[:, idx, 2] = ctx.start[idx, 2] + d[:, col, 1]
        _parameters(ctx, {55: ("T1", 0), 56: ("T1", 1), 57: ("T2", 0), 58: ("T2", 1),
                          59: ("T3", 0), 60: ("T3", 1), 61: ("T4", 0), 62: ("T4", 1)})


class Cassi10(StagedVersion):
    """CASSI 1.0 (thesis 4.1). Subclasses change the lips by overriding :meth:`lip_stage`."""

    name = "cassi-1.0"

    def jaw_stage(self) -> Stage:
        return JawStage()

    def lip_stage(self) -> Stage:
        return LipFollowStage()

    def stages(self) -> list[Stage]:
        return [self.jaw_stage(), self.lip_stage(), NoseClearanceStage(), TongueStage()]
