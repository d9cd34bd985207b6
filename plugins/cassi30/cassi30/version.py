"""CASSI 3.0: CASSI 2.1's jaw, lips and nose with a thick, curved tongue that is kept behind the
teeth and under the palate, whose back follows T3-T4 along the pharynx outline (PHA.DAT), on a
face whose palate never reaches below the upper incisor tip (thesis 6.3's open faults).

Built only on the public protocol (:mod:`cassi.versions.protocol`: ``StagedVersion``, ``Stage``,
``TaskContext`` and the ``animated_face`` hook) and registered through the ``cassi.versions``
entry point group, like any third-party version.
"""
from __future__ import annotations

import numpy as np

from cassi.data import numbering as N
from cassi.data.errors import CassiInputError
from cassi.data.face import FaceModel
from cassi.versions.cassi10 import (NoseClearanceStage, incisor_wall_x, parameters_frame,
                                    place_tongue_tip)
from cassi.versions.cassi21 import Cassi21
from cassi.versions.protocol import Stage, TaskContext

from cassi30 import constants as K
from cassi30.collision import FrontTeeth, PalateHeights, soft_above, soft_below
from cassi30.face import lower_arch, thick_tongue_face, tongue_rows
from cassi30.shape import (PELLET_STATIONS, arch_half_width, back_points, centre_stations,
                           normals, sections, station_thickness_mm)

__all__ = ["Cassi30", "ThickTongueStage"]

_PELLETS = ("T1", "T2", "T3", "T4")
#: Frames the tongue is computed for at a time: every frame is independent of the others, and
#: the (frames x points x quads) temporaries of a 1,024-frame block stay in the CPU's cache,
#: where those of a whole 20,000-frame task (hundreds of MB) ran at memory speed.
BLOCK_FRAMES = 1024


def _pharynx(ctx: TaskContext) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """PHA.DAT in Parke (x, z): z ascending, x at those z, and the wall's unit direction top to
    bottom."""
    pha = getattr(ctx.profile, "pharynx_mm", None)
    if pha is None:
        raise CassiInputError(f"cassi-3.0 places the back of the tongue along the pharynx outline: "
                              f"subject {getattr(ctx.profile, 'subject', '?')} has no PHA.DAT")
    xz = ctx.mapping.to_parke(np.asarray(pha, np.float64))
    if xz.ndim != 2 or len(xz) < 2 or np.ptp(xz[:, 1]) <= 0:
        raise CassiInputError("PHA.DAT needs at least two points at different heights")
    order = np.argsort(xz[:, 1])
    d = xz[order[0]] - xz[order[-1]]
    return xz[order, 1], xz[order, 0], d / np.hypot(*d)


