"""A small synthetic mouth for the rubric's planted-defect tests (units: mm, 1 unit = 1 mm).

Axes as Parke's: x forward, y to the face's left, z up; left half only. The origin is the tip of
the upper front teeth (vertex 226's role). Teeth are two sheets each (front and back surface) plus
a side sheet running back along x; the tongue lies behind the teeth, the palate above them, the
lips in front. ``animate`` opens and closes the jaw by rotating the lower parts about a pivot far
behind, like Parke's jaw rotation, with the same small pellet noise on every moving vertex (data
jitter, which is no fault). Each ``plant_*`` returns a copy with one defect planted.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from cassi.harness.rubric.geometry import MouthParts


class _Builder:
    def __init__(self):
        self.pts: list[tuple[float, float, float]] = []
        self.names: dict[str, int] = {}

    def add(self, p, name=None) -> int:
        self.pts.append(tuple(float(c) for c in p))
        i = len(self.pts) - 1
        if name:
            self.names[name] = i
        return i

    def grid(self, corner, du, dv, nu=3, nv=3) -> np.ndarray:
        """A planar grid of (nu x nv) vertices; returns its triangles (T, 3)."""
        corner, du, dv = map(np.asarray, (corner, du, dv))
        idx = np.empty((nu, nv), int)
        for i in range(nu):
            for j in range(nv):
                idx[i, j] = self.add(corner + du * i / (nu - 1) + dv * j / (nv - 1))
        tris = []
        for i in range(nu - 1):
            for j in range(nv - 1):
                a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
                tris += [(a, b, c), (a, c, d)]
        return np.asarray(tris)


@dataclass
class Mouth:
    rest: np.ndarray            # (V, 3)
    parts: MouthParts
    names: dict
    lower: np.ndarray           # vertices that move with the jaw
    lower_lip: np.ndarray
    tongue: np.ndarray
    corners: np.ndarray
    pivot: np.ndarray = field(default_factory=lambda: np.array([-70.0, 0.0, 5.0]))


def build() -> Mouth:
    b = _Builder()
    # upper front teeth: front sheet x=0, back sheet x=-2, y 0..8, z 0..9 (tip at z=0)
    up_front = b.grid((0, 0, 0), (0, 8, 0), (0, 0, 9))
    up_back = b.grid((-2, 0, 0), (0, 8, 0), (0, 0, 9))
    up_side = b.grid((-30, 9, 0), (28, 0, 0), (0, 0, 7))
    tip = b.add((0, 0, 0), "upper_incisor_tip")
    up_molar = b.add((-30, 9, 0), "upper_molar")
    upper_teeth = list(range(0, len(b.pts)))
    # lower front teeth: front x=-1, back x=-3, y 0..7, z -9..1 (tip z=1: 1 mm overbite)
    n0 = len(b.pts)
    lo_front = b.grid((-1, 0, -9), (0, 7, 0), (0, 0, 10))
    lo_back = b.grid((-3, 0, -9), (0, 7, 0), (0, 0, 10))
    lo_side = b.grid((-30, 8, -6), (27, 0, 0), (0, 0, 7))
    lo_tip = b.add((-1, 0, 1), "lower_incisor_tip")
    lo_gum = b.add((-1, 0, -8), "lower_gum")
    lo_molar = b.add((-30, 8, 1), "lower_molar")
    lower_teeth = list(range(n0, len(b.pts)))
    # tongue: centerline tip, T1..T4, back; six edge vertices at y=4
    t0 = len(b.pts)
    centre = [(-5, 0, -2), (-8, 0, -1), (-14, 0, 0), (-20, 0, 1), (-26, 0, 0), (-32, 0, -3)]
    edge = [(-7, 4, -2.5), (-10, 5, -1.5), (-15, 6, -0.5), (-20, 6, 0), (-26, 5, -1), (-31, 4, -3)]
    for p in centre + edge:
        b.add(p)
    tongue = np.arange(t0, t0 + 12)
    tedges = [(t0 + i, t0 + i + 1) for i in range(5)] + [(t0 + 6 + i, t0 + 7 + i) for i in range(5)] \
        + [(t0 + i, t0 + 6 + i) for i in range(6)]
    # palate: z = 10 over x -30..-3, y 0..8
    p0 = len(b.pts)
    palate_tris = b.grid((-30, 0, 10), (27, 0, 0), (0, 8, 0), 4, 3)
    palate = np.arange(p0, len(b.pts))
    # lips
    L = {}
    for name, p in {
        "67": (5, 0, 8), "68": (4.5, 8, 7.5), "69": (3, 14, 5),
        "64": (5, 0, 4), "61": (4, 0, 0.1), "62": (3.8, 8, 0.1), "63": (2.5, 14, 0.3),
        "70": (1, 19, 0), "287": (1.5, 16, 0.0), "300": (1.2, 17.5, 0.0),
        "58": (4, 0, -0.1), "59": (3.8, 8, -0.1), "60": (2.5, 14, -0.3),
        "55": (4.5, 0, -4), "49": (4.5, 0, -8), "50": (4, 8, -7.5), "51": (2.5, 14, -5),
        "71": (5.5, 0, 11), "72": (5, 8, 10.5), "73": (3.5, 14, 8),
        "subnasale": (7, 0, 14),
        "41": (3.5, 0, -11), "42": (3, 8, -10.5), "43": (2, 14, -8),
        "chin": (6, 0, -16), "chin_low": (2, 0, -22),
    }.items():
        L[name] = b.add(p, name)
    j0 = len(b.pts)
    for p in [(-60, 30, -20), (-40, 35, -25), (-20, 30, -25), (0, 20, -22), (-55, 35, 0)]:
        b.add(p)
    jaw = np.concatenate([[L["chin"], L["chin_low"], L["41"]], np.arange(j0, len(b.pts))])
    rest = np.asarray(b.pts, float)
    names = dict(b.names, **{k: v for k, v in L.items()})
    tri = lambda *ts: np.concatenate(ts)  # noqa: E731
    parts = MouthParts(
        upper_teeth_tris=tri(up_front, up_back, up_side), lower_teeth_tris=tri(lo_front, lo_back, lo_side),
        tongue=tongue, tongue_edges=tedges, palate=palate, palate_tris=palate_tris,
        ul_outer=L["67"], ll_outer=L["49"], ul_inner=L["61"], ll_inner=L["58"],
        upper_inner=[L["61"], L["62"], L["63"]], lower_inner=[L["58"], L["59"], L["60"]],
        inner_corner=L["287"], upper_outer=[L["67"], L["68"], L["69"]],
        lower_outer=[L["49"], L["50"], L["51"]], corner=L["70"],
        lip_points=[L[k] for k in ("67", "68", "69", "64", "61", "62", "63", "70", "287", "300",
                                   "58", "59", "60", "55", "49", "50", "51")],
        above_lip=[L["71"], L["72"], L["73"]], below_lip=[L["41"], L["42"], L["43"]],
        subnasale=L["subnasale"], chin=L["chin"], chin_low=L["chin_low"],
        upper_incisor_tip=tip, lower_incisor_tip=lo_tip, lower_gum=lo_gum,
        upper_molar=up_molar, lower_molar=lo_molar, jaw_point=lo_gum, jaw=jaw)
    lower_lip = np.asarray([L[k] for k in ("58", "59", "60", "55", "49", "50", "51",
                                           "41", "42", "43")])
    lower = np.concatenate([lower_teeth, lower_lip, [L["chin"], L["chin_low"]],
                            np.arange(j0, len(b.pts))])
    return Mouth(rest, parts, names, np.asarray(lower), lower_lip, tongue,
                 np.asarray([L["70"], L["287"], L["300"]]))


def _rotate(p, pivot, theta):
    """Rotate points (F, n, 3) about ``pivot`` in x-z by theta (F,) radians: front goes down."""
    d = p - pivot
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    out = p.copy()
    out[..., 0] = pivot[0] + d[..., 0] * c + d[..., 2] * s
    out[..., 2] = pivot[2] - d[..., 0] * s + d[..., 2] * c
    return out


@dataclass
class Anim:
    positions: np.ndarray
    diagnostics: pd.DataFrame
    frames: np.ndarray
    version: str = "synthetic"


def jaw_theta(F: int, open_rad: float) -> np.ndarray:
    """The jaw angle per frame of :func:`animate`: open and close twice, closed at both ends."""
    return open_rad * np.sin(np.pi * 2 * np.arange(F) / (F - 1)) ** 2


def on_jaw(m: Mouth, anim: "Anim", rest_point, *, open_rad: float) -> np.ndarray:
    """Where a point fixed to the lower teeth at ``rest_point`` is in every frame: (F, 3)."""
    F = anim.positions.shape[0]
    theta = jaw_theta(F, open_rad)
    ref = m.parts.lower_incisor_tip
    p = _rotate(np.repeat(np.asarray(rest_point, float)[None, None], F, 0), m.pivot, theta)[:, 0]
    r = _rotate(np.repeat(m.rest[ref][None, None], F, 0), m.pivot, theta)[:, 0]
    return p + (anim.positions[:, ref] - r)  # plus the frame's noise


def animate(m: Mouth, *, F: int = 200, open_rad: float = 0.10, noise: float = 0.03,
            seed: int = 0, switch_every: int = 40) -> Anim:
    """Open and close the jaw twice (closed at start and end); same noise on every vertex."""
    t = np.arange(F)
    theta = jaw_theta(F, open_rad)
    pos = np.repeat(m.rest[None], F, axis=0)
    pos[:, m.lower] = _rotate(pos[:, m.lower], m.pivot, theta)
    pos[:, m.tongue] = _rotate(pos[:, m.tongue], m.pivot, 0.6 * theta)
    pos[:, m.corners] = _rotate(pos[:, m.corners], m.pivot, 0.35 * theta)
    rng = np.random.default_rng(seed)
    pos += rng.normal(0, noise, (F, 1, 3))  # the head's pellet noise: every vertex alike
    # OUTER_ABC_CALC changes branch twice as often as the ellipse switches between horizontal
    # and vertical: only the latter is the thesis's "ellipse switch"
    branch = (t // (switch_every // 2)) % 3
    ellipse = np.where((t // switch_every) % 2 == 1, "vertical", "horizontal")
    diag = pd.DataFrame({"frame": t, "outer_abc_branch": branch.astype(np.int8),
                         "ellipse": ellipse.astype(object)})
    return Anim(pos.astype(np.float32), diag, t.copy())


def round_opening(m: Mouth, anim: Anim) -> Anim:
    """Wide-open lips of a smooth outline (task 106): the inner outline's side vertices on the
    half-ellipses through 61 (58), the inner corner 287 and its height; the rigid jaw alone
    gives a flat-topped hexagon (CASSI 1.0's fault)."""
    pos = anim.positions.astype(float).copy()
    p = m.parts
    c = pos[:, p.inner_corner]
    for centre, side in ((p.ul_inner, p.upper_inner[1:]), (p.ll_inner, p.lower_inner[1:])):
        h = pos[:, centre, 2] - c[:, 2]
        for v in side:
            t = np.clip(pos[:, v, 1] / c[:, 1], 0.0, 1.0)
            pos[:, v, 2] = c[:, 2] + h * np.sqrt(1.0 - t ** 2)
    return Anim(pos.astype(np.float32), anim.diagnostics, anim.frames)


def protrude(m: Mouth, anim: Anim, *, forward: float = 5.0, round_to: float = 0.75) -> Anim:
    """Task 118: the lips move forward and the corners in, peaking at the middle of the task."""
    F = anim.positions.shape[0]
    w = np.sin(np.pi * np.arange(F) / (F - 1)) ** 2
    pos = anim.positions.astype(float).copy()
    lips = m.parts.lip_points
    pos[:, lips, 0] += forward * w[:, None]
    pos[:, lips, 1] *= (1 - (1 - round_to) * w)[:, None]
    # CASSI moves the points above and below the lips by part of the lips' motion (4.2.2)
    near = np.concatenate([m.parts.above_lip, m.parts.below_lip])
    pos[:, near, 0] += forward * w[:, None]
    return Anim(pos.astype(np.float32), anim.diagnostics, anim.frames)


def copy(anim: Anim) -> Anim:
    return Anim(anim.positions.astype(float).copy(), anim.diagnostics.copy(), anim.frames.copy())
