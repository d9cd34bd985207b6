"""Exact geometric measures for the rubric, over an animation's vertex positions.

Every function here is pure: arrays in, arrays or numbers out. Positions are ``(F, V, 3)`` in
Parke units with the face's numbering (row ``i`` is Parke vertex ``i + 1``), X forward, Y to the
face's left, Z up, left half only (the right half is the mirror ``y -> -y``). Which rows are the
teeth, the tongue, the lips ... is given explicitly by a :class:`MouthParts` (0-based row
indices), so tests can build small synthetic mouths and the real face supplies its own through
:func:`mouth_parts`. Lengths are returned in millimetres: ``mm_per_unit`` converts (thesis 4.1.1
scales the pellets by ``p / d``, Parke jaw length over the subject's jaw length, so one Parke unit
is ``d / p`` millimetres).

The measures are what the thesis's authors judged by eye (thesis chapter 5, restated in
``shared/spec/rubric.md``); the thresholds that turn them into negatives live in
:mod:`cassi.harness.rubric.registry`, never here.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.face.build import MATERIAL_NAMES
from cassi.data.face import numbering as N
from cassi.versions.mapping import XrmbToParke

from cassi.harness.rubric.registry import FRONT_TEETH_MIN_NX, FRONT_TEETH_SHARE

__all__ = [
    "MouthParts", "mouth_parts", "mm_per_unit", "surface_hits", "front_triangles",
    "tongue_teeth_penetration", "tongue_palate_penetration", "tongue_penetrations",
    "lip_teeth_penetration",
    "inner_lip_gap", "lower_lip_below_teeth", "protrusion_difference", "lip_nose_clearance",
    "concavity", "corner_misplacement", "excess_jitter", "switch_jumps",
    "palate_below_incisor", "teeth_overlap", "teeth_slope", "teeth_gap", "lip_rounding",
    "opening_polygon", "polygon_extent", "outline_angles", "profile_angle", "max_protrusion_frame",
]


def _arr(x) -> np.ndarray:
    return np.asarray(x, dtype=np.int64).reshape(-1)


@dataclass(frozen=True)
class MouthParts:
    """Which rows of the positions array form each part of the mouth (0-based indices).

    Attributes
    ----------
    upper_teeth_tris, lower_teeth_tris : int (T, 3)
        Triangles of the upper and the lower teeth surfaces.
    tongue : int (K,)
        Tongue vertices; ``tongue_edges`` int (E, 2) its edges (sampled between the vertices).
    palate : int (P,), palate_tris : int (Q, 3)
        The palatal outline surface (empty when the face has none).
    ul_outer, ll_outer : int
        Vertices 67 and 49, the outer edges of the lips where the UL and LL pellets sit.
    ul_inner, ll_inner : int
        Vertices 61 and 58, the inner outline at the centerline (the lips' contact edges).
    upper_inner, lower_inner : int (3,)
        Inner outline, centerline to corner: 61, 62, 63 and 58, 59, 60; ``inner_corner`` 287.
    upper_outer, lower_outer : int (3,)
        Outer outline: 67, 68, 69 and 49, 50, 51; ``corner`` 70.
    lip_points : int (L,)
        Every lip vertex (49-70, 287, 300), tested against the teeth surface.
    above_lip, below_lip : int (3,)
        71, 72, 73 above the upper lip and 41, 42, 43 below the lower lip (thesis 4.2.2).
    subnasale : int
        The base of the nose on the centerline (the top of the upper-lip profile).
    chin, chin_low : int
        Soft-tissue chin point and a point under it on the jaw line (the chin profile).
    upper_incisor_tip : int
        Vertex 226, the bottom of the top front teeth.
    lower_incisor_tip : int
        The top (cutting edge) of the lower front teeth.
    lower_gum : int
        Vertex 258 (MANi): where the gums and the lower front teeth meet.
    upper_molar, lower_molar : int
        Lowest back upper-teeth vertex and highest back lower-teeth vertex (occlusal line ends).
    jaw_point : int
        A rigid jaw vertex for jaw motion (258); lip jitter is compared with this one.
    jaw : int (J,)
        The jaw's vertices (Parke's first rotation zone, 14-43) for its shape (Table B).
    """

    upper_teeth_tris: np.ndarray
    lower_teeth_tris: np.ndarray
    tongue: np.ndarray
    tongue_edges: np.ndarray
    palate: np.ndarray
    palate_tris: np.ndarray
    ul_outer: int
    ll_outer: int
    ul_inner: int
    ll_inner: int
    upper_inner: np.ndarray
    lower_inner: np.ndarray
    inner_corner: int
    upper_outer: np.ndarray
    lower_outer: np.ndarray
    corner: int
    lip_points: np.ndarray
    above_lip: np.ndarray
    below_lip: np.ndarray
    subnasale: int
    chin: int
    chin_low: int
    upper_incisor_tip: int
    lower_incisor_tip: int
    lower_gum: int
    upper_molar: int
    lower_molar: int
    jaw_point: int
    jaw: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        for name in ("upper_teeth_tris", "lower_teeth_tris", "palate_tris"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), np.int64).reshape(-1, 3))
        object.__setattr__(self, "tongue_edges",
                           np.asarray(self.tongue_edges, np.int64).reshape(-1, 2))
        for name in ("tongue", "palate", "upper_inner", "lower_inner", "upper_outer",
                     "lower_outer", "lip_points", "above_lip", "below_lip", "jaw"):
            object.__setattr__(self, name, _arr(getattr(self, name)))


# ----------------------------------------------------------------------------------------------
# Building the parts from the real face
# ----------------------------------------------------------------------------------------------

def _poly_parts(poly):
    if hasattr(poly, "material"):
        return poly.material, tuple(getattr(poly, "vertices", ()))
    return poly[0], tuple(poly[1])


def _material_name(materials, mat) -> str | None:
    if isinstance(mat, str):
        return mat
    if materials is not None:
        try:
            m = materials[mat]
            return m if isinstance(m, str) else getattr(m, "name", None)
        except (KeyError, IndexError, TypeError):
            pass
    return MATERIAL_NAMES.get(int(mat))


def _polys_by_material(face, wanted) -> np.ndarray:
    """Triangles (0-based, fan-split) of the face's polygons whose material name is in ``wanted``."""
    tris = []
    materials = getattr(face, "materials", None)
    for poly in getattr(face, "polygons", ()):
        mat, verts = _poly_parts(poly)
        name = _material_name(materials, mat)
        if name is None or name.lower() not in wanted:
            continue
        v = [int(x) - 1 for x in verts]
        for k in range(1, len(v) - 1):
            tris.append((v[0], v[k], v[k + 1]))
    return np.asarray(tris, np.int64).reshape(-1, 3)


