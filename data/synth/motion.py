"""Articulatory trajectories of the synthetic corpus: phone targets -> smooth pellet tracks.

Model (pure numpy/scipy, vectorised over frames)
------------------------------------------------
1. A task is a list of segments ``(start_s, end_s, spec)``; a phone's spec comes from
   :data:`PHONE_SPECS`, oral-motor programmes build their own. A spec sets targets for nine
   articulatory channels (:data:`CHANNELS`): jaw opening angle, upper/lower lip protrusion, upper-lip
   lowering, lower-lip raising (relative to the jaw), tongue tip and tongue body displacement (in the
   jaw's frame). Unspecified channels (NaN) are interpolated in time between the neighbouring
   segments that specify them: this is the classic "look-ahead" coarticulation (lip rounding spreads
   over consonants that do not care about the lips, the tongue keeps moving through a /p/).
2. Contact targets (tongue tip on the alveolar ridge, dorsum on the velum) are absolute points on
   the subject's own palate; they are converted to the jaw's frame with the jaw angle targeted at
   that moment, so that the jaw and the tongue share the work as in real speech.
3. Each channel's step-wise target drives a critically damped fourth-order system (two cascaded
   critically damped second-order stages, no overshoot): the velocity profile is bell-shaped and
   the acceleration continuous, as in real articulator movements (a second-order system jumps in
   acceleration at every target change, which the second difference of real XRMB tracks does
   not show). 10-90 % rise time 3.36/omega, as for a second-order system of natural frequency
   omega; targets anticipated by the half-rise time. Channel speeds (omega) differ: tongue tip
   fastest, upper lip slowest.
4. Kinematics: the jaw rotates about the condyle and slides forward as it opens; MNI and MNM are
   rigid points of it and it carries the lower lip and the tongue. Lips cannot pass through each
   other (soft contact, compression), the lower lip cannot pass behind the upper incisors (its
   labiodental limit, the subject's MIN LL), and tongue pellets stay below the palate (soft
   contact).
5. Tracking noise (:data:`NOISE`, per pellet) is added last.

Calibration (:data:`KINEMATIC_TARGETS`; the tests check the generated corpus against it, and
``cassi corpus stats`` measures it on any corpus):

=============================  ==============  ==============================================
figure                         target          source
=============================  ==============  ==============================================
MNI vertical range, "sa sa"    15-25 mm        issue 10's XRMB measurement (task "sa sa sa",
(task 105)                                     JW11, JW45); jaw movement measured at a
                                               mandibular incisor pellet as in Green et al.
                                               2007 (JSLHR 50:928)
MNI peak speed (99th pct.),    150-250 mm/s    same; peak tangential jaw/lip/tongue speeds
"sa sa"                                        of the same order in McClean 2000 (JSLHR
                                               43:205) and Westbury, Lindstrom & McClean
                                               2002 (JSLHR 45:651, 44 XRMB talkers)
LL, T1 peak speed, "sa sa"     150-250 mm/s    same
LL, T1 vertical extent, "sa"   15-30 mm        same
UL extent in speech            1-3 mm          same; Loefqvist & Gracco 1994 (ASA 128,
                                               4pSP7): upper-lip heights at /p b/ closure
                                               spread over 3 mm, the lower lip's over 5 mm
MNI-MNM distance SD            < 0.3 mm        rigid jaw plus tracking noise (issue 10);
                                               thesis Figure 3.9 (real JW45): 0.09 mm
second difference RMS          UL < 10 um,     issue 10; thesis Figure 3.9 (real JW45, at
                               tongue above    rest): UL 0.9, LL 5, tongue 4-7, jaw 2-3 um
                               UL and jaw
UL-LL distance, 0.1th and 1st  22.0, 25.5 mm   real JW11 frames (:data:`REAL_FRAME_TARGETS`):
percentile, JW11, all tasks    (within 10 %)   the 43,260 frames of the Wisconsin XRMB
                                               database's JW11 in Qin & Carreira-Perpiñán
                                               2010 (ICASSP; eecqin/TongueReconstruction,
                                               dat/jw11.mat); sets :data:`CLOSURE_PRESS`
jaw length MNI-MNM, JW11       42.6 mm         same; JW11's row of the subject table
MNI height, 95th / 50th / 5th  -4.8, -8.2,     same: the jaw's resting height (the subject
percentile, JW11               -13.9 mm        table) and its opening (the phones' angles)
=============================  ==============  ==============================================

Lip pellets sit on the vermilion borders (Westbury & Hashi 1997, J. Phonetics 25:405; Westbury,
Severson & Hashi 1999, ICPhS 14:2025); the lower one can be drawn back to the upper incisors in
/f v/, which is where the thesis's near-zero MIN LL values (Figure 4.16) put it.

Coordinates: XRMB head frame (thesis 3.2.3), millimetres; x forward out of the mouth, y up, origin
at the tips of the upper central incisors.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from cassi.data.synth.subjects import SubjectFigures, palate_y

CHANNELS = ("jaw", "ulp", "ull", "llp", "llr", "tipx", "tipy", "bodx", "body")
_IDX = {c: i for i, c in enumerate(CHANNELS)}
#: Natural frequency (rad/s) of each channel's critically damped dynamics (the 10-90 % rise time
#: is 3.36/omega): tongue tip fastest, upper lip slowest.
OMEGA = np.array([26.0, 20.0, 20.0, 36.0, 40.0, 42.0, 42.0, 28.0, 28.0])
#: Each of the two cascaded stages runs at this multiple of omega, so that the fourth-order
#: system's 10-90 % rise time (4.94 stage time constants) equals a second-order one's (3.36/omega).
STAGE_FACTOR = 4.94 / 3.36
#: Targets are anticipated by the fourth-order system's half-rise time (3.67 stage time constants),
#: so a gesture is half-way at its segment's start.
ANTICIPATION = 3.67 / STAGE_FACTOR
#: Calibration targets of the generated corpus: (figure, pellet or None, tasks, low, high). The
#: figures are those of :mod:`cassi.data.corpus.stats`; see the module docstring for the sources.
KINEMATIC_TARGETS: tuple[tuple, ...] = (
    ("y_range", "MNI", (105,), 15.0, 25.0),
    ("speed_p99", "MNI", (105,), 150.0, 250.0),
    ("speed_p99", "LL", (105,), 150.0, 250.0),
    ("speed_p99", "T1", (105,), 150.0, 250.0),
    ("y_range", "LL", (105,), 15.0, 30.0),
    ("y_range", "T1", (105,), 15.0, 30.0),
    ("x_range", "UL", tuple(range(1, 102)), 1.0, 3.0),
    ("y_range", "UL", tuple(range(1, 102)), 1.0, 3.0),
    ("jaw_distance_sd", None, tuple(range(1, 119)), 0.0, 0.3),
    ("d2_rms_um", "UL", tuple(range(1, 119)), 0.0, 10.0),
)
#: Real-recording figures (issue 23): (subject, task, figure of cassi.data.corpus.stats, pellet
#: or None, real value, tolerance kind, tolerance). The generated file, read as the checks read
#: it (1000000 masked, Mis.dat not consulted), must lie within the factor (or mm) of the real.
#: JW11 task 105 ("sa sa sa"): issue 23 measured the real recording against generator 4's
#: synthetic one: UL 99th-pct. speed 0.14 of the real (synthetic 1.92 mm/s -> real 13.7),
#: T3 second difference 10 x the real (476 um -> 48), lip midpoint mean -4.5 mm, first valid
#: row -1.9 mm. JW45 task 13 (thesis Figure 3.9, 13 rows at rest): lip midpoint +0.91 mm.
REAL_RECORDING_TARGETS: tuple[tuple, ...] = (
    ("JW11", 105, "speed_p99", "UL", 13.7, "factor", 2.0),
    ("JW11", 105, "d2_rms_um", "T3", 48.0, "factor", 2.0),
    ("JW11", 105, "lip_mid_mean", None, -4.5, "mm", 3.0),
    ("JW11", 105, "lip_mid_first", None, -1.9, "mm", 3.0),
    ("JW45", 13, "lip_mid_first", None, 0.91, "mm", 3.0),
)
#: Real-frame distributions (figure of cassi.data.corpus.stats, real value, mm): the Wisconsin
#: XRMB database's JW11, the 43,260 frames Qin & Carreira-Perpiñán used (ICASSP 2010; file
#: dat/jw11.mat of the repository eecqin/TongueReconstruction; not consecutive, so distributions
#: only), measured with ``cassi corpus stats``. The generated JW11, all its tasks measured the
#: same way, must lie within REAL_FRAMES_TOLERANCE (relative) of each: the lips pressed together
#: (CLOSURE_PRESS), the jaw length and the jaw's resting height (JW11's row of
#: :mod:`cassi.data.synth.subjects`), the jaw's opening (the phones' jaw angles, unchanged:
#: MNI's 5th-95th percentile spread is 9.1 mm real, 9.7 mm generated), and the upper lip drawn
#: back by the open jaw (UL_BACK_MM_PER_DEG).
REAL_FRAME_TARGETS: tuple[tuple[str, float], ...] = (
    ("ul_ll_p001", 22.0),
    ("ul_ll_p01", 25.5),
    ("jaw_distance_median", 42.6),
    ("mni_y_p95", -4.8),
    ("mni_y_median", -8.2),
    ("mni_y_p05", -13.9),
    ("ul_back_wide_jaw", 1.06),
)
REAL_FRAMES_TOLERANCE = 0.10
#: Upper-lip rise (mm) per degree of jaw opening: the upper lip elevates in opening gestures
#: ("The effects of varying lower-lip displacement on upper-lip movements: implications for the
#: coordination of speech movements", five speakers, strain gauges). The gain is set from the real
#: JW11 "sa sa sa" upper-lip speed (REAL_RECORDING_TARGETS): 0.12 mm/deg gives the real 13.7 mm/s
#: with the synthetic jaw's 117 deg/s; a 14 deg opening raises the lip 1.7 mm, inside the 1-3 mm
#: speech extent of KINEMATIC_TARGETS.
UL_RISE_MM_PER_DEG = 0.12
#: Upper-lip retraction (mm) per degree of jaw opening: the opening jaw draws the upper lip back
#: as well as down over the incisors. Set on the real JW11 frames (REAL_FRAME_TARGETS,
#: ``ul_back_wide_jaw``): where the jaw is open wider than in 99 % of them, the upper lip pellet's
#: median x lies 1.06 mm behind its median over all frames. Without this gain the generated JW11
#: put it 0.07 mm behind (its upper lip moved fore and aft only with the phones' rounding); the
#: figure grows linearly with the gain (0.83 mm at 0.08 mm/deg), 0.10 gives 1.00 mm. Jaw wagging
#: (task 106, 10-14 degrees) then carries the upper lip 1.0-1.4 mm back at its widest, where the
#: generator held it within 0.1 mm of rest; in speech JW11's upper lip x range stays 2.0 mm.
UL_BACK_MM_PER_DEG = 0.10
PERIOD_S = 6866e-6
#: Jaw slide forward (mm) per degree of opening, along the articular eminence.
JAW_SLIDE_MM_PER_DEG = 0.12
_SLIDE_DIR = np.array([math.cos(math.radians(-25.0)), math.sin(math.radians(-25.0))])
#: Bilabial closure (/p b m/, the lip-closing and swallowing tasks): the lips press together
#: until the vertical UL-LL pellet distance is CLOSURE_PRESS of the subject's resting UL-LL
#: distance (thesis Figure 4.25's lip thickness times the jaw length), varying by
#: CLOSURE_PRESS_SD (relative SD) from closure to closure; soft contact stops them at
#: LIPS_PRESSED_MIN of it. One rule for every subject (pressing compresses the lips in proportion
#: to their height), set on the real JW11 frames (REAL_FRAME_TARGETS): there the UL-LL distance's
#: 0.1th and 1st percentiles are 22.0 and 25.5 mm, 0.53 and 0.61 of JW11's resting 41.6 mm
#: (0.976 x 42.6; the real task 5 starts at 41.5 mm). The former rule (lips meeting at 0.8 of the
#: rest, pressed to 0.74) left the generated JW11 at 27.8 and 29.3 mm.
CLOSURE_PRESS = 0.55
CLOSURE_PRESS_SD = 0.08
LIPS_PRESSED_MIN = 0.45
#: Tongue pellets stay this far below the palatal outline (pellet radius plus tissue), mm.
PALATE_CLEARANCE_MM = 1.2
#: Tracking noise per pellet (UL LL T1 T2 T3 T4 MNI MNM): standard deviation (mm) and corner
#: frequency (Hz) of a slowly wandering error. The real files were resampled with smoothing
#: splines (thesis 3.2.4), so their error is smooth from row to row: at rest, thesis Figure 3.9
#: (real JW45) has second differences (RMS) of 0.9 um (UL), 5 um (LL), 4-7 um (tongue) and 2-3 um
#: (jaw), which these reproduce within a factor of about 2 (tests/data/synth/test_synth_corpus.py). The jaw
#: pellets' error keeps the MNI-MNM distance within a few tenths of a millimetre (rigid jaw;
#: real JW45: SD 0.09 mm over its 13 printed rows).
NOISE = {"sd_mm": np.array([0.04, 0.06, 0.10, 0.10, 0.10, 0.10, 0.08, 0.08]),
         "corner_hz": np.array([2.0, 4.0, 3.5, 3.5, 3.5, 3.5, 2.5, 2.5])}

# ----------------------------------------------------------------------------- phone targets
# Spec keys: jaw (deg), prot (fraction of the subject's speech rounding; negative = spreading),
# lips ("close" | "labiodental" | "round" | "open"), tip / body: ("own", dx, dy) displacement in the
# jaw frame scaled by the tongue size, ("alv", back_mm, gap_mm) a point on the palate back_mm behind
# its front end, ("vel", fwd_mm, gap_mm) a point fwd_mm in front of its back end, ("abs", x, y).
_V = {  # vowels: jaw deg, body (dx, dy), prot
    "IY": (1.5, (7.0, 7.0), -0.6), "IH": (2.5, (5.0, 4.0), -0.3), "EH": (4.2, (3.0, 0.5), -0.2),
    "AE": (6.3, (1.5, -3.0), -0.2), "AA": (7.0, (-5.0, -5.0), 0.0), "AO": (5.6, (-6.0, -3.0), 0.5),
    "AH": (4.2, (-1.0, -1.5), 0.0), "UH": (2.8, (-4.0, 3.0), 0.5), "UW": (1.8, (-5.0, 6.0), 1.0),
    "OW": (3.5, (-5.0, 1.0), 0.8), "ER": (2.8, (-2.0, 4.0), 0.4),
}
PHONE_SPECS: dict[str, dict] = {}
for _p, (_j, (_bx, _by), _pr) in _V.items():
    PHONE_SPECS[_p] = {"jaw": _j, "prot": _pr, "lips": "open", "body": ("own", _bx, _by),
                       "tip": ("own", 0.4 * _bx, 0.5 * _by + (3.0 if _p == "ER" else 0.0))}
del _p, _j, _bx, _by, _pr
#: Diphthongs: two targets, share of the duration of the first.
DIPHTHONGS = {"AY": ("AA", "IY", 0.55), "AW": ("AA", "UW", 0.55), "OY": ("AO", "IY", 0.55),
              "EY": ("EH", "IY", 0.6)}
PHONE_SPECS.update({
    "P": {"jaw": 3.0, "lips": "close"}, "B": {"jaw": 3.0, "lips": "close"},
    "M": {"jaw": 3.0, "lips": "close"},
    "F": {"jaw": 2.5, "lips": "labiodental"}, "V": {"jaw": 2.5, "lips": "labiodental"},
    "TH": {"jaw": 3.0, "tip": ("abs", 1.0, -1.5)}, "DH": {"jaw": 3.0, "tip": ("abs", 1.0, -1.5)},
    "T": {"jaw": 1.5, "tip": ("alv", 4.0, 0.0)}, "D": {"jaw": 1.5, "tip": ("alv", 4.0, 0.0)},
    "N": {"jaw": 2.0, "tip": ("alv", 4.0, 0.0)},
    "L": {"jaw": 3.0, "tip": ("alv", 4.5, 0.0), "body": ("own", -2.0, -2.0)},
    "S": {"jaw": 1.0, "tip": ("alv", 3.0, 2.5), "prot": -0.2},
    "Z": {"jaw": 1.0, "tip": ("alv", 3.0, 2.5), "prot": -0.2},
    "SH": {"jaw": 1.5, "tip": ("alv", 9.0, 2.0), "body": ("own", 2.0, 3.0), "prot": 0.8},
    "ZH": {"jaw": 1.5, "tip": ("alv", 9.0, 2.0), "body": ("own", 2.0, 3.0), "prot": 0.8},
    "CH": {"jaw": 1.5, "tip": ("alv", 7.0, 0.0), "body": ("own", 2.0, 3.0), "prot": 0.8},
    "JH": {"jaw": 1.5, "tip": ("alv", 7.0, 0.0), "body": ("own", 2.0, 3.0), "prot": 0.8},
    "K": {"jaw": 3.0, "body": ("vel", 10.0, 0.0)}, "G": {"jaw": 3.0, "body": ("vel", 10.0, 0.0)},
    "NG": {"jaw": 3.0, "body": ("vel", 10.0, 0.0)},
    "Y": {"jaw": 2.0, "body": ("own", 7.0, 7.5), "prot": -0.4},
    "W": {"jaw": 2.5, "body": ("own", -5.0, 6.0), "prot": 1.0, "lips": "round"},
    "R": {"jaw": 3.0, "tip": ("alv", 12.0, 5.0), "body": ("own", -3.0, 1.0), "prot": 0.6},
    "HH": {},
})
#: The resting posture: what silence and the start of every recording look like.
REST_SPEC = {"jaw": 0.0, "prot": 0.0, "lips": "open", "tip": ("own", 0.0, 0.0),
             "body": ("own", 0.0, 0.0)}
#: Pauses longer than this return to rest; shorter ones leave every channel unspecified.
REST_PAUSE_S = 0.3


@dataclass(frozen=True)
class Anatomy:
    """A subject's resting pellets and articulator geometry, mm (from :class:`SubjectFigures`)."""

    fig: SubjectFigures
    rest: np.ndarray        # (8, 2) resting pellets UL LL T1 T2 T3 T4 MNI MNM
    condyle: np.ndarray     # (2,)
    d_rest: float           # resting UL-LL pellet distance
    d_closed: float         # UL-LL pellet distance with the lips just touching
    round_ul: float         # speech lip rounding of UL (mm forward)
    round_ll: float
    spread_ul: float        # speech lip spreading of UL (mm back)
    ll_floor_x: float       # the lower lip pellet cannot pass behind this x (upper incisors), mm

    @classmethod
    def of(cls, fig: SubjectFigures) -> "Anatomy":
        pal = fig.palate
        ts = fig.tongue_scale
        ul, ll = np.array(fig.ul_rest_mm), np.array(fig.ll_rest_mm)
        xs = pal[0] + (pal[6] - pal[0]) * np.array([0.08, 0.42, 0.72, 0.97]) * ts ** 0.3
        xs = np.maximum(xs, pal[6] - 2.0)
        gaps = np.array([4.5, 10.5, 12.0, 17.0]) * ts
        tongue = np.column_stack([xs, palate_y(pal, xs) - gaps])
        rest = np.vstack([ul, ll, tongue, fig.mni_mm, fig.mnm_mm])
        dist = float(np.hypot(*(ul - ll)))
        # speech moves the upper lip 1-3 mm (KINEMATIC_TARGETS): rounding and spreading stay
        # well short of the subject's extremes, which the oral-motor tasks reach
        return cls(fig, rest, np.array(fig.condyle_mm, float), d_rest=dist, d_closed=0.8 * dist,
                   round_ul=min(1.5, 0.3 * fig.max_protrusion_ul_mm),
                   round_ll=min(4.0, 0.6 * fig.max_protrusion_ll_mm),
                   spread_ul=min(0.8, fig.spread_ul_mm),
                   ll_floor_x=fig.min_ll * fig.jaw_length_mm)


