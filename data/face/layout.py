"""Building blocks of the face generator: materials, named nodes, polygons over node keys,
and stitching rows of nodes into quads and triangles."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cassi.data.face.surface import surface_point

#: Materials (Parke's 1-4 and this project's additions); values are render part names.
MATERIAL_NAMES: dict[int, str] = {
    1: "skin", 2: "lips", 3: "eyelash", 4: "teeth", 5: "tongue", 6: "palate",
    7: "eye_white", 8: "iris", 9: "fringe", 10: "pupil", 11: "reflection", 12: "eyebrow",
}
PARKE_MATERIAL_NAMES = {1: "flesh", 2: "lips", 3: "eyelash", 4: "teeth"}
SKIN, LIPS, EYELASH, TEETH, TONGUE, PALATE = 1, 2, 3, 4, 5, 6
EYE_WHITE, IRIS, FRINGE, PUPIL, REFLECTION, EYEBROW = 7, 8, 9, 10, 11, 12
#: Materials whose polygons are not mirrored (both eyes are explicit).
UNMIRRORED_MATERIALS = frozenset({EYE_WHITE, IRIS, FRINGE, PUPIL, REFLECTION})


@dataclass
class _Node:
    key: str          # unique name while building
    pos: np.ndarray   # (3,)
    want: object      # a fixed vertex number (int) or a pool name (str)
    closed: np.ndarray | None = None  # st2 position where it differs (eyelids)


@dataclass
class Layout:
    """What the generator builds before numbering: nodes, polygons over node keys."""

    nodes: dict[str, _Node] = field(default_factory=dict)
    polys: list[tuple[int, tuple[str, ...], tuple[int, ...]]] = field(default_factory=list)
    #: named groups of node keys that parameters act on (eyelid, brow, cheek, ...)
    regions: dict[str, list[str]] = field(default_factory=dict)

    def add(self, key, pos, want, closed=None) -> str:
        if key in self.nodes:
            raise ValueError(f"duplicate node {key}")
        self.nodes[key] = _Node(key, np.asarray(pos, float), want,
                                None if closed is None else np.asarray(closed, float))
        return key

    def poly(self, material, keys, crease=None):
        keys = tuple(keys)
        if len(set(keys)) != len(keys):
            raise ValueError(f"degenerate polygon {keys}")
        self.polys.append((material, keys, tuple(crease or (0,) * len(keys))))


def _smooth(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _row_angles(phi_front, phi_back, thetas, *, knee=90.0):
    """Elevation along a row: phi_front at the front, phi_back at the back, blending mostly
    behind ``knee`` degrees of azimuth."""
    th = np.asarray(thetas, float)
    s = _smooth((th - knee * 0.35) / (180.0 - knee * 0.35))
    return phi_front + (phi_back - phi_front) * s


def _stitch(lay: Layout, lower: list[str], upper: list[str], material=SKIN):
    """Stitch two rows (front -> back) into quads/triangles by arc-length fraction.

    Polygons are emitted clockwise seen from outside (Parke's order): for a lower row L and an
    upper row U running front to back on the left side, outside is +y-ish, and the order
    L[i], U[i], U[i+1], L[i+1] runs clockwise seen from outside.
    """
    # shared prefix / suffix (rows that merge, rows split round a hole): stitch only the part
    # in between, keeping the last shared node at each end
    while len(lower) > 1 and len(upper) > 1 and lower[1] == upper[1] and lower[0] == upper[0]:
        lower, upper = lower[1:], upper[1:]
    while len(lower) > 1 and len(upper) > 1 and lower[-2] == upper[-2] and \
            lower[-1] == upper[-1]:
        lower, upper = lower[:-1], upper[:-1]
    if lower == upper:
        return

    def frac(row):
        p = np.array([lay.nodes[k].pos for k in row])
        d = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
        return d / d[-1] if d[-1] > 0 else np.linspace(0, 1, len(row))

    fl, fu = frac(lower), frac(upper)
    i = j = 0
    while i < len(lower) - 1 or j < len(upper) - 1:
        if i < len(lower) - 1 and j < len(upper) - 1:
            a, b = fl[i + 1], fu[j + 1]
            if abs(a - b) < 0.35 * min(fl[i + 1] - fl[i], fu[j + 1] - fu[j]) and \
                    lower[i + 1] != upper[j + 1] and lower[i] != upper[j]:
                lay.poly(material, (lower[i], upper[j], upper[j + 1], lower[i + 1]))
                i += 1
                j += 1
                continue
            adv_lower = a <= b
        else:
            adv_lower = i < len(lower) - 1
        if adv_lower:
            tri = (lower[i], upper[j], lower[i + 1])
            i += 1
        else:
            tri = (lower[i], upper[j], upper[j + 1])
            j += 1
        if len(set(tri)) == 3:
            lay.poly(material, tri)


def _surface_row(lay: Layout, name: str, thetas, phis, wants) -> list[str]:
    pts = surface_point(np.asarray(thetas, float), np.asarray(phis, float))
    keys = []
    for k, (p, w) in enumerate(zip(pts, wants)):
        if abs(thetas[k]) < 1e-9 or abs(thetas[k] - 180.0) < 1e-9:
            p = p.copy()
            p[1] = 0.0  # centre-line vertices lie exactly on the midsagittal plane
        keys.append(lay.add(f"{name}.{k}", p, w))
    return keys
