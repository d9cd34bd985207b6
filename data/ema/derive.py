"""Pellets an EMA corpus lacks, derived by a declared rule (the coil map's ``derive``).

Each derived pellet is listed in the recording (``TaskRecording.derived``) and in the map's
resolved form; nothing is derived without a rule in the map. The rules, in the XRMB head frame
(mm):

- ``extrapolate`` ``from: [A, B]``: ``B + (B - A)``, one more step along the line A -> B (T4
  from T2 and T3: an even spacing of the tongue pellets is assumed);
- ``midpoint`` ``from: [A, B]``: ``(A + B) / 2``;
- ``jaw-rotation`` (MNM): the mandible is rigid and turns about a fixed centre. JW11's jaw, the
  one measured in the project (:data:`cassi.data.synth.subjects.SUBJECTS`, real XRMB frames):
  MNI-MNM 42.6 mm (the median of 43,260 frames), MNM 5.1 deg above the line behind MNI, the
  centre of rotation at (-76.7, +20.3) mm from the closed jaw's MNI. The closed jaw is the valid
  frame where MNI is at its 95th height percentile (JW11's frames put the closed jaw there);
  each frame's jaw angle is MNI's angle about the centre, and MNM sits 42.6 mm from MNI, the
  closed jaw's MNI -> MNM turned by that angle (the jaw stays rigid);
- ``jaw-coil`` ``coil: c`` (MNM): 42.6 mm (JW11, as above) from MNI toward a second jaw coil.
"""
from __future__ import annotations

import numpy as np

from cassi.data.synth.subjects import SUBJECTS
from cassi.data.xrmb.files import PELLETS

_JAW = SUBJECTS["JW11"]
JAW_LENGTH_MM = _JAW.jaw_length_mm
#: MNM - MNI on the closed jaw: JAW_LENGTH_MM behind, at JW11's jaw slope (negative: MNM above).
_SLOPE = np.radians(_JAW.jaw_slope_deg)
CLOSED_MNM_OFFSET = JAW_LENGTH_MM * np.array([-np.cos(_SLOPE), -np.sin(_SLOPE)])
#: The jaw's centre of rotation relative to the closed jaw's MNI (JW11).
JAW_CENTRE_OFFSET = np.asarray(_JAW.condyle_mm) - np.asarray(_JAW.mni_mm)
CLOSED_PERCENTILE = 95


def describe(name: str, rule: dict) -> str:
    """One line for the reports: the pellet and how it was derived."""
    kind = rule["rule"]
    if "from" in rule:
        return f"{name}: {kind} from {' and '.join(rule['from'])}"
    if kind == "jaw-coil":
        return f"{name}: {JAW_LENGTH_MM} mm from MNI toward coil {rule['coil']} (JW11's jaw)"
    return f"{name}: rigid jaw about JW11's centre of rotation, {JAW_LENGTH_MM} mm behind MNI"


def derive_pellets(xy: np.ndarray, rules: dict[str, dict], coil_xy: dict[str, np.ndarray]
                   ) -> None:
    """Fill the derived pellets of ``xy`` (F, 8, 2) in place (NaN where an input is missing).

    ``coil_xy``: head-frame positions (F, 2) of the coils a rule names (``jaw-coil``).
    """
    for name in sorted(rules, key=lambda n: rules[n]["rule"] in ("jaw-rotation", "jaw-coil")):
        rule = rules[name]
        p = PELLETS.index(name)
        if rule["rule"] in ("extrapolate", "midpoint"):
            a, b = (xy[:, PELLETS.index(q)] for q in rule["from"])
            xy[:, p] = b + (b - a) if rule["rule"] == "extrapolate" else 0.5 * (a + b)
        elif rule["rule"] == "jaw-coil":
            mni = xy[:, PELLETS.index("MNI")]
            d = coil_xy[rule["coil"]] - mni
            xy[:, p] = mni + JAW_LENGTH_MM * d / np.linalg.norm(d, axis=1, keepdims=True)
        else:
            xy[:, p] = _rigid_jaw(xy[:, PELLETS.index("MNI")])


def _rigid_jaw(mni: np.ndarray) -> np.ndarray:
    ok = np.isfinite(mni).all(axis=1)
    out = np.full_like(mni, np.nan)
    if not ok.any():
        return out
    height = np.percentile(mni[ok, 1], CLOSED_PERCENTILE)
    closed = mni[ok][np.argmin(np.abs(mni[ok, 1] - height))]
    centre = closed + JAW_CENTRE_OFFSET
    angle = (np.arctan2(*(mni[ok] - centre).T[::-1]) - np.arctan2(*(closed - centre)[::-1]))
    arm = CLOSED_MNM_OFFSET
    c, s = np.cos(angle), np.sin(angle)
    out[ok] = mni[ok] + np.column_stack([c * arm[0] - s * arm[1], s * arm[0] + c * arm[1]])
    return out
