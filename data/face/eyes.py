"""Parke's eyes (dissertation 3.1.1-3.1.2 and Appendix A).

Each eyeball is built about its own origin with the X axis through the centre of the pupil: a
12-sided pupil, a ring of 12 iris quadrilaterals, a ring for the iris fringe and rings of white
closing the ball behind (Parke's hemisphere, closed so that it renders from any view), plus a
6-sided reflection spot tangent to the lens sphere. The eyeball is then rotated by the
orientation angles alpha (about Z) and beta (about Y) that make it look at a target point, and
moved to its place in the face (Appendix A's [T_orient][T_face]).

Eyelids (:func:`eyelid_positions`) are interpolated in two dimensions between the closed (st2)
and open (st1) extremes and projected onto a sphere slightly larger than the eyeball
(dissertation 3.1.2).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.data.face.build import (EYE_CENTRE, EYE_WHITE, FRINGE, IRIS, LID_LIP_GAP, PUPIL,
                                   REFLECTION, eyelid_ring_2d, project_to_sphere)

#: Sides of the pupil polygon and of every ring (dissertation 3.1.1).
SIDES = 12
SPOT_SIDES = 6
#: Polar angles (degrees from the pupil axis) of the white rings behind the iris.
WHITE_RINGS_DEG = (55.0, 80.0, 105.0, 135.0, 160.0)
#: Vertices per eyeball: pupil centre, pupil edge, fringe-inner, iris edge, white rings, back
#: pole, reflection spot (centre + 6).
VERTS_PER_EYE = 1 + SIDES * (3 + len(WHITE_RINGS_DEG)) + 1 + 1 + SPOT_SIDES


@dataclass(frozen=True)
class EyeParams:
    """Parke's eye parameters (thesis Table 3.1): 41 pupil fraction, 42 fringe fraction,
    43 iris fraction, 44 eyeball radius (Parke units), plus the reflection spot size (a fraction
    of the iris radius, dissertation Figure 3.9)."""

    pupil_fraction: float = 0.4
    fringe_fraction: float = 0.85
    iris_fraction: float = 0.4
    radius: float = 70.0
    spot_fraction: float = 0.18


def orientation_angles(eye_centre, target) -> tuple[float, float]:
    """Appendix A's alpha and beta (radians) that turn an eye at ``eye_centre`` to ``target``.

    alpha = arctan((Y_T - Y_E) / (X_T - X_E)); beta = arctan((Z_E - Z_T) / L) with L the
    horizontal distance; angles positive counter-clockwise (beta > 0 looks down).
    """
    e = np.asarray(eye_centre, float)
    t = np.asarray(target, float)
    dx, dy = t[0] - e[0], t[1] - e[1]
    alpha = float(np.arctan2(dy, dx))
    L = float(np.hypot(dx, dy))
    beta = float(np.arctan2(e[2] - t[2], L))
    return alpha, beta


def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_y(b):
    # positive beta turns the +X axis downwards (-Z): looking down
    c, s = np.cos(b), np.sin(b)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def orientation_matrix(alpha: float, beta: float) -> np.ndarray:
    """Rotation (3, 3) taking the eyeball's +X (pupil axis) to the gaze direction: first beta
    about Y (pitch), then alpha about Z (yaw), both about the eyeball's centre."""
    return _rot_z(alpha) @ _rot_y(beta)


