"""Head correction and the XRMB head frame for EMA coils.

XRMB's head frame (thesis 3.2.3; :mod:`cassi.data.xrmb.files`): origin at the tip of the upper
incisors, +x along the maxillary occlusal plane out of the mouth, +y normal to it toward the roof
of the mouth, millimetres; the midsagittal plane. An EMA recording is brought there in three
steps, all rigid (no scaling):

1. head correction: each frame's reference coils are fitted (least squares, Kabsch 1976) to
   their positions at the recording's first frame where all of them are valid, and the same
   rotation and translation moves every coil of that frame;
2. the head frame: origin at the upper-incisor reference coil, axes from the coil map (the
   recording's own axes, or an occlusal plane from two coils: the front minus the back
   coil is +x; +y is normal to it, toward the nose bridge);
3. the midsagittal projection: the lateral coordinate is dropped.

Frames where a reference is missing cannot be corrected: every coil is missing there.
"""
from __future__ import annotations

import numpy as np

from cassi.common.errors import CassiInputError


def kabsch(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rigid motions taking ``source`` onto ``target`` in the least-squares sense.

    Parameters
    ----------
    source : float64 (F, K, D)
        K points per frame (D = 2 or 3).
    target : float64 (K, D)

    Returns
    -------
    R : float64 (F, D, D), t : float64 (F, D)
        ``target ~ source @ R.T + t`` per frame (proper rotations: no reflection).
    """
    src_c = source.mean(axis=1)
    tgt_c = target.mean(axis=0)
    h = np.einsum("fki,kj->fij", source - src_c[:, None, :], target - tgt_c)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(np.einsum("fij,fjk->fik", u, vt).transpose(0, 2, 1)))
    fix = np.ones(u.shape[:2])
    fix[:, -1] = np.where(d == 0, 1.0, d)
    rot = np.einsum("fji,fj,fkj->fik", vt, fix, u)  # V diag(1,..,d) U^T
    return rot, tgt_c - np.einsum("fij,fj->fi", rot, src_c)


def head_correct(coils: np.ndarray, refs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move every frame so that its reference coils sit where they are in the first full frame.

    Parameters
    ----------
    coils : float64 (F, N, D), NaN where missing
    refs : float64 (F, K, D), the reference coils

    Returns
    -------
    corrected : float64 (F, N, D), NaN where the coil or any reference is missing
    template : float64 (K, D), the references' positions the frames were fitted to
    ok : bool (F,), frames with every reference valid
    """
    ok = np.isfinite(refs).all(axis=(1, 2))
    if not ok.any():
        raise CassiInputError("no frame has every reference coil valid: the head cannot be "
                              "followed")
    template = refs[int(np.flatnonzero(ok)[0])]
    out = np.full_like(coils, np.nan)
    rot, t = kabsch(refs[ok], template)
    out[ok] = np.einsum("fij,fnj->fni", rot, coils[ok]) + t[:, None, :]
    return out, template, ok


def frame_axes(*, origin: np.ndarray, forward: np.ndarray, toward_up: np.ndarray,
               lateral: np.ndarray | None = None) -> np.ndarray:
    """Rows: the head frame's x, y (and lateral) unit vectors in recording coordinates.

    ``forward``: a vector along +x (out of the mouth). ``toward_up``: a point above the occlusal
    plane (the nose bridge); +y points to its side. ``lateral`` (3-D): a vector across the head
    (right minus left mastoid); without it the midsagittal plane is the one through
    ``origin``, ``forward`` and ``toward_up``.
    """
    x = forward / _norm(forward, "the occlusal plane's front and back coils coincide")
    up = toward_up - origin
    if x.shape[0] == 2:
        y = np.array([-x[1], x[0]])
        return np.stack([x, y if up @ y > 0 else -y])
    n = lateral if lateral is not None else np.cross(x, up)
    n = n - (n @ x) * x
    n = n / _norm(n, "the reference coils do not span the midsagittal plane")
    y = np.cross(n, x)
    if up @ y < 0:
        y, n = -y, -n
    return np.stack([x, y, n])


def _norm(v: np.ndarray, why: str) -> float:
    length = float(np.linalg.norm(v))
    if not length > 1e-9:
        raise CassiInputError(why)
    return length


def to_head_frame(points: np.ndarray, origin: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """float64 (..., 2): ``points`` (..., D) in the head frame's x, y (the midsagittal plane)."""
    return np.einsum("ij,...j->...i", axes[:2], points - origin)
