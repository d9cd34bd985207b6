"""Lip thickness: CASSI 2.0's equal lips (section 4.2.3, step 8 of Figure 4.28) and CASSI 2.1's
low-lips adjustment with its Hermite blend (section 4.3).

All functions are elementwise over frames (arrays (F,)); lengths are Parke units, z is up.
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from cassi.common.errors import CassiInputError

from cassi.versions import lips_constants as K

__all__ = [
    "ThicknessRule",
    "EQUAL_THICKNESS",
    "LOW_LIPS_THICKNESS",
    "LowLipsReading",
    "blend_inner_corner_z",
    "centreline_z",
    "current_thickness",
    "hermite_f1",
    "hermite_f2",
    "is_low_lips",
    "low_lips_margin",
    "rounding_t",
    "thick_from_lipthick",
]


def thick_from_lipthick(lipthick: float, parke_jaw_distance: float) -> float:
    """Thick, the thickness of one relaxed lip in Parke units (section 4.2.3).

    lipthick.txt holds the mean UL-LL distance at the first valid row divided by the XRMB jaw
    length; scaling to Parke space multiplies by Parke's jaw distance p (the 4.1.1 mapping
    scales by p/d), and the two lips are assumed equally thick, so the result is halved.

    >>> thick_from_lipthick(0.5, 100.0)
    25.0
    """
    if not (np.isfinite(lipthick) and lipthick > 0):
        raise CassiInputError(f"lip thickness must be a positive number, got {lipthick!r}")
    if not (np.isfinite(parke_jaw_distance) and parke_jaw_distance > 0):
        raise CassiInputError(f"Parke jaw distance must be positive, got {parke_jaw_distance!r}")
    return float(lipthick) * float(parke_jaw_distance) / 2.0


def rounding_t(cp, *, onset: float = K.ROUNDING_ONSET_C) -> np.ndarray:
    """How far the lips have rounded: ``t = (onset - c') / onset`` clipped to [0, 1].

    0 at and above the onset (c' >= 50: not rounding), 1 when fully rounded (c' <= 0). This is
    the t of the 2.1 blending functions (section 4.3.3: "c' slightly less than 50, t ~ 0 ...
    c' = 0, t = 1") and the rounding amount of step 8.
    """
    cp = np.asarray(cp, dtype=np.float64)
    return np.clip((onset - cp) / onset, 0.0, 1.0)


def current_thickness(
    thick: float, cp, *, onset: float = K.ROUNDING_ONSET_C, gain: float | None = None
) -> np.ndarray:
    """Step 8 of LIP MOVEMENT: currthick, equal to Thick unless the lips round (c' < 50).

    ``currthick = Thick * (1 + gain * t)`` with t from :func:`rounding_t`; continuous at the
    onset and ``(1 + gain) Thick`` when fully rounded.
    """
    gain = K.THICKEN_GAIN if gain is None else gain  # read at the call (cassi.versions.ranges)
    return thick * (1.0 + gain * rounding_t(cp, onset=onset))


@dataclass(frozen=True)
class ThicknessRule:
    """How currthick is split between the lips: upper = ``upper * currthick``, lower likewise.

    CASSI 2.0 uses equal lips (1, 1); CASSI 2.1 uses (2/3, 4/3) for low-lip subjects.
    """

    name: str
    upper: float
    lower: float

    def split(self, currthick) -> tuple[np.ndarray, np.ndarray]:
        """(currthick_upp, currthick_low), arrays (F,)."""
        ct = np.asarray(currthick, dtype=np.float64)
        return self.upper * ct, self.lower * ct


EQUAL_THICKNESS = ThicknessRule("equal", 1.0, 1.0)
LOW_LIPS_THICKNESS = ThicknessRule(
    "low-lips", K.UPPER_THICK_FRACTION_LOW, K.LOWER_THICK_FRACTION_LOW
)


def centreline_z(z67, z49, upper_thick, lower_thick) -> dict[int, np.ndarray]:
    """Steps 9 and 10: z of the centre-line vertices 64, 61 (upper) and 52, 55, 58 (lower).

    ``z64 = z67 - 1/2 upper``, ``z61 = z67 - upper``; ``z52 = z49 + 1/3 lower``,
    ``z55 = z49 + 2/3 lower``, ``z58 = z49 + lower`` (section 4.2.3; Figure 4.29 for 2.1).
    67 and 49 themselves stay on their pellets.
    """
    z67 = np.asarray(z67, dtype=np.float64)
    z49 = np.asarray(z49, dtype=np.float64)
    u1, u2 = K.UPPER_CENTRELINE_FRACTIONS
    l1, l2, l3 = K.LOWER_CENTRELINE_FRACTIONS
    return {
        64: z67 - u1 * upper_thick,
        61: z67 - u2 * upper_thick,
        52: z49 + l1 * lower_thick,
        55: z49 + l2 * lower_thick,
        58: z49 + l3 * lower_thick,
    }


class LowLipsReading(str, Enum):
    """Which threshold section 4.3.1's comparison uses (the text and the results disagree).

    TEXT: the inside edge starts more than ``threshold`` units *below* vertex 226 (the words).
    RESULTS: the inside edge starts lower than ``threshold`` units *above* 226 (what fits the
    subjects the thesis reports changed; see ``lips_constants.LOW_LIPS_READING``).
    """

    TEXT = "text"
    RESULTS = "results"


def low_lips_margin(z_inside_start: float, z226: float, *, reading: LowLipsReading | str,
                    threshold: float = K.LOW_LIPS_THRESHOLD) -> float:
    """Section 4.3.1: how far the upper lip's starting inside edge lies below the threshold
    height (Parke units, signed): > 0 adjusts the lips, <= 0 leaves them as in 2.0.

    Parameters
    ----------
    z_inside_start : float
        z67 - currthick at the first valid row (the upper lip as thick as the lower, as in 2.0).
    z226 : float
        z of vertex 226, the tip of the upper front teeth.
    reading : LowLipsReading
        TEXT: threshold height z226 - threshold; RESULTS: z226 + threshold.
    """
    reading = LowLipsReading(reading)
    height = z226 - threshold if reading is LowLipsReading.TEXT else z226 + threshold
    return float(height - z_inside_start)


def is_low_lips(z61_start: float, z226: float, *, threshold: float = K.LOW_LIPS_THRESHOLD,
                reading: LowLipsReading | str = LowLipsReading.TEXT) -> bool:
    """Section 4.3.1: does the upper lip's inside edge start beyond the threshold? With the
    TEXT reading: more than 20 units below 226 (:func:`low_lips_margin` > 0).

    Parameters
    ----------
    z61_start : float
        z of the upper lip's inside edge at the first frame (z67 - currthick, equal lips).
    z226 : float
        z of vertex 226, the tip of the upper front teeth.
    """
    return low_lips_margin(z61_start, z226, reading=reading, threshold=threshold) > 0.0


def hermite_f1(t) -> np.ndarray:
    """Equation 4.20: ``F1 = 2t^3 - 3t^2 + 1`` (1 at t = 0, 0 at t = 1, flat at both ends)."""
    t = np.asarray(t, dtype=np.float64)
    return (2.0 * t - 3.0) * t * t + 1.0


def hermite_f2(t) -> np.ndarray:
    """Equation 4.21: ``F2 = -2t^3 + 3t^2`` (= 1 - F1)."""
    t = np.asarray(t, dtype=np.float64)
    return (3.0 - 2.0 * t) * t * t


def blend_inner_corner_z(z287, z60, cp, *, onset: float = K.ROUNDING_ONSET_C) -> np.ndarray:
    """Section 4.3.3: z of the inside corner 287 blended toward vertex 60's as the lips round.

    ``z = F1(t) z287 + F2(t) z60`` with ``t = (50 - c') / 50`` clipped to [0, 1]: 287 keeps its
    own z while c' >= 50 and takes 60's z at full rounding (c' <= 0).
    """
    t = rounding_t(cp, onset=onset)
    return hermite_f1(t) * np.asarray(z287, dtype=np.float64) + hermite_f2(t) * np.asarray(
        z60, dtype=np.float64
    )
