"""The parabolic track of CASSI 2.0 (thesis section 4.2.2, Eq. 4.19).

Seen from above (x forward, y to the side), each lip vertex slides on a "backwards C" parabola
whose vertex is the x of its centre-line vertex: as the corners move toward each other (y
shrinks) the lip points slide forward instead of folding back through the teeth.
"""
from __future__ import annotations

import numpy as np

from cassi.common.errors import CassiInputError

from cassi.versions import lips_constants as K

__all__ = ["track_x", "track_y_for_x"]


def track_x(y, h, *, p: float = K.TRACK_P) -> np.ndarray:
    """Equation 4.19: ``x = y^2 / (4p) + h`` (k = 0: the track is symmetric about y = 0).

    Parameters
    ----------
    y : array
        Horizontal front-view position of the vertex (Parke units).
    h : array broadcastable with y
        x of the vertex's centre-line vertex (67, 64, 61, 58, 55, 52 or 49), Parke units.
    p : float
        Focus distance; negative so the parabola opens backwards (the thesis chose -37).

    Returns
    -------
    ndarray
        x of the vertex, <= h.
    """
    if not p < 0:
        raise CassiInputError(f"the parabolic track needs p < 0 (opening backwards), got {p!r}")
    y = np.asarray(y, dtype=np.float64)
    return y * y / (4.0 * p) + np.asarray(h, dtype=np.float64)


def track_y_for_x(x, h, *, p: float = K.TRACK_P) -> np.ndarray:
    """Inverse of :func:`track_x` for y >= 0: where the track reaches depth x (x <= h)."""
    if not p < 0:
        raise CassiInputError(f"the parabolic track needs p < 0 (opening backwards), got {p!r}")
    depth = np.asarray(h, dtype=np.float64) - np.asarray(x, dtype=np.float64)
    return np.sqrt(np.maximum(depth, 0.0) * (-4.0 * p))
