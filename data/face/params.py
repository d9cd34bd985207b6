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

from cassi.data.face import eyes as E
from cassi.data.face import numbering as N
from cassi.data.face.build import EYE_CENTRE
from cassi.common.errors import CassiInputError


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


#: Each parameter's start value (its effect is often relative to it).
_START = start_values()


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

    A positive angle opens the mouth: with Equations 3.5-3.6 as written, a positive theta turns
    a point in front of the pivot (x > x_107) downwards, so the chin swings down and back.
    """
    v = np.asarray(vertices, np.float64).copy()
    zones = N.PARKE_JAW_ZONES if zones is None else zones
    pv = v[pivot - 1][[0, 2]]
    for _, frac, verts, axes in zones:
        idx = np.asarray(verts, np.int64) - 1
        v[idx] = _rotate_xz(v[idx], pv, np.radians(degrees * frac), axes)
    return v


def _region(face, name) -> np.ndarray:
    return np.asarray(face.regions.get(name, ()), np.int64) - 1


def _interpolate(v, face, idx, value):
    """Parke's interpolation: st2 at 0, st1 at 1 (dissertation chapter 2)."""
    if len(idx):
        v[idx] = face.st2[idx] + (face.st1[idx] - face.st2[idx]) * value


def apply_parameters(face, values: dict[int, float], *, clamp: bool = False,
                     gaze_target=None, light=None, viewer=None):
    """The face with Parke's parameters applied (start values for the ones not given).

    Every parameter of Table 3.1 acts (50, smoothness, is recorded for the renderer):

    * interpolation between st2 (0) and st1 (1): 1 eyelids, 2 brow arch, 13 mouth expression;
    * scaling: 5-6 eyelid width/height (re-projected onto the lid sphere), 7-9 the head about
      the origin, 10-11 the nose's tip and bridge widths, 12 the mouth width, 19 the jaw width
      (tapered from the chin to zero at the back of the jaw, dissertation 3.4.2), 20 the cheeks,
      35 chin-to-mouth, 36 chin-to-eye, 37 eye-to-forehead heights, 46 growth (cheeks, jaw);
    * translation: 3 brow separation, 14 lips forward, 15 the inner corner 287 in y, 16-18 the
      mouth corners, 21 the lower lip's f tuck, 22 upper lip raise (tapered to the corner,
      relative to its start 15), 26-27 nose tip, 28-30 eyeballs (30 relative to its start -15),
      31-32 chin, 38-40 eyelids with the eyeballs, 47-48 teeth (48 relative to its start 38);
    * rotation: 4 jaw rotation about vertex 107 with Table 3.2's zones;
    * eyes: 41-44 rebuild the eyeballs (pupil, fringe, iris fractions, radius), 45 the lid
      sphere's radius; the eyes look at ``gaze_target`` (Appendix A), with the reflection spot
      placed for the ``light`` and ``viewer`` directions (face coordinates; default a light
      above-left of a viewer straight ahead).

    Regions that a model lacks (Parke's own files carry no region names) are left alone.
    """
    vals = check_parameters(values, clamp=clamp)
    v = face.st1.copy()
    n_parke = min(len(v), N.EYES_FIRST - 1)
    centre = face.eye_centres[0] if len(face.eye_centres) else EYE_CENTRE
    lids = (_region(face, "eyelid"), _region(face, "eyelid_lip"))
    brow = _region(face, "brow")
    _interpolate(v, face, brow, vals[2])
    _interpolate(v, face, _region(face, "mouth_expression"), vals[13])
    _eyelids_and_brow(v, face, vals, centre, lids, brow)
    _nose(v, vals)
    _mouth(v, vals)
    _chin_jaw_cheeks(v, face, vals)
    # 47-48: the teeth (relative to their start values)
    teeth = _rows(v, N.TEETH)
    v[teeth, 0] += vals[47] - _START[47]
    v[teeth, 2] += vals[48] - _START[48]
    _vertical_proportions(v, vals, n_parke, centre, lids)
    # 4: jaw rotation with Parke's zones (last of the face's own deformations)
    if vals[4] != 0.0 and n_parke >= N.PARKE_VERTEX_COUNT:
        v = jaw_rotation(v, vals[4])
    _eyeballs(v, face, vals, centre[2], gaze_target, light, viewer)
    # 7-9: head scales about the origin (last, so they scale everything)
    v *= np.array([vals[7], vals[8], vals[9]])
    return replace(face, vertices=v, parameters=vals)


