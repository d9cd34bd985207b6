"""CASSI 3.0: CASSI 2.1's jaw, lips and nose with a thick, curved tongue that is kept behind the
teeth and under the palate, whose back follows T3-T4 along the pharynx outline (PHA.DAT), on a
face whose palate never reaches below the upper incisor tip (thesis 6.3's open faults).

Built only on the public protocol (:mod:`cassi.versions.protocol`: ``StagedVersion``, ``Stage``,
``TaskContext`` and the ``animated_face`` hook) and registered through the ``cassi.versions``
entry point group, like any third-party version.
"""
from __future__ import annotations

import numpy as np

from cassi.data.face import numbering as N
from cassi.common.errors import CassiInputError
from cassi.data.face.model import FaceModel
from cassi.data.xrmb.files import NOMINAL_PERIOD_US, recording_period_us, rows_spanning
from cassi.versions import constants as cassi10_constants
from cassi.versions.cassi10 import NoseClearanceStage, parameters_frame, place_tongue_tip
from cassi.versions.cassi21 import Cassi21
from cassi.versions.protocol import PELLET_INDEX, Stage, TaskContext, held_pellets

from cassi30 import constants as K
from cassi30.collision import FrontTeeth, PalateHeights, soft_above, soft_below
from cassi30.face import lower_arch, thick_tongue_face, tongue_rows
from cassi30.shape import (PELLET_STATIONS, arch_half_width, back_points, centre_stations,
                           normals, sections, station_thickness_mm)

__all__ = ["Cassi30", "ThickTongueStage", "settle", "slew"]

_PELLETS = ("T1", "T2", "T3", "T4")
#: Frames the tongue is computed for at a time: every frame is independent of the others, and
#: the (frames x points x quads) temporaries of a 1,024-frame block stay in the CPU's cache,
#: where those of a whole 20,000-frame task (hundreds of MB) ran at memory speed.
BLOCK_FRAMES = 1024
#: How far ahead the tongue looks for the jaw's gap shutting: 24 frames at XRMB's 146 Hz
#: (164 ms) is longer than its way out takes to withdraw at TONGUE_SPEED_MM_S (the 24 mm turn
#: and ~20 mm in front of the teeth in task 118: 110 ms). A time, so a recording at another
#: rate looks as far ahead in its own rows (LOOKAHEAD_FRAMES at XRMB's).
LOOKAHEAD_US = 24 * NOMINAL_PERIOD_US
LOOKAHEAD_FRAMES = rows_spanning(LOOKAHEAD_US, NOMINAL_PERIOD_US)


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


def slew(target: np.ndarray, time_s: np.ndarray, rate: float, carried: dict, key: str
         ) -> np.ndarray:
    """``target`` (F,) followed at no more than ``rate`` per second, up or down (the first
    frame of a task takes its target); ``carried[key]`` holds the last value and time for the
    frames that follow, so chunks give the values of the whole task. A loop over the frames,
    about a microsecond each."""
    out = np.empty_like(target)
    prev, prev_t = carried.get(key, (None, None))
    t_list, g_list = time_s.tolist(), target.tolist()
    for f, (t, g) in enumerate(zip(t_list, g_list)):
        if prev is not None and g != prev:
            step = rate * (t - prev_t)
            g = min(max(g, prev - step), prev + step)
        out[f] = prev = g
        prev_t = t
    if len(out):
        carried[key] = (prev, prev_t)
    return out


def settle(target: np.ndarray, time_s: np.ndarray, tau: float, carried: dict, key: str
           ) -> np.ndarray:
    """``target`` (F,) through two first-order lags of time constant ``tau`` seconds in series
    (critically damped; the first frame of a task starts settled on its target);
    ``carried[key]`` holds both lags' last values and time, so chunks give the values of the
    whole task. After :func:`slew` it rounds the corners where the rate limit starts and stops:
    a rate-limited ramp's velocity flips in one frame, which the rubric's jitter measure (a
    quadratic fit over 9 frames) reads as shake; settled, the velocity and its change are
    continuous. A ramp at rate ``r`` comes out ``2 * r * tau`` late."""
    out = np.empty_like(target)
    state = carried.get(key)
    t_list, g_list = time_s.tolist(), target.tolist()
    if state is None and g_list:
        state = (g_list[0], g_list[0], t_list[0])
    a, b, prev_t = state if state is not None else (0.0, 0.0, 0.0)
    for f, (t, g) in enumerate(zip(t_list, g_list)):
        k = 1.0 - np.exp(-max(t - prev_t, 0.0) / tau)
        a += k * (g - a)
        b += k * (a - b)
        out[f] = b
        prev_t = t
    if len(out):
        carried[key] = (a, b, prev_t)
    return out


