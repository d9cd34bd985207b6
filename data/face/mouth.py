"""Teeth, tongue and palate of the generated face (inside the mouth).

Parke's teeth: 8 quads per quadrant and set (the labial/buccal face of each tooth) along
parabolic dental arches; CASSI's flat 12-vertex tongue inside the lower arch (thesis 4.1.1,
Figure 4.6); the palate surface from PAL.DAT's outline (4.1.1 "Palatal Outline"), resampled to
a fixed number of stations so that every subject's face has the same vertex count.
"""
from __future__ import annotations

import numpy as np

from cassi.data.face import numbering as N
from cassi.data.face.layout import PALATE, TEETH, TONGUE, Layout


#: Dental arches: tooth widths along the arch (mm) for Parke's 8 quads per quadrant. The first
#: molar is two quads so that quads 7 and 8 meet where the first and second molars do (CASSI's
#: MANm site, midpoint of 281 and 286).
TOOTH_WIDTHS_MM = np.array([8.5, 6.5, 7.5, 7.0, 6.5, 5.0, 5.0, 10.0])
LOWER_TOOTH_WIDTHS_MM = np.array([5.3, 5.9, 6.9, 7.0, 7.1, 5.6, 5.6, 10.5])
UPPER_TIP = np.array([345.0, 0.0, -258.0])     # vertex 226
#: Gap between neighbouring teeth along the arch, Parke units (each side).
TOOTH_GAP = 0.8
UPPER_TOOTH_HEIGHT = 42.0
LOWER_TIP = np.array([338.0, 0.0, -250.0])     # lower incisor tip (overbite 8, overjet 7)
LOWER_TOOTH_HEIGHT = 38.0
#: The lower teeth's gum line (where the MANi and MANm sites lie) falls this much (Parke units
#: per unit behind the central incisor) toward the molars, so that the MANm site (281/286) sits
#: ~2.5 mm below the MANi site (258), as the XRMB pellets do (MNM 2-3 mm below MNI, JW45
#: Figure 3.9: -7.5 and -9.9 mm); the lower biting edges stay level (the occlusal plane is the
#: XRMB x axis), under the upper teeth's tips.
LOWER_GUM_SLOPE = 0.0712


def _arch(front_x, widths_mm, half_width_back, depth):
    """Points along a parabolic dental arch from the centre line backwards (left side).

    Returns float (9, 2) of (x, y) at the tooth boundaries and the outward normals (9, 2).
    """
    # parabola x = front_x - depth * (y / half_width_back) ** 2, sampled by arc length
    ys = np.linspace(0, half_width_back * 1.4, 4000)
    xs = front_x - depth * (ys / half_width_back) ** 2
    s = np.r_[0.0, np.cumsum(np.hypot(np.diff(xs), np.diff(ys)))]
    b = np.r_[0.0, np.cumsum(widths_mm * N.UNITS_PER_MM)]
    yb = np.interp(b, s, ys)
    xb = front_x - depth * (yb / half_width_back) ** 2
    # outward normal of the parabola: gradient of (x - front_x + depth*(y/h)^2)
    nx = np.ones_like(yb)
    ny = 2 * depth * yb / half_width_back ** 2
    nrm = np.hypot(nx, ny)
    return np.stack([xb, yb], 1), np.stack([nx / nrm, ny / nrm], 1)


def arch_points(which: str):
    """Boundaries (x, y) and normals of the upper or lower arch (for tests and the tongue)."""
    if which == "upper":
        return _arch(UPPER_TIP[0], TOOTH_WIDTHS_MM, 105.0, 175.0)
    return _arch(LOWER_TIP[0] - 2.0, LOWER_TOOTH_WIDTHS_MM, 98.0, 170.0)


