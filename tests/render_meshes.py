"""Small meshes for the renderer tests, independent of cassi.data.face.model.

``SimpleTopology`` follows the RenderTopology protocol the renderer uses: ``triangles`` (part ->
int (T, 3)), ``expand(positions (V, 3)) -> dict[part, float32 (W, 3)]`` (one gather per part) and
``half``. ``toy_head`` builds a head-shaped set of parts in Parke units and axes (X forward, Y
left, Z up) so that every view has something to show.
"""
from __future__ import annotations

import numpy as np


class SimpleTopology:
    def __init__(self, parts: dict[str, tuple[np.ndarray, np.ndarray]], half: bool = False):
        # parts: name -> (gather int (W,), triangles int (T, 3) into the gathered array)
        self._gather = {k: np.asarray(g, np.int64) for k, (g, _) in parts.items()}
        self.triangles = {k: np.asarray(t, np.int64) for k, (_, t) in parts.items()}
        self.half = half

    def expand(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        p = np.asarray(positions, np.float32)
        return {k: p[g] for k, g in self._gather.items()}


def quad(v0, v1, v2, v3):
    return np.array([v0, v1, v2, v3], float), np.array([[0, 1, 2], [0, 2, 3]])


def ellipsoid(center, radii, n_u=24, n_v=16, y_min=None):
    """UV ellipsoid: vertices (N, 3), triangles (T, 3). ``y_min=0`` keeps the left half only
    (open at y = 0)."""
    u = np.linspace(0, 2 * np.pi, n_u, endpoint=False)
    v = np.linspace(0, np.pi, n_v + 1)[1:-1]
    uu, vv = np.meshgrid(u, v, indexing="ij")
    pts = np.stack([np.cos(uu) * np.sin(vv), np.sin(uu) * np.sin(vv), np.cos(vv)], -1).reshape(-1, 3)
    pts = np.vstack([pts, [[0, 0, 1], [0, 0, -1]]])
    pts = pts * np.asarray(radii) + np.asarray(center)
    nv = len(v)
    top, bot = n_u * nv, n_u * nv + 1
    tris = []
    for i in range(n_u):
        j = (i + 1) % n_u
        for k in range(nv - 1):
            a, b, c, d = i * nv + k, j * nv + k, j * nv + k + 1, i * nv + k + 1
            tris += [[a, b, c], [a, c, d]]
        tris += [[top, j * nv, i * nv], [bot, i * nv + nv - 1, j * nv + nv - 1]]
    tris = np.array(tris)
    if y_min is not None:
        keep = pts[tris][:, :, 1].mean(axis=1) >= y_min
        tris = tris[keep]
    return pts, tris


def toy_head(half: bool = False) -> tuple[SimpleTopology, np.ndarray]:
    """A toy head: skin (ellipsoid), lips, teeth, tongue, palate, two eyes (one when ``half``).

    Returns the topology and the positions (V, 3) of all its vertices (the same V for the full
    and the half head, like RenderTopology).
    """
    y_min = 0.0 if half else None
    blocks: list[tuple[str, np.ndarray, np.ndarray]] = []
    blocks.append(("skin", *ellipsoid((60, 0, -120), (330, 270, 470), 28, 18, y_min)))
    blocks.append(("lips", *ellipsoid((385, 0, -290), (40, 110, 45), 16, 8, y_min)))
    blocks.append(("teeth", *ellipsoid((330, 0, -285), (35, 95, 40), 12, 6, y_min)))
    blocks.append(("tongue", *ellipsoid((230, 0, -320), (110, 80, 25), 12, 6, y_min)))
    blocks.append(("palate", *ellipsoid((240, 0, -235), (120, 90, 20), 12, 6, y_min)))
    for k, c in enumerate([(300, 110, 60), (300, -110, 60)]):
        blocks.append((f"eye_white{k}", *ellipsoid(c, (40, 40, 40), 12, 8)))
        blocks.append((f"iris{k}", *ellipsoid((c[0] + 36, c[1], c[2]), (8, 18, 18), 10, 6)))
    positions, parts, offset = [], {}, 0
    for name, pts, tris in blocks:
        positions.append(pts)
        if half and name.endswith("1"):  # the right eye is not in the half head
            offset += len(pts)
            continue
        gather = np.arange(offset, offset + len(pts))
        if name in parts:  # same part name twice: merge
            g0, t0 = parts[name]
            parts[name] = (np.concatenate([g0, gather]), np.vstack([t0, tris + len(g0)]))
        else:
            parts[name] = (gather, tris)
        offset += len(pts)
    return SimpleTopology(parts, half=half), np.vstack(positions)