def _rows(v: np.ndarray, numbers) -> np.ndarray:
    """0-based rows of vertex numbers this model has (Parke's own files stop at 287)."""
    a = np.asarray(numbers, np.int64).reshape(-1) - 1
    return a[a < len(v)]


def _changed(vals: dict[int, float], *numbers: int) -> bool:
    """Whether any of these parameters is off its start value."""
    return any(vals[k] != _START[k] for k in numbers)


def _eyelids_and_brow(v, face, vals, centre, lids, brow) -> None:
    """1, 5-6, 38-40, 44-45: the eyelids on their spheres; 3: the brow's separation."""
    # Eyelids (dissertation 3.1.2): the lid vertices' two dimensions (width y, height z about
    # the eyeball's centre) are interpolated between closed (st2) and open (st1), scaled by
    # parameters 5 and 6, and projected back onto the sphere that carries each ring: the lid
    # sphere (radius parameter 45) for the lid and its margin, the eyeball (parameter 44) for
    # the lid's inner lip. Parameters 38-40 move the lids with the eyeballs.
    for idx, radius_param in zip(lids, (45, 44)):
        if not len(idx):
            continue
        rel1 = face.st1[idx] - centre
        rel2 = face.st2[idx] - centre
        radius = np.linalg.norm(rel1, axis=1) * vals[radius_param] / _START[radius_param]
        yz = rel2[:, 1:] + (rel1[:, 1:] - rel2[:, 1:]) * vals[1]
        yz = yz * np.array([vals[5], vals[6]])
        rr = np.linalg.norm(yz, axis=1)
        lim = 0.98 * radius
        yz *= np.where(rr > lim, lim / np.maximum(rr, 1e-9), 1.0)[:, None]
        x = np.sqrt(np.maximum(radius ** 2 - np.sum(yz ** 2, axis=1), 0.0))
        v[idx] = centre + np.column_stack([x, yz]) + np.array([vals[38], vals[39], vals[40]])
    if len(brow):
        # 3: brow separation moves the inner end (tapered to the outer end) away from the nose
        w = np.linspace(1.0, 0.0, len(brow))
        v[brow, 1] += vals[3] * w


def _nose(v, vals) -> None:
    """10-11: the nose's tip and bridge widths; 26-27: the nose tip's offsets."""
    if _changed(vals, 10, 11):
        nose = _rows(v, N.NOSE)
        tipz = v[N.NOSE_TIP_CENTRE - 1, 2]
        lower = nose[v[nose, 2] <= tipz + 40.0]
        upper = np.setdiff1d(nose, lower)
        v[lower, 1] *= vals[10]
        v[upper, 1] *= vals[11]
    tip = _rows(v, N.NOSE_TIP)
    v[tip, 0] += vals[26]
    v[tip, 2] += vals[27]


def _mouth(v, vals) -> None:
    """12, 14-18: the mouth's width, lips forward, corners; 21 f tuck; 22 upper lip raise."""
    corners = _rows(v, (N.CORNER, N.CORNER_MIDDLE, N.INNER_CORNER))
    lips = _rows(v, N.UPPER_LIP + N.LOWER_LIP)
    mouth = np.concatenate([lips, corners])
    v[mouth, 1] *= vals[12]
    v[mouth, 0] += vals[14]
    v[N.INNER_CORNER - 1, 1] += vals[15]
    v[corners] += np.array([vals[16], vals[17], vals[18]])
    # 21: f tuck moves the lower lip down and forward (+) or up and back (-), tapered to the
    # corner like Parke's jaw zones (centre 1, then 0.9, 0.75)
    taper = {0: 1.0, 1: 0.9, 2: 0.75}
    for row in N.LOWER_LIP_ROWS:
        for j, n in enumerate(row):
            v[n - 1, 0] += 0.5 * vals[21] * taper[j]
            v[n - 1, 2] -= vals[21] * taper[j]
    # 22: raise the upper lip; full effect at the centre, none at the corner (dissertation 3.3)
    for row in N.UPPER_LIP_ROWS:
        for j, n in enumerate(row):
            v[n - 1, 2] += (vals[22] - _START[22]) * (1.0 - j / 3.0)


