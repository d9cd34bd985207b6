"""Per-subject figures of the synthetic corpus: one table, with the source of every column.

Each of the thesis's 15 subjects (thesis 3.2.5 less JW29; the rows of ../shared/reference/profiles/
maxprotru.txt) gets its own anatomy. The generator calibrates the resting lips and the maximum lip
protrusion so that preprocessing the generated corpus (thesis 4.2.1, 4.2.3, Appendix B)
reproduces the subject's published profile.

Sources of the columns
----------------------
- ``sex``: the database handbook's speaker table 4.1 (Westbury 1994), as distributed with the
  public alignments (``speaker_demographics1.csv``).
- ``rest_ul, rest_ll, max_ul, max_ll, min_ul, min_ll``: thesis Figure 4.16 (``maxprotru.txt``),
  values divided by the jaw length; two printing defects repaired as noted in
  ../shared/reference/README.md.
- ``lipthick``: thesis Figure 4.25 (``lipthick.txt``), divided by the jaw length.
- JW45's jaw pellets (``mni_mm``, ``jaw_length_mm``, ``jaw_slope_deg``) are those of thesis
  Figure 3.9 (JW45_013.TXY, first valid row: MNI (-0.699, -7.452), MNM (-34.792, -9.862) mm).
- JW11's jaw pellets are the real JW11's (Wisconsin XRMB database). ``jaw_length_mm`` 42.6: the
  median MNI-MNM distance of the 43,260 JW11 frames Qin & Carreira-Perpiñán used (ICASSP 2010;
  repository eecqin/TongueReconstruction, dat/jw11.mat; the real task 5 starts at 42.7 mm).
  ``mni_mm`` (-0.8, -4.7) and ``jaw_slope_deg`` -5.1 (MNM above MNI): the real task 5's first
  valid row, MNI (-0.79, -4.69), MNM (-43.36, -0.93) mm; the frames' MNI height (95th
  percentile -4.8 mm, median -8.2 mm) puts the closed jaw there too. The thesis prints no jaw
  length in mm, and its profile of JW11 agrees with 42.6 mm: rest UL 0.345 and LL 0.229 times
  42.6 are 14.7 and 9.7 mm (the frames' median UL and LL x: 14.9, 9.4 mm), lipthick 0.976 times
  42.6 is 41.6 mm (the real task 5's first UL-LL distance: 41.5 mm); the generator's former
  37.9 mm gave 13.1, 8.7 and 37.0 mm. JW11's head measures were derived (rule below) with those
  former pellets (MNI y -7.6 mm, jaw length 37.9 mm) and are kept: the real pellets sit higher on
  the incisor and further back along the molars, which moves the pellets, not the bone.
- The other subjects' ``jaw_length_mm`` is this generator's guess, with one floor from the thesis
  and published anatomy: the lip pellets are "glued to the outside of the lips at the upper and
  lower edges of the lips" (thesis 3.2.3), and lipthick is their average distance in the first
  valid row of every task, where "the lips are lightly placed together" (4.2.3). Lips lightly
  together hold their two vermilions between the pellets, so lipthick times the jaw length is at
  least the closed vermilion span of the subject's sex (:data:`VERMILION_HEIGHTS_MM`: 17.05 mm men,
  18.11 mm women). A guess below that floor is raised to it, rounded up to 0.1 mm
  (:func:`jaw_floor_mm`): JW21 33.9 -> 35.1, JW25 32.0 -> 43.8, JW27 31.1 -> 40.9, JW502 34.1 ->
  36.9 mm (the guesses put JW25's and JW27's resting pellets 13.3 and 13.8 mm apart, thinner than
  any adult's closed lips). Three of the raised jaws lie between the two real ones (JW45 34.18,
  JW11 42.6 mm) and JW25's is 1.2 mm longer than JW11's (the MNM pellet sits "in the vicinity
  of the area between the first and second mandibular molars", 3.2.3, so its spacing from MNI
  varies with where it was glued). The rule
  was written down before any result of the raised jaws was looked at; what it moves is the
  face's scale (4.1.1), so the resting mouth, 1.39 times the jaw length, as well. The head
  measures were derived with the former guesses and are kept, as for JW11: a longer pellet
  spacing moves the molar pellet, not the bone.
- JW12's palate parameters are a least-squares fit (max error 0.42 mm) to thesis Figure 3.11
  (JW12 PAL.DAT).
- ``gonion_mm``, ``gnathion_mm`` (the head measures written to ``Headmeasures.txt``): not printed
  in the thesis; derived once per subject by the rule below from the subject's own jaw pellets,
  jaw length and sex, rounded to 0.1 mm and frozen here (plausible, not measured). The XRMB
  frame's x axis is the maxillary occlusal plane, so the angle that matters is the occlusal-to-
  mandibular-plane angle, cephalometric norm about 13-18 deg (SN-MP 32 minus SN-OP 14; Downs's
  FH-MP 21.9 minus his FH-OP 9.3), steeper for long faces.

  * gnathion y = MNI y - S, S (MNI pellet on the lower incisor -> lowest point of the chin,
    i.e. crown below the pellet, root and symphysis) drawn around 35.5 mm (male) / 33 mm
    (female), sd 1.6: gnathion 38-46 mm below the upper incisor tip (lower anterior face height
    incisor tip -> menton about 40-45 mm). Gnathion x: the chin 7 mm behind to 3 mm in front of
    the incisors (retruded to prominent chins), unchanged from the first table.
  * mandibular plane (gnathion -> gonion) rising backward at 17 deg + 2 deg per mm that S
    exceeds the sex mean (long faces steeper) + sd 1.5 deg, clipped to 13-24 deg: 13.4-21.3.
  * gonion x = gnathion x - (79 mm + 1.3 x (jaw length - 34.5 mm) + sd 1.2 mm): the body of
    the mandible scales with the MNI-MNM spacing of the subject's own teeth; gonion 78-89 mm
    behind the incisors, 73-84 mm behind the gnathion (Go-Gn 76-88 mm).
  * Checks against the rest of the table (tests/data/synth/test_synth_model.py): MNI 32-37 mm and MNM
    20-25 mm above the mandibular plane (teeth on the body of the jaw); the gonion 33-42 mm
    below the jaw's centre of rotation (``condyle_mm`` of :mod:`cassi.data.synth.motion`) and
    within 12 mm of it front to back (the ramus hangs below the joint). That centre sits lower
    than the anatomical condyle (it also stands for the condyle's glide), so the distance is
    shorter than a condylion-gonion ramus height (about 50-55 mm).
- ``lip_mid_y_mm`` (height of the resting lips' midpoint above the upper incisor tip, issue 23):
  from real recordings where one is known, else from published norms, never from which
  subjects CASSI 2.1 should change.

  * JW45: +0.9 mm, the real JW45 task 13 (thesis Figure 3.9: UL y 11.596, LL y -9.772 mm at
    the first valid row).
  * JW11: -1.9 mm, the real JW11 task 105 at its first valid row (issue 23's measurement).
  * the others, by sex (:data:`LIP_MID_BY_SEX`): with the lips together at rest the midpoint
    of the vermilion-border pellets lies half the difference of the vermilion heights below
    the lips' meeting line, which the resting incisor display puts above the incisor tip:
    display (Vig & Brundo 1978, J. Prosthet. Dent. 39:502, "The kinetics of anterior tooth
    display": 1.91 mm men, 3.40 mm women) minus (lower - upper vermilion height) / 2
    (Pietruski & Majak 2022, Aesthet. Surg. J. 42:1130, men 11.15 - 5.9 mm; Pietruski et al.
    2022, Aesthet. Plast. Surg., women 11.64 - 6.47 mm): -0.7 mm (M), +0.8 mm (F). The two real
    male recordings (+0.9, -1.9) bracket the male figure.
- ``min_ul``, ``min_ll`` (MIN UL, MIN LL of Figure 4.16): the lower lip reaches its minimum in
  /f v/, drawn back onto the upper incisors (``Anatomy.ll_floor_x`` of
  :mod:`cassi.data.synth.motion`): every subject's MIN LL is reproduced within 0.01. MIN UL is
  reproduced (within 0.01) for the five subjects whose published value is above 0.1 of the jaw
  length (JW18, JW19, JW32, JW41, JW502: the upper lip 1.9-6.2 mm behind rest, reached in lip
  spreading). For the other ten the published MIN UL is 0.0074-0.0117, i.e. the upper-lip pellet
  0.25-0.44 mm in front of the incisor tip, 11-20 mm behind its rest position: no speech or
  oral-motor gesture draws the upper lip's vermilion back onto the incisor tip (spreading moves
  it 1.9-6.2 mm in the five others). The generator spreads them by a typical 1.5 mm instead
  (:attr:`SubjectFigures.spread_ul_mm`): their generated MIN UL is 0.30-0.50.
- Everything else (the other subjects' jaw length above its floor, their pellet placement,
  condyle, palate shape, pharynx, lip height, tongue size) is this generator's choice: drawn
  once around typical adult values (larger for the male speakers) and frozen here. They are
  plausible, not measured.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Adult vermilion heights (mm) by sex, (upper, lower): Pietruski & Majak 2022 (Aesthet. Surg. J.
#: 42:1130, men) and Pietruski et al. 2022 (Aesthet. Plast. Surg., women). They place the resting
#: lips here and set the face's closed-lip span (:data:`cassi.data.face.build.CLOSED_LIP_SPAN`).
VERMILION_HEIGHTS_MM = {"M": (5.9, 11.15), "F": (6.47, 11.64)}


def jaw_floor_mm(sex: str, lipthick: float) -> float:
    """The shortest jaw length (mm, rounded up to 0.1) at which a subject's lipthick (UL-LL over
    the jaw length in the first valid rows, thesis Figure 4.25) holds the closed vermilions of its
    sex between the lip pellets (module docstring)."""
    upper, lower = VERMILION_HEIGHTS_MM[sex]
    return math.ceil(round((upper + lower) / lipthick * 10.0, 6)) / 10.0


#: Resting lip midpoint above the incisor tip (mm) by sex, from published norms (see the module
#: docstring): incisor display at rest minus half the vermilion-height difference.
LIP_MID_BY_SEX = {sex: round(display - (VERMILION_HEIGHTS_MM[sex][1] - VERMILION_HEIGHTS_MM[sex][0])
                             / 2, 1) for sex, display in (("M", 1.91), ("F", 3.40))}
#: Resting lip midpoints measured on real recordings (module docstring).
LIP_MID_REAL = {"JW45": 0.9, "JW11": -1.9}


@dataclass(frozen=True)
class SubjectFigures:
    """The figures the generator uses for one subject (lengths in mm, XRMB head frame).

    Attributes
    ----------
    name, sex : str
    rest_ul, rest_ll, max_ul, max_ll, min_ul, min_ll : float
        Thesis Figure 4.16, divided by the jaw length.
    lipthick : float
        Thesis Figure 4.25, divided by the jaw length.
    jaw_length_mm : float
        Distance MNI-MNM (rigid jaw).
    mni_mm : (float, float)
        Resting (teeth nearly together) MNI pellet.
    jaw_slope_deg : float
        Angle of MNM below the horizontal through MNI, degrees.
    condyle_mm : (float, float)
        Centre of jaw rotation (temporomandibular joint).
    palate : tuple
        ``(x_front, y_front, height, width, shape, tilt, x_back, n_points)`` of the palatal outline
        ``y = y_front + height * (1 - exp(-(u / width) ** shape)) - tilt * u``, ``u = x_front - x``.
    pharynx_x_mm : (float, float)
        x of the posterior pharyngeal wall at y = +10 and y = -40 mm.
    gonion_mm, gnathion_mm : (float, float)
        Head measures (angle of the jaw, point of the chin) with the jaw at rest (as MNI, MNM);
        the gonion behind and above the gnathion (see the module docstring).
    lip_mid_y_mm : float
        Height of the midpoint between the resting UL and LL pellets.
    tongue_scale : float
        Size of the tongue and of its movements relative to a typical male speaker.
    """

    name: str
    sex: str
    rest_ul: float
    rest_ll: float
    max_ul: float
    max_ll: float
    min_ul: float
    min_ll: float
    lipthick: float
    jaw_length_mm: float
    mni_mm: tuple[float, float]
    jaw_slope_deg: float
    condyle_mm: tuple[float, float]
    palate: tuple
    pharynx_x_mm: tuple[float, float]
    gonion_mm: tuple[float, float]
    gnathion_mm: tuple[float, float]
    lip_mid_y_mm: float
    tongue_scale: float

    # ---- derived anatomy -------------------------------------------------------------------
    @property
    def mnm_mm(self) -> tuple[float, float]:
        """Resting MNM pellet: jaw_length_mm behind MNI, jaw_slope_deg below the horizontal."""
        a = np.radians(self.jaw_slope_deg)
        return (self.mni_mm[0] - self.jaw_length_mm * np.cos(a),
                self.mni_mm[1] - self.jaw_length_mm * np.sin(a))

    @property
    def mandibular_plane_deg(self) -> float:
        """Angle (degrees) at which the mandibular plane, gnathion -> gonion, rises backward
        above the XRMB x axis (the maxillary occlusal plane)."""
        dx = self.gnathion_mm[0] - self.gonion_mm[0]
        dy = self.gonion_mm[1] - self.gnathion_mm[1]
        return float(np.degrees(np.arctan2(dy, dx)))

    @property
    def ul_rest_mm(self) -> tuple[float, float]:
        """Resting UL pellet, calibrated: x = rest_ul * d, UL-LL distance = lipthick * d."""
        return (self.rest_ul * self.jaw_length_mm, self.lip_mid_y_mm + 0.5 * self._lip_dy)

    @property
    def ll_rest_mm(self) -> tuple[float, float]:
        return (self.rest_ll * self.jaw_length_mm, self.lip_mid_y_mm - 0.5 * self._lip_dy)

    @property
    def _lip_dy(self) -> float:
        d = self.jaw_length_mm
        dist, dx = self.lipthick * d, (self.rest_ul - self.rest_ll) * d
        return float(np.sqrt(dist * dist - dx * dx))

    @property
    def max_protrusion_ul_mm(self) -> float:
        """Forward travel of UL from rest to the maximum (task 118)."""
        return (self.max_ul - self.rest_ul) * self.jaw_length_mm

    @property
    def max_protrusion_ll_mm(self) -> float:
        return (self.max_ll - self.rest_ll) * self.jaw_length_mm

    @property
    def spread_ul_mm(self) -> float:
        """Backward travel of UL in spread lips: the published minimum where it is physiological
        (more than 0.1 of the jaw length), else a typical 1.5 mm."""
        if self.min_ul > 0.1:
            return (self.rest_ul - self.min_ul) * self.jaw_length_mm
        return 1.5

    def palate_outline(self) -> np.ndarray:
        """float64 (P, 2) mm: palatal outline front to back (like JW12's PAL.DAT)."""
        xf, yf, h, w, k, tilt, xb, n = self.palate
        # denser at the front where the outline bends, like the real files
        s = np.linspace(0.0, 1.0, int(n)) ** 1.25
        x = xf + (xb - xf) * s
        return np.column_stack([x, palate_y(self.palate, x)])

    def pharynx_outline(self) -> np.ndarray:
        """float64 (3, 2) mm: posterior pharyngeal wall, top to bottom (a straight-ish line)."""
        top, bottom = self.pharynx_x_mm
        y = np.array([10.0, -15.0, -40.0])
        x = np.array([top, 0.5 * (top + bottom) - 0.8, bottom])
        return np.column_stack([x, y])


def palate_y(palate: tuple, x: np.ndarray) -> np.ndarray:
    """Height (mm) of the palatal outline above x (mm); flat beyond both ends."""
    xf, yf, h, w, k, tilt, xb, _ = palate
    u = np.clip(xf - np.asarray(x, dtype=np.float64), 0.0, xf - xb)
    return yf + h * (1.0 - np.exp(-(u / w) ** k)) - tilt * u


_S = SubjectFigures
#: The 15 subjects, in the order of maxprotru.txt.
SUBJECTS: dict[str, SubjectFigures] = {s.name: s for s in (
    _S("JW11", "M", 0.345274, 0.228690, 0.519758, 0.439836, 0.009925, 0.003348, 0.975998,
       jaw_length_mm=42.6, mni_mm=(-0.8, -4.7), jaw_slope_deg=-5.1, condyle_mm=(-77.5, 15.6),
       palate=(-4.3, 8.1, 23.1, 12.9, 1.47, 0.09, -53.6, 12), pharynx_x_mm=(-89.8, -90.9),
       gonion_mm=(-89.0, -17.1), gnathion_mm=(-5.3, -44.2),
       lip_mid_y_mm=LIP_MID_REAL["JW11"], tongue_scale=0.99),
    _S("JW12", "M", 0.541010, 0.390205, 0.730061, 0.485915, 0.011575, -0.102688, 0.629742,
       jaw_length_mm=37.4, mni_mm=(-0.6, -7.8), jaw_slope_deg=5.2, condyle_mm=(-81.4, 16.5),
       palate=(-5.0, 8.5, 19.73, 13.19, 1.55, 0.14, -53.1, 12), pharynx_x_mm=(-82.6, -93.1),
       gonion_mm=(-84.7, -19.3), gnathion_mm=(-3.6, -43.0),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=1.05),
    _S("JW15", "M", 0.452623, 0.426632, 0.606981, 0.524212, 0.008840, 0.007371, 0.579452,
       jaw_length_mm=34.0, mni_mm=(0.5, -8.6), jaw_slope_deg=3.6, condyle_mm=(-78.1, 15.3),
       palate=(-4.4, 7.2, 20.4, 14.8, 1.5, 0.12, -54.2, 12), pharynx_x_mm=(-86.6, -85.1),
       gonion_mm=(-82.9, -18.0), gnathion_mm=(-3.7, -45.4),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=1.01),
    _S("JW16", "F", 0.431169, 0.399125, 0.600965, 0.572621, 0.008847, 0.008228, 0.823341,
       jaw_length_mm=31.5, mni_mm=(1.3, -7.2), jaw_slope_deg=4.2, condyle_mm=(-80.6, 18.7),
       palate=(-5.0, 9.3, 23.8, 15.5, 1.69, 0.09, -50.9, 14), pharynx_x_mm=(-79.7, -78.6),
       gonion_mm=(-79.1, -15.2), gnathion_mm=(-5.8, -41.1),
       lip_mid_y_mm=LIP_MID_BY_SEX["F"], tongue_scale=0.92),
    _S("JW18", "M", 0.536166, 0.490561, 0.834940, 0.896159, 0.427359, 0.244083, 0.534753,
       jaw_length_mm=33.6, mni_mm=(-0.6, -7.4), jaw_slope_deg=3.7, condyle_mm=(-81.1, 16.0),
       palate=(-5.9, 10.5, 20.3, 12.9, 1.51, 0.19, -51.6, 13), pharynx_x_mm=(-80.7, -92.2),
       gonion_mm=(-78.1, -16.9), gnathion_mm=(2.2, -42.5),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=1.05),
    _S("JW19", "M", 0.492486, 0.471077, 0.684463, 0.774152, 0.371975, 0.172287, 0.785441,
       jaw_length_mm=34.6, mni_mm=(-1.4, -8.4), jaw_slope_deg=3.7, condyle_mm=(-81.0, 16.6),
       palate=(-4.3, 8.0, 23.0, 14.9, 1.26, 0.15, -51.8, 16), pharynx_x_mm=(-83.5, -88.9),
       gonion_mm=(-80.1, -24.6), gnathion_mm=(-1.8, -43.3),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=0.99),
    _S("JW21", "F", 0.335453, 0.278352, 0.502530, 0.440367, 0.008934, 0.007164, 0.517419,
       jaw_length_mm=35.1, mni_mm=(-1.5, -7.4), jaw_slope_deg=3.1, condyle_mm=(-77.4, 16.6),
       palate=(-5.2, 9.0, 18.9, 15.1, 1.44, 0.17, -47.6, 10), pharynx_x_mm=(-82.0, -80.2),
       gonion_mm=(-82.7, -16.5), gnathion_mm=(-5.3, -39.8),
       lip_mid_y_mm=LIP_MID_BY_SEX["F"], tongue_scale=0.95),
    _S("JW24", "M", 0.365504, 0.409801, 0.621404, 0.600709, 0.007542, 0.008639, 0.604045,
       jaw_length_mm=34.9, mni_mm=(-1.0, -8.7), jaw_slope_deg=2.3, condyle_mm=(-84.8, 18.4),
       palate=(-4.3, 9.2, 17.7, 12.6, 1.66, 0.18, -54.0, 11), pharynx_x_mm=(-84.0, -89.2),
       gonion_mm=(-86.1, -21.5), gnathion_mm=(-6.9, -44.0),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=0.99),
    _S("JW25", "F", 0.363746, 0.404857, 0.668489, 0.787208, 0.007766, 0.008383, 0.414120,
       jaw_length_mm=43.8, mni_mm=(-1.5, -6.8), jaw_slope_deg=4.1, condyle_mm=(-79.9, 21.5),
       palate=(-4.4, 10.2, 19.5, 13.1, 1.64, 0.09, -46.3, 10), pharynx_x_mm=(-74.2, -81.4),
       gonion_mm=(-78.4, -20.2), gnathion_mm=(-5.1, -39.8),
       lip_mid_y_mm=LIP_MID_BY_SEX["F"], tongue_scale=0.88),
    _S("JW27", "F", 0.349867, 0.342236, 0.639942, 0.535901, 0.007401, 0.005606, 0.442891,
       jaw_length_mm=40.9, mni_mm=(-0.2, -6.5), jaw_slope_deg=6.0, condyle_mm=(-76.0, 16.9),
       palate=(-4.8, 8.7, 16.7, 13.7, 1.44, 0.17, -50.2, 14), pharynx_x_mm=(-80.0, -79.5),
       gonion_mm=(-80.6, -17.2), gnathion_mm=(-6.8, -38.4),
       lip_mid_y_mm=LIP_MID_BY_SEX["F"], tongue_scale=0.89),
    _S("JW32", "M", 0.445339, 0.441625, 0.621980, 0.609274, 0.284189, 0.259924, 0.503228,
       jaw_length_mm=38.2, mni_mm=(-0.5, -8.8), jaw_slope_deg=5.1, condyle_mm=(-81.5, 16.2),
       palate=(-4.6, 8.1, 21.0, 16.6, 1.42, 0.16, -56.3, 14), pharynx_x_mm=(-86.2, -90.9),
       gonion_mm=(-85.9, -17.5), gnathion_mm=(-3.4, -45.1),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=1.03),
    _S("JW40", "M", 0.528038, 0.384745, 0.767303, 0.524264, 0.011705, 0.007449, 0.752903,
       jaw_length_mm=35.5, mni_mm=(-1.5, -6.4), jaw_slope_deg=6.8, condyle_mm=(-83.9, 17.6),
       palate=(-5.4, 8.6, 16.6, 14.3, 1.71, 0.11, -55.7, 13), pharynx_x_mm=(-86.0, -91.8),
       gonion_mm=(-80.7, -19.0), gnathion_mm=(-1.0, -42.2),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=0.95),
    _S("JW41", "M", 0.477164, 0.465303, 0.821385, 0.649093, 0.406428, 0.212140, 0.719188,
       jaw_length_mm=35.7, mni_mm=(-0.1, -8.5), jaw_slope_deg=1.2, condyle_mm=(-81.5, 19.8),
       palate=(-4.5, 8.3, 18.5, 15.0, 1.51, 0.05, -54.5, 13), pharynx_x_mm=(-86.6, -89.8),
       gonion_mm=(-83.4, -21.4), gnathion_mm=(-2.5, -45.4),
       lip_mid_y_mm=LIP_MID_BY_SEX["M"], tongue_scale=1.0),
    _S("JW45", "M", 0.462957, 0.355955, 0.692150, 0.564495, 0.010773, 0.008101, 0.619474,
       jaw_length_mm=34.18, mni_mm=(-0.7, -7.45), jaw_slope_deg=4.04, condyle_mm=(-84.6, 17.0),
       palate=(-4.3, 8.8, 18.3, 14.3, 1.39, 0.12, -55.0, 16), pharynx_x_mm=(-85.6, -87.1),
       gonion_mm=(-85.1, -18.0), gnathion_mm=(-6.9, -44.4),
       lip_mid_y_mm=LIP_MID_REAL["JW45"], tongue_scale=1.0),
    _S("JW502", "F", 0.319526, 0.268207, 0.582271, 0.563677, 0.264849, -0.037349, 0.491017,
       jaw_length_mm=36.9, mni_mm=(-0.3, -7.4), jaw_slope_deg=2.6, condyle_mm=(-82.2, 20.8),
       palate=(-5.1, 7.3, 19.4, 13.4, 1.38, 0.08, -51.1, 13), pharynx_x_mm=(-81.4, -80.8),
       gonion_mm=(-82.7, -12.6), gnathion_mm=(-5.7, -42.6),
       lip_mid_y_mm=LIP_MID_BY_SEX["F"], tongue_scale=0.91),
)}
del _S


def subject_figures(name: str) -> SubjectFigures:
    """The figures of one subject (case-insensitive name); KeyError names the known subjects."""
    key = name.upper()
    if key not in SUBJECTS:
        raise KeyError(f"unknown subject {name!r}; known: {', '.join(SUBJECTS)}")
    return SUBJECTS[key]
