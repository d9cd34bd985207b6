"""The implicit head behind the generated face: cranium, face and neck blended, a designed
midsagittal profile fading off to the sides, and local relief (eye sockets, brows, cheekbones).

The head is star-shaped about :data:`CENTRE`: every skin point is ``CENTRE + r * direction``
for an azimuth (0 forward, 90 to the face's left) and an elevation (90 up), in degrees. Parke
units, X forward, Y to the face's left, Z up.
"""
from __future__ import annotations

import numpy as np

#: Rays of the star-shaped head start here (inside every primitive).
CENTRE = np.array([0.0, 0.0, -60.0])

#: The midsagittal profile (x, z) from the base of the neck to the crown, Parke units.
PROFILE = np.array([
    (45, -594), (100, -450), (138, -425), (210, -415), (290, -420), (326, -423), (352, -408),
    (366, -385), (372, -358), (366, -336), (350, -318), (352, -302), (370, -291), (388, -280),
    (380, -262), (372, -250), (382, -238), (394, -222), (386, -205), (376, -190), (366, -172),
    (384, -160), (425, -150), (446, -136), (442, -115), (424, -88), (402, -45), (378, -5),
    (356, 33), (362, 62), (374, 92), (371, 140), (362, 200), (343, 262), (312, 330),
    (262, 392), (195, 442), (115, 480), (30, 498), (-60, 495),
], dtype=np.float64)

#: Eye: eyeball centre (left eye), Parke units. Cornea apex = centre + radius along +x.
EYE_CENTRE = np.array([250.0, 124.0, 22.0])


# ---------------------------------------------------------------------------------------------
# the implicit head
# ---------------------------------------------------------------------------------------------

def _ellipsoid_sdf(p, centre, semi):
    q = (p - centre) / semi
    return (np.linalg.norm(q, axis=-1) - 1.0) * np.min(semi)


def _neck_sdf(p):
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    xc = -100.0 + 0.16 * (z + 594.0)
    rx = 150.0 + 0.04 * (z + 594.0)
    ry = 190.0 - 0.03 * (z + 594.0)
    f = (np.sqrt(((x - xc) / rx) ** 2 + (y / ry) ** 2) - 1.0) * np.minimum(rx, ry)
    return np.maximum(f, z + 120.0)


def _smin(a, b, k):
    """Smooth minimum (a soft union of two implicit solids), blend radius ~k units."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def head_sdf(p: np.ndarray) -> np.ndarray:
    """Approximate signed distance (Parke units, < 0 inside) of the base head: cranium, face
    and neck blended (no profile, no relief)."""
    cranium = _ellipsoid_sdf(p, np.array([-10.0, 0.0, 118.0]), np.array([372.0, 282.0, 382.0]))
    face = _ellipsoid_sdf(p, np.array([135.0, 0.0, -175.0]), np.array([232.0, 180.0, 250.0]))
    jaw = _ellipsoid_sdf(p, np.array([60.0, 0.0, -300.0]), np.array([240.0, 158.0, 130.0]))
    f = _smin(cranium, face, 80.0)
    f = _smin(f, jaw, 60.0)
    return _smin(f, _neck_sdf(p), 70.0)


def _directions(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack([np.cos(p) * np.cos(t), np.cos(p) * np.sin(t), np.sin(p)], axis=-1)


def _base_radius_exact(theta_deg, phi_deg) -> np.ndarray:
    d = _directions(np.asarray(theta_deg, float), np.asarray(phi_deg, float))
    lo = np.zeros(d.shape[:-1])
    hi = np.full(d.shape[:-1], 1500.0)
    for _ in range(34):  # bisection: the base head is star-shaped about CENTRE
        mid = 0.5 * (lo + hi)
        inside = head_sdf(CENTRE + d * mid[..., None]) < 0
        lo = np.where(inside, mid, lo)
        hi = np.where(inside, hi, mid)
    return 0.5 * (lo + hi)


_GRID_STEP = 0.5
_GRID: list = []


def _radius_grid():
    """The base head's radius tabulated every 0.5 degree (computed once per process)."""
    if not _GRID:
        th = np.arange(-10.0, 190.0 + 1e-9, _GRID_STEP)
        ph = np.arange(-90.0, 90.0 + 1e-9, _GRID_STEP)
        T, P = np.meshgrid(th, ph, indexing="ij")
        _GRID.append((th, ph, _base_radius_exact(T, P)))
    return _GRID[0]


