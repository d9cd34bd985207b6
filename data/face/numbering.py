"""Vertex numbers of the Parke-compatible face, as CASSI's thesis names them.

All numbers are Parke's 1-based vertex numbers: ``FaceModel.vertices[n - 1]`` is vertex ``n``.
Sources: thesis 3.1.1-3.1.3 (Figures 3.1-3.7, Table 3.2), 4.1.1 (Figures 4.4-4.7), 4.1.3
(Table 4.3), 4.2 (Figure 4.17: the lip outlines and the added corner vertex 300).

Scale
-----
Parke's units are not stated in the sources. The excerpt of ``st1.pts`` (thesis Figure 3.2) puts
the base of the neck at z = -594 with the neck 2 x 187 units wide there and the underside of the
chin (vertex 16) 281 units in front of the neck and 171 units above its base. A real neck base is
about 95-115 mm wide and the chin ~70 mm in front of it, which gives about 0.25 mm per unit; the
same scale makes Parke's start eyeball radius (parameter 44 = 70 units) 17.5 mm and the iris
(parameter 43 = 0.4 of it) 7 mm, close to real eyes. The generated head is built at
``MM_PER_UNIT = 0.25``: about 925 units (231 mm) from the chin to the top of the head. CASSI maps
the XRMB data by the ratio p/d of the model's jaw length to the subject's (4.1.1), so this scale
only sets the face's proportions, not the mapping.
"""
from __future__ import annotations

#: Millimetres per Parke unit in the generated face (see the module docstring).
MM_PER_UNIT = 0.25
#: Parke units per millimetre.
UNITS_PER_MM = 1.0 / MM_PER_UNIT


def _r(a: int, b: int) -> tuple[int, ...]:
    """Inclusive range of vertex numbers."""
    return tuple(range(a, b + 1))


# --- counts -------------------------------------------------------------------------------
#: Parke's vertex count in st1.pts (thesis Figure 3.2: "287 275").
PARKE_VERTEX_COUNT = 287
#: The last vertex of the tongue and the added corner vertex (4.1.1, 4.2).
TONGUE_FIRST, TONGUE_LAST = 288, 299
CORNER_MIDDLE = 300
#: The palate surface starts here; its size is fixed (PALATE_STATIONS x PALATE_ACROSS).
PALATE_FIRST = 301
#: Palate surface: stations along PAL.DAT's outline (front to back) x points across each
#: station from the centre line to the edge (left half; the right half is the mirror).
PALATE_STATIONS = 12
PALATE_ACROSS = 5
PALATE_COUNT = PALATE_STATIONS * PALATE_ACROSS
PALATE_LAST = PALATE_FIRST + PALATE_COUNT - 1
#: Eyeballs follow the palate: both eyes explicitly (Parke's eyes are not mirrored; each looks
#: at the target on its own, dissertation Appendix A).
EYES_FIRST = PALATE_LAST + 1

# --- neck, under the chin, jaw, cheek (Table 3.2, Figure 3.6) -------------------------------
NECK_BASE = _r(1, 5)
NECK = _r(6, 10)
UNDER_CHIN = _r(11, 13)
NECK_AND_UNDER_CHIN = _r(1, 13)
JAW = _r(14, 43)
#: Back of the jaw: moved from the 1st to the 3rd zone by CASSI 1.0 (Table 4.3).
JAW_BACK = (22, 30)
#: Below the lower lip, following 49, 50, 51 by half (thesis 4.2, "To create more natural
#: movement").
BELOW_LIP = (41, 42, 43)
LOWER_CHEEK = _r(44, 48)
#: Most influenced by the lip corner 70 (4.2).
CHEEK_BY_CORNER = 44

