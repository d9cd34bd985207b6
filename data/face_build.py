"""The generator of the face's geometry in Parke's structure (left half, Parke units).

Parke's own data files cannot ship, so the head is generated: a smooth implicit head (cranium,
face and neck blended), given a designed midsagittal profile (chin, lips, nose, forehead) that
fades off to the sides, and local relief (eye sockets, brows, cheekbones). Vertices are laid out
in rows from the front centre line (y = 0) round to the back centre line, from the base of the
neck to the crown; consecutive rows are stitched into quads and triangles. Two rows split
around a hole: the mouth (the lips fill it, Parke's 3 + 4 rows of lip vertices and the corner
vertices 70 / 300 / 287) and each eye (eyelid rings projected onto a sphere about the eyeball,
dissertation 3.1.2). Teeth (Parke's 8 quads per quadrant), the flat 12-vertex tongue and the
palate surface are added inside the mouth.

Everything here is deterministic: the same call gives the same numbers, so the topology is
fixed for every subject (only the palate's vertex positions depend on PAL.DAT).

Polygons are emitted in Parke's order, which (Figure 3.3's ``1 1 6 7 2`` with Figure 3.2's
vertices) runs clockwise seen from outside; :mod:`cassi.data.topology` flips them for rendering.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cassi.data import numbering as N
from cassi.data.parke_io import Polygon

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

#: Rays of the star-shaped head start here (inside every primitive).
CENTRE = np.array([0.0, 0.0, -60.0])

#: Parke's own vertices 1-17 (thesis Figure 3.2); the generated head uses them as they are.
PARKE_EXCERPT = {
    1: (45, 0, -594), 2: (28, 50, -585), 3: (-8, 105, -565), 4: (-45, 147, -542),
    5: (-90, 187, -518), 6: (100, 0, -450), 7: (93, 45, -445), 8: (70, 97, -412),
    9: (52, 127, -380), 10: (24, 158, -330), 11: (138, 0, -425), 12: (123, 45, -420),
    13: (103, 85, -386), 14: (210, 0, -415), 15: (215, 50, -410), 16: (326, 0, -423),
    17: (302, 60, -418),
}

#: The midsagittal profile (x, z) from the base of the neck to the crown, Parke units.
PROFILE = np.array([
    (45, -594), (100, -450), (138, -425), (210, -415), (290, -420), (326, -423), (352, -408),
    (366, -385), (372, -358), (366, -336), (350, -318), (352, -302), (370, -291), (388, -280),
    (380, -262), (372, -250), (382, -238), (394, -222), (386, -205), (376, -190), (366, -172),
    (384, -160), (425, -150), (446, -136), (442, -115), (424, -88), (402, -45), (378, -5),
    (356, 33), (362, 62), (374, 92), (371, 140), (362, 200), (343, 262), (312, 330),
    (262, 392), (195, 442), (115, 480), (30, 498), (-60, 495),
], dtype=np.float64)

#: Eye: eyeball centre (left eye), Parke units. Cornea apex = centre + radius along +x.
EYE_CENTRE = np.array([250.0, 124.0, 22.0])


# ---------------------------------------------------------------------------------------------
# the implicit head
# ---------------------------------------------------------------------------------------------

def _ellipsoid_sdf(p, centre, semi):
    q = (p - centre) / semi
    return (np.linalg.norm(q, axis=-1) - 1.0) * np.min(semi)


def _neck_sdf(p):
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    xc = -100.0 + 0.16 * (z + 594.0)
    rx = 150.0 + 0.04 * (z + 594.0)
    ry = 190.0 - 0.03 * (z + 594.0)
    f = (np.sqrt(((x - xc) / rx) ** 2 + (y / ry) ** 2) - 1.0) * np.minimum(rx, ry)
    return np.maximum(f, z + 120.0)


def _smin(a, b, k):
    """Smooth minimum (a soft union of two implicit solids), blend radius ~k units."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def head_sdf(p: np.ndarray) -> np.ndarray:
    """Approximate signed distance (Parke units, < 0 inside) of the base head: cranium, face
    and neck blended (no profile, no relief)."""
    cranium = _ellipsoid_sdf(p, np.array([-10.0, 0.0, 118.0]), np.array([372.0, 282.0, 382.0]))
    face = _ellipsoid_sdf(p, np.array([135.0, 0.0, -175.0]), np.array([232.0, 180.0, 250.0]))
    jaw = _ellipsoid_sdf(p, np.array([60.0, 0.0, -300.0]), np.array([240.0, 158.0, 130.0]))
    f = _smin(cranium, face, 80.0)
    f = _smin(f, jaw, 60.0)
    return _smin(f, _neck_sdf(p), 70.0)


