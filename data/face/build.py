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
vertices) runs clockwise seen from outside; :mod:`cassi.data.face.topology` flips them for rendering.
"""
from __future__ import annotations

import numpy as np

from cassi.data.face import numbering as N
from cassi.data.face.layout import (  # noqa: F401  (re-exported for the face and the tests)
    EYEBROW, EYE_WHITE, EYELASH, FRINGE, IRIS, LIPS, MATERIAL_NAMES, PALATE, PARKE_MATERIAL_NAMES,
    PUPIL, REFLECTION, SKIN, TEETH, TONGUE, UNMIRRORED_MATERIALS, Layout, _smooth, _row_angles,
    _stitch, _surface_row)
from cassi.data.face.mouth import (  # noqa: F401
    DEFAULT_PALATE_MM, LOWER_TIP, UPPER_TIP, _palate, _teeth, _tongue, arch_points,
    DEFAULT_PALATE_XZ, palate_surface, resample_outline)
from cassi.data.face.surface import (  # noqa: F401
    CENTRE, EYE_CENTRE, PROFILE, _eye_angles, angles_of, surface_at_z, surface_point,
    surface_radius)

#: Parke's own vertices 1-17 (thesis Figure 3.2); the generated head uses them as they are.
PARKE_EXCERPT = {
    1: (45, 0, -594), 2: (28, 50, -585), 3: (-8, 105, -565), 4: (-45, 147, -542),
    5: (-90, 187, -518), 6: (100, 0, -450), 7: (93, 45, -445), 8: (70, 97, -412),
    9: (52, 127, -380), 10: (24, 158, -330), 11: (138, 0, -425), 12: (123, 45, -420),
    13: (103, 85, -386), 14: (210, 0, -415), 15: (215, 50, -410), 16: (326, 0, -423),
    17: (302, 60, -418),
}


# ---------------------------------------------------------------------------------------------
# building
# ---------------------------------------------------------------------------------------------

def _merge(lay: "Layout", own: list[str], base: list[str], from_theta: float) -> list[str]:
    """A row that joins ``base`` at the side: its own nodes, then base's nodes from azimuth
    ``from_theta`` on (saves vertices behind the face, where the head is smooth)."""
    tail = [k for k in base if angles_of(lay.nodes[k].pos)[0] >= from_theta - 1e-6]
    return own + tail


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
    # (lower path, upper path) per row, from the base of the neck to the crown
    rows = _neck_rows(lay) + _chin_rows(lay)
    mouth_rows = _mouth_rows(lay)
    rows += mouth_rows + _nose_rows(lay, below=mouth_rows[-1][1])
    eye_row, eye = _eye_row(lay)
    rows += [eye_row] + _upper_head_rows(lay)
    _stitch_rows(lay, rows, eye)
    _teeth(lay)
    _tongue(lay)
    _palate(lay, palate_xz)
    lay.add("pivot", JAW_PIVOT_POS, N.JAW_PIVOT)
    return lay


_FREE = "free"


def _plain(keys: list[str]) -> tuple[list[str], list[str]]:
    """A row that does not split: the same path below and above."""
    return (keys, keys)


def _mixed_row(lay: Layout, name: str, numbers, spec) -> list[str]:
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


def _elevation_row(lay: Layout, name: str, phi_f, phi_b, thetas, wants, knee=90.0) -> list[str]:
    """A row on the surface at elevations from ``phi_f`` in front to ``phi_b`` behind."""
    phis = _row_angles(phi_f, phi_b, thetas, knee=knee)
    return _surface_row(lay, name, thetas, list(phis), wants)


def _height_row(lay: Layout, name: str, thetas, zs, wants) -> list[str]:
    """A row on the surface at the heights ``zs``."""
    keys = []
    pts = surface_at_z(np.asarray(thetas, float), np.asarray(zs, float))
    for k, (t, p, w) in enumerate(zip(thetas, pts, wants)):
        if abs(t) < 1e-9 or abs(t - 180.0) < 1e-9:
            p[1] = 0.0
        keys.append(lay.add(f"{name}.{k}", p, w))
    return keys


def _neck_rows(lay: Layout) -> list[tuple]:
    """The neck and under the chin: Parke's excerpt vertices, continued round the back."""
    F = _FREE
    # the base of the neck rises from the front (z = -594) round to the back, like a bust's cut
    r0 = _fixed_row(lay, "r0", [1, 2, 3, 4, 5], 0, [145.0, 180.0], [F] * 2, zs=[-492.0, -485.0])
    r1 = _fixed_row(lay, "r1", [6, 7, 8, 9, 10], 0, [140.0, 180.0], [F] * 2, zs=[-400.0, -395.0])
    r2 = _fixed_row(lay, "r2", [11, 12, 13], 0, [58.0, 84.0, 128.0, 180.0], [F] * 4,
                    zs=[-392.0, -320.0, -322.0, -325.0])
    r3 = _merge(lay, _mixed_row(lay, "r3", [14, 15], [(30.0, ("phi", -57.5), "jaw"),
                                                      (46.0, ("z", -380.0), "jaw")]), r2, 84.0)
    # the jaw line: from the chin (16) back to the angle of the jaw (22), then round the nape.
    # The gonion (22) sits ~85 mm behind the upper incisor tip (226) and ~27 mm above the
    # gnathion (26), so the mandibular plane 26 -> 22 rises ~18 degrees backward, as a real
    # jaw's does (15-25 degrees); CASSI 1.0 turns the chin from here onto the head measures.
    r4 = _mixed_row(lay, "r4", [16, 17], [
        (23.0, ("z", -394.0), "jaw"), (34.0, ("z", -376.0), "jaw"),
        (47.0, ("z", -357.0), "jaw"), (63.0, ("z", -332.0), "jaw"),
        (GONION_THETA, ("z", GONION_Z), N.GONION),
        (110.0, ("z", -285.0), F), (140.0, ("z", -275.0), F), (180.0, ("z", -270.0), F)])
    return [_plain(r) for r in (r0, r1, r2, r3, r4)]