def jaw_transform(anat: Anatomy, theta_deg: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Carry jaw-frame points with the jaw.

    Parameters
    ----------
    theta_deg : (F,) jaw opening, degrees (0 = rest).
    pts : (F, K, 2), (K, 2) or (2,) points in the resting jaw frame, mm.

    Returns
    -------
    (F, K, 2) head-frame points, mm: rotated about the condyle (opening moves the chin down) and
    slid forward-down by :data:`JAW_SLIDE_MM_PER_DEG` per degree.
    """
    th = np.radians(np.asarray(theta_deg, float))[:, None]
    c, s = np.cos(th), np.sin(th)
    rel = np.asarray(pts, float) - anat.condyle
    if rel.ndim == 1:
        rel = rel[None, :]
    if rel.ndim == 2:
        rel = np.broadcast_to(rel, (th.shape[0],) + rel.shape)
    x = anat.condyle[0] + c * rel[..., 0] + s * rel[..., 1]
    y = anat.condyle[1] - s * rel[..., 0] + c * rel[..., 1]
    slide = JAW_SLIDE_MM_PER_DEG * np.asarray(theta_deg, float)[:, None]
    return np.stack([x + slide * _SLIDE_DIR[0], y + slide * _SLIDE_DIR[1]], axis=-1)


def _jaw_inverse(anat: Anatomy, theta_deg: float, p: np.ndarray) -> np.ndarray:
    th = math.radians(theta_deg)
    q = np.asarray(p, float) - JAW_SLIDE_MM_PER_DEG * theta_deg * _SLIDE_DIR - anat.condyle
    c, s = math.cos(th), math.sin(th)
    return anat.condyle + np.array([c * q[0] - s * q[1], s * q[0] + c * q[1]])


def expand_phones(segments: list[tuple[float, float, str]]) -> list[tuple[float, float, dict]]:
    """Phone segments ``(start_s, end_s, ARPAbet label)`` -> spec segments.

    Stress digits are ignored; diphthongs become two targets; ``sp``/``sil``/empty labels are
    pauses (rest when longer than :data:`REST_PAUSE_S`); unknown labels are unspecified.
    """
    out: list[tuple[float, float, dict]] = []
    for t0, t1, lab in segments:
        p = "".join(ch for ch in lab.upper() if ch.isalpha())
        if p in ("", "SP", "SIL", "SPN"):
            out.append((t0, t1, REST_SPEC if t1 - t0 > REST_PAUSE_S else {}))
        elif p in DIPHTHONGS:
            a, b, share = DIPHTHONGS[p]
            tm = t0 + share * (t1 - t0)
            out.append((t0, tm, PHONE_SPECS[a]))
            out.append((tm, t1, PHONE_SPECS[b]))
        else:
            out.append((t0, t1, PHONE_SPECS.get(p, {})))
    return out


def _point(anat: Anatomy, spec) -> np.ndarray | None:
    """Absolute head-frame point of a contact spec, or None for an ``own`` spec."""
    kind = spec[0]
    pal = anat.fig.palate
    if kind == "abs":
        return np.array(spec[1:3], float)
    if kind == "alv":
        x = pal[0] - spec[1]
    elif kind == "vel":
        x = pal[6] + spec[1]
    else:
        return None
    return np.array([x, float(palate_y(pal, x)) - PALATE_CLEARANCE_MM - spec[2]])


def segment_targets(anat: Anatomy, segs: list[tuple[float, float, dict]],
                    rng: np.random.Generator, *, jaw_gain: float = 1.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Channel targets per segment.

    ``jaw_gain`` scales the phones' jaw angles (the task type's speaking style, see
    :data:`cassi.data.synth.program.JAW_GAIN`).

    Returns
    -------
    starts : (S,) segment start times, s.
    targets : (S, 9) targets in :data:`CHANNELS` order; every NaN filled by interpolation in time.
    """
    n = len(segs)
    starts = np.array([s[0] for s in segs], float)
    mids = np.array([0.5 * (s[0] + s[1]) for s in segs], float)
    tg = np.full((n, len(CHANNELS)), np.nan)
    ts = anat.fig.tongue_scale
    jit = rng.normal(0.0, 1.0, size=(n, 5))
    jaw = np.array([s[2].get("jaw", np.nan) for s in segs], float)
    jaw = jaw * jaw_gain * (1.0 + 0.08 * jit[:, 0])
    jaw = _fill(mids, jaw)
    tg[:, 0] = jaw
    rest = anat.rest
    ll_jaw = jaw_transform(anat, jaw, rest[1])[:, 0]        # LL carried by the targeted jaw
    ll_jaw_y = ll_jaw[:, 1]
    for i, (_, _, spec) in enumerate(segs):
        if not spec:
            continue
        pr = spec.get("prot")
        if pr is not None:
            a_ul = anat.round_ul if pr >= 0 else anat.spread_ul
            a_ll = anat.round_ll if pr >= 0 else anat.spread_ul * 0.6
            f = 1.0 + 0.08 * jit[i, 1]
            tg[i, 1], tg[i, 3] = pr * a_ul * f, pr * a_ll * f
        if "ulp_mm" in spec:
            tg[i, 1] = spec["ulp_mm"]
        if "llp_mm" in spec:
            tg[i, 3] = spec["llp_mm"]
        lips = spec.get("lips")
        if lips is not None:
            ull = {"close": 1.5, "labiodental": 0.5, "round": 0.8}.get(lips, 0.0)
            tg[i, 2] = ull
            ul_y = rest[0, 1] - ull
            if lips == "close":       # pellets closer than at contact: the lips press together
                press = CLOSURE_PRESS * (1.0 + CLOSURE_PRESS_SD * jit[i, 4])
                tg[i, 4] = ul_y - press * anat.d_rest - ll_jaw_y[i]
            elif lips == "labiodental":
                # lower lip up and drawn back onto the upper incisors (its floor)
                tg[i, 4] = ul_y - 1.05 * anat.d_closed - ll_jaw_y[i]
                tg[i, 3] = min(-1.5, anat.ll_floor_x - 0.5 - ll_jaw[i, 0])
            elif lips == "round":
                tg[i, 4] = max(0.0, ul_y - 1.15 * anat.d_closed - ll_jaw_y[i])
            else:
                tg[i, 4] = 0.0
        for key, col, base in (("tip", 5, rest[2]), ("body", 7, rest[4])):
            sp = spec.get(key)
            if sp is None:
                continue
            p = _point(anat, sp)
            if p is None:
                own = np.array(sp[1:3], float) * ts + 0.5 * jit[i, 2:4] * ts
            else:
                own = _jaw_inverse(anat, jaw[i], p) - base
            tg[i, col:col + 2] = own
    for c in range(1, len(CHANNELS)):
        tg[:, c] = _fill(mids, tg[:, c])
    return starts, tg


def _fill(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    ok = np.isfinite(v)
    if not ok.any():
        return np.zeros_like(v)
    if ok.all():
        return v
    return np.interp(t, t[ok], v[ok])


def smooth(starts: np.ndarray, targets: np.ndarray, n_frames: int, *,
           period_s: float = PERIOD_S) -> np.ndarray:
    """Frame-wise channel trajectories (F, 9) from step targets, critically damped per channel.

    Each channel is two cascaded critically damped second-order stages at
    ``STAGE_FACTOR * omega`` (no overshoot, continuous acceleration). The state starts at rest on
    the first segment's targets; each channel sees its targets :data:`ANTICIPATION` / omega early.
    """
    t = np.arange(n_frames) * period_s
    out = np.empty((n_frames, targets.shape[1]))
    for c, om in enumerate(OMEGA):
        idx = np.searchsorted(starts, t + ANTICIPATION / om, side="right") - 1
        u = targets[np.clip(idx, 0, len(starts) - 1), c]
        a = math.exp(-STAGE_FACTOR * om * period_s)
        b, den = [(1.0 - a) ** 2], [1.0, -2.0 * a, a * a]
        zi = np.array([u[0] * (2 * a - a * a), -a * a * u[0]])  # steady state at u[0]
        y = lfilter(b, den, u, zi=zi)[0]
        out[:, c] = lfilter(b, den, y, zi=zi)[0]
    return out


def _soft_ceiling(y: np.ndarray, ceiling: np.ndarray, s: float = 0.35) -> np.ndarray:
    """min(y, ceiling), smoothly over about s mm (exact far below the ceiling)."""
    return ceiling - s * np.logaddexp(0.0, (ceiling - y) / s)


def pellets(anat: Anatomy, ch: np.ndarray) -> np.ndarray:
    """Pellet tracks (F, 8, 2) mm from channel trajectories (F, 9) (no noise)."""
    rest = anat.rest
    n = ch.shape[0]
    theta = np.maximum(ch[:, 0], -0.3)          # teeth stop the jaw closing further
    own = np.zeros((n, 8, 2))
    tip, body = ch[:, 5:7], ch[:, 7:9]
    own[:, 2] = tip
    own[:, 3] = 0.4 * tip + 0.6 * body
    own[:, 4] = body
    own[:, 5] = 0.85 * body
    carried = jaw_transform(anat, theta, rest[None, 1:8] + own[:, 1:8])  # LL, T1-4, MNI, MNM
    out = np.empty((n, 8, 2))
    out[:, 0, 0] = rest[0, 0] + ch[:, 1] - UL_BACK_MM_PER_DEG * np.maximum(theta, 0.0)
    out[:, 0, 1] = rest[0, 1] - ch[:, 2] + UL_RISE_MM_PER_DEG * np.maximum(theta, 0.0)
    out[:, 1:] = carried
    out[:, 1, 0] += ch[:, 3]
    out[:, 1, 1] += ch[:, 4]
    # the upper incisors stop the lower lip going further back (soft contact)
    out[:, 1, 0] = -_soft_ceiling(-out[:, 1, 0], -anat.ll_floor_x, 0.25)
    # lips meet: LL stays below UL by the most pressed lips' distance (soft contact)
    out[:, 1, 1] = _soft_ceiling(out[:, 1, 1], out[:, 0, 1] - LIPS_PRESSED_MIN * anat.d_rest,
                                 0.6)
    # tongue pellets under the palate where the palate is above them
    pal = anat.fig.palate
    tx = out[:, 2:6, 0]
    ceil = palate_y(pal, tx) - PALATE_CLEARANCE_MM
    inside = tx < pal[0] + 1.0
    out[:, 2:6, 1] = np.where(inside, _soft_ceiling(out[:, 2:6, 1], ceil), out[:, 2:6, 1])
    return out


def add_noise(xy: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Tracking noise, per pellet :data:`NOISE`: white noise low-passed by a critically damped
    second-order filter at the pellet's corner frequency, scaled to its standard deviation."""
    raw = rng.normal(0.0, 1.0, size=xy.shape)
    out = xy.copy()
    for p, (sd, fc) in enumerate(zip(NOISE["sd_mm"], NOISE["corner_hz"])):
        a = math.exp(-2.0 * math.pi * fc * PERIOD_S)
        noise = lfilter([(1.0 - a) ** 2], [1.0, -2.0 * a, a * a], raw[:, p], axis=0)
        # stationary variance of the two-pole filter driven by unit white noise
        var = (1.0 - a) ** 4 * (1.0 + a * a) / ((1.0 - a * a) * ((1.0 + a * a) ** 2 - 4.0 * a * a))
        out[:, p] += noise * (sd / math.sqrt(var))
    return out
