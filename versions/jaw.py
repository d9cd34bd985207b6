"""Jaw rotation: Parke's (thesis 3.1.3) and CASSI 1.0's (thesis 4.1.3), vectorised over frames.

Notation (thesis Figure 4.8): the jaw line runs from point 1 to point 2 (MANi, MANm). The
original line ``(x1, y1)-(x2, y2)`` is rotated to ``(x1', y1')-(x2', y2')`` by ``theta`` about the
point of rotation ``(a, b)``. In Parke space the second coordinate is z.

* Eq. 4.1 / 4.2: ``tan alpha = (y1 - y2) / (x1 - x2)``, ``tan beta = (y1' - y2') / (x1' - x2')``;
  we take the angles with ``atan2`` so a line turned past vertical keeps its quadrant.
* Eq. 4.3: ``theta = alpha - beta``. Eqs. 4.4-4.5 (and 3.3-3.6) rotate a point *clockwise* by
  theta (``x' - a = (x - a) cos + (y - b) sin``), which lowers the slope angle by theta, so the
  angle of rotation that carries the original line onto the current one is ``alpha - beta``:
  positive theta opens the jaw (the chin, in front of the pivot, goes down).
* Eq. 4.6: ``b = [(y' + x sin - y cos)(1 - cos) - (x' - x cos - y sin) sin] / (2 - 2 cos)``
* Eq. 4.7: ``a = [y' + x sin - y cos - b (1 - cos)] / sin``
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from cassi.versions import constants as K
from cassi.versions.constants import Zone

__all__ = [
    "line_angle",
    "jaw_angle",
    "rotation_point",
    "rotate_about",
    "JawMotion",
    "solve_jaw_motion",
    "fixed_pivot_motion",
    "apply_zones",
]


def line_angle(p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Angle of incline of the line p2 -> p1 (Eqs. 4.1-4.2), radians in (-pi, pi].

    Parameters
    ----------
    p1, p2 : float (..., 2)
        Points 1 and 2 (x, y) of the jaw line.
    """
    d = np.asarray(p1, dtype=np.float64) - np.asarray(p2, dtype=np.float64)
    return np.arctan2(d[..., 1], d[..., 0])


def jaw_angle(start1: np.ndarray, start2: np.ndarray, cur1: np.ndarray, cur2: np.ndarray) -> np.ndarray:
    """Angle of rotation theta = alpha - beta (Eq. 4.3), wrapped to (-pi, pi], radians.

    ``start*`` and ``cur*`` broadcast: (2,) against (F, 2) gives (F,).
    """
    theta = line_angle(start1, start2) - line_angle(cur1, cur2)
    return (theta + np.pi) % (2.0 * np.pi) - np.pi


