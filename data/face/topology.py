"""Render topology: the mirrored, triangulated face, per part, with one gather per part.

Parke defines the left half; the right half is its mirror y -> -y (thesis 3.1.1). Eyes are the
exception (both are explicit, each looks at the target on its own). A :class:`RenderTopology`
is built once per face topology; per frame, :meth:`RenderTopology.expand` turns the face's
(V, 3) positions into each part's vertex array with a single fancy index and a sign flip, so
animation costs one gather per part.

Orientation: Parke's polygons run clockwise seen from outside (thesis Figures 3.2-3.3); the
render triangles here run counter-clockwise seen from outside (right-hand normals point out),
the mirrored copies included.

``half=True`` keeps the left half only (y >= 0): the head cut at the midsagittal plane, open at
y = 0, so that teeth, tongue and palate show in the half-face view.

The face's one ``teeth`` material becomes two render parts: ``teeth_upper`` (Parke's upper teeth,
vertices 223-254, 226 the upper incisor tip) and ``teeth_lower`` (255-286, moved by the jaw), so
that the masks tell the upper from the lower teeth exactly (lip centering in the front view);
the renderer gives both the ``teeth`` material (longest material name the part starts with).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cassi.data.face import numbering as N

#: Render parts, in a fixed order (materials map to these names). ``teeth_upper`` takes the
#: place the single ``teeth`` part had and ``teeth_lower`` comes last, so that every other part
#: keeps the mask id it had before the split (golden masks, masks of earlier runs).
PARTS = ("skin", "lips", "eyelash", "eyebrow", "teeth_upper", "tongue", "palate", "eye_white",
         "iris", "fringe", "pupil", "reflection", "teeth_lower")

#: The face material split into two render parts, and the parts.
TEETH_MATERIAL = "teeth"
TEETH_UPPER, TEETH_LOWER = "teeth_upper", "teeth_lower"

#: |y| below which a vertex counts as on the centre line (shared by both halves), Parke units.
MIDLINE_EPS = 1e-6


@dataclass(frozen=True, eq=False)
class Part:
    """One render part.

    Attributes
    ----------
    gather : int64 (W,)
        Row of the face's positions for each of the part's vertices.
    sign : float32 (W,)
        +1 for the left half (and explicit vertices), -1 for mirrored copies (y is negated).
    triangles : int64 (T, 3)
        Zero-based into the part's W vertices, counter-clockwise seen from outside.
    """

    gather: np.ndarray
    sign: np.ndarray
    triangles: np.ndarray


@dataclass(frozen=True, eq=False)
class RenderTopology:
    """Per part triangles of the mirrored (or half) head and their gathers."""

    parts: dict[str, Part]
    vertex_count: int
    half: bool = False
    part_names: tuple[str, ...] = field(default=())

    def __post_init__(self):
        if not self.part_names:
            object.__setattr__(self, "part_names", tuple(self.parts))

    @property
    def triangles(self) -> dict[str, np.ndarray]:
        return {k: p.triangles for k, p in self.parts.items()}

    def expand(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        """Positions (V, 3) in face numbering -> dict part -> float32 (W, 3)."""
        pos = np.asarray(positions)
        if pos.shape != (self.vertex_count, 3):
            raise ValueError(f"positions must be ({self.vertex_count}, 3), not {pos.shape}")
        out = {}
        for name, part in self.parts.items():
            v = pos[part.gather].astype(np.float32, copy=True)
            v[:, 1] *= part.sign
            out[name] = v
        return out

    def merged_gather(self) -> tuple[np.ndarray, np.ndarray]:
        """Face row (int64) and y sign (float64) of each merged vertex, in the order
        :meth:`mesh` gives them (first use, parts in order): what the glTF export and the
        report's viewer send instead of the merged vertices themselves."""
        seen: dict[tuple[int, float], int] = {}
        for part in self.parts.values():
            for g, s in zip(part.gather.tolist(), part.sign.tolist()):
                seen.setdefault((g, s), len(seen))
        keys = list(seen)
        return (np.asarray([k[0] for k in keys], np.int64),
                np.asarray([k[1] for k in keys], np.float64))

    def mesh(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """All parts as one mesh: vertices float64 (W, 3), triangles (T, 3) and the part index
        of each triangle (for tests and previews). Vertices shared between parts are merged
        (same gather row and sign)."""
        keys: dict[tuple[int, float], int] = {}
        verts, tris, part_of = [], [], []
        pos = np.asarray(positions, np.float64)
        for pi, (name, part) in enumerate(self.parts.items()):
            local = np.empty(len(part.gather), np.int64)
            for j, (g, s) in enumerate(zip(part.gather.tolist(), part.sign.tolist())):
                k = (g, s)
                if k not in keys:
                    keys[k] = len(verts)
                    p = pos[g].copy()
                    p[1] *= s
                    verts.append(p)
                local[j] = keys[k]
            tris.append(local[part.triangles])
            part_of.append(np.full(len(part.triangles), pi))
        return (np.asarray(verts).reshape(-1, 3), np.concatenate(tris).reshape(-1, 3),
                np.concatenate(part_of))


def _triangulate(vs: tuple[int, ...], pos: np.ndarray) -> list[tuple[int, int, int]]:
    """Split a polygon (face numbering, 0-based) into triangles keeping its order; quads are
    split along the shorter diagonal (fixed once for the topology)."""
    if len(vs) == 3:
        return [tuple(vs)]
    if len(vs) == 4:
        a, b, c, d = vs
        if np.linalg.norm(pos[a] - pos[c]) <= np.linalg.norm(pos[b] - pos[d]):
            return [(a, b, c), (a, c, d)]
        return [(a, b, d), (b, c, d)]
    return [(vs[0], vs[k], vs[k + 1]) for k in range(1, len(vs) - 1)]


def _teeth_part(vertex_numbers) -> str:
    """``teeth_lower`` for a teeth polygon whose vertices are all lower teeth (Parke's 255-286,
    the ones the jaw moves), else ``teeth_upper``."""
    lower = all(N.LOWER_TEETH_FIRST <= int(v) <= N.LOWER_TEETH_LAST for v in vertex_numbers)
    return TEETH_LOWER if lower else TEETH_UPPER


def render_topology(face, *, half: bool = False) -> RenderTopology:
    """Build the render topology of a :class:`cassi.data.face.model.FaceModel`.

    Parameters
    ----------
    face
        The face (its neutral ``vertices`` fix the centre line and the quads' diagonals).
    half
        Left half only (y >= 0), open at the midsagittal plane.
    """
    pos = np.asarray(face.vertices, np.float64)
    V = pos.shape[0]
    on_mid = np.abs(pos[:, 1]) < MIDLINE_EPS
    per_part: dict[str, list[tuple[int, int, int]]] = {}
    mirrored_part: dict[str, bool] = {}
    for poly in face.polygons:
        mat = face.materials.get(poly.material)
        name = mat.name if mat is not None else f"material{poly.material}"
        if name == TEETH_MATERIAL:
            name = _teeth_part(poly.vertices)
        mirrored = True if mat is None else bool(mat.mirrored)
        vs = tuple(int(v) - 1 for v in poly.vertices)
        if not mirrored and half and pos[list(vs), 1].mean() < 0:
            continue  # the right eye is not in the half view
        for t in _triangulate(vs, pos):
            per_part.setdefault(name, []).append(t)
        mirrored_part[name] = mirrored_part.get(name, True) and mirrored
    parts = {}
    order = [p for p in PARTS if p in per_part] + sorted(set(per_part) - set(PARTS))
    for name in order:
        tris = np.asarray(per_part[name], np.int64)
        # Parke's order is clockwise from outside: reverse to counter-clockwise
        tris = tris[:, ::-1]
        used = np.unique(tris)
        gather = list(used)
        sign = [1.0] * len(used)
        local = {int(g): i for i, g in enumerate(used)}
        out = [[local[int(v)] for v in t] for t in tris]
        if mirrored_part[name] and not half:
            mirror_local = {}
            for g in used:
                if on_mid[g]:
                    mirror_local[int(g)] = local[int(g)]
                else:
                    mirror_local[int(g)] = len(gather)
                    gather.append(int(g))
                    sign.append(-1.0)
            # mirroring reverses orientation: flip the order back
            out += [[mirror_local[int(t[2])], mirror_local[int(t[1])], mirror_local[int(t[0])]]
                    for t in tris]
        parts[name] = Part(np.asarray(gather, np.int64), np.asarray(sign, np.float32),
                           np.asarray(out, np.int64).reshape(-1, 3))
    return RenderTopology(parts, V, half=half)


# --- mesh checks (used by tests and the preview) -----------------------------------------------

def boundary_edges(triangles: np.ndarray) -> np.ndarray:
    """Edges (E, 2) used by exactly one triangle (the mesh's open boundary)."""
    t = np.asarray(triangles, np.int64)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    s = np.sort(e, axis=1)
    uniq, counts = np.unique(s, axis=0, return_counts=True)
    return uniq[counts == 1]


def nonmanifold_edges(triangles: np.ndarray) -> np.ndarray:
    """Edges (E, 2) used by more than two triangles."""
    t = np.asarray(triangles, np.int64)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    uniq, counts = np.unique(np.sort(e, axis=1), axis=0, return_counts=True)
    return uniq[counts > 2]


def inconsistent_edges(triangles: np.ndarray) -> np.ndarray:
    """Directed edges (E, 2) that two triangles traverse in the same direction (an orientation
    flip between neighbours)."""
    t = np.asarray(triangles, np.int64)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    uniq, counts = np.unique(e, axis=0, return_counts=True)
    return uniq[counts > 1]


def boundary_loops(triangles: np.ndarray) -> list[list[int]]:
    """The open boundary as closed loops of vertex indices."""
    edges = boundary_edges(triangles)
    nxt: dict[int, list[int]] = {}
    for a, b in edges.tolist():
        nxt.setdefault(a, []).append(b)
        nxt.setdefault(b, []).append(a)
    seen: set[tuple[int, int]] = set()
    loops = []
    for a, b in edges.tolist():
        if (min(a, b), max(a, b)) in seen:
            continue
        loop = [a]
        prev, cur = a, b
        seen.add((min(a, b), max(a, b)))
        while cur != a:
            loop.append(cur)
            cands = [n for n in nxt[cur] if (min(cur, n), max(cur, n)) not in seen]
            if not cands:
                break
            prev, cur = cur, cands[0]
            seen.add((min(prev, cur), max(prev, cur)))
        loops.append(loop)
    return loops


def signed_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """Signed volume (positive for outward counter-clockwise triangles of a closed surface)."""
    v = np.asarray(vertices, np.float64)
    t = np.asarray(triangles, np.int64)
    return float(np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6)