class ThickTongueStage:
    """The tongue of CASSI 3.0 (see the module docstring); replaces CASSI 1.0's tongue stage."""

    name = "tongue"

    def _setup(self, ctx: TaskContext) -> dict:
        plan = ctx.state.get("tongue30")
        if plan is None:
            scale = ctx.mapping.scale
            face = ctx.face
            palate = [p.vertices for p in face.polygons_of("palate")]
            tris = np.asarray([(q[0], q[k], q[k + 1]) for q in palate
                               for k in range(1, len(q) - 1)], np.int64) - 1
            lower = [N.lower_tooth(k) for k in range(N.TEETH_PER_SET)]
            upper = [tuple(N.upper_tooth(k)[i] for i in (3, 2, 1, 0))
                     for k in range(N.TEETH_PER_SET)]
            front = FrontTeeth.front_edges
            pz, px, wall = _pharynx(ctx)
            plan = {
                "rows": tongue_rows(np.shape(ctx.neutral)[0]),
                "scale": scale,
                "arch": lower_arch(ctx.start),
                "palate": PalateHeights(ctx.start, tris, K.PALATE_GRID_MM * scale),
                "teeth": FrontTeeth(front(ctx.start, upper, min_nx=K.FRONT_TEETH_MIN_NX),
                                    front(ctx.start, lower, min_nx=K.FRONT_TEETH_MIN_NX)),
                "pharynx": (pz, px, wall),
                "thickness": station_thickness_mm() * scale,
            }
            ctx.state["tongue30"] = plan
        return plan

    def tongue(self, ctx: TaskContext, pellets: np.ndarray, teeth: np.ndarray
               ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The tongue's vertices for each frame.

        Parameters
        ----------
        pellets : float (F, 4, 2)
            T1-T4, Parke (x, z).
        teeth : float (F, V, 3)
            Positions with the teeth placed (the jaw stage's work).

        Returns
        -------
        vertices : float (F, STATIONS, C, 3)
        diagnostics : dict of float (F,) columns, subject mm
        """
        plan = self._setup(ctx)
        scale, w = plan["scale"], K.SOFTNESS_MM * plan["scale"]
        margin = K.COLLISION_MARGIN_MM * scale
        # The incisors' rows only (1..258), in float64 once: place_tongue_tip and
        # incisor_wall_x would otherwise convert the whole (F, V, 3) float32 array per call.
        incisors = np.asarray(teeth[:, :N.MANI], np.float64)
        tip, _ = place_tongue_tip(pellets[:, 0], pellets[:, 1], incisors, scale)
        pz, px, wall = plan["pharynx"]
        back = back_points(pellets[:, 2], pellets[:, 3], wall, K.BACK_STEP_MM * scale)
        wall_x = np.interp(back[..., 1], pz, px)
        back[..., 0] = soft_above(back[..., 0], wall_x + K.PHARYNX_CLEARANCE_MM * scale, w)
        st = centre_stations(tip, pellets, back)
        out = self._protruded(tip, pellets[:, 0], incisors, margin)
        passing, lo, hi = self._pass_between_teeth(st, out, incisors, margin,
                                                    K.PROTRUSION_ZONE_MM * scale)
        width = arch_half_width(*plan["arch"], st[..., 0], scale=scale)
        width[:, 0] = K.HALF_WIDTH_TIP_MM * scale
        v = sections(st, normals(st), width, plan["thickness"])
        # In a protruded frame, the whole section of each front station near or past the
        # teeth fits in the gap (the underside behind the teeth would otherwise hang below
        # the lower incisors' tip, and its edges to the points in the gap cut through them).
        near = incisors[:, [N.UPPER_INCISOR_TIP - 1, N.LOWER_INCISOR_TIP - 1], 0].min(axis=1)
        squeeze = (out & (hi > lo))[:, None] & (
            st[:, :K.TEETH_STATIONS, 0] > (near - 0.5 * K.PROTRUSION_ZONE_MM * scale)[:, None])
        squeeze[:, 2] |= passing
        part = v[:, :K.TEETH_STATIONS, :, 2]
        v[:, :K.TEETH_STATIONS, :, 2] = np.where(
            squeeze[..., None], np.clip(part, lo[:, None, None], hi[:, None, None]), part)
        # Under the palate: each dorsum point, and the underside point below it moves with it
        # (the tongue is pressed down, not flattened).
        top = v[..., :K.DORSUM_COLUMNS, :]
        bound = plan["palate"](top[..., 0], top[..., 1]) - margin
        dz = soft_below(top[..., 2], bound, w) - top[..., 2]
        v[..., :K.DORSUM_COLUMNS, 2] += dz
        under = np.arange(K.DORSUM_COLUMNS, v.shape[2])
        v[..., under, 2] += dz[..., v.shape[2] - 1 - under]
        # Behind the front teeth, or between them.
        front = v[:, :K.TEETH_STATIONS].reshape(v.shape[0], -1, 3)
        before = front.copy()
        plan["teeth"].keep_out(teeth, front, margin, protruding=out)
        v[:, :K.TEETH_STATIONS] = front.reshape(v.shape[0], K.TEETH_STATIONS, -1, 3)
        dx = np.linalg.norm(front - before, axis=-1)
        sites = v[:, list(PELLET_STATIONS), 0][..., [0, 2]]
        diag = {"tongue_protruded": out,
                "tongue_palate_push_mm": -dz.min(axis=(1, 2)) / scale,
                "tongue_teeth_push_mm": dx.max(axis=1) / scale,
                "tongue_site_shift_mm": np.linalg.norm(sites - pellets, axis=-1).max(1) / scale}
        return v, diag

    @staticmethod
    def _protruded(tip: np.ndarray, t1: np.ndarray, teeth: np.ndarray, margin: float
                   ) -> np.ndarray:
        """bool (F,): the tongue is out between the teeth. The tip (placed ahead of T1, behind
        the incisors unless T1 itself is there) is in front of the incisors' surface and T1 is
        at the height of the jaw's gap or in front of the upper incisors: a T1 behind the teeth
        and above the gap (an alveolar contact) keeps the tip behind the teeth instead, so no
        edge from T1 to the tip cuts through the upper incisors."""
        hi = teeth[:, N.UPPER_INCISOR_TIP - 1, 2] - margin
        lo = teeth[:, N.LOWER_INCISOR_TIP - 1, 2] + margin
        ahead = tip[:, 0] > incisor_wall_x(teeth, tip[:, 1]) - margin
        t1_through = ((t1[:, 1] >= lo) & (t1[:, 1] <= hi)) | (
            t1[:, 0] > teeth[:, N.UPPER_INCISOR_TIP - 1, 0] - margin)
        return ahead & t1_through

    @staticmethod
    def _pass_between_teeth(st: np.ndarray, out: np.ndarray, teeth: np.ndarray, margin: float,
                            zone: float) -> None:
        """In a protruded frame whose T1 is past the upper incisors and whose T2 is not, the
        station between them (no pellet site) is where the tongue passes the teeth: just
        behind the upper incisors, within the zone, at a height inside the jaw's gap, so that
        neither of its neighbours' edges cuts through a tooth. ``st`` changes in place.

        Returns the frames where it did, bool (F,), and the gap's low and high ends (F,)."""
        x_upper = teeth[:, N.UPPER_INCISOR_TIP - 1, 0]
        hi = teeth[:, N.UPPER_INCISOR_TIP - 1, 2] - margin
        lo = teeth[:, N.LOWER_INCISOR_TIP - 1, 2] + margin
        place = x_upper - 0.5 * zone
        fix = out & (st[:, 1, 0] > x_upper - margin) & (st[:, 3, 0] < place - margin) & (hi > lo)
        st[fix, 2, 0] = place[fix]
        st[fix, 2, 1] = np.clip(st[fix, 2, 1], lo[fix], hi[fix])
        return fix, lo, hi

    def initialise(self, ctx: TaskContext) -> None:
        plan = self._setup(ctx)
        first = np.stack([ctx.pellet(p)[:1] for p in _PELLETS], axis=1)      # (1, 4, 2)
        v, _ = self.tongue(ctx, first, ctx.start[None])
        ctx.start[plan["rows"]] = v.reshape(-1, 3)

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        plan = self._setup(ctx)
        pellets = np.stack([ctx.pellet(p) for p in _PELLETS], axis=1)        # (F, 4, 2)
        diags = []
        for a in range(0, len(positions), BLOCK_FRAMES):
            b = a + BLOCK_FRAMES
            v, diag = self.tongue(ctx, pellets[a:b], positions[a:b])
            positions[a:b, plan["rows"]] = v.reshape(v.shape[0], -1, 3)
            diags.append(diag)
        ctx.diagnostics.update({k: np.concatenate([d[k] for d in diags]) for k in diags[0]})
        parameters_frame(ctx, {55: ("T1", 0), 56: ("T1", 1), 57: ("T2", 0), 58: ("T2", 1),
                               59: ("T3", 0), 60: ("T3", 1), 61: ("T4", 0), 62: ("T4", 1)})


class Cassi30(Cassi21):
    """CASSI 3.0: 2.1's jaw and lip stages and nose clearance, then :class:`ThickTongueStage`,
    on the face of :meth:`animated_face`."""

    name = "cassi-3.0"

    def animated_face(self, face: FaceModel) -> FaceModel:
        """The face 3.0 animates (the protocol's hook, see
        :func:`cassi.versions.protocol.version_face`): :func:`cassi30.face.thick_tongue_face`."""
        return thick_tongue_face(face)

    def stages(self) -> list[Stage]:
        return [self.jaw_stage(), self.lip_stage(), NoseClearanceStage(), ThickTongueStage()]
