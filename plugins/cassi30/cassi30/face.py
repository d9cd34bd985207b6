"""The face CASSI 3.0 animates, derived from the subject's shared face: the flat 12-vertex
tongue becomes a thick, curved one, and the palate is fitted above the upper incisor tip.

Vertices 1..V of the shared face keep their numbers and meaning (the rubric and the jaw and lip
stages address them by number); the tongue's Parke numbers keep theirs too: 288-293 are the
top centre of the tip, T1-T4 and the first back station, 294-299 the lateral margins of those
stations. The other tongue vertices are added after the shared face's last vertex.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from cassi.data.face import numbering as N
from cassi.data.face.model import FaceModel
from cassi.data.xrmb.parke_io import Polygon

from cassi30 import constants as K
from cassi30.shape import (BACK_STATION, PELLET_STATIONS, STATIONS, arch_half_width,
                           back_points, centre_stations, normals, sections,
                           station_thickness_mm)

__all__ = ["thick_tongue_face", "tongue_numbers", "tongue_rows", "lower_arch", "fit_palate",
           "MARK"]

#: Added to the face's description, so that deriving twice returns the same face.
MARK = " + CASSI 3.0 tongue"
#: Stations whose section keeps Parke's numbers: tip, T1-T4, the first back point.
_NAMED_STATIONS = (0,) + PELLET_STATIONS + (BACK_STATION,)
_EDGE_COLUMN = K.DORSUM_COLUMNS - 1


def tongue_numbers(n_shared: int) -> np.ndarray:
    """1-based vertex numbers of the tongue's vertices, int (STATIONS, C): Parke's 288-299 where
    they belong, then ``n_shared + 1, ...`` station by station."""
    cols = len(K.SECTION_PHI)
    out = np.zeros((STATIONS, cols), np.int64)
    for s, centre, edge in zip(_NAMED_STATIONS, N.TONGUE_CENTRE, N.TONGUE_EDGE):
        out[s, 0], out[s, _EDGE_COLUMN] = centre, edge
    free = out == 0
    out[free] = n_shared + 1 + np.arange(int(free.sum()))
    return out


def tongue_rows(n_own: int) -> np.ndarray:
    """0-based rows of the tongue's vertices, int (STATIONS * C,) station by station, in a
    derived face of ``n_own`` vertices (its added vertices follow the shared face's)."""
    added = STATIONS * len(K.SECTION_PHI) - len(N.TONGUE)
    return tongue_numbers(n_own - added).ravel() - 1


def lower_arch(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lower teeth's biting line as (x ascending, |y|): float (P,), float (P,), Parke units."""
    v = np.asarray(vertices, np.float64)
    tips = [n for k in range(N.TEETH_PER_SET) for n in N.lower_tooth(k)[:2]]
    p = v[np.asarray(tips) - 1]
    order = np.argsort(p[:, 0], kind="stable")
    return p[order, 0], np.abs(p[order, 1])


def rest_tongue(vertices: np.ndarray, scale: float = N.UNITS_PER_MM) -> np.ndarray:
    """The thick tongue at rest, float (STATIONS, C, 3), on the shared face's own centre line
    (tip, T1-T4 of Parke's tongue), the back turning straight down (no pharynx at rest);
    ``scale``: the face's Parke units per mm (``FaceModel.units_per_mm``)."""
    v = np.asarray(vertices, np.float64)
    xz = v[:, [0, 2]]
    tip = xz[None, N.TONGUE_TIP - 1]
    pel = xz[None, np.asarray(N.TONGUE_PELLETS) - 1]
    back = back_points(pel[:, 2], pel[:, 3], np.array([0.0, -1.0]),
                       K.BACK_STEP_MM * scale)
    st = centre_stations(tip, pel, back)
    ax, ay = lower_arch(v)
    width = arch_half_width(ax, ay, st[..., 0], scale=scale)
    width[:, 0] = K.HALF_WIDTH_TIP_MM * scale
    return sections(st, normals(st), width, station_thickness_mm() * scale)[0]


def fit_palate(vertices: np.ndarray, scale: float = N.UNITS_PER_MM) -> np.ndarray:
    """The vertices with every palate vertex at least PALATE_ABOVE_INCISOR_MM (subject mm, at
    ``scale`` Parke units a mm: ``FaceModel.units_per_mm``) above the upper incisor tip (226);
    a copy."""
    v = np.array(vertices, np.float64)
    rows = np.asarray(N.PALATE) - 1
    floor = v[N.UPPER_INCISOR_TIP - 1, 2] + K.PALATE_ABOVE_INCISOR_MM * scale
    v[rows, 2] = np.maximum(v[rows, 2], floor)
    return v


def _material(face: FaceModel, name: str) -> int:
    for number, m in face.materials.items():
        if m.name == name:
            return int(number)
    raise ValueError(f"the face has no {name!r} material")


def _polygons(numbers: np.ndarray, material: int) -> list[Polygon]:
    """Quads between neighbouring stations round the section, and a fan closing each end;
    Parke's order (clockwise seen from outside)."""
    S, C = numbers.shape
    polys = []
    for s in range(S - 1):
        for k in range(C - 1):
            polys.append(Polygon(material, (int(numbers[s, k]), int(numbers[s + 1, k]),
                                            int(numbers[s + 1, k + 1]), int(numbers[s, k + 1]))))
    for k in range(1, C - 1):
        polys.append(Polygon(material, (int(numbers[0, 0]), int(numbers[0, k]),
                                        int(numbers[0, k + 1]))))
        polys.append(Polygon(material, (int(numbers[-1, 0]), int(numbers[-1, k + 1]),
                                        int(numbers[-1, k]))))
    return polys


def thick_tongue_face(face: FaceModel) -> FaceModel:
    """``face`` with the thick, curved tongue and the fitted palate (see the module docstring).

    A face already derived (its description ends with :data:`MARK`) is returned as it is.
    """
    if face.description.endswith(MARK):
        return face
    n = face.vertex_count
    numbers = tongue_numbers(n)
    extra = int(numbers.max()) - n
    tongue = _material(face, "tongue")
    rows = numbers.ravel() - 1
    scale = face.units_per_mm  # the subject's p / d, as the animation's (ctx.mapping.scale)

    def grow(a: np.ndarray) -> np.ndarray:
        out = np.concatenate([fit_palate(a, scale), np.zeros((extra, 3))])
        out[rows] = rest_tongue(a, scale).reshape(-1, 3)
        return out

    polys = [p for p in face.polygons if p.material != tongue] + _polygons(numbers, tongue)
    return dataclasses.replace(face, vertices=grow(face.vertices), polygons=tuple(polys),
                               st1=grow(face.st1), st2=grow(face.st2),
                               description=face.description + MARK)
