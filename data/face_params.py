"""Parke's parameters (thesis Table 3.1; dissertation chapter 3): start values, ranges and how
each acts on the face (interpolation, scaling, translation, rotation).

``apply_parameters(face, {number: value})`` recomputes ``face.vertices`` from the face's st1/st2
sets with every parameter at its start value except those given. A value outside its range is a
:class:`CassiInputError` unless ``clamp=True``. Ranges are the thesis's "(a - b)" where it gives
one, else the dissertation's Figures 3.9, 3.13 and 3.15, else (marked CHOSEN) the span of the
values the thesis tried in Table 3.1's last column.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cassi.data import numbering as N
from cassi.data.errors import CassiInputError


@dataclass(frozen=True)
class Parameter:
    number: int
    name: str
    start: float
    low: float
    high: float
    kind: str          # interpolation | scaling | translation | rotation | eye | render
    source: str


def _p(number, name, start, low, high, kind, source):
    return Parameter(number, name, float(start), float(low), float(high), kind, source)


#: Table 3.1 (with ranges). Sources: T = thesis Table 3.1 "(a - b)", D = dissertation figure,
#: C = CHOSEN from the values tried in Table 3.1's last column.
PARAMETERS: dict[int, Parameter] = {p.number: p for p in (
    _p(1, "eye opening", 0.9, 0.0, 1.0, "interpolation", "T"),
    _p(2, "eyebrow arch", 0.5, 0.0, 1.0, "interpolation", "T"),
    _p(3, "eyebrow separation", 0.0, -25.0, 25.0, "translation", "T 0-25; D 3.9 -25..25"),
    _p(4, "jaw rotation", 0.0, 0.0, 20.0, "rotation", "T"),
    _p(5, "eyelid Y scale", 1.0, 0.5, 1.5, "scaling", "D 3.15"),
    _p(6, "eyelid Z scale", 1.0, 0.5, 1.5, "scaling", "D 3.15"),
    _p(7, "head X scale", 1.0, 0.5, 2.0, "scaling", "C (Table 3.1 tries 0.5 and 2)"),
    _p(8, "head Y scale", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(9, "head Z scale", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(10, "nose tip Y scale", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(11, "nose bridge Y scale", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(12, "mouth Y scale", 1.0, 0.5, 2.0, "scaling", "C (D 3.13 gives 0.5-1.5)"),
    _p(13, "mouth interpolation", 1.0, 0.0, 1.0, "interpolation", "T"),
    _p(14, "mouth X offset", 0.0, -20.0, 30.0, "translation", "C/D 3.13"),
    _p(15, "287 Y offset", 0.0, 0.0, 25.0, "translation", "D 3.13 corner width"),
    _p(16, "mouth corner X offset", 0.0, -25.0, 25.0, "translation", "D 3.13"),
    _p(17, "mouth corner Y offset", 0.0, -25.0, 25.0, "translation", "D 3.13"),
    _p(18, "mouth corner Z offset", 0.0, -25.0, 25.0, "translation", "D 3.13"),
    _p(19, "jaw Y scale", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(20, "cheek Y scale", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(21, "lower lip f tuck", 0.0, -20.0, 10.0, "translation", "C/D 3.13"),
    _p(22, "raise upper lip", 15.0, 0.0, 30.0, "translation", "C (D 3.13 gives 0-20)"),
    _p(26, "nose tip X offset", 0.0, -50.0, 50.0, "translation", "D 3.15"),
    _p(27, "nose tip Z offset", 0.0, -50.0, 50.0, "translation", "D 3.15"),
    _p(28, "eyeball X offset", 0.0, -20.0, 20.0, "translation", "C"),
    _p(29, "eyeball Y offset", 0.0, -20.0, 20.0, "translation", "C"),
    _p(30, "eyeball Z offset", -15.0, -45.0, 15.0, "translation", "C"),
    _p(31, "chin X offset", 0.0, -50.0, 50.0, "translation", "D 3.15"),
    _p(32, "chin Z offset", 0.0, -50.0, 50.0, "translation", "D 3.15"),
    _p(35, "chin to mouth scaling", 1.0, 0.5, 2.0, "scaling", "C (D 3.15 .5-1.5)"),
    _p(36, "chin to eye scaling", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(37, "eye to forehead scaling", 1.0, 0.5, 2.0, "scaling", "C"),
    _p(38, "eyelid X offset", 0.0, -20.0, 20.0, "translation", "C"),
    _p(39, "eyelid Y offset", 0.0, -20.0, 20.0, "translation", "C"),
    _p(40, "eyelid Z offset", 0.0, -20.0, 20.0, "translation", "C"),
    _p(41, "pupil fraction", 0.4, 0.0, 1.0, "eye", "T"),
    _p(42, "fringe fraction", 0.85, 0.1, 1.0, "eye", "T"),
    _p(43, "iris fraction", 0.4, 0.0, 1.0, "eye", "T"),
    _p(44, "eyeball radius", 70.0, 35.0, 100.0, "eye", "C (D 3.9 eyeball size 50-100)"),
    _p(45, "eyelid radius", 80.0, 75.0, 100.0, "eye", "C"),
    _p(46, "growth factor", 0.0, -0.1, 0.1, "scaling", "C"),
    _p(47, "teeth X offset", 0.0, -10.0, 20.0, "translation", "C"),
    _p(48, "teeth Z offset", 38.0, 0.0, 70.0, "translation", "C"),
    _p(50, "smoothness", 1.0, 0.0, 1.0, "render", "T"),
)}


def start_values() -> dict[int, float]:
    return {n: p.start for n, p in PARAMETERS.items()}


def check_parameters(values: dict[int, float], *, clamp: bool = False) -> dict[int, float]:
    """Validate (or clamp) parameter values; returns the full set with start values filled in.

    Raises
    ------
    CassiInputError
        Unknown parameter number, non-finite value, or a value outside its range when
        ``clamp`` is False.
    """
    out = start_values()
    for number, value in values.items():
        try:
            n = int(number)
        except (TypeError, ValueError):
            raise CassiInputError(f"parameter number {number!r} is not an integer") from None
        if n not in PARAMETERS:
            raise CassiInputError(f"unknown Parke parameter {n}; known: "
                                  f"{', '.join(map(str, sorted(PARAMETERS)))}")
        p = PARAMETERS[n]
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise CassiInputError(f"parameter {n} ({p.name}): {value!r} is not a number") from None
        if not np.isfinite(v):
            raise CassiInputError(f"parameter {n} ({p.name}): {value!r} is not finite")
        if not p.low <= v <= p.high:
            if not clamp:
                raise CassiInputError(f"parameter {n} ({p.name}) = {v:g} is outside "
                                      f"{p.low:g}..{p.high:g}")
            v = min(max(v, p.low), p.high)
        out[n] = v
    return out


# --- applying ----------------------------------------------------------------------------------

def _rotate_xz(pts, pivot_xz, angle_rad, axes="xz"):
    """Parke's Equations 3.5-3.6: rotate (x, z) about the pivot by ``angle_rad``; positive
    opens the jaw (the chin moves down and back)."""
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    x = pts[:, 0] - pivot_xz[0]
    z = pts[:, 2] - pivot_xz[1]
    out = pts.copy()
    xr = x * c + z * s + pivot_xz[0]
    zr = z * c - x * s + pivot_xz[1]
    if "x" in axes:
        out[:, 0] = xr
    out[:, 2] = zr
    return out


def jaw_rotation(vertices: np.ndarray, degrees: float, *, zones=None,
                 pivot: int = N.JAW_PIVOT) -> np.ndarray:
    """Parke's jaw rotation (3.1.3): each zone of Table 3.2 rotated by its fraction of the angle
    about vertex 107 (x and z, or z only). float (V, 3) -> float (V, 3).

    A positive angle opens the mouth: Equations 3.5-3.6 with theta = -degrees, so that the chin
    (in front of and below the pivot) swings down.
    """
    v = np.asarray(vertices, np.float64).copy()
    zones = N.PARKE_JAW_ZONES if zones is None else zones
    pv = v[pivot - 1][[0, 2]]
    for _, frac, verts, axes in zones:
        idx = np.asarray(verts, np.int64) - 1
        v[idx] = _rotate_xz(v[idx], pv, -np.radians(degrees * frac), axes)
    return v


def _eyelid_numbers(face) -> np.ndarray:
    diff = np.any(np.abs(face.st2 - face.st1) > 1e-9, axis=1)
    return np.flatnonzero(diff)


def apply_parameters(face, values: dict[int, float], *, clamp: bool = False,
                     gaze_target=None):
    """The face with Parke's parameters applied (start values for the ones not given).

    Implemented here: 1 (eyelid interpolation st1 <-> st2), 4 (jaw rotation, Table 3.2 zones),
    5-6 (eyelid scales), 7-9 (head scales about the origin), 10-11 (nose scales), 12 (mouth
    width), 26-27 (nose tip offsets), 28-30 (eyeball offsets), 31-32 (chin offsets), 38-40
    (eyelid + eyeball offsets), 41-45 (eyeball construction), 47-48 (teeth offsets, relative to
    the start values).
    """
    from cassi.data import eyes as E
    from cassi.data.face_build import EYE_CENTRE

    vals = check_parameters(values, clamp=clamp)
    st1, st2 = face.st1, face.st2
    v = st1.copy()
    n_parke = min(len(v), N.EYES_FIRST - 1)

    # 1: eyelid opening, linear interpolation between closed (st2, 0) and open (st1, 1)
    o = vals[1]
    lid = _eyelid_numbers(face)
    v[lid] = st2[lid] + (st1[lid] - st2[lid]) * o
    # 5, 6: eyelid Y / Z scale about the eye centre (in the lid's 2D frame), 38-40 offsets
    centre = face.eye_centres[0] if len(face.eye_centres) else EYE_CENTRE
    if len(lid):
        off = v[lid] - centre
        off[:, 1] *= vals[5]
        off[:, 2] *= vals[6]
        # keep the lid on its sphere after scaling
        r0 = np.linalg.norm(v[lid] - centre, axis=1)
        r1 = np.linalg.norm(off, axis=1)
        off *= (r0 / np.maximum(r1, 1e-9))[:, None]
        v[lid] = centre + off + np.array([vals[38], vals[39], vals[40]])

    # 10, 11: nose scales (Y) about the centre line; 26, 27: nose tip offsets
    nose = np.asarray(N.NOSE) - 1
    tipz = v[N.NOSE_TIP_CENTRE - 1, 2]
    lower = nose[v[nose, 2] <= tipz + 40.0]
    upper = np.setdiff1d(nose, lower)
    v[lower, 1] *= vals[10]
    v[upper, 1] *= vals[11]
    tip = np.asarray(N.NOSE_TIP) - 1
    v[tip, 0] += vals[26]
    v[tip, 2] += vals[27]

    # 12: mouth width
    mouth = np.asarray(N.UPPER_LIP + N.LOWER_LIP + (N.CORNER, N.INNER_CORNER,
                                                    N.CORNER_MIDDLE)) - 1
    v[mouth, 1] *= vals[12]

    # 31, 32: chin offsets (the 1st jaw zone)
    chin = np.asarray(N.JAW) - 1
    v[chin, 0] += vals[31]
    v[chin, 2] += vals[32]

    # 47, 48: teeth offsets relative to the start values (48 starts at 38)
    teeth = np.asarray(N.TEETH) - 1
    v[teeth, 0] += vals[47] - PARAMETERS[47].start
    v[teeth, 2] += vals[48] - PARAMETERS[48].start

    # 4: jaw rotation with Parke's zones
    if vals[4] != 0.0 and n_parke >= N.PARKE_VERTEX_COUNT:
        v = jaw_rotation(v, vals[4])

    # eyes: 28-30 and 38-40 move the eyeballs; 41-44 rebuild them
    centres = np.asarray(face.eye_centres, np.float64).copy()
    if face.eyes_first is not None and len(centres) == 2:
        shift = np.array([vals[28] + vals[38], vals[29] + vals[39],
                          vals[30] - PARAMETERS[30].start + vals[40]])
        params = E.EyeParams(pupil_fraction=vals[41], fringe_fraction=vals[42],
                             iris_fraction=vals[43], radius=vals[44])
        from cassi.data.face import default_gaze_target
        target = default_gaze_target() if gaze_target is None else np.asarray(gaze_target)
        for k in range(2):
            c = centres[k] + shift * np.array([1.0, 1.0 if k == 0 else -1.0, 1.0])
            first = face.eyes_first + k * E.VERTS_PER_EYE
            v[first - 1:first - 1 + E.VERTS_PER_EYE] = E.place_eye(c, target, params)

    # 7-9: head scales about the origin (last, so they scale everything)
    v *= np.array([vals[7], vals[8], vals[9]])
    return replace(face, vertices=v, parameters=vals)


def look_at(face, target):
    """The face with both eyes turned to ``target`` (Parke units, face coordinates)."""
    return apply_parameters(face, {k: val for k, val in face.parameters.items()
                                   if val != PARAMETERS[k].start}, gaze_target=target)