def eyeball_local(params: EyeParams = EyeParams(), *, light=None, viewer=None,
                  alpha: float = 0.0, beta: float = 0.0) -> np.ndarray:
    """Eyeball vertices about its own centre, pupil along +X. float (VERTS_PER_EYE, 3).

    The reflection spot sits on the lens sphere where the half-way direction between the light
    and the viewer points (Appendix A: gamma/delta averaged, theta = gamma - alpha,
    phi = delta - beta); ``light``/``viewer`` are directions in face coordinates (default: both
    straight ahead, +X, slightly above).
    """
    p = params
    Re = float(p.radius)
    Ri = p.iris_fraction                # iris radius as a fraction of the eyeball radius
    ang_i = np.arcsin(min(Ri, 0.999))
    ang_f = np.arcsin(min(Ri * p.fringe_fraction, 0.999))
    ang_p = np.arcsin(min(Ri * p.pupil_fraction, 0.999))
    phis = np.radians(np.arange(SIDES) * 360.0 / SIDES)

    def ring(polar):
        return np.stack([np.full(SIDES, np.cos(polar)), np.sin(polar) * np.cos(phis),
                         np.sin(polar) * np.sin(phis)], axis=1) * Re

    verts = [np.array([[Re, 0.0, 0.0]])]
    for polar in (ang_p, ang_f, ang_i):
        verts.append(ring(polar))
    for deg in WHITE_RINGS_DEG:
        verts.append(ring(np.radians(deg)))
    verts.append(np.array([[-Re, 0.0, 0.0]]))
    # lens (Appendix A): centre L_C along X, L_C = (sqrt(1 - Ri^2) - Ri) Re; its sphere reaches
    # a little beyond the eyeball at the pupil (the cornea's bulge).
    Lc = (np.sqrt(1.0 - Ri ** 2) - Ri) * Re
    RL = Re - Lc + 0.04 * Re
    light = np.array([1.0, 0.25, 0.45]) if light is None else np.asarray(light, float)
    viewer = np.array([1.0, 0.0, 0.0]) if viewer is None else np.asarray(viewer, float)
    g = 0.5 * (np.arctan2(light[1], light[0]) + np.arctan2(viewer[1], viewer[0]))
    d = 0.5 * (np.arctan2(light[2], np.hypot(light[0], light[1]))
               + np.arctan2(viewer[2], np.hypot(viewer[0], viewer[1])))
    theta = g - alpha
    phi = d - beta
    # keep the spot on the lens (over the iris): clamp the angles to the iris cap
    lim = 0.8 * ang_i
    theta = float(np.clip(theta, -lim, lim))
    phi = float(np.clip(phi, -lim, lim))
    n = np.array([np.cos(phi) * np.cos(theta), np.cos(phi) * np.sin(theta), np.sin(phi)])
    centre = np.array([Lc, 0.0, 0.0]) + n * (RL + 0.01 * Re)
    # hexagon tangent to the lens at that point
    u = np.cross(n, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    rs = p.spot_fraction * Ri * Re
    a6 = np.radians(np.arange(SPOT_SIDES) * 360.0 / SPOT_SIDES)
    spot = centre + rs * (np.cos(a6)[:, None] * u + np.sin(a6)[:, None] * v)
    verts.append(centre[None])
    verts.append(spot)
    out = np.concatenate(verts, axis=0)
    assert out.shape[0] == VERTS_PER_EYE
    return out


def eyeball_polygons(first: int) -> list[tuple[int, tuple[int, ...]]]:
    """(material, 1-based vertex numbers) of one eyeball whose vertices start at ``first``,
    ordered clockwise seen from outside (Parke's order, like the face)."""
    polys = []
    centre = first
    rings = [first + 1 + SIDES * k for k in range(3 + len(WHITE_RINGS_DEG))]
    back = first + 1 + SIDES * len(rings)
    for j in range(SIDES):
        j2 = (j + 1) % SIDES
        polys.append((PUPIL, (centre, rings[0] + j2, rings[0] + j)))
    mats = [IRIS, FRINGE] + [EYE_WHITE] * (len(rings) - 2)
    for k in range(len(rings) - 1):
        for j in range(SIDES):
            j2 = (j + 1) % SIDES
            polys.append((mats[k], (rings[k] + j, rings[k] + j2, rings[k + 1] + j2,
                                    rings[k + 1] + j)))
    for j in range(SIDES):
        j2 = (j + 1) % SIDES
        polys.append((EYE_WHITE, (rings[-1] + j, rings[-1] + j2, back)))
    sc = back + 1
    for j in range(SPOT_SIDES):
        j2 = (j + 1) % SPOT_SIDES
        polys.append((REFLECTION, (sc, sc + 1 + j2, sc + 1 + j)))
    return polys


def place_eye(centre, target, params: EyeParams = EyeParams(), *, light=None,
              viewer=None) -> np.ndarray:
    """Eyeball vertices (VERTS_PER_EYE, 3) at ``centre`` looking at ``target`` (face coords)."""
    alpha, beta = orientation_angles(centre, target)
    local = eyeball_local(params, light=light, viewer=viewer, alpha=alpha, beta=beta)
    R = orientation_matrix(alpha, beta)
    return np.asarray(centre, float) + local @ R.T


def gaze_direction(eye_vertices: np.ndarray) -> np.ndarray:
    """Unit vector from an eyeball's centre through its pupil centre (first vertex)."""
    v = np.asarray(eye_vertices, float)
    ring_front = v[0]
    back = v[1 + SIDES * (3 + len(WHITE_RINGS_DEG))]
    d = ring_front - back
    return d / np.linalg.norm(d)


def eyelid_positions(opening: float, centre, *, lid_radius: float = 80.0,
                     eyeball_radius: float = 70.0, y_scale: float = 1.0,
                     z_scale: float = 1.0) -> dict[str, np.ndarray]:
    """Eyelid rings (A lid, B margin, C lid lip) for an opening in [0, 1] (parameter 1),
    interpolated in 2D and projected onto spheres about the eyeball (dissertation 3.1.2).

    Returns a dict ring -> float (8, 3) in face coordinates (left eye).
    """
    o = float(np.clip(opening, 0.0, 1.0))
    radii = {"A": lid_radius + 6.0, "B": lid_radius, "C": eyeball_radius + LID_LIP_GAP}
    return {r: project_to_sphere(eyelid_ring_2d(o, r, y_scale=y_scale, z_scale=z_scale),
                                 centre, rad) for r, rad in radii.items()}


def default_gaze_target() -> np.ndarray:
    """Where the neutral face looks: straight ahead, about 1.5 m away at eye height."""
    return np.array([EYE_CENTRE[0] + 6000.0, 0.0, EYE_CENTRE[2]])