def _teeth(lay: Layout):
    """Parke's teeth: 8 quads per quadrant and set, the labial/buccal face of each tooth."""
    for which in ("upper", "lower"):
        pts, _ = arch_points(which)
        for k in range(N.TEETH_PER_SET):
            # a small gap between neighbouring teeth (none at the centre line)
            a, b = pts[k], pts[k + 1]
            g = TOOTH_GAP / max(np.linalg.norm(b - a), 1e-9)
            a2 = a if k == 0 else a + (b - a) * g
            b2 = b - (b - a) * g
            (x0, y0), (x1, y1) = a2, b2
            # molars are shorter crowns; the occlusal plane curves up slightly behind
            if which == "upper":
                tip = UPPER_TIP[2] + 0.02 * (UPPER_TIP[0] - np.array([x0, x1]))
                h = UPPER_TOOTH_HEIGHT * (1.0 if k < 3 else 0.8)
                gum = tip + h
                v = N.upper_tooth(k)  # gum-mesial, gum-distal, tip-distal, tip-mesial
                quad = [(x0, y0, gum[0]), (x1, y1, gum[1]), (x1, y1, tip[1]), (x0, y0, tip[0])]
                if k == 0:
                    quad[0] = (x0, 0.0, gum[0])
                    quad[3] = tuple(UPPER_TIP)
            else:
                # level biting edges; the gum line from MANi's height falling toward the molars
                tip = np.full(2, LOWER_TIP[2])
                front = pts[0, 0]
                gum = LOWER_TIP[2] - LOWER_TOOTH_HEIGHT \
                    - LOWER_GUM_SLOPE * (front - np.array([x0, x1]))
                v = N.lower_tooth(k)  # tip-mesial, tip-distal, gum-distal, gum-mesial
                quad = [(x0, y0, tip[0]), (x1, y1, tip[1]), (x1, y1, gum[1]), (x0, y0, gum[0])]
            keys = [lay.add(f"tooth.{which}.{k}.{j}", quad[j], v[j]) for j in range(4)]
            # upper: (gum-m, gum-d, tip-d, tip-m) seen from outside (+x/+y) runs clockwise
            # lower: (tip-m, tip-d, gum-d, gum-m) likewise clockwise from outside
            lay.poly(TEETH, keys)


def _tongue(lay: Layout):
    """The flat 12-vertex tongue inside the lower arch (4.1.1, Figure 4.6)."""
    z = LOWER_TIP[2] - 22.0
    xs = np.array([LOWER_TIP[0] - 28.0, 0, 0, 0, 0, 0], float)
    # T1 ~10 mm behind the tip, T4 ~60 mm (thesis 3.2.3); equal thirds between
    xs[1] = xs[0] - 10 * N.UNITS_PER_MM
    xs[4] = xs[0] - 58 * N.UNITS_PER_MM
    xs[2] = xs[1] + (xs[4] - xs[1]) / 3
    xs[3] = xs[1] + 2 * (xs[4] - xs[1]) / 3
    xs[5] = xs[4] - 12 * N.UNITS_PER_MM
    pts, _ = arch_points("lower")
    # inner half-width of the arch at each x, less a margin
    order = np.argsort(pts[:, 0])
    def arch_half(x):
        return np.interp(x, pts[order, 0], pts[order, 1], left=pts[order, 1][0],
                         right=0.0)
    half = np.array([arch_half(x) for x in xs]) - 18.0
    half[0] = 12.0
    half = np.clip(half, 12.0, 80.0)
    half[5] = half[4] * 0.9
    centre = [lay.add(f"tongue.c{k}", (xs[k], 0.0, z), N.TONGUE_CENTRE[k]) for k in range(6)]
    edge = [lay.add(f"tongue.e{k}", (xs[k] - (6.0 if k == 0 else 0.0), half[k], z),
                    N.TONGUE_EDGE[k]) for k in range(6)]
    for k in range(5):
        # seen from above (+z, the outside of the flat tongue) clockwise: c_k, e_k, e_k+1, c_k+1
        lay.poly(TONGUE, (centre[k], centre[k + 1], edge[k + 1], edge[k]))


