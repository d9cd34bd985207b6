"""The shape of CASSI 3.0's tongue: a centre line through the tip, T1-T4 and back points, and a
thick, curved cross-section at each station along it. Pure functions, frames leading.

Coordinates are Parke's (x forward, y to the left, z up), left half; a station's section is
drawn in the plane spanned by y and the dorsum's normal in the x-z plane.
"""
from __future__ import annotations

import numpy as np

from cassi30 import constants as K

__all__ = ["STATIONS", "PELLET_STATIONS", "BACK_STATION", "centre_stations", "back_points",
           "normals", "sections", "station_thickness_mm", "arch_half_width"]

#: Stations along the centre line: tip, T1, T1-T2, T2, T2-T3, T3, T3-T4, T4, then the back
#: points (the ones between pellets put the curve through the sites, not a polyline).
STATIONS = 8 + K.BACK_POINTS
#: The stations of T1-T4 (their section's top centre is the pellet site).
PELLET_STATIONS = (1, 3, 5, 7)
#: The first back point: CASSI 1.0's back vertex (293) is its top centre.
BACK_STATION = 8


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)


def back_points(t3: np.ndarray, t4: np.ndarray, wall_dir: np.ndarray, step: float) -> np.ndarray:
    """Back points behind T4: each step turns from T3 -> T4 toward the pharyngeal wall.

    Parameters
    ----------
    t3, t4 : float (F, 2)
        T3 and T4, Parke (x, z).
    wall_dir : float (2,)
        Unit direction of the pharyngeal wall, top to bottom (PHA.DAT).
    step : float
        Arc length between back points, Parke units.

    Returns
    -------
    float (F, BACK_POINTS, 2)
    """
    u = _unit(np.asarray(t4, np.float64) - np.asarray(t3, np.float64))
    out = np.empty((u.shape[0], K.BACK_POINTS, 2))
    p = np.asarray(t4, np.float64)
    for k, a in enumerate(K.BACK_TURN):
        p = p + step * _unit((1.0 - a) * u + a * np.asarray(wall_dir, np.float64))
        out[:, k] = p
    return out


def centre_stations(tip: np.ndarray, pellets: np.ndarray, back: np.ndarray) -> np.ndarray:
    """The centre line's stations: float (F, STATIONS, 2) Parke (x, z).

    ``tip`` (F, 2), ``pellets`` (F, 4, 2) T1-T4, ``back`` (F, BACK_POINTS, 2). Between two
    pellets the station is the Catmull-Rom midpoint of the curve through its neighbours.
    """
    knots = np.concatenate([tip[:, None], pellets, back], axis=1)         # tip, T1..T4, B..
    out = np.empty((knots.shape[0], STATIONS, 2))
    out[:, 0:2] = knots[:, 0:2]
    for j in range(3):                                                     # T1-T2 .. T3-T4
        p0, p1, p2, p3 = (knots[:, j + i] for i in range(4))
        out[:, 2 + 2 * j] = (9.0 * (p1 + p2) - p0 - p3) / 16.0
        out[:, 3 + 2 * j] = p2
    out[:, 8:] = back
    return out


def normals(stations: np.ndarray) -> np.ndarray:
    """Unit normals of the dorsum at each station, float (F, S, 2) (x, z): the tangent (tip
    toward back, central differences) turned so that a backward tangent gives straight up."""
    t = np.empty_like(stations)
    t[:, 1:-1] = stations[:, 2:] - stations[:, :-2]
    t[:, 0] = stations[:, 1] - stations[:, 0]
    t[:, -1] = stations[:, -1] - stations[:, -2]
    t = _unit(t)
    return np.stack([t[..., 1], -t[..., 0]], axis=-1)


def station_thickness_mm() -> np.ndarray:
    """Thickness per station, mm (STATIONS,): the blade, T1, the body, the root thinning."""
    back = K.THICKNESS_BODY_MM + (K.THICKNESS_ROOT_END_MM - K.THICKNESS_BODY_MM) * (
        np.arange(1, K.BACK_POINTS + 1) / K.BACK_POINTS)
    return np.concatenate([[K.THICKNESS_TIP_MM, K.THICKNESS_T1_MM,
                            0.5 * (K.THICKNESS_T1_MM + K.THICKNESS_BODY_MM)],
                           np.full(5, K.THICKNESS_BODY_MM), back])


def arch_half_width(arch_x: np.ndarray, arch_y: np.ndarray, x: np.ndarray, *, scale: float
                    ) -> np.ndarray:
    """Half-width of the tongue at ``x`` (any shape): the lower arch's half-width there less
    ARCH_MARGIN_MM, within HALF_WIDTH_MIN/MAX_MM (Parke units; ``arch_x`` ascending)."""
    w = np.interp(x, arch_x, arch_y, left=arch_y[0], right=0.0) - K.ARCH_MARGIN_MM * scale
    return np.clip(w, K.HALF_WIDTH_MIN_MM * scale, K.HALF_WIDTH_MAX_MM * scale)


def sections(stations: np.ndarray, normal: np.ndarray, half_width: np.ndarray,
             thickness: np.ndarray) -> np.ndarray:
    """The tongue's vertices: float (F, S, C, 3), C = len(SECTION_PHI).

    Parameters
    ----------
    stations, normal : float (F, S, 2)
        Centre line (x, z) and the dorsum's unit normal there.
    half_width : float (F, S)
    thickness : float (S,) or (F, S)
        Parke units.
    """
    phi = K.SECTION_PHI
    y = np.sin(phi)
    y[-1] = 0.0                                  # exactly on the midsagittal plane
    h = 0.5 * (np.cos(phi) - 1.0)                # 0 on the dorsum's top, -1 on the underside
    depth = np.asarray(thickness, np.float64)[..., None] * h          # (F|1, S, C)
    out = np.empty(stations.shape[:2] + (len(phi), 3))
    out[..., 0] = stations[..., 0, None] + depth * normal[..., 0, None]
    out[..., 1] = half_width[..., None] * y
    out[..., 2] = stations[..., 1, None] + depth * normal[..., 1, None]
    return out