def _chin_rows(lay: Layout) -> list[tuple]:
    """The chin and jaw: rows given by height at the side (the jaw line rises to the ear)."""
    F = _FREE
    # 30 above the gonion on the back of the ramus (the pair CASSI 1.0 moves to the 3rd zone)
    r5 = _height_row(lay, "r5", [0, 7, 15, 24, 35, 49, 66, GONION_THETA, 108, 132, 156, 180],
                     [GNATHION_Z, -411, -401, -381, -357, -332, -306, -262, -240, -228, -223,
                      -220],
                     ["jaw"] * 7 + [30, F, F, F, F])
    r6 = _merge(lay, _height_row(lay, "r6", [0, 7, 14, 22, 31, 42, 56],
                                 [-358, -357, -355, -350, -340, -325, -302],
                                 [24, "jaw", "jaw", "jaw", "jaw", F, F]), r5, 74.0)
    return [_plain(r5), _plain(r6)]


def _mouth_rows(lay: Layout) -> list[tuple]:
    """The lips, the row below them, the mouth row (split round the lips) and the row above."""
    F = _FREE
    lip = _lips(lay)
    corner_theta = lip["corner_theta"]
    _mouth_expression(lay)
    r7 = _height_row(lay, "r7", [0.0, lip["col_theta"][1], lip["col_theta"][2],
                                 corner_theta + 6.0, 34, 46, 60, 82, 106, 142, 180],
                     [-306, -304, -299, -292, -286, -276, -262, -215, -190, -175, -170],
                     [41, 42, 43, 45, "jaw", "jaw", "jaw", F, F, F, F])
    # the mouth row: the lower and upper outer lip outlines share the corner and the cheek
    mouth_tail = _height_row(lay, "rm", [corner_theta + 9.0, 36, 48, 62],
                             [-250, -248, -243, -235], [44, 46, 47, 48])
    mouth_tail = _merge(lay, mouth_tail, r7, 82.0)
    lower_path = list(lip["lower_outer"]) + [lip["corner"]] + mouth_tail
    upper_path = list(lip["upper_outer"]) + [lip["corner"]] + mouth_tail
    r8 = _height_row(lay, "r8", [0.0, lip["col_theta"][1], lip["col_theta"][2],
                                 corner_theta + 4.0, 35, 48, 64, 84, 108, 143, 180],
                     [-194, -195, -198, -204, -212, -210, -202, -178, -150, -130, -125],
                     [71, 72, 73] + [F] * 8)
    return [_plain(r7), (lower_path, upper_path), _plain(r8)]