def mouth_parts(face) -> MouthParts:
    """The :class:`MouthParts` of a :class:`cassi.data.face.model.FaceModel`.

    Vertex numbers come from :mod:`cassi.data.face.numbering` (thesis Figures 3.7, 4.4-4.7, 4.17,
    Table 3.2). Teeth, tongue and palate surfaces come from the face's polygons by material
    (the tongue's vertices: 288-299, then those its polygons add);
    teeth polygons using the lower teeth's vertices (255-286) are the lower set. The occlusal
    line ends are the tips of tooth quad 7 (the second molars) and of quad 0 (the incisors).
    """
    V = np.asarray(face.vertices).shape[0]
    teeth = _polys_by_material(face, {"teeth"})
    is_lower = np.any((teeth >= N.LOWER_TEETH_FIRST - 1) & (teeth <= N.LOWER_TEETH_LAST - 1), axis=1)
    tongue_tris = _polys_by_material(face, {"tongue"})
    if len(tongue_tris):
        edges = np.concatenate([tongue_tris[:, [0, 1]], tongue_tris[:, [1, 2]], tongue_tris[:, [2, 0]]])
        edges = np.unique(np.sort(edges, axis=1), axis=0)
    else:
        edges = np.zeros((0, 2), np.int64)
    z = lambda nums: [int(v) - 1 for v in nums]  # noqa: E731 - Parke number -> row
    # The tongue: Parke's numbers first (tip, T1-T4, back, edges: m_tongue_back_v reads the
    # centre line by position), then any further vertex of the tongue's polygons (a version's
    # own face may give the tongue more, cassi.versions.protocol.version_face).
    tongue = z(N.TONGUE)
    tongue += sorted(set(np.unique(tongue_tris).tolist()) - set(tongue))
    lips = [v for v in z(N.LOWER_LIP + N.UPPER_LIP + (N.CORNER, N.INNER_CORNER, N.CORNER_MIDDLE))
            if v < V]
    return MouthParts(
        upper_teeth_tris=teeth[~is_lower], lower_teeth_tris=teeth[is_lower],
        tongue=tongue, tongue_edges=edges,
        palate=[v for v in z(N.PALATE) if v < V], palate_tris=_polys_by_material(face, {"palate"}),
        ul_outer=N.UL - 1, ll_outer=N.LL - 1,
        ul_inner=N.UPPER_INNER[0] - 1, ll_inner=N.LOWER_INNER[0] - 1,
        upper_inner=z(N.UPPER_INNER), lower_inner=z(N.LOWER_INNER), inner_corner=N.INNER_CORNER - 1,
        upper_outer=z(N.UPPER_OUTER), lower_outer=z(N.LOWER_OUTER), corner=N.CORNER - 1,
        lip_points=lips, above_lip=z(N.ABOVE_LIP), below_lip=z(N.BELOW_LIP),
        subnasale=N.SUBNASALE - 1, chin=N.CHIN - 1, chin_low=N.CHIN_LOW - 1,
        upper_incisor_tip=N.UPPER_INCISOR_TIP - 1, lower_incisor_tip=N.LOWER_INCISOR_TIP - 1,
        lower_gum=N.MANI - 1,
        # second molars' distal tips: upper quad 7 is gum-mesial, gum-distal, tip-distal,
        # tip-mesial; lower quad 7 is tip-mesial, tip-distal, gum-distal, gum-mesial
        upper_molar=N.upper_tooth(7)[2] - 1, lower_molar=N.lower_tooth(7)[1] - 1,
        jaw_point=N.MANI - 1, jaw=z(N.JAW))