def _directions(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack([np.cos(p) * np.cos(t), np.cos(p) * np.sin(t), np.sin(p)], axis=-1)


def _base_radius_exact(theta_deg, phi_deg) -> np.ndarray:
    d = _directions(np.asarray(theta_deg, float), np.asarray(phi_deg, float))
    lo = np.zeros(d.shape[:-1])
    hi = np.full(d.shape[:-1], 1500.0)
    for _ in range(34):  # bisection: the base head is star-shaped about CENTRE
        mid = 0.5 * (lo + hi)
        inside = head_sdf(CENTRE + d * mid[..., None]) < 0
        lo = np.where(inside, mid, lo)
        hi = np.where(inside, hi, mid)
    return 0.5 * (lo + hi)


_GRID_STEP = 0.5
_GRID: list = []


def _radius_grid():
    """The base head's radius tabulated every 0.5 degree (computed once per process)."""
    if not _GRID:
        th = np.arange(-10.0, 190.0 + 1e-9, _GRID_STEP)
        ph = np.arange(-90.0, 90.0 + 1e-9, _GRID_STEP)
        T, P = np.meshgrid(th, ph, indexing="ij")
        _GRID.append((th, ph, _base_radius_exact(T, P)))
    return _GRID[0]


def base_radius(theta_deg, phi_deg) -> np.ndarray:
    """Distance from :data:`CENTRE` to the base head along (azimuth, elevation), degrees
    (bilinear in a 0.5-degree table of the exact bisection)."""
    th, ph, R = _radius_grid()
    t = np.clip(np.asarray(theta_deg, float), th[0], th[-1])
    p = np.clip(np.asarray(phi_deg, float), ph[0], ph[-1])
    ft = (t - th[0]) / _GRID_STEP
    fp = (p - ph[0]) / _GRID_STEP
    i = np.clip(np.floor(ft).astype(int), 0, len(th) - 2)
    j = np.clip(np.floor(fp).astype(int), 0, len(ph) - 2)
    a, b = ft - i, fp - j
    return ((1 - a) * (1 - b) * R[i, j] + a * (1 - b) * R[i + 1, j]
            + (1 - a) * b * R[i, j + 1] + a * b * R[i + 1, j + 1])


def _profile_radius(phi_deg):
    """Distance from CENTRE to the designed profile along elevation phi (azimuth 0)."""
    px = PROFILE[:, 0] - CENTRE[0]
    pz = PROFILE[:, 1] - CENTRE[2]
    ang = np.degrees(np.arctan2(pz, px))
    rad = np.hypot(px, pz)
    # the profile is star-shaped about CENTRE: its angles increase monotonically
    return np.interp(phi_deg, ang, rad)


def _profile_width(phi_deg):
    """Angular half-width (degrees) over which the profile's relief fades to the base head."""
    table = np.array([  # elevation, width
        (-90, 60), (-62, 45), (-48, 26), (-38, 20), (-30, 17), (-22, 16), (-17, 11),
        (-12, 8.0), (-5, 7.0), (5, 6.5), (13, 8), (20, 22), (30, 40), (90, 60)])
    return np.interp(phi_deg, table[:, 0], table[:, 1])


def _bump(theta, phi, t0, p0, st, sp, amp):
    return amp * np.exp(-(((theta - t0) / st) ** 2 + ((phi - p0) / sp) ** 2))


def surface_radius(theta_deg, phi_deg) -> np.ndarray:
    """Distance from :data:`CENTRE` to the face's skin along (azimuth, elevation), degrees.

    Azimuth 0 is forward (+x), 90 is the face's left (+y); elevation 90 is up.
    """
    th = np.asarray(theta_deg, float)
    ph = np.asarray(phi_deg, float)
    base = base_radius(th, ph)
    front = base_radius(np.zeros_like(ph), ph)
    delta = _profile_radius(ph) - front
    w = np.exp(-(th / _profile_width(ph)) ** 2)
    r = base + delta * w
    # relief: eye socket, brow ridge, cheekbone, temple, side of the nose
    et, ep = _eye_angles()
    r += _bump(th, ph, et, ep, 9.0, 6.5, -32.0)
    r += _bump(th, ph, et + 2.0, ep + 10.0, 11.0, 3.5, 12.0)
    r += _bump(th, ph, et + 14.0, ep - 14.0, 10.0, 6.0, 14.0)
    r += _bump(th, ph, 62.0, ep + 14.0, 10.0, 10.0, -10.0)
    r += _bump(th, ph, 28.0, -18.0, 9.0, 7.0, -6.0)
    return r


def _eye_angles():
    d = EYE_CENTRE + np.array([70.0, 0.0, 0.0]) - CENTRE
    return (float(np.degrees(np.arctan2(d[1], d[0]))),
            float(np.degrees(np.arctan2(d[2], np.hypot(d[0], d[1])))))


def surface_point(theta_deg, phi_deg) -> np.ndarray:
    """Points (..., 3) on the skin at (azimuth, elevation) in degrees."""
    th = np.asarray(theta_deg, float)
    ph = np.asarray(phi_deg, float)
    return CENTRE + _directions(th, ph) * surface_radius(th, ph)[..., None]


def angles_of(p) -> tuple[float, float]:
    """(azimuth, elevation) in degrees of point ``p`` seen from :data:`CENTRE`."""
    d = np.asarray(p, float) - CENTRE
    return (float(np.degrees(np.arctan2(d[1], d[0]))),
            float(np.degrees(np.arctan2(d[2], np.hypot(d[0], d[1])))))


# ---------------------------------------------------------------------------------------------
# the layout: named nodes in rows
# ---------------------------------------------------------------------------------------------

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


# ---------------------------------------------------------------------------------------------
# building
# ---------------------------------------------------------------------------------------------

BACK_THETAS = [125.0, 150.0, 180.0]


def _merge(lay: "Layout", own: list[str], base: list[str], from_theta: float) -> list[str]:
    """A row that joins ``base`` at the side: its own nodes, then base's nodes from azimuth
    ``from_theta`` on (saves vertices behind the face, where the head is smooth)."""
    tail = [k for k in base if angles_of(lay.nodes[k].pos)[0] >= from_theta - 1e-6]
    return own + tail


def surface_at_z(theta_deg, z) -> np.ndarray:
    """Skin points (..., 3) at azimuths ``theta_deg`` whose heights are ``z`` (bisection on
    the elevation, vectorised)."""
    th = np.asarray(theta_deg, float)
    zz = np.asarray(z, float)
    th, zz = np.broadcast_arrays(th, zz)
    lo = np.full(th.shape, -89.0)
    hi = np.full(th.shape, 89.0)
    for _ in range(36):
        mid = 0.5 * (lo + hi)
        below = surface_point(th, mid)[..., 2] < zz
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return surface_point(th, 0.5 * (lo + hi))


def _fixed_row(lay, name, numbers, phi_back, extra_thetas, extra_wants, *, zs=None):
    """A row starting with some of Parke's excerpt vertices, continuing on the surface (at
    elevations blending to ``phi_back``, or at heights ``zs``)."""
    keys = [lay.add(f"{name}.p{n}", PARKE_EXCERPT[n], n) for n in numbers]
    th0, ph0 = angles_of(PARKE_EXCERPT[numbers[-1]])
    ths = np.asarray(extra_thetas, float)
    if zs is not None:
        pts = surface_at_z(ths, np.asarray(zs, float))
        for k, (t, p, w) in enumerate(zip(ths, pts, extra_wants)):
            if abs(t - 180.0) < 1e-9:
                p[1] = 0.0
            keys.append(lay.add(f"{name}.{k}", p, w))
        return keys
    phs = ph0 + (phi_back - ph0) * _smooth((ths - th0) / (180.0 - th0))
    keys += _surface_row(lay, name, list(ths), list(phs), extra_wants)
    return keys


def build_layout(*, palate_xz: np.ndarray | None = None) -> Layout:
    """Generate the nodes and polygons (before numbering). See :func:`build_geometry`."""
    lay = Layout()

    def merge(own, base, from_theta):
        return _merge(lay, own, base, from_theta)

    rows: list[tuple[list[str], list[str]]] = []  # (lower path, upper path) per row

    def plain(keys):
        rows.append((keys, keys))
        return keys

    # --- neck and under the chin: Parke's excerpt vertices, continued round the back -------
    F = "free"
    # the base of the neck rises from the front (z = -594) round to the back, like a bust's cut
    plain(_fixed_row(lay, "r0", [1, 2, 3, 4, 5], 0, [145.0, 180.0], [F] * 2,
                     zs=[-492.0, -485.0]))
    plain(_fixed_row(lay, "r1", [6, 7, 8, 9, 10], 0, [140.0, 180.0], [F] * 2,
                     zs=[-400.0, -395.0]))
    r2 = plain(_fixed_row(lay, "r2", [11, 12, 13], 0, [58.0, 84.0, 128.0, 180.0], [F] * 4,
                          zs=[-392.0, -312.0, -320.0, -325.0]))
    def mixed(name, numbers, spec):
        """Excerpt vertices, then nodes at (azimuth, ("phi", elevation) | ("z", height))."""
        keys = [lay.add(f"{name}.p{n}", PARKE_EXCERPT[n], n) for n in numbers]
        ts = np.array([t for t, _, _ in spec], float)
        vals = np.array([v for _, (_, v), _ in spec], float)
        by_phi = surface_point(ts, vals)
        by_z = surface_at_z(ts, vals)
        for k, (t, (kind, val), w) in enumerate(spec):
            p = (by_phi if kind == "phi" else by_z)[k].copy()
            if abs(t - 180.0) < 1e-9:
                p[1] = 0.0
            keys.append(lay.add(f"{name}.{k}", p, w))
        return keys

    plain(merge(mixed("r3", [14, 15], [(30.0, ("phi", -57.5), "jaw"),
                                       (46.0, ("z", -380.0), "jaw")]), r2, 84.0))
    # the jaw line: from the chin (16) back to the angle of the jaw (22), then round the nape
    r4 = plain(mixed("r4", [16, 17], [
        (22.0, ("phi", -50.5), "jaw"), (32.0, ("phi", -52.5), "jaw"),
        (44.0, ("phi", -55.0), "jaw"), (58.0, ("z", -352.0), "jaw"), (74.0, ("z", -318.0), 22),
        (100.0, ("z", -280.0), F), (140.0, ("z", -270.0), F), (180.0, ("z", -265.0), F)]))

    # --- chin and jaw: rows given by height at the side (the jaw line rises to the ear) -------
    def srow(name, phi_f, phi_b, thetas, wants, knee=90.0):
        phis = _row_angles(phi_f, phi_b, thetas, knee=knee)
        return _surface_row(lay, name, thetas, list(phis), wants)

    def zrow(name, thetas, zs, wants):
        keys = []
        pts = surface_at_z(np.asarray(thetas, float), np.asarray(zs, float))
        for k, (t, p, w) in enumerate(zip(thetas, pts, wants)):
            if abs(t) < 1e-9 or abs(t - 180.0) < 1e-9:
                p[1] = 0.0
            keys.append(lay.add(f"{name}.{k}", p, w))
        return keys

    r5 = plain(zrow("r5", [0, 7, 15, 24, 34, 46, 60, 74, 100, 130, 155, 180],
                    [-395, -393, -388, -378, -358, -336, -318, -295, -245, -230, -225, -222],
                    ["jaw"] * 7 + [30, F, F, F, F]))
    plain(merge(zrow("r6", [0, 7, 14, 22, 31, 42, 56],
                     [-358, -357, -355, -350, -340, -325, -302],
                     [24, "jaw", "jaw", "jaw", "jaw", F, F]), r5, 74.0))

    # --- the mouth: below-lip row, lips, above-lip row ---------------------------------------
    lip = _lips(lay)
    corner_theta = lip["corner_theta"]
    _mouth_expression(lay)
    r7 = plain(zrow("r7", [0.0, lip["col_theta"][1], lip["col_theta"][2], corner_theta + 6.0,
                           34, 46, 60, 82, 106, 142, 180],
                    [-306, -304, -299, -292, -286, -276, -262, -215, -190, -175, -170],
                    [41, 42, 43, 45, "jaw", "jaw", "jaw", F, F, F, F]))
    # the mouth row: the lower and upper outer lip outlines share the corner and the cheek
    mouth_tail = zrow("rm", [corner_theta + 9.0, 36, 48, 62], [-250, -248, -243, -235],
                      [44, 46, 47, 48])
    mouth_tail = merge(mouth_tail, r7, 82.0)
    lower_path = list(lip["lower_outer"]) + [lip["corner"]] + mouth_tail
    upper_path = list(lip["upper_outer"]) + [lip["corner"]] + mouth_tail
    rows.append((lower_path, upper_path))
    r8 = plain(zrow("r8", [0.0, lip["col_theta"][1], lip["col_theta"][2], corner_theta + 4.0,
                           35, 48, 64, 84, 108, 143, 180],
                    [-194, -195, -198, -204, -212, -210, -202, -178, -150, -130, -125],
                    [71, 72, 73] + [F] * 8))

    # --- nose rows ---------------------------------------------------------------------------
    plain(merge(srow("r9", -16.0, -3.0, [0, 5, 10, 15, 24, 36, 50],
                     [80, 81, "nose", "nose", F, F, F]), r8, 64.0))
    r10 = plain(srow("r10", -13.0, 4.0, [0, 5, 9.5, 14, 22, 34, 50, 68, 88, 110, 135, 158, 180],
                     ["nose"] * 5 + [F] * 8))
    plain(merge(srow("r11", -9.5, 9.0, [0, 4.5, 8.5, 13, 21, 33],
                     [82, "nose", "nose", "nose", "nose", F]), r10, 50.0))
    plain(merge(srow("r12", -3.0, 15.0, [0, 4.5, 8.5, 13, 22, 34, 50],
                     ["nose"] * 4 + [F] * 3), r10, 68.0))

    # --- the eye row: split round the eye -----------------------------------------------------
    eye = _eye(lay)
    head = srow("re", 8.0, 24.0, [0.0, 5.0], ["nose", "nose"])
    tail = srow("ret", 8.0, 30.0, [45.0, 58.0, 76.0, 98.0, 122.0, 150.0, 180.0], [F] * 7)
    rows.append((head + eye["lower"] + tail, head + eye["upper"] + tail))

    # --- brows, forehead, crown ----------------------------------------------------------------
    r13 = plain(srow("r13", 22.0, 40.0, [0, 7, 14, 22, 31, 41, 53, 68, 90, 118, 148, 180],
                     ["nose", "nose"] + [F] * 10))
    _brows(lay, r13[2:7])
    plain(srow("r14", 34.0, 51.0, [0, 12, 25, 38, 53, 72, 95, 122, 150, 180], [F] * 10))
    plain(srow("r15", 48.0, 62.0, [0, 15, 31, 48, 68, 92, 120, 150, 180], [F] * 9))
    plain(srow("r16", 63.0, 72.0, [0, 20, 44, 72, 104, 140, 180], [F] * 7))
    plain(srow("r17", 76.0, 80.0, [0, 38, 76, 114, 150, 180], [F] * 6))
    top = [lay.add("top", surface_point(90.0, 89.9) * np.array([1, 0, 1]), F)]
    rows.append((top, top))

    for (_, up), (low, _) in zip(rows[:-1], rows[1:]):
        _stitch(lay, up, low)
    # the brow: the band between the brow row and the orbit ring's upper nodes
    band = set(lay.regions["brow"]) | set(eye["upper"][1:4])
    lay.polys = [(EYEBROW if m == SKIN and set(k) <= band else m, k, c)
                 for m, k, c in lay.polys]
    lay.regions["eye_socket"] = list(eye["orbit"])
    lay.regions["forehead"] = [k for k in lay.nodes if k.startswith(("r14.", "r15."))]
    lay.regions["cheek"] = [k for k in lay.nodes if k.split(".")[0] in
                            ("r8", "r9", "r10", "r11", "r12", "rm") and
                            22.0 <= angles_of(lay.nodes[k].pos)[0] <= 62.0]

    _teeth(lay)
    _tongue(lay)
    _palate(lay, palate_xz)
    lay.add("pivot", JAW_PIVOT_POS, N.JAW_PIVOT)
    return lay


#: Parke's jaw pivot (vertex 107): about the temporomandibular joint, in front of the ear.
JAW_PIVOT_POS = np.array([12.0, 190.0, -95.0])


#: Mouth expression (parameter 13): st1 is the neutral mouth (value 1, "slightly turned up"),
#: st2 the corners turned down (value 0). Drop in z (Parke units) per vertex.
MOUTH_FROWN = {"lip.corner": 12.0, "lip.corner300": 12.0, "lip.corner287": 11.0}
MOUTH_FROWN_COLUMNS = (0.0, 2.0, 6.0)


def _mouth_expression(lay: Layout):
    keys = []
    for k, node in lay.nodes.items():
        if not k.startswith("lip."):
            continue
        drop = MOUTH_FROWN.get(k)
        if drop is None:
            drop = MOUTH_FROWN_COLUMNS[int(k.rsplit(".", 1)[1])]
        if drop:
            node.closed = node.pos - np.array([0.0, 0.0, drop])
            keys.append(k)
    lay.regions["mouth_expression"] = keys


def _lips(lay: Layout) -> dict:
    """Parke's lips (Figures 3.7, 4.4, 4.5, 4.17): rows of 3 vertices from the centre line
    (y = 0, a/3, 2a/3) plus the corners 70 (outer), 300 (middle), 287 (inner).

    Lips slightly apart at rest (the mouth opening is the inner outline 61-63 / 58-60 / 287).
    """
    a = 98.0                      # half mouth width (corner 70), Parke units (~24.5 mm)
    z_st = -251.0                 # stomion height
    ys = np.array([0.0, a / 3, 2 * a / 3])
    # x falls off from the centre line along a parabolic track (4.2's lip track)
    def xtrack(x0, y, k=0.0068):
        return x0 - k * y ** 2
    ell = np.sqrt(1.0 - (ys / a) ** 2)
    rows = {
        # name: (x at centre, z at centre, z falloff toward the corner)
        "upper_outer": (394.0, -222.0),   # 67: UL pellet site, top edge of the upper lip
        "upper_middle": (389.0, -238.0),  # 64
        "upper_inner": (368.0, -249.0),   # 61
        "lower_inner": (366.0, -254.0),   # 58
        "lower_mu": (380.0, -259.0),      # 55
        "lower_ml": (389.0, -269.0),      # 52
        "lower_outer": (388.0, -281.0),   # 49: LL pellet site, bottom edge of the lower lip
    }
    numbers = {
        "upper_outer": N.UPPER_OUTER, "upper_middle": N.UPPER_MIDDLE,
        "upper_inner": N.UPPER_INNER, "lower_inner": N.LOWER_INNER,
        "lower_mu": N.LOWER_MIDDLE_UPPER_ROW, "lower_ml": N.LOWER_MIDDLE_LOWER_ROW,
        "lower_outer": N.LOWER_OUTER,
    }
    keys = {}
    for name, (x0, z0) in rows.items():
        ks = []
        for j, y in enumerate(ys):
            # heights shrink toward the corner like an ellipse about the stomion
            z = z_st + (z0 - z_st) * (0.35 + 0.65 * ell[j])
            x = xtrack(x0, y)
            ks.append(lay.add(f"lip.{name}.{j}", (x, y, z), numbers[name][j]))
        keys[name] = ks
    corner = lay.add("lip.corner", (xtrack(374.0, a), a, z_st + 1.0), N.CORNER)
    middle = lay.add("lip.corner300", (xtrack(362.0, a * 0.97), a * 0.97, z_st), N.CORNER_MIDDLE)
    inner = lay.add("lip.corner287", (xtrack(350.0, a * 0.93), a * 0.93, z_st - 1.0),
                    N.INNER_CORNER)
    up = [keys["upper_outer"], keys["upper_middle"], keys["upper_inner"]]
    up_corner = [corner, middle, inner]
    low = [keys["lower_outer"], keys["lower_ml"], keys["lower_mu"], keys["lower_inner"]]
    low_corner = [corner, middle, middle, inner]
    # upper lip: outer row is above; rows run front-to-back along +y; clockwise from outside
    for r in range(2):
        a_row, b_row = up[r], up[r + 1]
        for j in range(2):
            lay.poly(LIPS, (a_row[j], a_row[j + 1], b_row[j + 1], b_row[j]))
        lay.poly(LIPS, (a_row[2], up_corner[r], up_corner[r + 1], b_row[2]))
    for r in range(3):
        a_row, b_row = low[r], low[r + 1]
        for j in range(2):
            lay.poly(LIPS, (a_row[j], b_row[j], b_row[j + 1], a_row[j + 1]))
        ca, cb = low_corner[r], low_corner[r + 1]
        if ca == cb:
            lay.poly(LIPS, (a_row[2], b_row[2], ca))
        else:
            lay.poly(LIPS, (a_row[2], b_row[2], cb, ca))
    col_theta = [angles_of(lay.nodes[k].pos)[0] for k in keys["lower_outer"]]
    return {
        "upper_outer": keys["upper_outer"], "lower_outer": keys["lower_outer"],
        "corner": corner, "corner_theta": angles_of(lay.nodes[corner].pos)[0],
        "col_theta": col_theta,
    }


# --- eyes -------------------------------------------------------------------------------------

#: Parke's start values: eyeball radius (parameter 44) and eyelid sphere radius (45).
EYEBALL_RADIUS = 70.0
EYELID_RADIUS = 80.0
#: Radius of the sphere (about the eyeball centre) that carries the skin ring round the lids.
ORBIT_RADIUS = 94.0
#: Eyelid rings in 2D (width along y, height along z) about the eye centre, open and closed:
#: ring B is the lid margin (8 points: inner corner, 3 lower, outer corner, 3 upper), ring A
#: the lid above/below it; ring C (the lid's lip, touching the eyeball) follows ring B.
_EYE_W = 60.0
_LID_OPEN = {"upper": 21.0, "lower": -15.0}
_LID_CLOSED = {"upper": -10.0, "lower": -12.0}


def eyelid_ring_2d(opening: float, ring: str = "B", *, y_scale: float = 1.0,
                   z_scale: float = 1.0) -> np.ndarray:
    """2D (y, z) offsets from the eye centre of an eyelid ring, interpolated between the
    closed (``opening`` 0) and open (1) extremes (dissertation 3.1.2). float (8, 2).

    Order: inner corner, lower lid (3, inner to outer), outer corner, upper lid (3, outer to
    inner).
    """
    o = float(opening)
    up = _LID_CLOSED["upper"] + (_LID_OPEN["upper"] - _LID_CLOSED["upper"]) * o
    lo = _LID_CLOSED["lower"] + (_LID_OPEN["lower"] - _LID_CLOSED["lower"]) * o
    w = _EYE_W
    grow = {"C": 0.92, "B": 1.0, "A": 1.3}[ring]
    shape = np.array([0.0, 0.82, 1.0, 0.82])  # height profile across the lid
    ys = np.array([-w, -w / 2, 0.0, w / 2, w * 1.05])
    pts = [(ys[0] * grow, 2.0)]
    for k, y in enumerate(ys[1:4]):
        pts.append((y * grow, lo * shape[k + 1] * (1.0 if ring != "A" else 1.6) - (2 if ring == "A" else 0)))
    pts.append((ys[4] * grow, 5.0))
    for k, y in enumerate(ys[3:0:-1]):
        hz = up * shape[3 - k] if ring != "A" else max(up, 6.0) * shape[3 - k] + 22.0
        pts.append((y * grow, hz))
    out = np.array(pts, float)
    out[:, 0] *= y_scale
    out[:, 1] *= z_scale
    return out


def project_to_sphere(yz: np.ndarray, centre: np.ndarray, radius: float) -> np.ndarray:
    """Project 2D (y, z) offsets onto the front of a sphere about ``centre`` (x forward).

    float (..., 2) -> float (..., 3). Offsets beyond the radius are pulled onto the sphere's
    silhouette.
    """
    yz = np.asarray(yz, float)
    r2 = np.sum(yz ** 2, axis=-1)
    scale = np.where(r2 > (0.98 * radius) ** 2, 0.98 * radius / np.sqrt(np.maximum(r2, 1e-12)), 1)
    yz = yz * scale[..., None]
    x = np.sqrt(np.maximum(radius ** 2 - np.sum(yz ** 2, axis=-1), 0.0))
    return np.asarray(centre, float) + np.stack([x, yz[..., 0], yz[..., 1]], axis=-1)


def _eye(lay: Layout) -> dict:
    """The left eye's opening: orbital ring on the skin, lid ring A, margin B, lid lip C."""
    c = EYE_CENTRE
    # orbital ring on the skin surface, around the eye's angular position
    et, ep = _eye_angles()
    # the orbit ring: a wider 2D ring projected onto a sphere about the eyeball, so that the
    # skin round the lids always clears the eyeball
    orbit_yz = np.array([(-94.0, 4.0), (-50.0, -38.0), (0.0, -44.0), (52.0, -38.0),
                         (100.0, 2.0), (56.0, 46.0), (0.0, 52.0), (-50.0, 44.0)])
    orbit_p = project_to_sphere(orbit_yz, c, ORBIT_RADIUS)
    orbit = []
    for k in range(8):
        t_, p_ = angles_of(orbit_p[k])
        surf = surface_point(t_, p_)
        # the farther of the sphere and the skin (seen from the head's centre)
        pt = surf if np.linalg.norm(surf - CENTRE) > np.linalg.norm(orbit_p[k] - CENTRE) \
            else orbit_p[k]
        orbit.append(lay.add(f"eye.o{k}", pt, "free"))
    rings = {}
    for ring, radius in (("A", EYELID_RADIUS + 6.0), ("B", EYELID_RADIUS),
                         ("C", EYEBALL_RADIUS + 1.5)):
        op = project_to_sphere(eyelid_ring_2d(0.9, ring), c, radius)
        cl = project_to_sphere(eyelid_ring_2d(0.0, ring), c, radius)
        # st1 holds the fully open lid (opening 1); st2 the closed lid
        op = project_to_sphere(eyelid_ring_2d(1.0, ring), c, radius)
        rings[ring] = [lay.add(f"eye.{ring}{k}", op[k], "free", closed=cl[k]) for k in range(8)]
    # quads between consecutive rings; ring order: 0 inner corner, 1-3 lower, 4 outer, 5-7 upper
    order = [orbit, rings["A"], rings["B"], rings["C"]]
    for r in range(3):
        outer, inner = order[r], order[r + 1]
        for k in range(8):
            k2 = (k + 1) % 8
            mat = SKIN
            if r == 2 and k in (4, 5, 6, 7):
                mat = EYELASH  # the upper lid's margin carries the lashes
            # rings run inner corner -> lower -> outer corner -> upper: counter-clockwise seen
            # from the front (+y to the right), so this order is clockwise from outside
            lay.poly(mat, (outer[k], inner[k], inner[k2], outer[k2]))
    lower = [orbit[0], orbit[1], orbit[2], orbit[3], orbit[4]]
    upper = [orbit[0], orbit[7], orbit[6], orbit[5], orbit[4]]
    lay.regions["eyelid"] = rings["A"] + rings["B"]
    lay.regions["eyelid_lip"] = list(rings["C"])
    return {"lower": lower, "upper": upper, "ring_C": rings["C"], "orbit": orbit}


#: Eyebrow arch (parameter 2): z offsets (Parke units) of the brow, inner end to outer end, at
#: arch 1 ("upside-down V") relative to the neutral brow (arch 0.5); arch 0 is the opposite
#: ("slopes down from the centre to the edge").
BROW_ARCH = np.array([-5.0, 2.0, 7.0, 2.0, -6.0])


def _brows(lay: Layout, brow: list[str]):
    """Brow vertices with their st1 (arch 1) and st2 (arch 0) extremes about the neutral."""
    for k, d in zip(brow, BROW_ARCH):
        node = lay.nodes[k]
        neutral = node.pos.copy()
        node.pos = neutral + np.array([0.0, 0.0, d])
        node.closed = neutral - np.array([0.0, 0.0, d])
    lay.regions["brow"] = list(brow)


# --- teeth, tongue, palate --------------------------------------------------------------------

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
                tip = LOWER_TIP[2] + 0.02 * (LOWER_TIP[0] - np.array([x0, x1]))
                h = LOWER_TOOTH_HEIGHT * (1.0 if k < 3 else 0.8)
                gum = tip - h
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
        palate_xz = xrmb_to_parke_xz(DEFAULT_PALATE_MM)
    surf = palate_surface(palate_xz)
    keys = [[lay.add(f"palate.{s}.{a}", surf[s, a], N.palate_vertex(s, a))
             for a in range(N.PALATE_ACROSS)] for s in range(N.PALATE_STATIONS)]
    for s in range(N.PALATE_STATIONS - 1):
        for a in range(N.PALATE_ACROSS - 1):
            # the palate's visible side faces down (into the mouth): clockwise seen from below
            lay.poly(PALATE, (keys[s][a], keys[s][a + 1], keys[s + 1][a + 1], keys[s + 1][a]))


def xrmb_to_parke_xz(xy_mm: np.ndarray, scale: float | None = None) -> np.ndarray:
    """XRMB midsagittal (x, y) mm -> Parke (x, z): origin at vertex 226, ``scale`` units/mm
    (default :data:`cassi.data.numbering.UNITS_PER_MM`)."""
    s = N.UNITS_PER_MM if scale is None else float(scale)
    xy = np.asarray(xy_mm, float)
    return np.stack([UPPER_TIP[0] + s * xy[:, 0], UPPER_TIP[2] + s * xy[:, 1]], axis=1)