def _nose_rows(lay: Layout, below: list[str]) -> list[tuple]:
    """The nose's rows, above the row ``below`` the nose."""
    F = _FREE
    r9 = _merge(lay, _elevation_row(lay, "r9", -16.0, -3.0, [0, 5, 10, 15, 24, 36, 50],
                                    [80, 81, "nose", "nose", F, F, F]), below, 64.0)
    r10 = _elevation_row(lay, "r10", -13.0, 4.0,
                         [0, 5, 9.5, 14, 22, 34, 50, 68, 88, 110, 135, 158, 180],
                         ["nose"] * 5 + [F] * 8)
    r11 = _merge(lay, _elevation_row(lay, "r11", -9.5, 9.0, [0, 4.5, 8.5, 13, 21, 33],
                                     [82, "nose", "nose", "nose", "nose", F]), r10, 50.0)
    r12 = _merge(lay, _elevation_row(lay, "r12", -3.0, 15.0, [0, 4.5, 8.5, 13, 22, 34, 50],
                                     ["nose"] * 4 + [F] * 3), r10, 68.0)
    return [_plain(r) for r in (r9, r10, r11, r12)]


def _eye_row(lay: Layout) -> tuple[tuple, dict]:
    """The eye row, split round the eye; the row and the eye's nodes."""
    eye = _eye(lay)
    head = _elevation_row(lay, "re", 8.0, 24.0, [0.0, 5.0], ["nose", "nose"])
    tail = _elevation_row(lay, "ret", 8.0, 30.0, [45.0, 58.0, 76.0, 98.0, 122.0, 150.0, 180.0],
                          [_FREE] * 7)
    return (head + eye["lower"] + tail, head + eye["upper"] + tail), eye


def _upper_head_rows(lay: Layout) -> list[tuple]:
    """The brows, the forehead and the crown."""
    F = _FREE
    r13 = _elevation_row(lay, "r13", 22.0, 40.0, [0, 7, 14, 22, 31, 41, 53, 68, 90, 118, 148, 180],
                         ["nose", "nose"] + [F] * 10)
    _brows(lay, r13[2:7])
    rows = [r13,
            _elevation_row(lay, "r14", 34.0, 51.0, [0, 12, 25, 38, 53, 72, 95, 122, 150, 180],
                           [F] * 10),
            _elevation_row(lay, "r15", 48.0, 62.0, [0, 15, 31, 48, 68, 92, 120, 150, 180],
                           [F] * 9),
            _elevation_row(lay, "r16", 63.0, 72.0, [0, 20, 44, 72, 104, 140, 180], [F] * 7),
            _elevation_row(lay, "r17", 76.0, 80.0, [0, 38, 76, 114, 150, 180], [F] * 6),
            [lay.add("top", surface_point(90.0, 89.9) * np.array([1, 0, 1]), F)]]
    return [_plain(r) for r in rows]


def _stitch_rows(lay: Layout, rows: list[tuple], eye: dict) -> None:
    """Stitch consecutive rows into polygons; the brow's material and the skin's regions."""
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


#: The gonion (vertex 22, the angle of the jaw): azimuth (degrees) and height (Parke units) on
#: the skin: about 85 mm behind 226 and 27 mm above the gnathion (26), so the mandibular plane
#: rises ~18 degrees backward. The gnathion (26, the point of the chin on the centre line) sits
#: low on the chin, ~39 mm below 226 and just above the menton (16): near where the head
#: measures put a subject's gnathion, so CASSI 1.0's initialisation moves the jaw little.
GONION_THETA = 88.0
GONION_Z = -308.0
GNATHION_Z = -415.0

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