def mm_per_unit(face_vertices: np.ndarray, jaw_length_mm: float | None) -> float:
    """Millimetres per Parke unit, d / p: the inverse of the thesis's 4.1.1 mapping scale
    (:class:`cassi.versions.mapping.XrmbToParke`, the one place that computes p).

    Parameters
    ----------
    face_vertices : float (V, 3)
        The face in Parke units.
    jaw_length_mm : float
        The subject's distance MNI-MNM (mm).

    Raises
    ------
    CassiInputError
        Without a positive jaw length, or when the face's jaw length p is zero: no millimetre
        can be measured, and a guessed scale would grade every check wrongly.
    """
    if jaw_length_mm is None:
        raise CassiInputError("the subject's jaw length (profile.jaw_length_mm) is needed to "
                              "measure in millimetres (thesis 4.1.1)")
    return 1.0 / XrmbToParke.from_face(face_vertices, jaw_length_mm).scale


# ----------------------------------------------------------------------------------------------
# Surface queries
# ----------------------------------------------------------------------------------------------

_AXES = {0: (1, 2), 1: (0, 2), 2: (0, 1)}


def surface_hits(points: np.ndarray, tri_pos: np.ndarray, *, axis: int = 0,
                 eps: float = 1e-9, chunk: int = 2_000_000) -> tuple[np.ndarray, np.ndarray]:
    """Where a line through each point along ``axis`` crosses a triangle surface.

    Parameters
    ----------
    points : float (F, P, 3)
        Query points per frame.
    tri_pos : float (F, T, 3, 3)
        Triangle corners per frame (the surface moves with the jaw).
    axis : int
        0 = x (forward), 1 = y, 2 = z.

    Returns
    -------
    lo, hi : float (F, P)
        The smallest and the largest ``axis`` coordinate of the surface crossings on the line
        through each point; NaN where the line misses the surface.
    """
    points = np.asarray(points, dtype=np.float64)
    tri_pos = np.asarray(tri_pos, dtype=np.float64)
    F, P, _ = points.shape
    T = tri_pos.shape[1]
    lo = np.full((F, P), np.nan)
    hi = np.full((F, P), np.nan)
    if T == 0 or P == 0:
        return lo, hi
    u, v = _AXES[axis]
    step = max(1, chunk // max(1, P * T))
    tol = -1e-7
    for s in range(0, F, step):
        e = min(F, s + step)
        tri = tri_pos[s:e]                                         # (f, T, 3, 3)
        # Per triangle: its corners' coordinates and the barycentric denominator (the same
        # operations as per pair, done once), each (f * T,)
        (au, av, ax), (bu, bv, bx), (cu, cv, cx) = (
            tuple(tri[:, :, k, i].reshape(-1) for i in (u, v, axis)) for k in range(3))
        den = (bu - au) * (cv - av) - (cu - au) * (bv - av)
        ok = np.abs(den) > eps
        den = np.where(ok, den, 1.0)
        # Broad phase: only the (point, triangle) pairs whose (u, v) falls in the triangle's
        # bounding box (widened past the barycentric tolerance) are solved, usually a few per
        # point: the same values as solving every pair, at a fraction of the work. A triangle
        # without a denominator has no inside.
        tu, tv = tri[..., u], tri[..., v]
        umin, umax, vmin, vmax = tu.min(-1), tu.max(-1), tv.min(-1), tv.max(-1)
        pad = 1e-6 * (umax - umin + vmax - vmin) + 1e-9
        box, at, pu, pv = _box_pairs(points[s:e, :, u], points[s:e, :, v], umin - pad,
                                     umax + pad, vmin - pad, vmax + pad, ok)
        w1 = ((bu[box] - pu) * (cv[box] - pv) - (cu[box] - pu) * (bv[box] - pv)) / den[box]
        w2 = ((cu[box] - pu) * (av[box] - pv) - (au[box] - pu) * (cv[box] - pv)) / den[box]
        w3 = 1.0 - w1 - w2
        inside = (w1 >= tol) & (w2 >= tol) & (w3 >= tol)
        box, at, w1, w2, w3 = box[inside], at[inside], w1[inside], w2[inside], w3[inside]
        val = w1 * ax[box] + w2 * bx[box] + w3 * cx[box]
        lo[s:e], hi[s:e] = _extremes(val, at, (e - s, P))
    return lo, hi


def _box_pairs(pu: np.ndarray, pv: np.ndarray, ulo: np.ndarray, uhi: np.ndarray,
               vlo: np.ndarray, vhi: np.ndarray, live: np.ndarray):
    """The (point, triangle) pairs of each frame with ``ulo <= pu <= uhi`` and
    ``vlo <= pv <= vhi``, for the ``live`` triangles: points ``pu``, ``pv`` (f, P), boxes
    ``ulo`` ... (f, T), ``live`` (f * T,).

    Each frame's points sorted by ``u`` give each box the run of points within its ``u`` range
    (the points below its lower bound, and those not above its upper, counted in one stable
    sort of the points with the bounds: the same comparisons); only those pairs are compared
    in ``v``, so the work follows the pairs near a box, not every point against every
    triangle. The same pairs come out, ordered by frame and triangle (so each point's in
    triangle order) rather than by point.

    Returns ``box`` (frame * T + triangle), ``at`` (frame * P + point) and the points' ``u``
    and ``v``, each (K,).
    """
    f, P = pu.shape
    T = ulo.shape[1]
    # lower bounds, then points, then upper bounds: among equal values a lower bound sorts
    # before the points (counting those below it), an upper bound after them
    merged = np.argsort(np.concatenate([ulo, pu, uhi], axis=1), axis=1, kind="stable")
    is_point = (merged >= T) & (merged < T + P)
    below = np.cumsum(is_point, axis=1)                 # points at or before each position
    row = np.arange(f, dtype=np.int64)[:, None]
    first, last = np.empty(f * T, np.int64), np.empty(f * T, np.int64)
    is_lo, is_hi = merged < T, merged >= T + P
    first[(merged + row * T)[is_lo]] = below[is_lo]
    last[(merged - (T + P) + row * T)[is_hi]] = below[is_hi]
    order = (merged - T + row * P)[is_point]            # flat, each frame's points by u
    su, sv = pu.reshape(-1)[order], pv.reshape(-1)[order]
    counts = np.where(live, np.maximum(last - first, 0), 0)
    n = int(counts.sum())
    # flat index into the sorted points: each run's start in its frame, then 0, 1, ...
    start = (first.reshape(f, T) + P * row).reshape(-1)
    idx = np.repeat(start - (np.cumsum(counts) - counts), counts) + np.arange(n)
    # A NaN in a box makes all four of its bounds NaN (the shared pad), and a NaN u sorts
    # last, past every finite bound: the v comparisons alone then decide as all four did.
    p_v = sv[idx]
    keep = ((p_v >= np.repeat(vlo.reshape(-1), counts))
            & (p_v <= np.repeat(vhi.reshape(-1), counts)))
    idx = idx[keep]
    box = np.repeat(np.arange(f * T, dtype=np.int64), counts)[keep]
    return box, order[idx], su[idx], p_v[keep]


def _extremes(val: np.ndarray, at: np.ndarray, shape) -> tuple:
    """Per point (flat ``at`` into ``shape``): the smallest and the largest ``val`` of its
    crossings; NaN where it has none (or only non-finite ones).

    A point's crossings come in triangle order, as when every pair was solved point by
    point: which of 0.0 and -0.0 (equal) a minimum keeps depends on that order."""
    n = int(np.prod(shape))
    many = np.bincount(at, minlength=n)[at] > 1
    low, high = np.full(n, np.inf), np.full(n, -np.inf)
    low[at[~many]] = val[~many]                  # a point's only crossing: its min and max
    high[at[~many]] = val[~many]
    np.minimum.at(low, at[many], val[many])
    np.maximum.at(high, at[many], val[many])
    return (np.where(np.isfinite(low), low, np.nan).reshape(shape),
            np.where(np.isfinite(high), high, np.nan).reshape(shape))


def front_triangles(rest: np.ndarray, tris: np.ndarray, *, front_share: float = FRONT_TEETH_SHARE,
                    min_nx: float = FRONT_TEETH_MIN_NX) -> np.ndarray:
    """The triangles of a teeth set that face forward or backward at the front of the arch.

    The thesis judged the tongue poking "through the upper or the lower front teeth" from the
    front view; a line along x through a point only meets the front teeth sensibly (the side
    teeth run along x). Kept: triangles whose centroid lies in the front ``front_share`` of the
    set's x range and whose unit normal has ``|n_x| >= min_nx`` (the registry's
    ``FRONT_TEETH_SHARE`` and ``FRONT_TEETH_MIN_NX``, with their reasons).

    Parameters
    ----------
    rest : float (V, 3)
        Rest positions.
    tris : int (T, 3)

    Returns
    -------
    int (T', 3)
    """
    tris = np.asarray(tris, np.int64).reshape(-1, 3)
    if len(tris) == 0:
        return tris
    p = np.asarray(rest, np.float64)[tris]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    norm = np.linalg.norm(n, axis=1)
    nx = np.abs(n[:, 0]) / np.where(norm > 0, norm, 1.0)
    cx = p[:, :, 0].mean(1)
    xs = p[:, :, 0]
    x0 = xs.max() - front_share * (xs.max() - xs.min())
    return tris[(cx >= x0) & (nx >= min_nx) & (norm > 0)]


def _edge_samples(pos: np.ndarray, verts: np.ndarray, edges: np.ndarray, per_edge: int) -> np.ndarray:
    """Vertex positions plus ``per_edge`` evenly spaced interior points of each edge: (F, P, 3)."""
    pts = [pos[:, verts]]
    if len(edges) and per_edge > 0:
        t = (np.arange(1, per_edge + 1) / (per_edge + 1))[None, None, :, None]
        a = pos[:, edges[:, 0]][:, :, None, :]
        b = pos[:, edges[:, 1]][:, :, None, :]
        pts.append((a + t * (b - a)).reshape(pos.shape[0], -1, 3))
    out = np.concatenate(pts, axis=1)
    out[..., 1] = np.abs(out[..., 1])  # left half: a point a hair right of the cut is mirrored
    return out


def tongue_teeth_penetration(pos: np.ndarray, parts: MouthParts, *, rest: np.ndarray | None = None,
                             per_edge: int = 3) -> dict[str, np.ndarray]:
    """How far the tongue passes forward through the upper and the lower front teeth.

    A tongue point (vertex or edge sample) whose (y, z) falls on the front teeth's silhouette
    should lie behind the teeth's back (lingual) surface; the depth is how far forward of that
    surface it is (Parke units; 0 when behind).

    Returns
    -------
    dict with ``upper``, ``lower`` : float (F,) the deepest penetration per frame.
    """
    pos = np.asarray(pos, np.float64)
    rest = pos[0] if rest is None else np.asarray(rest, np.float64)
    return _tongue_teeth(pos, _edge_samples(pos, parts.tongue, parts.tongue_edges, per_edge),
                         parts, rest)


def _tongue_teeth(pos: np.ndarray, pts: np.ndarray, parts: MouthParts, rest: np.ndarray) -> dict:
    out = {}
    for key, tris in (("upper", parts.upper_teeth_tris), ("lower", parts.lower_teeth_tris)):
        tris = front_triangles(rest, tris)
        lo, _ = surface_hits(pts, pos[:, tris], axis=0)
        depth = np.where(np.isnan(lo), 0.0, np.maximum(pts[..., 0] - lo, 0.0))
        out[key] = depth.max(axis=1) if depth.shape[1] else np.zeros(pos.shape[0])
    return out


def tongue_palate_penetration(pos: np.ndarray, parts: MouthParts, *, per_edge: int = 3) -> np.ndarray:
    """How far the tongue rises through the palatal surface, per frame (Parke units, >= 0)."""
    pos = np.asarray(pos, np.float64)
    if len(parts.palate_tris) == 0:
        return np.zeros(pos.shape[0])
    return _tongue_palate(pos, _edge_samples(pos, parts.tongue, parts.tongue_edges, per_edge),
                          parts)


def _tongue_palate(pos: np.ndarray, pts: np.ndarray, parts: MouthParts) -> np.ndarray:
    if len(parts.palate_tris) == 0:
        return np.zeros(pos.shape[0])
    lo, _ = surface_hits(pts, pos[:, parts.palate_tris], axis=2)
    depth = np.where(np.isnan(lo), 0.0, np.maximum(pts[..., 2] - lo, 0.0))
    return depth.max(axis=1)


def tongue_penetrations(pos: np.ndarray, parts: MouthParts, *, rest: np.ndarray | None = None,
                        per_edge: int = 3) -> dict[str, np.ndarray]:
    """:func:`tongue_teeth_penetration`'s ``upper`` and ``lower`` and
    :func:`tongue_palate_penetration` as ``palate``, from one sampling of the tongue."""
    pos = np.asarray(pos, np.float64)
    rest = pos[0] if rest is None else np.asarray(rest, np.float64)
    pts = _edge_samples(pos, parts.tongue, parts.tongue_edges, per_edge)
    return {**_tongue_teeth(pos, pts, parts, rest), "palate": _tongue_palate(pos, pts, parts)}


def lip_teeth_penetration(pos: np.ndarray, parts: MouthParts, *, rest: np.ndarray | None = None,
                          which: str = "both") -> np.ndarray:
    """How far lip vertices sink behind the front surface of the front teeth, per frame.

    ``which``: ``upper`` (upper lip against all front teeth), ``lower`` (lower lip against the
    lower front teeth, thesis Table 5.9 "the lower lip passes through the bottom set of teeth"),
    or ``both``. Returns float (F,), Parke units, >= 0.
    """
    pos = np.asarray(pos, np.float64)
    rest = pos[0] if rest is None else np.asarray(rest, np.float64)
    upper_lip = np.concatenate([parts.upper_inner, parts.upper_outer, [parts.inner_corner]])
    lower_lip = np.concatenate([parts.lower_inner, parts.lower_outer])
    if which == "upper":
        lips, tris = upper_lip, np.concatenate([parts.upper_teeth_tris, parts.lower_teeth_tris])
    elif which == "lower":
        lips, tris = lower_lip, parts.lower_teeth_tris
    else:
        lips = parts.lip_points
        tris = np.concatenate([parts.upper_teeth_tris, parts.lower_teeth_tris])
    tris = front_triangles(rest, tris)
    pts = pos[:, lips].copy()
    pts[..., 1] = np.abs(pts[..., 1])
    _, hi = surface_hits(pts, pos[:, tris], axis=0)
    depth = np.where(np.isnan(hi), 0.0, np.maximum(hi - pts[..., 0], 0.0))
    return depth.max(axis=1) if depth.shape[1] else np.zeros(pos.shape[0])


# ----------------------------------------------------------------------------------------------
# Lips
# ----------------------------------------------------------------------------------------------

def inner_lip_gap(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """Vertical gap between the lips' contact edges at the centerline, per frame (Parke units).

    ``z(61) - z(58)``: positive = the lips are apart, 0 = touching, negative = the lower lip's
    edge is above the upper's (the lips cross, thesis 4.2.2 "the lips overlap").
    """
    pos = np.asarray(pos, np.float64)
    return pos[:, parts.ul_inner, 2] - pos[:, parts.ll_inner, 2]


def lower_lip_below_teeth(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """How far the lower lip's edge (58) is below the bottom of the lower front teeth (258).

    Positive = the whole lower front teeth and gum line show above the lower lip (thesis
    Table 5.3: "the lower lip often goes below the bottom of the lower front teeth").
    """
    pos = np.asarray(pos, np.float64)
    return pos[:, parts.lower_gum, 2] - pos[:, parts.ll_inner, 2]


def protrusion_difference(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """``x(49) - x(67)``: how far the lower lip sticks out beyond the upper, per frame."""
    pos = np.asarray(pos, np.float64)
    return pos[:, parts.ll_outer, 0] - pos[:, parts.ul_outer, 0]


def protrusion_sum(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """Per frame: x of the upper plus the lower lip pellet vertex (its maximum is the frame of
    maximum protrusion), (F,)."""
    pos = np.asarray(pos, np.float64)
    return pos[:, parts.ul_outer, 0] + pos[:, parts.ll_outer, 0]


def max_protrusion_frame(pos: np.ndarray, parts: MouthParts) -> int:
    """The frame of maximum lip protrusion: largest mean x of the two lip pellet vertices."""
    return int(np.argmax(protrusion_sum(pos, parts)))


def lip_nose_clearance(pos: np.ndarray, parts: MouthParts, rest: np.ndarray) -> np.ndarray:
    """Distance (x, z) from the upper lip's edge (67) to the nose base, over its rest value.

    1 = as at rest; toward 0 the upper lip runs into the nose (thesis Table 5.8); negative when
    the lip's edge is above the nose base.
    """
    pos = np.asarray(pos, np.float64)
    rest = np.asarray(rest, np.float64)
    d = pos[:, parts.subnasale, [0, 2]] - pos[:, parts.ul_outer, [0, 2]]
    d0 = rest[parts.subnasale, [0, 2]] - rest[parts.ul_outer, [0, 2]]
    n0 = float(np.linalg.norm(d0)) or 1.0
    sign = np.sign(pos[:, parts.subnasale, 2] - pos[:, parts.ul_outer, 2])
    return sign * np.linalg.norm(d, axis=1) / n0


def concavity(pos: np.ndarray, upper: int, mid: int, lower: int) -> np.ndarray:
    """How far ``mid`` lies behind the chord from ``upper`` to ``lower`` in the side view.

    Profile (x, z) only; positive = behind the chord (concave, caved in), per frame, Parke
    units. Used for the points above and under the lip and the chin (thesis Tables 5.8, 5.9).
    """
    pos = np.asarray(pos, np.float64)
    a = pos[:, upper][:, [0, 2]]
    b = pos[:, lower][:, [0, 2]]
    m = pos[:, mid][:, [0, 2]]
    d = b - a
    n = np.stack([d[:, 1], -d[:, 0]], axis=1)  # points forward (+x) when a is above b
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    n *= np.where(n[:, :1] < 0, -1.0, 1.0)
    return -np.sum((m - a) * n, axis=1)


def corner_misplacement(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """How far the lip corner (70) lies outside the band its neighbours allow, per frame.

    The corner should lie vertically between the last upper (69) and lower (51) outer-outline
    vertices and no farther forward than the more forward of them (thesis Table 5.9, "the lip
    corners badly placed relative to the other lip points"). Parke units, >= 0.
    """
    pos = np.asarray(pos, np.float64)
    c = pos[:, parts.corner]
    up = pos[:, parts.upper_outer[-1]]
    lo = pos[:, parts.lower_outer[-1]]
    ztop = np.maximum(up[:, 2], lo[:, 2])
    zbot = np.minimum(up[:, 2], lo[:, 2])
    dz = np.maximum(c[:, 2] - ztop, 0.0) + np.maximum(zbot - c[:, 2], 0.0)
    dx = np.maximum(c[:, 0] - np.maximum(up[:, 0], lo[:, 0]), 0.0)
    return np.hypot(dz, dx)


def lip_rounding_at(first: np.ndarray, at: np.ndarray, parts: MouthParts) -> float:
    """Corner half-width in frame ``at`` over that in frame ``first`` (each float (V, 3))."""
    w0 = abs(float(first[parts.corner, 1])) or 1.0
    return float(abs(float(at[parts.corner, 1])) / w0)


def lip_rounding(pos: np.ndarray, parts: MouthParts) -> tuple[float, int]:
    """Narrowing of the mouth at maximum protrusion: corner half-width there over at the start.

    Returns ``(ratio, frame)``; ratio 1 = the corners did not move in (no lip rounding,
    thesis Table 5.8), smaller = rounder.
    """
    pos = np.asarray(pos, np.float64)
    f = max_protrusion_frame(pos, parts)
    return lip_rounding_at(pos[0], pos[f], parts), f


def opening_polygon(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """The lip opening in the front view, full mouth (mirrored): (F, N, 2) of (y, z).

    Inner outline 61-62-63, inner corner 287, 60-59-58, then its mirror image.
    """
    pos = np.asarray(pos, np.float64)
    left = np.concatenate([parts.upper_inner, [parts.inner_corner], parts.lower_inner[::-1]])
    half = pos[:, left][:, :, [1, 2]].copy()
    half[..., 0] = np.abs(half[..., 0])
    mirror = half[:, ::-1].copy()
    mirror[..., 0] *= -1
    # right half goes 58 (centre) ... 287 ... 61: skip the duplicate centerline points
    return np.concatenate([half, mirror[:, 1:-1]], axis=1)


def polygon_extent(poly: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Area and extent (area / bounding-box area) of polygons (F, N, 2).

    An ellipse fills pi/4 = 0.785 of its box, a diamond or a triangle 0.5 (thesis Table 5.9:
    "lips very triangular or diamond-shaped"). Returns ``(area, extent)`` per frame.
    """
    y, z = poly[..., 0], poly[..., 1]
    area = 0.5 * np.abs(np.sum(y * np.roll(z, -1, axis=1) - np.roll(y, -1, axis=1) * z, axis=1))
    box = np.ptp(y, axis=1) * np.ptp(z, axis=1)
    return area, np.where(box > 0, area / np.where(box > 0, box, 1.0), np.nan)


def outline_angles(poly: np.ndarray) -> np.ndarray:
    """Interior angle, degrees, at every vertex of closed polygons (F, N, 2) -> (F, N).

    180 where the outline runs straight on; a smooth outline turns a little at each vertex, an
    angular one (a hexagon: 120) turns all at once at a few.
    """
    poly = np.asarray(poly, np.float64)
    u = np.roll(poly, 1, axis=1) - poly
    v = np.roll(poly, -1, axis=1) - poly
    cos = np.sum(u * v, -1) / np.maximum(np.linalg.norm(u, axis=-1) * np.linalg.norm(v, axis=-1), 1e-12)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def profile_angle(pos: np.ndarray, a: int, b: int, c: int) -> np.ndarray:
    """Interior angle at ``b`` of the side-view polyline a-b-c, degrees, per frame."""
    pos = np.asarray(pos, np.float64)
    u = pos[:, a][:, [0, 2]] - pos[:, b][:, [0, 2]]
    v = pos[:, c][:, [0, 2]] - pos[:, b][:, [0, 2]]
    cos = np.sum(u * v, 1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-12)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


#: Savitzky-Golay window (frames) and order separating jitter from motion: 9 frames = 62 ms at
#: XRMB's 146 Hz; articulator movements (50-200 ms) stay in the fit, frame-to-frame shake does not.
def _shake(x: np.ndarray, window: int, order: int) -> np.ndarray:
    """Distance of each frame from a local polynomial fit of its neighbours: (F, ...) -> (F, ...)."""
    from scipy.signal import savgol_filter  # noqa: PLC0415

    if x.shape[0] < window:
        return np.zeros(x.shape[:-1])
    smooth = savgol_filter(x, window, order, axis=0, mode="interp")
    return np.linalg.norm(x - smooth, axis=-1)


def excess_jitter(pos: np.ndarray, points, ref_points, *, window: int, order: int) -> np.ndarray:
    """Frame-to-frame shake of lip points beyond that of reference points, per frame.

    Shake is the distance of a point from a local polynomial fit (degree ``order``) over
    ``window`` frames
    (Savitzky-Golay), so smooth movements, even fast ones, give ~0 and alternating or one-frame
    displacements give their size. Jitter the jaw (or a lip pellet) shows equally comes from the
    data and is no fault (thesis Table 5.8): the excess is the largest shake of ``points`` minus
    the largest shake of ``ref_points`` in that frame (>= 0). Parke units, (F,).
    """
    pos = np.asarray(pos, np.float64)
    F = pos.shape[0]
    if F < window:
        return np.zeros(F)
    lip = _shake(pos[:, np.asarray(points, np.int64)], window, order).max(axis=1)
    ref = _shake(pos[:, np.atleast_1d(np.asarray(ref_points, np.int64))], window, order).max(axis=1)
    return np.maximum(lip - ref, 0.0)


def corner_step_excess(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """Per frame i: how far the lip corners moved from frame i-1 beyond the jaw point's move,
    ``|step of the corner| - |step of the jaw point|`` (>= 0; 0 at the first frame), (F,)."""
    pos = np.asarray(pos, np.float64)
    out = np.zeros(pos.shape[0])
    if pos.shape[0] < 2:
        return out
    corners = np.asarray([parts.corner, parts.inner_corner])
    step = np.linalg.norm(pos[1:, corners] - pos[:-1, corners], axis=-1).max(axis=1)
    jstep = np.linalg.norm(pos[1:, parts.jaw_point] - pos[:-1, parts.jaw_point], axis=-1)
    out[1:] = np.maximum(step - jstep, 0.0)
    return out


def switch_jumps_from(excess: np.ndarray, branch) -> tuple[np.ndarray, np.ndarray]:
    """The corner jumps (:func:`corner_step_excess`) at the frames where a label changes.

    Parameters
    ----------
    excess : float (F,)
    branch : (F,) array-like or None
        A label per frame (the rubric passes the ``ellipse`` diagnostic, horizontal or
        vertical); None = no switches known.

    Returns
    -------
    jump : float (F,)
        The excess at frames where the branch differs from the previous frame, 0 elsewhere
        (Parke units).
    switches : int (S,)
        The switch frames.
    """
    excess = np.asarray(excess, np.float64)
    F = excess.shape[0]
    jump = np.zeros(F)
    if branch is None or F < 2:
        return jump, np.zeros(0, np.int64)
    b = np.asarray(branch)
    if b.shape[0] != F:
        return jump, np.zeros(0, np.int64)
    sw = np.flatnonzero(b[1:] != b[:-1]) + 1
    jump[sw] = excess[sw]
    return jump, sw


def switch_jumps(pos: np.ndarray, parts: MouthParts, branch) -> tuple[np.ndarray, np.ndarray]:
    """Jumps of the lip corners where a per-frame label changes (:func:`switch_jumps_from` of
    :func:`corner_step_excess`)."""
    return switch_jumps_from(corner_step_excess(pos, parts), branch)


# ----------------------------------------------------------------------------------------------
# Teeth and palate
# ----------------------------------------------------------------------------------------------

def palate_below_incisor(pos0: np.ndarray, parts: MouthParts) -> float:
    """How far the palatal outline reaches below the tip of the upper front teeth (226).

    ``pos0`` float (V, 3): the face at initialization. Parke units, >= 0 (thesis Table 5.4).
    """
    pos0 = np.asarray(pos0, np.float64)
    if len(parts.palate) == 0:
        return 0.0
    return float(max(pos0[parts.upper_incisor_tip, 2] - pos0[parts.palate, 2].min(), 0.0))


def teeth_overlap(pos: np.ndarray, parts: MouthParts) -> tuple[np.ndarray, np.ndarray]:
    """Vertical overlap of the front and of the back teeth per frame (Parke units).

    Front: ``z(lower incisor tip) - z(226)``; back: ``z(lower molar) - z(upper molar)``.
    Positive = the upper teeth cover the lower ones by that much (overbite); negative = gap.
    """
    pos = np.asarray(pos, np.float64)
    front = pos[:, parts.lower_incisor_tip, 2] - pos[:, parts.upper_incisor_tip, 2]
    back = pos[:, parts.lower_molar, 2] - pos[:, parts.upper_molar, 2]
    return front, back


def teeth_gap(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """Vertical gap between the front teeth, ``z(226) - z(lower incisor tip)``, per frame."""
    front, _ = teeth_overlap(pos, parts)
    return -front


def teeth_slope(pos: np.ndarray, parts: MouthParts) -> np.ndarray:
    """Slope of the lower occlusal line relative to the upper one, degrees, per frame.

    Lower line: lower molar -> lower incisor tip; upper: upper molar -> 226, both in the side
    view. Positive = the lower teeth slant upward toward the front (thesis Table 5.3).
    """
    pos = np.asarray(pos, np.float64)

    def ang(back, front):
        d = pos[:, front][:, [0, 2]] - pos[:, back][:, [0, 2]]
        return np.degrees(np.arctan2(d[:, 1], d[:, 0]))

    return (ang(parts.lower_molar, parts.lower_incisor_tip)
            - ang(parts.upper_molar, parts.upper_incisor_tip))