def _gap(teeth: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """The low and high end of the jaw's gap between the incisor tips, less the margin (F,)."""
    return (teeth[:, N.LOWER_INCISOR_TIP - 1, 2] + margin,
            teeth[:, N.UPPER_INCISOR_TIP - 1, 2] - margin)


def _jaw_heights(ctx: TaskContext) -> tuple[np.ndarray, np.ndarray, int]:
    """The lower incisor pellet's (MNI) Parke z and time (s) on every row of the recording, held
    where invalid, and the look-ahead in the recording's rows: what the frames after a chunk
    will do to the jaw's gap, read from the data (so every chunk sees the same future, and
    chunks equal the whole task)."""
    rec = ctx.rec
    first = int(ctx.rows[0]) if len(ctx.rows) else 0
    xy, _ = held_pellets(rec.xy_mm, rec.valid, first)
    z = ctx.mapping.to_parke(xy[:, PELLET_INDEX["MNI"]])[:, 1]
    t = np.asarray(rec.time_us, np.float64)[first:first + len(z)] * 1e-6
    return np.concatenate([np.full(first, z[0] if len(z) else 0.0), z]), \
        np.concatenate([np.full(first, t[0] if len(t) else 0.0), t]), \
        rows_spanning(LOOKAHEAD_US, recording_period_us(rec.time_us))


def _time_to_shut(jaw: tuple[np.ndarray, np.ndarray, int], rows: np.ndarray, gap: np.ndarray,
                  time_s: np.ndarray) -> np.ndarray:
    """Seconds until the jaw's gap (F,) next shuts within the look-ahead, predicted from the
    lower incisor pellet's rise (the lower teeth move with it; the upper ones are fixed): +inf
    where it stays open that long, 0 where it is shut."""
    z, t, lookahead = jaw
    k = np.arange(lookahead + 1)
    idx = np.minimum(rows[:, None] + k, len(z) - 1)
    shut = gap[:, None] - (z[idx] - z[rows][:, None]) <= 0.0          # (F, K+1)
    dt = t[idx] - time_s[:, None]
    return np.where(shut, dt, np.inf).min(axis=1)


class ThickTongueStage:
    """The tongue of CASSI 3.0 (see the module docstring); replaces CASSI 1.0's tongue stage."""

    name = "tongue"
    #: The pellets between two others, which a leave-one-out animation may withhold.
    predicts = ("T2", "T3")

    def predict_withheld(self, ctx: TaskContext, name: str) -> np.ndarray:
        """Where 3.0's centre line puts a withheld T2 or T3 (Parke (x, z), (F, 2)): the
        Catmull-Rom midpoint of the curve through the pellets kept, as between any two pellets
        (:func:`cassi30.shape.centre_stations`). The knot beyond the free end (the tip for T2,
        the first back point for T3, both drawn from the withheld pellet) is the mirror image of
        its neighbour's, the usual end condition."""
        names = list(_PELLETS)
        i = names.index(name)
        if set(names[i - 1:i + 2:2]) & set(ctx.withheld):
            raise CassiInputError(f"cannot predict {name} with a neighbour withheld too")
        p = {n: ctx.pellet(n) for n in names if n != name}
        if name == "T2":
            p0, p1, p2, p3 = 2.0 * p["T1"] - p["T3"], p["T1"], p["T3"], p["T4"]
        else:
            p0, p1, p2, p3 = p["T1"], p["T2"], p["T4"], 2.0 * p["T4"] - p["T2"]
        return (9.0 * (p1 + p2) - p0 - p3) / 16.0

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
                "jaw_z": _jaw_heights(ctx),
            }
            ctx.state["tongue30"] = plan
        return plan

    def tongue(self, ctx: TaskContext, pellets: np.ndarray, teeth: np.ndarray,
               time_s: np.ndarray, carried: dict, rows: np.ndarray
               ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The tongue's vertices for each frame.

        Parameters
        ----------
        pellets : float (F, 4, 2)
            T1-T4, Parke (x, z).
        teeth : float (F, V, 3)
            Positions with the teeth placed (the jaw stage's work).
        time_s : float (F,)
            The frames' times, seconds.
        carried : dict
            What the frames before these leave for them (:func:`slew`).
        rows : int (F,)
            The frames' rows of the recording (their place in ``plan["jaw_z"]``).

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
        ramp = K.PROTRUSION_RAMP_MM * scale
        approach, allowance = self._protrusion(pellets[:, 0], incisors, margin, ramp, scale)
        lo, hi = _gap(incisors, margin)
        gap_open = np.clip((hi - lo) / (K.GAP_OPEN_MM * scale), 0.0, 1.0)
        # How far along its way out the tongue is, moving no faster than a tongue: the first
        # TURN_MM turn its front toward the gap, the rest is how far it may be in front of the
        # teeth. One quantity, so the front is at the gap's height before it passes the teeth
        # and stays there until it is back behind them.
        turn = K.TURN_MM * scale
        # Never farther out than the tongue can withdraw before the gap next shuts (the jaw
        # closing on a protruded tongue would otherwise snap it behind the teeth in a frame).
        speed = K.TONGUE_SPEED_MM_S * scale
        # The settling below makes the way out 2 * tau late: withdraw that much earlier.
        ahead = _time_to_shut(plan["jaw_z"], rows, hi - lo, time_s) - 2.0 * K.SETTLE_S
        way = slew(np.minimum(gap_open * (turn * approach + allowance),
                              speed * np.maximum(ahead, 0.0)), time_s,
                   K.TONGUE_SPEED_MM_S * scale, carried, "way out")
        way = settle(way, time_s, K.SETTLE_S, carried, "way settled")
        toward, release = np.minimum(way / turn, 1.0), np.maximum(way - turn, 0.0)
        passing = self._pass_between_teeth(st, toward, incisors, margin, lo, hi,
                                           K.PROTRUSION_ZONE_MM * scale)
        width = arch_half_width(*plan["arch"], st[..., 0], scale=scale)
        width[:, 0] = K.HALF_WIDTH_TIP_MM * scale
        v = sections(st, normals(st), width, plan["thickness"])
        # As the tongue heads out, the whole section of each front station near or past the
        # teeth moves into the gap (the underside behind the teeth would otherwise hang below
        # the lower incisors' tip, and its edges to the points in the gap cut through them):
        # in part within a crown's thickness (PROTRUSION_ZONE_MM) behind the teeth's front, in
        # full from half of it, so the sections move there continuously.
        near = incisors[:, [N.UPPER_INCISOR_TIP - 1, N.LOWER_INCISOR_TIP - 1], 0].min(axis=1)
        half_zone = 0.5 * K.PROTRUSION_ZONE_MM * scale
        nearness = np.clip((st[:, :K.TEETH_STATIONS, 0] - (near - 2.0 * half_zone)[:, None])
                           / half_zone, 0.0, 1.0)
        nearness[:, 2] = np.maximum(nearness[:, 2], passing)
        weight = (toward[:, None] * nearness)[..., None]
        part = v[:, :K.TEETH_STATIONS, :, 2]
        inside = np.clip(part, lo[:, None, None], np.maximum(hi, lo)[:, None, None])
        v[:, :K.TEETH_STATIONS, :, 2] = part + weight * (inside - part)
        # Under the palate: each dorsum point, and the underside point below it moves with it
        # (the tongue is pressed down, not flattened).
        top = v[..., :K.DORSUM_COLUMNS, :]
        bound = plan["palate"](top[..., 0], top[..., 1]) - margin
        # The mesh's edges run straight between the stations: under a palate that dips between
        # two of them, the edge would cross it though both ends keep the margin. So each point
        # also keeps under the palate halfway to its neighbours along the tongue.
        mid = 0.5 * (top[:, 1:] + top[:, :-1])
        between = plan["palate"](mid[..., 0], mid[..., 1]) - margin
        bound[:, 1:] = np.minimum(bound[:, 1:], between)
        bound[:, :-1] = np.minimum(bound[:, :-1], between)
        dz = soft_below(top[..., 2], bound, w) - top[..., 2]
        v[..., :K.DORSUM_COLUMNS, 2] += dz
        under = np.arange(K.DORSUM_COLUMNS, v.shape[2])
        v[..., under, 2] += dz[..., v.shape[2] - 1 - under]
        # Behind the front teeth, or between them.
        front = v[:, :K.TEETH_STATIONS].reshape(v.shape[0], -1, 3)
        before = front.copy()
        plan["teeth"].keep_out(teeth, front, margin, toward_gap=toward, release=release)
        v[:, :K.TEETH_STATIONS] = front.reshape(v.shape[0], K.TEETH_STATIONS, -1, 3)
        dx = np.linalg.norm(front - before, axis=-1)
        sites = v[:, list(PELLET_STATIONS), 0][..., [0, 2]]
        diag = {"tongue_protruded": release > 0, "tongue_gap_weight": toward,
                "tongue_release_mm": release / scale,
                "tongue_palate_push_mm": -dz.min(axis=(1, 2)) / scale,
                "tongue_teeth_push_mm": dx.max(axis=1) / scale,
                "tongue_site_shift_mm": np.linalg.norm(sites - pellets, axis=-1).max(1) / scale}
        return v, diag

    @staticmethod
    def _protrusion(t1: np.ndarray, teeth: np.ndarray, margin: float, ramp: float, scale: float
                    ) -> tuple[np.ndarray, np.ndarray]:
        """How far the data puts the tongue on its way out between the teeth, per frame,
        continuously (an on/off switch made the front jump by up to 11 mm in the frame it
        flipped).

        ``e`` is how far T1 is past the upper incisors' front less the margin. Over the last
        ``ramp`` of T1's approach (``-ramp < e < 0``) ``approach`` rises smoothly from 0 to 1
        (the front of the tongue heads for the gap); past the front (``e > 0``) the tongue may
        be twice ``e`` in front of the teeth's surface until that is the tip's lead on T1
        (``TONGUE_TIP_AHEAD_MM``), then ``e`` plus that lead: so it reaches the data's positions
        within T1's first 8 mm past them, and never needs more.

        Returns
        -------
        approach : float (F,) in [0, 1]
        allowance : float (F,) >= 0, Parke units
        """
        e = t1[:, 0] - (teeth[:, N.UPPER_INCISOR_TIP - 1, 0] - margin)
        s = np.clip(e / ramp + 1.0, 0.0, 1.0)
        e = np.maximum(e, 0.0)
        lead = cassi10_constants.TONGUE_TIP_AHEAD_MM * scale
        return s * s * (3.0 - 2.0 * s), e + np.minimum(e, lead)

    @staticmethod
    def _pass_between_teeth(st: np.ndarray, toward: np.ndarray, teeth: np.ndarray,
                            margin: float, lo: np.ndarray, hi: np.ndarray, zone: float
                            ) -> np.ndarray:
        """As the tongue heads out while T2 is behind the teeth, the station between T1 and T2
        (no pellet site) moves to where the tongue passes the teeth: just behind the upper
        incisors, within the zone, at a height inside the jaw's gap, so that neither of its
        neighbours' edges cuts through a tooth. By the weight ``toward`` times how far T2 is
        behind that place (in full from half the zone: a T2 that close to the teeth is in the
        gap itself), so it moves there continuously. ``st`` changes in place.

        ``lo``, ``hi``: the jaw's gap (:func:`_gap`). Returns the weight it moved by, float
        (F,)."""
        # never ahead of T1 (a tongue drawn back while its front is still at the gap's height)
        place = np.minimum(teeth[:, N.UPPER_INCISOR_TIP - 1, 0] - 0.5 * zone,
                           st[:, 1, 0] - margin)
        behind = np.clip((place - margin - st[:, 3, 0]) / (0.5 * zone), 0.0, 1.0)
        w = toward * behind
        z = np.clip(st[:, 2, 1], lo, np.maximum(hi, lo))
        st[:, 2, 0] += w * (place - st[:, 2, 0])
        st[:, 2, 1] += w * (z - st[:, 2, 1])
        return w

    def initialise(self, ctx: TaskContext) -> None:
        plan = self._setup(ctx)
        first = np.stack([ctx.pellet(p)[:1] for p in _PELLETS], axis=1)      # (1, 4, 2)
        t0 = np.asarray(ctx.rec.time_us, np.float64)[ctx.rows[:1]] * 1e-6
        v, _ = self.tongue(ctx, first, ctx.start[None], t0, {}, ctx.rows[:1])
        ctx.start[plan["rows"]] = v.reshape(-1, 3)

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        plan = self._setup(ctx)
        pellets = np.stack([ctx.pellet(p) for p in _PELLETS], axis=1)        # (F, 4, 2)
        time_s = np.asarray(ctx.rec.time_us, np.float64)[ctx.rows] * 1e-6
        carried = plan.setdefault("carried", {})        # from one chunk of frames to the next
        diags = []
        for a in range(0, len(positions), BLOCK_FRAMES):
            b = a + BLOCK_FRAMES
            v, diag = self.tongue(ctx, pellets[a:b], positions[a:b], time_s[a:b], carried,
                                  ctx.rows[a:b])
            positions[a:b, plan["rows"]] = v.reshape(v.shape[0], -1, 3)
            diags.append(diag)
        ctx.diagnostics.update({k: np.concatenate([d[k] for d in diags])
                                for k in (diags[0] if diags else ())})
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