#: A typical palate outline (x, y in mm, XRMB coordinates: origin at the upper incisor tips, x
#: forward, y up), front to back; shaped like the outline of thesis Figure 3.11.
DEFAULT_PALATE_MM = np.array([
    (-5.0, 8.5), (-10.0, 11.5), (-15.0, 16.8), (-19.1, 19.6), (-23.9, 22.4), (-29.1, 22.9),
    (-36.7, 23.4), (-41.1, 23.3), (-45.0, 22.7), (-47.2, 22.3), (-51.2, 21.8), (-53.1, 21.3),
])


#: The typical palate on the generated face, designed like the teeth in mm from the upper
#: incisor tip at the model's own scale (a subject's palate is mapped by
#: :class:`cassi.versions.mapping.XrmbToParke`, p/d, instead).
DEFAULT_PALATE_XZ = np.stack([UPPER_TIP[0] + N.UNITS_PER_MM * DEFAULT_PALATE_MM[:, 0],
                              UPPER_TIP[2] + N.UNITS_PER_MM * DEFAULT_PALATE_MM[:, 1]], axis=1)


def resample_outline(xy: np.ndarray, n: int) -> np.ndarray:
    """Resample a polyline (front to back) to ``n`` points equally spaced by arc length."""
    xy = np.asarray(xy, float)
    seg = np.hypot(*np.diff(xy, axis=0).T)
    s = np.r_[0.0, np.cumsum(seg)]
    t = np.linspace(0.0, s[-1], n)
    return np.stack([np.interp(t, s, xy[:, 0]), np.interp(t, s, xy[:, 1])], axis=1)


def palate_surface(palate_xz: np.ndarray) -> np.ndarray:
    """The palate's left half: float (STATIONS, ACROSS, 3), Parke units.

    ``palate_xz`` is the centre-line outline in Parke (x, z), front to back, any length >= 2.
    Narrow at the front, wider behind, sloping down from the centre line to its edges
    (thesis 4.1.1, "Palatal Outline"); the edges meet the upper teeth's gum line.
    """
    st = resample_outline(palate_xz, N.PALATE_STATIONS)
    pts, _ = arch_points("upper")
    order = np.argsort(pts[:, 0])
    gum_z = UPPER_TIP[2] + UPPER_TOOTH_HEIGHT * 0.8
    out = np.zeros((N.PALATE_STATIONS, N.PALATE_ACROSS, 3))
    for s, (x, z) in enumerate(st):
        # inner half-width of the upper arch at this x (the palate sits inside the teeth)
        w = float(np.interp(x, pts[order, 0], pts[order, 1], left=pts[order, 1][0],
                            right=0.0)) - 10.0
        frac = s / (N.PALATE_STATIONS - 1)
        w = max(w, 25.0 + 50.0 * frac)
        for a in range(N.PALATE_ACROSS):
            u = a / (N.PALATE_ACROSS - 1)
            y = w * u
            # slope down to the edges: reach the gum line at the edge, never above the centre
            edge_z = min(z, gum_z)
            zz = z + (edge_z - z) * u ** 1.6
            out[s, a] = (x - 4.0 * u, y, zz)
    return out


def _palate(lay: Layout, palate_xz):
    if palate_xz is None:
        palate_xz = DEFAULT_PALATE_XZ
    surf = palate_surface(palate_xz)
    keys = [[lay.add(f"palate.{s}.{a}", surf[s, a], N.palate_vertex(s, a))
             for a in range(N.PALATE_ACROSS)] for s in range(N.PALATE_STATIONS)]
    for s in range(N.PALATE_STATIONS - 1):
        for a in range(N.PALATE_ACROSS - 1):
            # the palate's visible side faces down (into the mouth): clockwise seen from below
            lay.poly(PALATE, (keys[s][a], keys[s][a + 1], keys[s + 1][a + 1], keys[s + 1][a]))