# --- lips (Figures 3.7, 4.4, 4.5, 4.17) -------------------------------------------------------
LOWER_LIP = _r(49, 60)
UPPER_LIP = _r(61, 69)
#: Centre-line vertices (y = 0).
LOWER_LIP_CENTRE = (49, 52, 55, 58)
UPPER_LIP_CENTRE = (61, 64, 67)
LIP_CENTRE_TOP_TO_BOTTOM = (67, 64, 61, 58, 55, 52, 49)
#: Lip pellet vertices: UL on the upper edge of the upper lip, LL on the lower edge of the lower.
UL = 67
LL = 49
CORNER = 70
INNER_CORNER = 287
#: Outlines of Figure 4.17 (centre to corner): outer, middle, inner.
UPPER_OUTER = (67, 68, 69)
LOWER_OUTER = (49, 50, 51)
UPPER_MIDDLE = (64, 65, 66)
LOWER_MIDDLE_UPPER_ROW = (55, 56, 57)
LOWER_MIDDLE_LOWER_ROW = (52, 53, 54)
UPPER_INNER = (61, 62, 63)
LOWER_INNER = (58, 59, 60)
#: Lip rows from the centre line outwards, top (outer upper edge) to bottom (outer lower edge).
UPPER_LIP_ROWS = (UPPER_OUTER, UPPER_MIDDLE, UPPER_INNER)
LOWER_LIP_ROWS = (LOWER_INNER, LOWER_MIDDLE_UPPER_ROW, LOWER_MIDDLE_LOWER_ROW, LOWER_OUTER)
ABOVE_LIP = (71, 72, 73)

# --- nose (Figure 3.6) ------------------------------------------------------------------------
NOSE = _r(80, 101)

# --- jaw pivot (3.1.3) ------------------------------------------------------------------------
JAW_PIVOT = 107

# --- teeth (Figure 3.3, 4.7) ------------------------------------------------------------------
#: Eight quads per side for each set (Parke's 32 teeth quads over both halves, dissertation 3.3).
UPPER_TEETH = _r(223, 254)
LOWER_TEETH = _r(255, 286)
TEETH = _r(223, 286)
TEETH_PER_SET = 8
LOWER_TEETH_FIRST, LOWER_TEETH_LAST = 255, 286
UPPER_TEETH_FIRST, UPPER_TEETH_LAST = 223, 254
#: The bottom of the top front teeth: the XRMB origin maps here (4.1.1).
TEETH_TIP = 226
UPPER_INCISOR_TIP = 226
#: MANi pellet vertex: outer surface of the lower central incisors at the gum line (4.1.1).
MANI = 258
#: MANm: the point halfway between these two vertices (4.1.1), where the lower first and second
#: molars meet at the gum line. The generated teeth: quads 0-4 the incisors, canine and
#: premolars, quads 5 and 6 the two halves of the broad first molar, quad 7 the second molar,
#: so that 281 (end of quad 6) and 286 (start of quad 7) flank the first/second molar contact.
MANM_PAIR = (281, 286)
#: Tip of the lower central incisors (same quad as MANi, the biting edge at the centre line).
LOWER_INCISOR_TIP = 255


def upper_tooth(k: int) -> tuple[int, int, int, int]:
    """Vertices of upper tooth quad ``k`` (0 = central incisor ... 7 = second molar).

    Order: gum-mesial, gum-distal, tip-distal, tip-mesial (so 226 is the central incisor's tip at
    the centre line).
    """
    if not 0 <= k < TEETH_PER_SET:
        raise IndexError(k)
    a = 223 + 4 * k
    return (a, a + 1, a + 2, a + 3)


def lower_tooth(k: int) -> tuple[int, int, int, int]:
    """Vertices of lower tooth quad ``k``: tip-mesial, tip-distal, gum-distal, gum-mesial.

    So 258 (MANi) is the central incisor's gum line at the centre line, and 281 / 286 are the gum
    line where quads 6 and 7 (0-based) meet (the first and second molars: CASSI's MANm site).
    """
    if not 0 <= k < TEETH_PER_SET:
        raise IndexError(k)
    a = 255 + 4 * k
    return (a, a + 1, a + 2, a + 3)


