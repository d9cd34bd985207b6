"""XRMB coordinates -> Parke's model (thesis 4.1.1, "Mapping the XRMB Coordinate System").

Both systems have x forward; XRMB y (up, toward the roof of the mouth) corresponds to Parke z
(up). Pellets are scaled by p / d, d being the subject's jaw length (MNI-MNM, mm) and p the
matching distance on the model (vertex 258 to the midpoint of 281 and 286), then translated so
that the XRMB origin (between the tips of the upper central incisors) lands on vertex 226, the
bottom of the model's top front teeth. The pellets lie on the midsagittal plane, Parke's y = 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.face import numbering as N
from cassi.data.face.model import FaceModel, build_face, jaw_length_units, subject_units_per_mm
from cassi.data.xrmb.files import check_palate_length
from cassi.versions import constants as K

__all__ = ["XrmbToParke", "model_jaw_length", "subject_face"]


def model_jaw_length(vertices: np.ndarray) -> float:
    """p: distance from vertex 258 (MANi) to the midpoint of 281 and 286 (MANm), x-z plane
    (:func:`cassi.data.face.model.jaw_length_units`).

    Parameters
    ----------
    vertices : float (V, 3)
        Parke vertices (row i = vertex i + 1), Parke units.
    """
    return jaw_length_units(vertices)


def _jaw_length_d(jaw_length_mm) -> float:
    """The subject's jaw length d (MNI-MNM, mm) as a float; :class:`CassiInputError` unless it
    is a positive number."""
    try:
        d = float(jaw_length_mm)
    except (TypeError, ValueError):
        d = float("nan")
    if not np.isfinite(d) or d <= 0:
        raise CassiInputError(f"jaw length must be a positive number of mm, got {jaw_length_mm!r}")
    return d


@dataclass(frozen=True)
class XrmbToParke:
    """The affine map XRMB (x, y) mm -> Parke (x, z) units.

    Attributes
    ----------
    scale : float
        Parke units per mm, p / d.
    origin : float64 (2,)
        Parke (x, z) of vertex 226, where the XRMB origin goes.
    """

    scale: float
    origin: np.ndarray

    @classmethod
    def from_face(cls, vertices: np.ndarray, jaw_length_mm: float) -> "XrmbToParke":
        """Build the map from the model's vertices (V, 3) and the subject's jaw length d (mm)."""
        d = _jaw_length_d(jaw_length_mm)
        v = np.asarray(vertices, dtype=np.float64)
        p = model_jaw_length(v)
        if not np.isfinite(p) or p <= 0:
            raise CassiInputError("the face model's jaw length (vertex 258 to 281/286) is zero")
        return cls(scale=subject_units_per_mm(v, d),
                   origin=v[K.V_UPPER_INCISOR_TIP - 1, [0, 2]].copy())

    def to_parke(self, xy_mm: np.ndarray) -> np.ndarray:
        """XRMB (..., 2) mm (x forward, y up) -> Parke (..., 2) units (x forward, z up)."""
        return np.asarray(xy_mm, dtype=np.float64) * self.scale + self.origin

    def to_xrmb(self, xz: np.ndarray) -> np.ndarray:
        """The inverse: Parke (..., 2) (x, z) -> XRMB (..., 2) mm."""
        return (np.asarray(xz, dtype=np.float64) - self.origin) / self.scale

    def x_to_parke(self, x_mm: np.ndarray | float) -> np.ndarray | float:
        """An XRMB x alone (mm) -> Parke x (the key x values of 4.2.1 are mapped this way)."""
        return np.asarray(x_mm, dtype=np.float64) * self.scale + self.origin[0]

    def to_parke3(self, xy_mm: np.ndarray) -> np.ndarray:
        """XRMB (..., 2) -> Parke (..., 3) on the midsagittal plane (y = 0)."""
        xz = self.to_parke(xy_mm)
        out = np.zeros(xz.shape[:-1] + (3,), dtype=np.float64)
        out[..., 0] = xz[..., 0]
        out[..., 2] = xz[..., 1]
        return out


def subject_face(*, palate_mm: np.ndarray | None = None, jaw_length_mm: float | None = None,
                 head_measures=None) -> FaceModel:
    """A subject's face: the neutral face with the subject's PAL.DAT outline as its palate,
    mapped like the pellets (thesis 4.1.1: scaled by p / d, translated to vertex 226).

    Parameters
    ----------
    palate_mm : float (P, 2), optional
        PAL.DAT (XRMB mm: origin at the upper incisor tips, x forward, y up), either direction;
        default: the generator's typical palate.
    jaw_length_mm : float, optional
        The subject's jaw length d (MNI-MNM, mm); default: the model's own scale
        (:data:`cassi.data.face.numbering.UNITS_PER_MM`).
    head_measures : optional
        Kept on the face for the versions' chin and jaw adjustment.
    """
    # refused even where no palate needs it
    d = None if jaw_length_mm is None else _jaw_length_d(jaw_length_mm)
    if palate_mm is None:
        return build_face(head_measures=head_measures, jaw_length_mm=d)
    pal = np.asarray(palate_mm, dtype=np.float64)
    if pal.ndim != 2 or pal.shape[1] != 2 or len(pal) < 2 or not np.isfinite(pal).all():
        raise CassiInputError("palate_mm must be a finite (P >= 2, 2) array of x, y mm")
    check_palate_length(pal)
    if pal[0, 0] < pal[-1, 0]:
        pal = pal[::-1].copy()  # given back to front: PAL.DAT runs front to back
    neutral = build_face().vertices
    if d is None:
        mapping = XrmbToParke(scale=N.UNITS_PER_MM,
                              origin=neutral[K.V_UPPER_INCISOR_TIP - 1, [0, 2]].copy())
    else:
        mapping = XrmbToParke.from_face(neutral, d)
    return build_face(palate_mm=pal, palate_xz=mapping.to_parke(pal), head_measures=head_measures,
                      jaw_length_mm=d)