def rotation_point(x: np.ndarray, y: np.ndarray, xp: np.ndarray, yp: np.ndarray,
                   theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The point of rotation (a, b) that carries (x, y) to (x', y') by theta (Eqs. 4.6-4.7).

    All arguments broadcast. Where ``|theta| < THETA_EPS`` the point is at infinity and NaN is
    returned (see :func:`solve_jaw_motion` for the limit used there).
    """
    x, y, xp, yp, theta = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64)
                                                for v in (x, y, xp, yp, theta)))
    c, s = np.cos(theta), np.sin(theta)
    # 1 - cos(theta) written as 2 sin^2(theta / 2): the same quantity, but without the
    # cancellation that makes 1 - cos(1e-8) exactly 0 in floating point.
    omc = 2.0 * np.sin(0.5 * theta) ** 2
    small = np.abs(theta) < K.THETA_EPS
    with np.errstate(divide="ignore", invalid="ignore"):
        b = ((yp + x * s - y * c) * omc - (xp - x * c - y * s) * s) / (2.0 * omc)
        a = (yp + x * s - y * c - b * omc) / s
    return np.where(small, np.nan, a), np.where(small, np.nan, b)


def rotate_about(points: np.ndarray, theta: np.ndarray, center: np.ndarray) -> np.ndarray:
    """Rotate points by theta about center with Parke's Eqs. 3.3-3.4 (clockwise for theta > 0).

    Parameters
    ----------
    points : float (..., N, 2) or (N, 2)
    theta : float (...,)
    center : float (..., 2)

    Returns
    -------
    float64 (..., N, 2)
    """
    p = np.asarray(points, dtype=np.float64)
    t = np.asarray(theta, dtype=np.float64)[..., None]
    ctr = np.asarray(center, dtype=np.float64)[..., None, :]
    c, s = np.cos(t), np.sin(t)
    dx = p[..., 0] - ctr[..., 0]
    dz = p[..., 1] - ctr[..., 1]
    out = np.empty(np.broadcast_shapes(p.shape, ctr.shape), dtype=np.float64)
    out[..., 0] = dx * c + dz * s + ctr[..., 0]
    out[..., 1] = dz * c - dx * s + ctr[..., 1]
    return out


@dataclass(frozen=True)
class JawMotion:
    """Per-frame jaw rotation.

    Attributes
    ----------
    theta : float64 (F,)
        Angle of rotation, radians (positive opens).
    point : float64 (F, 2)
        Point of rotation (a, b); NaN where ``|theta| < THETA_EPS``.
    anchor : float64 (F, 2)
        The point whose motion fixed (a, b) (point 1 before rotation).
    shift : float64 (F, 2)
        That point's displacement: the limit motion used where theta is ~0.
    """

    theta: np.ndarray
    point: np.ndarray
    anchor: np.ndarray
    shift: np.ndarray

    @property
    def degrees(self) -> np.ndarray:
        return np.degrees(self.theta)


def solve_jaw_motion(start1: np.ndarray, start2: np.ndarray, cur1: np.ndarray,
                     cur2: np.ndarray, *, anchor: int = K.ROTATION_ANCHOR) -> JawMotion:
    """Angle (Eqs. 4.1-4.3) and point of rotation (Eqs. 4.6-4.7) for every frame.

    Parameters
    ----------
    start1, start2 : float (2,) or (F, 2)
        The starting jaw line: point 1 (MANi) and point 2 (MANm), (x, y).
    cur1, cur2 : float (F, 2) or (2,)
        The rotated jaw line in each frame.
    anchor : {1, 2}
        The point whose motion Eqs. 4.6-4.7 solve (a, b) from: it follows its target exactly.
    """
    theta = np.atleast_1d(jaw_angle(start1, start2, cur1, cur2))
    if anchor not in (1, 2):
        raise ValueError(f"anchor must be 1 or 2, got {anchor!r}")
    s1 = np.asarray(start1 if anchor == 1 else start2, dtype=np.float64)
    c1 = np.asarray(cur1 if anchor == 1 else cur2, dtype=np.float64)
    s1b, c1b = np.broadcast_arrays(s1, c1)
    s1b = np.broadcast_to(s1b, theta.shape + (2,))
    c1b = np.broadcast_to(c1b, theta.shape + (2,))
    a, b = rotation_point(s1b[..., 0], s1b[..., 1], c1b[..., 0], c1b[..., 1], theta)
    return JawMotion(theta=theta, point=np.stack([a, b], axis=-1), anchor=s1b.copy(),
                     shift=c1b - s1b)


def fixed_pivot_motion(theta: np.ndarray, pivot: np.ndarray) -> JawMotion:
    """Parke's rotation (Eqs. 3.5-3.6): every frame about the same pivot (vertex 107)."""
    theta = np.atleast_1d(np.asarray(theta, dtype=np.float64))
    point = np.broadcast_to(np.asarray(pivot, dtype=np.float64), theta.shape + (2,)).copy()
    return JawMotion(theta=theta, point=point, anchor=point.copy(), shift=np.zeros_like(point))


def _zone_motion(src: np.ndarray, motion: JawMotion, fraction: float) -> np.ndarray:
    """src (N, 2) or (F, N, 2) rotated by fraction * theta about the frame's point -> (F, N, 2)."""
    theta = motion.theta * fraction
    small = np.abs(motion.theta) < K.THETA_EPS
    if not small.any():
        return rotate_about(src, theta, motion.point)
    center = np.where(small[:, None], 0.0, motion.point)
    out = rotate_about(src, np.where(small, 0.0, theta), center)
    # The limit of a rotation about a point at infinity: each zone translates by its fraction
    # of the anchor's displacement (continuous with the rotation as theta -> 0).
    srcb = np.broadcast_to(src, out.shape)
    lim = srcb + fraction * motion.shift[:, None, :]
    return np.where(small[:, None, None], lim, out)


def apply_zones(base: np.ndarray, motion: JawMotion, zones: Iterable[Zone],
                out: np.ndarray | None = None) -> np.ndarray:
    """Rotate each zone's vertices of ``base`` by its fraction of the jaw angle.

    Parameters
    ----------
    base : float (V, 3) or (F, V, 3)
        Vertex positions before the rotation (Parke units).
    motion : JawMotion
        F frames of rotation.
    zones : iterable of Zone
        Vertices (1-based), fraction of theta, axes ("xz" or "z": only z takes the rotated value).
    out : float64 (F, V, 3), optional
        Written in place (zones' vertices only); created from ``base`` when omitted.

    Returns
    -------
    float64 (F, V, 3)
    """
    base = np.asarray(base, dtype=np.float64)
    n = motion.theta.shape[0]
    if out is None:
        out = np.broadcast_to(base, (n,) + base.shape[-2:]).copy()
    for zone in zones:
        idx = zone.index()
        src = base[..., idx, :][..., [0, 2]]
        rot = _zone_motion(src, motion, zone.fraction)
        if zone.axes == "z":
            out[:, idx, 2] = rot[..., 1]
        else:
            out[:, idx, 0] = rot[..., 0]
            out[:, idx, 2] = rot[..., 1]
    return out