#: The closed-lip span, Parke units: the two lips' own heights on the centre line,
#: (z67 - z61) + (z58 - z49), i.e. 67 to 49 with the lips closed. Published vermilion heights
#: are measured so (labrale superius to stomion plus stomion to labrale inferius, lips closed), and
#: the pellets the face's 67 and 49 carry sit on the vermilion borders; the face is mapped by p/d
#: (thesis 4.1.1), so the span is a share of the jaw-pellet spacing: 17.05 mm, men's upper plus
#: lower vermilion height (5.9 + 11.15 mm, Pietruski & Majak 2022, Aesthet. Surg. J. 42:1130;
#: :data:`cassi.data.synth.subjects.VERMILION_HEIGHTS_MM`), over 38.39 mm, the mean of the real
#: jaw-pellet spacings (MNI-MNM) the project holds, JW11's 42.6 mm (median of 43,260 real frames)
#: and JW45's 34.18 mm (thesis Figure 3.9; both in :data:`cassi.data.synth.subjects.SUBJECTS`,
#: both men, hence the men's heights): 0.4441 of the face's jaw length p (140.72 units).
CLOSED_LIP_SPAN = 62.5
#: The designed lips' centre-line heights (z at the centre line, Parke units), before the span
#: is applied: the inner edges 61 and 58 (the resting gap between them, 5 units, 1.25 mm, the lips
#: lightly apart) and the share of each lip (equal) are the design's; each lip is scaled about its
#: inner edge so that the two heights add up to CLOSED_LIP_SPAN.
_LIP_ROWS_DESIGN = {
    # name: (x at centre, z at centre)
    "upper_outer": (394.0, -222.0),   # 67: UL pellet site, top edge of the upper lip
    "upper_middle": (389.0, -238.0),  # 64
    "upper_inner": (368.0, -249.0),   # 61
    "lower_inner": (366.0, -254.0),   # 58
    "lower_mu": (380.0, -259.0),      # 55
    "lower_ml": (389.0, -269.0),      # 52
    "lower_outer": (388.0, -281.0),   # 49: LL pellet site, bottom edge of the lower lip
}


def lip_rows() -> dict[str, tuple[float, float]]:
    """The lips' centre-line (x, z) by row name, with the closed-lip span applied."""
    d = _LIP_ROWS_DESIGN
    up_edge, low_edge = d["upper_inner"][1], d["lower_inner"][1]
    design_span = (d["upper_outer"][1] - up_edge) + (low_edge - d["lower_outer"][1])
    f = CLOSED_LIP_SPAN / design_span
    return {name: (x, (up_edge if name.startswith("upper") else low_edge)
                   + f * (z - (up_edge if name.startswith("upper") else low_edge)))
            for name, (x, z) in d.items()}


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
    rows = lip_rows()
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
#: The lid's lip (ring C) rides this far outside the eyeball, so that the chords between its
#: vertices clear the ball (a 32-unit chord on a 73-unit sphere sags 1.8 units).
LID_LIP_GAP = 3.5
#: Radius of the sphere (about the eyeball centre) that carries the skin ring round the lids.
ORBIT_RADIUS = 94.0
#: Eyelid rings in 2D (width along y, height along z) about the eye centre, open and closed:
#: ring B is the lid margin (8 points: inner corner, 3 lower, outer corner, 3 upper), ring A
#: the lid above/below it; ring C (the lid's lip, touching the eyeball) follows ring B.
_EYE_W = 60.0
_LID_OPEN = {"upper": 21.0, "lower": -15.0}
_LID_CLOSED = {"upper": -10.0, "lower": -12.0}


#: Per eyelid ring: width factor; lower lid (gain, offset); upper lid (gain, offset, floor).
#: Ring A, the lid's skin beyond the margin, sits further from the opening, and the upper lid's
#: fold stays at least 6 units above the eye's centre however far the lid closes.
_RINGS = {
    "C": {"grow": 0.92, "low": (1.0, 0.0), "up": (1.0, 0.0, None)},
    "B": {"grow": 1.0, "low": (1.0, 0.0), "up": (1.0, 0.0, None)},
    "A": {"grow": 1.3, "low": (1.6, -2.0), "up": (1.0, 22.0, 6.0)},
}
#: Height profile across the lid (inner corner to the middle to the outer side).
_LID_SHAPE = (0.82, 1.0, 0.82)


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
    spec = _RINGS[ring]
    g = spec["grow"]
    lo_gain, lo_off = spec["low"]
    up_gain, up_off, up_floor = spec["up"]
    if up_floor is not None:
        up = max(up, up_floor)
    w = _EYE_W
    ys = (-w / 2, 0.0, w / 2)
    pts = [(-w * g, 2.0)]                                                   # inner corner
    pts += [(y * g, lo * lo_gain * h + lo_off) for y, h in zip(ys, _LID_SHAPE)]
    pts.append((1.05 * w * g, 5.0))                                         # outer corner
    pts += [(y * g, up * up_gain * h + up_off)
            for y, h in zip(ys[::-1], _LID_SHAPE[::-1])]
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
                         ("C", EYEBALL_RADIUS + LID_LIP_GAP)):
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