# --- tongue (4.1.1, Figure 4.6) ---------------------------------------------------------------
TONGUE = _r(288, 299)
TONGUE_TIP = 288
#: T1..T4 pellet vertices, front to back.
T1, T2, T3, T4 = 289, 290, 291, 292
TONGUE_PELLETS = (T1, T2, T3, T4)
TONGUE_BACK = 293
#: Centre line of the tongue, front to back: tip, T1-T4, back.
TONGUE_CENTRE = (288, 289, 290, 291, 292, 293)
#: Edge vertices beside each centre vertex, front to back.
TONGUE_EDGE = _r(294, 299)

# --- palate -----------------------------------------------------------------------------------
PALATE = _r(PALATE_FIRST, PALATE_LAST)


def palate_vertex(station: int, across: int) -> int:
    """Vertex number of palate ``station`` (0 = front) and ``across`` (0 = centre line)."""
    if not (0 <= station < PALATE_STATIONS and 0 <= across < PALATE_ACROSS):
        raise IndexError((station, across))
    return PALATE_FIRST + station * PALATE_ACROSS + across


#: Palate centre line, front to back.
PALATE_CENTRE = tuple(palate_vertex(s, 0) for s in range(PALATE_STATIONS))

# --- landmarks the face generator places (named for the versions and the rubric) ---------------
#: Soft-tissue chin (most forward point of the chin on the centre line) and its underside.
POGONION = 24
CHIN = POGONION
MENTON = 16
CHIN_LOW = MENTON
#: Gnathion (point of the chin, on the centre line between pogonion and menton) and gonion
#: (angle of the jaw) of the neutral face, for CASSI's head-measure adjustment (4.1.1 "Chin and
#: Jaw Adjustments").
GNATHION = 26
GONION = 22
#: Lowest centre-line point of the nose (above the upper lip) and the nose tip.
SUBNASALE = 80
NOSE_TIP_CENTRE = 82
#: Vertices raised by CASSI's nose clearance rule (4.1.1): the tip and the underside (the
#: subnasale row 80, 81, 83, the nostril row 85-87 and the tip row 82, 90, 91).
NOSE_TIP = (80, 81, 82, 83, 85, 86, 87, 90, 91)

# --- jaw zones as data (Table 3.2 and Table 4.3) ------------------------------------------------
#: Parke's zones (Table 3.2): (zone, fraction of the jaw angle, vertices, axes adjusted).
PARKE_JAW_ZONES: tuple[tuple[str, float, tuple[int, ...], str], ...] = (
    ("1st", 1.0, JAW + LOWER_LIP_CENTRE, "xz"),
    ("2nd", 0.9, (50, 53, 56, 59) + LOWER_TEETH, "xz"),
    ("3rd", 0.75, UNDER_CHIN, "z"),
    ("3rd", 0.75, (51, 54, 57, 60), "xz"),
    ("4th", 0.5, NECK, "z"),
    ("5th", 0.35, LOWER_CHEEK + (CORNER, INNER_CORNER), "xz"),
)
#: CASSI 1.0's zones (Table 4.3): Parke's fractions x 1.11111, 22 and 30 moved to the 3rd zone,
#: lower lip no longer rotated. The table gives 0.999999 for the teeth (0.9 x 1.11111).
CASSI10_JAW_ZONES: tuple[tuple[str, float, tuple[int, ...], str], ...] = (
    ("1st", 1.11111, tuple(v for v in JAW if v not in JAW_BACK), "xz"),
    ("2nd", 0.999999, LOWER_TEETH, "xz"),
    ("3rd", 0.8333325, UNDER_CHIN, "z"),
    ("3rd", 0.8333325, JAW_BACK, "xz"),
    ("4th", 0.555555, NECK, "z"),
    ("5th", 0.3888885, LOWER_CHEEK, "xz"),
)
