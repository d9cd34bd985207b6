"""Every number the Parke baseline and CASSI 1.0 use, in one place, each with where it comes from.

Values the thesis states carry their table or section. Values it leaves unstated are marked
CHOSEN with the reason; tests in ``tests/versions/test_versions_*.py`` check the behaviour they produce.
Vertex numbers are Parke's 1-based numbers (``FaceModel.vertices[n - 1]``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.data.face import numbering as N

# --- vertices the thesis associates with pellets (4.1.1, Figures 4.4-4.7) -------------------
# The face model's numbering (cassi.data.face.numbering) is the one source of vertex numbers.
#: Bottom of the top front teeth: the XRMB origin is translated here (4.1.1 "Mapping").
V_UPPER_INCISOR_TIP = N.UPPER_INCISOR_TIP          # 226
#: The MANi pellet's vertex (4.1.1, Figure 4.7).
V_MANI = N.MANI                                    # 258
#: The MANm pellet sits halfway between these two vertices (4.1.1, Figure 4.7).
V_MANM_PAIR = N.MANM_PAIR                          # (281, 286)
#: Upper and lower lip pellets' vertices (4.1.1, Figures 4.4-4.5).
V_UL = N.UL                                        # 67
V_LL = N.LL                                        # 49
#: Tongue vertices of T1..T4 (4.1.1, Figure 4.6).
V_TONGUE_PELLETS = N.TONGUE_PELLETS                # (289, 290, 291, 292)
#: Parke's fixed jaw pivot (3.1.3, Equations 3.5-3.6).
V_PARKE_JAW_PIVOT = N.JAW_PIVOT                    # 107

# --- the mapping (4.1.1) -----------------------------------------------------------------
#: CHOSEN: p, "the distance between two approximately corresponding points in the model", is
#: measured in the x-z (midsagittal) projection, because d is measured between pellets that the
#: XRMB projects onto the midsagittal plane; vertex 281/286 lie off the midline (molars) and their
#: lateral offset has no XRMB counterpart.
MAPPING_DISTANCE_PLANE = "xz"

# --- jaw rotation (3.1.3, 4.1.3) ---------------------------------------------------------
#: CHOSEN: below this |theta| (radians) Equations 4.6-4.7 divide by ~0 and the point of rotation
#: runs off to infinity; the motion is then the limit of a rotation about a far point, a
#: translation of each zone by its fraction of the pellet displacement. 1e-9 rad keeps the
#: cancellation error of Eqs. 3.5-3.6 about a point ~1e9 units away below 1e-6 units.
THETA_EPS = 1e-9
#: CHOSEN: Eqs. 4.6-4.7 solve the point of rotation from one jaw point and its rotated image
#: ("(x, y)" and "(x', y')"), without saying which of the two; we use point 1 of Figure 4.8,
#: MANi, so the lower incisor follows its pellet exactly (with the teeth's fraction 0.999999 the
#: residual is below 1e-5 units for any real jaw angle), where the eye looks first. 2 = MANm.
ROTATION_ANCHOR = 1


@dataclass(frozen=True)
class Zone:
    """A rotation zone: vertices rotated by ``fraction`` * theta.

    ``axes`` is ``"xz"`` (x and z rotated) or ``"z"`` (only z takes the rotated value; Table 3.2's
    last column).
    """

    name: str
    fraction: float
    vertices: tuple[int, ...]
    axes: str = "xz"

    def index(self) -> np.ndarray:
        return np.asarray(self.vertices, dtype=np.int64) - 1


def _r(a: int, b: int) -> tuple[int, ...]:
    return tuple(range(a, b + 1))


#: Parke's rotation zones, Table 3.2 (fractions of the jaw angle, axes adjusted), from the face
#: model's numbering: 1st 1.0 jaw 14-43 and lip centre line; 2nd 0.9 lips 50, 53, 56, 59 and the
#: lower teeth 255-286; 3rd 0.75 under the chin 11-13 (z only) and lips 51, 54, 57, 60; 4th 0.5
#: the neck 6-10 (z only); 5th 0.35 the lower cheek 44-48 and the corners 70, 287.
PARKE_ZONES: tuple[Zone, ...] = tuple(Zone(f"{z} {i}", f, tuple(v), ax)
                                      for i, (z, f, v, ax) in enumerate(N.PARKE_JAW_ZONES))

#: CASSI 1.0's factor on Parke's fractions (4.1.3): "Parke's fractions of theta are multiplied by
#: 1.11111" so that the teeth get (almost) 100 % of the jaw rotation.
CASSI_FRACTION_FACTOR = 1.11111

#: CASSI 1.0's zones, Table 4.3: 22 and 30 move from the 1st to the 3rd zone; the lower lip
#: vertices are no longer rotated (4.1.2). The axes column, which Table 4.3 omits, is kept from
#: Table 3.2 (11-13 and the neck z only; 22 and 30, jaw vertices, x and z). Tests check these
#: against Parke's zones times 1.11111.
CASSI10_ZONES: tuple[Zone, ...] = tuple(Zone(f"{z} {i}", f, tuple(v), ax)
                                        for i, (z, f, v, ax) in enumerate(N.CASSI10_JAW_ZONES))
#: Table 4.3 as printed, for the test that the products above match it.
TABLE_4_3_PRINTED = {"1st": 1.11111, "2nd": 0.999999, "3rd": 0.8333325, "4th": 0.555555,
                     "5th": 0.3888885}
#: The vertices rotated by the initialisation's teeth rotation (Parke -> first-row jaw pellets);
#: every other zone is placed by the head-measures jaw rotation (4.1.3, last paragraph).
TEETH_VERTICES = N.LOWER_TEETH

# --- Parke's baseline (3.1.3) ------------------------------------------------------------
#: Parameter 4 "is between 0 and 20" degrees (3.1.3): the baseline clips the jaw angle taken from
#: the pellets to that range, as Parke's parameter could not go outside it.
PARKE_JAW_RANGE_DEG = (0.0, 20.0)

# --- parameters (Tables 4.1, 4.2) --------------------------------------------------------
#: Table 4.1: new parameters, their initial value 0.0, and the pellet and axis each follows.
NEW_PARAMETERS = {
    55: ("T1", "x"), 56: ("T1", "z"), 57: ("T2", "x"), 58: ("T2", "z"),
    59: ("T3", "x"), 60: ("T3", "z"), 61: ("T4", "x"), 62: ("T4", "z"),
    63: ("UL", "x"), 64: ("UL", "z"), 65: ("LL", "x"), 66: ("LL", "z"),
}
#: Table 4.2: Parke's parameters disabled in CASSI (lips 13-22, chin 19, 31-36, 46, teeth 47-48).
DISABLED_PARAMETERS = (13, 14, 16, 17, 18, 19, 21, 22, 31, 32, 35, 36, 46, 47, 48)
#: Parameter 4 is the jaw rotation; CASSI sets it from the pellets (4.1.2), so it is not settable.
JAW_PARAMETER = 4

# --- lips, nose and tongue following their pellets (4.1.1-4.1.2) --------------------------
#: CHOSEN: "the other vertices of the lip are then adjusted accordingly" (4.1.1). Every upper-lip
#: vertex takes UL's displacement and every lower-lip vertex LL's (Parameters 63-66 move a whole
#: lip, the thesis having one pellet per lip); the corners, shared by both lips, take this weighted
#: mix so that they stay between the lips when these part.
CORNER_WEIGHTS = {"UL": 0.5, "LL": 0.5}
#: CHOSEN: "a space always exists between the upper lip and the nose" (4.1.1): the nose tip is
#: raised so that its lowest vertex stays at least this far (mm of the subject, turned into Parke
#: units with the mapping's p / d) above the highest upper-lip vertex, and never demands more than
#: the neutral face's own gap, so a lip at or below its neutral height never moves the nose.
#: 2 mm: a visible space at the scale of the lips (~10 mm tall), small enough not to reshape it.
NOSE_LIP_MIN_GAP_MM = 2.0
#: Name -> (low, high, reason): the plausible range of each CHOSEN value that the default versions
#: use, declared before any sensitivity analysis (``cassi sensitivity`` animates at each end). The
#: tongue tip's distances below act only in the clamped tongue, no default's reading.
RANGES: dict[str, tuple[float, float, str]] = {
    "NOSE_LIP_MIN_GAP_MM": (1.0, 3.0, "a visible space at the scale of the lips: about one to two "
                                      "pixels of the preview front view (1.3 mm)"),
}
#: CHOSEN (4.1.1 says only "the other vertices on the tongue are adjusted accordingly"): each
#: edge vertex follows the centre vertex it lies beside; the edge beside the tip (294) keeps its
#: place beside the tip (it follows the tip, which is placed from T1 and T2, see below); the back
#: vertex and the edge beside it stay anchored (the rubric's "V shape at the back of the tongue
#: caused by the anchored back points" is that choice's known consequence, thesis 5.2 and 6.2
#: "adjusting the anchored points in the tongue"). ``None`` = anchored. The tip (288) itself is
#: listed as following T1 (its pellet), but is placed by :data:`TONGUE_TIP_AHEAD_MM` below.
TONGUE_FOLLOW: dict[int, int | None] = {N.TONGUE_TIP: N.T1, N.TONGUE_BACK: None}
for _centre, _edge in zip(N.TONGUE_CENTRE, N.TONGUE_EDGE):
    TONGUE_FOLLOW[_edge] = (N.T1 if _centre == N.TONGUE_TIP
                            else None if _centre == N.TONGUE_BACK else _centre)
del _centre, _edge
#: The tip (288) is placed IN FRONT OF T1 along the tongue's own centre line (the direction T2 ->
#: T1), not carried rigidly with T1's displacement: 4.1.1 "T1 was placed behind the tip of the
#: tongue" and the tip vertex "represents the tip of the tongue". Carrying the neutral model's
#: 40-unit tip offset (10 mm at Parke's scale, whatever the subject's p/d) put the tip ~10 mm
#: ahead of T1 and through the incisors in 98 % of task files (a bug, not thesis behaviour).
#: CHOSEN 8 mm (subject mm, turned into Parke units with p/d): the XRMB protocol glues T1 about
#: 1 cm behind the tip of the protruded tongue; at rest the tip is bunched, so a little less.
TONGUE_TIP_AHEAD_MM = 8.0
#: CHOSEN: the tip never comes closer than this (subject mm) to the lingual surface of the central
#: incisors (lower 255-258, upper 226-223 at the centre line; Parke's teeth are single surfaces, so
#: the surface is the tooth polygon itself): a real tongue tip rests behind the lower incisors.
#: 1.5 mm keeps the edge vertex beside the tip (294, 6 units behind the tip and 12 to the side,
#: where the arch has curved back ~4 units) behind the teeth as well.
TONGUE_TIP_TEETH_CLEARANCE_MM = 1.5
#: CHOSEN: the tip stays at least this far (subject mm) in front of T1 so the tip triangles never
#: collapse; when the data itself puts T1 at (or through) the incisors the tip goes with it (the
#: clearance above yields): the data is shown, not hidden.
TONGUE_TIP_MIN_AHEAD_MM = 1.0
#: The central incisors' centre-line edges (tip vertex, gum vertex) that bound the tip: lower
#: 255-258 (MANi's tooth), upper 226-223.
TONGUE_TIP_INCISOR_EDGES = ((N.LOWER_INCISOR_TIP, N.MANI),
                            (N.UPPER_INCISOR_TIP, N.upper_tooth(0)[0]))
#: CHOSEN from the evidence: the tongue meets the teeth as the thesis's versions did ("text"),
#: not kept behind them ("clamped", TONGUE_TIP_AHEAD_MM and the clearances above and below). 4.1.1
#: places 289-292 on T1-T4 and says only that "the other vertices on the tongue are adjusted
#: accordingly" (each follows its pellet; the tip follows T1, as TONGUE_FOLLOW has it); 6.2 lists
#: "collision detection to ensure that the tongue does not poke through the teeth or the palatal
#: outline" as future work, and the judges charged 1.0 tongues that poke through the front teeth
#: (Table 5.3; JW11 "noticeably through upper and lower teeth", three negatives). On the real
#: JW45 task 13 (thesis Figure 3.9, at rest) T1 lies 7.8 mm behind and 5.1 mm above the upper
#: incisor tip, so a tip carried 10 mm ahead of it (the neutral model's 40 units) reaches the
#: front of the incisors, as the judges saw. The clamped tongue is CASSI 3.0's kind of fix and
#: stays available (``Cassi10(tongue="clamped")``).
TONGUE_READING: str = "text"
#: "The tongue has been designed to fit inside the arch of the bottom teeth" (4.1.1, Figure 4.6):
#: an edge vertex that follows its centre vertex forward keeps its width, so with T1 a few mm
#: behind the incisors the edge beside T1 (295, 42.8 units to the side) came out through the side
#: of the arch. Each moving edge vertex is therefore held this far (subject mm, CHOSEN as the tip's
#: clearance) behind the front-facing part of the teeth's biting line (the tip edges of the lower
#: and upper tooth quads; segments whose normal is at least this far forward-facing, |n_x|, are the
#: arch's front, the rest run along the cheek and cannot be passed by moving forward).
TONGUE_ARCH_FRONT_NX = 0.5

# --- vertex sets (thesis 3.1.3 Figure 3.7 and 4.1.1 Figure 4.6) ---------------------------
#: "The upper lip is shown as vertices 61 to 69, the lower lip as 49 to 60, and the corners as 70
#: and 287" (3.1.3). CHOSEN: vertex 300, which 2.0 adds between 287 and 70 (4.2) and which the
#: face model always carries, moves with the corners in 1.0 so it never lags behind them.
UPPER_LIP_VERTICES = N.UPPER_LIP
LOWER_LIP_VERTICES = N.LOWER_LIP
LIP_CORNER_VERTICES = (N.CORNER, N.INNER_CORNER, N.CORNER_MIDDLE)
#: Parke's nose outline (3.1.3: "80 through 101 for the nose") and the tip the clearance raises.
NOSE_VERTICES = N.NOSE
NOSE_TIP_VERTICES = N.NOSE_TIP
#: The 12 tongue vertices added by CASSI (4.1.1): 4 on the pellets, tip, back and 6 edges.
TONGUE_VERTICES = N.TONGUE