def base_radius(theta_deg, phi_deg) -> np.ndarray:
    """Distance from :data:`CENTRE` to the base head along (azimuth, elevation), degrees
    (bilinear in a 0.5-degree table of the exact bisection)."""
    th, ph, R = _radius_grid()
    t = np.clip(np.asarray(theta_deg, float), th[0], th[-1])
    p = np.clip(np.asarray(phi_deg, float), ph[0], ph[-1])
    ft = (t - th[0]) / _GRID_STEP
    fp = (p - ph[0]) / _GRID_STEP
    i = np.clip(np.floor(ft).astype(int), 0, len(th) - 2)
    j = np.clip(np.floor(fp).astype(int), 0, len(ph) - 2)
    a, b = ft - i, fp - j
    return ((1 - a) * (1 - b) * R[i, j] + a * (1 - b) * R[i + 1, j]
            + (1 - a) * b * R[i, j + 1] + a * b * R[i + 1, j + 1])


def _profile_radius(phi_deg):
    """Distance from CENTRE to the designed profile along elevation phi (azimuth 0)."""
    px = PROFILE[:, 0] - CENTRE[0]
    pz = PROFILE[:, 1] - CENTRE[2]
    ang = np.degrees(np.arctan2(pz, px))
    rad = np.hypot(px, pz)
    # the profile is star-shaped about CENTRE: its angles increase monotonically
    return np.interp(phi_deg, ang, rad)


def _profile_width(phi_deg):
    """Angular half-width (degrees) over which the profile's relief fades to the base head."""
    table = np.array([  # elevation, width
        (-90, 60), (-62, 45), (-48, 26), (-38, 20), (-30, 17), (-22, 16), (-17, 11),
        (-12, 8.0), (-5, 7.0), (5, 6.5), (13, 8), (20, 22), (30, 40), (90, 60)])
    return np.interp(phi_deg, table[:, 0], table[:, 1])


def _bump(theta, phi, t0, p0, st, sp, amp):
    return amp * np.exp(-(((theta - t0) / st) ** 2 + ((phi - p0) / sp) ** 2))


def surface_radius(theta_deg, phi_deg) -> np.ndarray:
    """Distance from :data:`CENTRE` to the face's skin along (azimuth, elevation), degrees.

    Azimuth 0 is forward (+x), 90 is the face's left (+y); elevation 90 is up.
    """
    th = np.asarray(theta_deg, float)
    ph = np.asarray(phi_deg, float)
    base = base_radius(th, ph)
    front = base_radius(np.zeros_like(ph), ph)
    delta = _profile_radius(ph) - front
    w = np.exp(-(th / _profile_width(ph)) ** 2)
    r = base + delta * w
    # relief: eye socket, brow ridge, cheekbone, temple, side of the nose
    et, ep = _eye_angles()
    r += _bump(th, ph, et, ep, 9.0, 6.5, -32.0)
    r += _bump(th, ph, et + 2.0, ep + 10.0, 11.0, 3.5, 12.0)
    r += _bump(th, ph, et + 14.0, ep - 14.0, 10.0, 6.0, 14.0)
    r += _bump(th, ph, 62.0, ep + 14.0, 10.0, 10.0, -10.0)
    r += _bump(th, ph, 28.0, -18.0, 9.0, 7.0, -6.0)
    return r


def _eye_angles():
    d = EYE_CENTRE + np.array([70.0, 0.0, 0.0]) - CENTRE
    return (float(np.degrees(np.arctan2(d[1], d[0]))),
            float(np.degrees(np.arctan2(d[2], np.hypot(d[0], d[1])))))


def surface_point(theta_deg, phi_deg) -> np.ndarray:
    """Points (..., 3) on the skin at (azimuth, elevation) in degrees."""
    th = np.asarray(theta_deg, float)
    ph = np.asarray(phi_deg, float)
    return CENTRE + _directions(th, ph) * surface_radius(th, ph)[..., None]


def angles_of(p) -> tuple[float, float]:
    """(azimuth, elevation) in degrees of point ``p`` seen from :data:`CENTRE`."""
    d = np.asarray(p, float) - CENTRE
    return (float(np.degrees(np.arctan2(d[1], d[0]))),
            float(np.degrees(np.arctan2(d[2], np.hypot(d[0], d[1])))))


def surface_at_z(theta_deg, z) -> np.ndarray:
    """Skin points (..., 3) at azimuths ``theta_deg`` whose heights are ``z`` (bisection on
    the elevation, vectorised)."""
    th = np.asarray(theta_deg, float)
    zz = np.asarray(z, float)
    th, zz = np.broadcast_arrays(th, zz)
    lo = np.full(th.shape, -89.0)
    hi = np.full(th.shape, 89.0)
    for _ in range(36):
        mid = 0.5 * (lo + hi)
        below = surface_point(th, mid)[..., 2] < zz
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return surface_point(th, 0.5 * (lo + hi))