def _chin_jaw_cheeks(v, face, vals) -> None:
    """31-32: the chin's offsets; 19: the jaw's width; 20: the cheeks'; 46: growth."""
    jaw = _rows(v, N.JAW)
    v[jaw, 0] += vals[31]
    v[jaw, 2] += vals[32]
    if _changed(vals, 19):
        x_back, x_front = np.nanmin(v[jaw, 0]), np.nanmax(v[jaw, 0])
        w = (v[jaw, 0] - x_back) / max(x_front - x_back, 1e-9)
        v[jaw, 1] *= 1.0 + (vals[19] - 1.0) * w
    cheek = np.union1d(_region(face, "cheek"), _rows(v, N.LOWER_CHEEK))
    if _changed(vals, 20):
        y_c = v[N.CORNER - 1, 1]
        v[cheek, 1] = y_c + (v[cheek, 1] - y_c) * vals[20]
    if _changed(vals, 46):
        grow = np.union1d(cheek, jaw)
        v[grow, 1] *= 1.0 + vals[46]
        v[grow, 0] += vals[46] * 0.25 * np.abs(v[grow, 1])


def _vertical_proportions(v, vals, n_parke, centre, lids) -> None:
    """35-37: the face's heights scaled about the mouth and the eyes."""
    face_only = np.arange(n_parke)
    z_mouth = v[N.TEETH_TIP - 1, 2]
    z_eye = centre[2]
    if _changed(vals, 35):
        below_m = face_only[v[face_only, 2] < z_mouth]
        v[below_m, 2] = z_mouth + (v[below_m, 2] - z_mouth) * vals[35]
    if _changed(vals, 36):
        below_e = face_only[v[face_only, 2] < z_eye]
        v[below_e, 2] = z_eye + (v[below_e, 2] - z_eye) * vals[36]
    if _changed(vals, 37):
        above_e = face_only[v[face_only, 2] > z_eye]
        above_e = np.setdiff1d(above_e, np.concatenate(lids))
        v[above_e, 2] = z_eye + (v[above_e, 2] - z_eye) * vals[37]


def _eyeballs(v, face, vals, z_eye, gaze_target, light, viewer) -> None:
    """28-30, 38-40: the eyeballs' place; 41-44 rebuild them looking at ``gaze_target``."""
    centres = np.asarray(face.eye_centres, np.float64).copy()
    if face.eyes_first is None or len(centres) != 2:
        return
    shift = np.array([vals[28] + vals[38], vals[29] + vals[39],
                      vals[30] - _START[30] + vals[40]])
    params = E.EyeParams(pupil_fraction=vals[41], fringe_fraction=vals[42],
                         iris_fraction=vals[43], radius=vals[44])
    target = E.default_gaze_target() if gaze_target is None else np.asarray(gaze_target, float)
    for k in range(2):
        c = centres[k] + shift * np.array([1.0, 1.0 if k == 0 else -1.0, 1.0])
        c[2] = z_eye + (c[2] - z_eye) * 1.0
        first = face.eyes_first + k * E.VERTS_PER_EYE
        v[first - 1:first - 1 + E.VERTS_PER_EYE] = E.place_eye(c, target, params,
                                                                light=light, viewer=viewer)


def look_at(face, target, *, light=None, viewer=None):
    """The face with both eyes turned to ``target`` (Parke units, face coordinates); the other
    parameters keep the values the face was built with."""
    return apply_parameters(face, {k: val for k, val in face.parameters.items()
                                   if val != PARAMETERS[k].start}, gaze_target=target,
                            light=light, viewer=viewer)
