"""The animated face as one binary glTF 2.0 file (.glb), for Blender and any glTF viewer.

Layout:

- one vertex array: the mirrored render topology merged as in
  :meth:`cassi.data.face.topology.RenderTopology.mesh` (same vertex order:
  :meth:`~cassi.data.face.topology.RenderTopology.merged_gather`), the neutral face;
- mesh 0 holds the parts that move, one primitive per part with a material of the part's
  colour (:func:`cassi.renderer.views.material_for`), and one morph target per kept frame: the
  position deltas from the neutral face, sparse (only the vertices that move in some frame, so
  one index list serves every target); mesh 1 holds the parts that never move (no targets);
- one animation: a weights channel on mesh 0's node, key k at the recording time of frame k,
  weight 1 on target k and 0 on the others (a sparse accessor, so it grows linearly with the
  frames), LINEAR interpolation (between keys, the positions interpolate linearly);
- axes: glTF is +Y up and looks at the face from +Z: glTF (x, y, z) = Parke (y, z, x) (a cyclic
  permutation, so triangle orientation is kept), in metres at ``mm_per_unit`` mm a Parke unit
  (the export passes the subject's d / p; default the model's nominal MM_PER_UNIT).

``quantize=True`` stores positions and deltas as int16 (KHR_mesh_quantization, declared in
extensionsUsed and extensionsRequired) on one grid whose step and origin sit in the root node's
scale and translation; a frame then decodes to within half a step of its float positions.
No normals are written: viewers compute them from the animated positions.
"""
from __future__ import annotations

import json
import os
import struct
from dataclasses import dataclass

import numpy as np

from cassi.common.atomic import atomic_write_bytes
from cassi.data.face.numbering import MM_PER_UNIT
from cassi.data.face.topology import RenderTopology
from cassi.renderer.views import material_for

__all__ = ["GlbSummary", "glb_bytes", "write_glb", "AXES",
           "QUANTIZATION"]

#: glTF axis i is Parke axis AXES[i].
AXES = (1, 2, 0)
QUANTIZATION = "KHR_mesh_quantization"
#: Largest quantised magnitude used (int16 holds 32767; the rest is room for rounding).
_QMAX = 32000

_FLOAT, _SHORT, _USHORT, _UINT = 5126, 5122, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_GLB_MAGIC, _JSON_CHUNK, _BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942


@dataclass(frozen=True)
class GlbSummary:
    """What a .glb holds and how big it is."""

    frames: int
    vertices: int          # merged render vertices
    moving_vertices: int   # vertices a morph target stores (sparse)
    quantized: bool
    step: float            # quantisation step, Parke units (0.0 for float32)
    bytes: int             # the whole file
    target_bytes_per_frame: int   # one morph target's stored deltas (BIN only)

    @property
    def bytes_per_frame(self) -> float:
        """The whole file over its frames (JSON, keys and the still mesh included)."""
        return self.bytes / self.frames


def _gltf_positions(positions: np.ndarray, gather: np.ndarray, sign: np.ndarray) -> np.ndarray:
    """Face positions (..., V, 3) -> merged, mirrored vertices (..., W, 3) on glTF axes, Parke
    units, float64."""
    p = np.asarray(positions, np.float64)[..., gather, :]
    p[..., 1] *= sign
    return p[..., list(AXES)]


class _Bin:
    """The BIN chunk, built as bufferViews, each 4-byte aligned, and the accessors into it."""

    def __init__(self):
        self.chunks: list[bytes] = []
        self.size = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def view(self, data: bytes, *, target: int | None = None, stride: int | None = None) -> int:
        view = {"buffer": 0, "byteOffset": self.size, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        if stride is not None:
            view["byteStride"] = stride
        self.chunks.append(data)
        pad = -len(data) % 4
        self.chunks.append(b"\0" * pad)
        self.size += len(data) + pad
        self.views.append(view)
        return len(self.views) - 1

    def accessor(self, **kw) -> int:
        """Add an accessor; its index."""
        self.accessors.append(kw)
        return len(self.accessors) - 1

    def data(self) -> bytes:
        return b"".join(self.chunks)


def _vec3_rows(values: np.ndarray, dtype) -> bytes:
    """(N, 3) as vertex-attribute rows: int16 rows are padded to 8 bytes (glTF aligns every
    vertex-attribute element to 4 bytes)."""
    v = np.ascontiguousarray(values, dtype)
    if v.dtype.itemsize == 2:
        v = np.concatenate([v, np.zeros((len(v), 1), v.dtype)], axis=1)
    return v.tobytes()


def _minmax(values: np.ndarray, quantized: bool) -> tuple[list, list]:
    conv = int if quantized else float
    return ([conv(x) for x in values.min(axis=0)], [conv(x) for x in values.max(axis=0)])


def glb_bytes(topology: RenderTopology, neutral: np.ndarray, positions: np.ndarray,
              times_s: np.ndarray, *, quantize: bool = True, name: str = "CASSI face",
              mm_per_unit: float = MM_PER_UNIT) -> tuple[bytes, GlbSummary]:
    """The .glb of ``positions`` float (F, V, 3) Parke units (face numbering) keyed at
    ``times_s`` (F,) seconds, as morph targets over ``neutral`` (V, 3).

    glTF lengths are metres: a Parke unit is ``mm_per_unit`` mm, the subject's own size when it
    is ``1 / face.units_per_mm`` (d / p, thesis 4.1.1), else the model's nominal scale."""
    neutral, positions, times, metres = _checked_inputs(topology, neutral, positions, times_s,
                                                        mm_per_unit)
    F = len(positions)
    gather, sign = topology.merged_gather()
    W = len(gather)
    grid = _grid(_gltf_positions(neutral, gather, sign), _gltf_positions(positions, gather, sign),
                 quantize, metres)
    moving = np.flatnonzero(np.any(grid.deltas != 0, axis=(0, 2)))

    _, tris, part_of = topology.mesh(neutral)
    part_names = list(topology.parts)
    buf = _Bin()
    pos_acc, index_acc = _mesh_accessors(buf, grid, tris, part_of, len(part_names))
    targets, per_frame = _morph_targets(buf, grid, moving)
    meshes, nodes = _meshes_and_nodes(name, _animated_parts(tris, part_of, moving, W, part_names),
                                      pos_acc, index_acc, targets, grid, metres)

    gltf: dict = {"asset": {"version": "2.0", "generator": "cassi-farm cassi export"},
                  "scene": 0, "scenes": [{"name": name, "nodes": [len(nodes) - 1]}],
                  "nodes": nodes, "meshes": meshes, "materials": _materials(part_names)}
    if targets:
        gltf["animations"] = _animation(buf, times)
    gltf["accessors"] = buf.accessors
    gltf["bufferViews"] = buf.views
    gltf["buffers"] = [{"byteLength": buf.size}]
    if quantize:
        gltf["extensionsUsed"] = [QUANTIZATION]
        gltf["extensionsRequired"] = [QUANTIZATION]

    text = json.dumps(gltf, separators=(",", ":")).encode()
    data = _glb(text, buf.data())
    return data, GlbSummary(frames=F, vertices=W, moving_vertices=int(len(moving)),
                            quantized=quantize, step=float(grid.step), bytes=len(data),
                            target_bytes_per_frame=int(per_frame))


def _checked_inputs(topology: RenderTopology, neutral, positions, times_s, mm_per_unit):
    """Refuse inputs a .glb cannot hold; the arrays as stored, and metres a Parke unit."""
    if not (np.isfinite(mm_per_unit) and mm_per_unit > 0):
        raise ValueError(f"mm_per_unit must be a positive number, not {mm_per_unit!r}")
    metres = float(mm_per_unit) / 1000.0
    # float32 like the positions, so that a vertex that does not move has a delta of exactly 0
    neutral = np.asarray(neutral, np.float32)
    positions = np.asarray(positions, np.float32)
    times = np.asarray(times_s, np.float64)
    V = topology.vertex_count
    if topology.half:
        raise ValueError("export the whole (mirrored) head, not the half topology")
    if positions.ndim != 3 or positions.shape[1:] != (V, 3) or not len(positions):
        raise ValueError(f"positions must be (F >= 1, {V}, 3), not {positions.shape}")
    if times.shape != (len(positions),) or np.any(np.diff(times) <= 0):
        raise ValueError("times_s must be one strictly increasing time per frame")
    if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(neutral))):
        raise ValueError("positions must be finite")
    F = len(positions)
    if F * F >= 2 ** 32:
        raise ValueError(f"{F} frames is too many for one weights accessor; use a stride")
    return neutral, positions, times, metres


@dataclass(frozen=True)
class _Grid:
    """The neutral face and the per-frame deltas as stored, and how to decode them."""

    quantized: bool
    origin: np.ndarray     # Parke units (zeros for float32)
    step: float            # Parke units (0.0 for float32)
    base: np.ndarray       # (W, 3) int16 grid steps, or float32 metres
    deltas: np.ndarray     # (F, W, 3) likewise
    ctype: int             # the glTF component type
    dtype: type


def _grid(base: np.ndarray, frames: np.ndarray, quantize: bool, metres: float) -> _Grid:
    """Store the neutral face and the deltas: int16 on one grid, or float32 metres."""
    if quantize:
        lo = np.minimum(base.min(axis=0), frames.min(axis=(0, 1)))
        hi = np.maximum(base.max(axis=0), frames.max(axis=(0, 1)))
        origin = (lo + hi) / 2
        # one grid for positions and deltas: both must fit in int16
        reach = max(float(np.max(hi - lo)) / 2, float(np.abs(frames - base).max()), 1e-9)
        step = reach / _QMAX
        q_base = np.rint((base - origin) / step)
        return _Grid(True, origin, step, q_base.astype(np.int16),
                     (np.rint((frames - origin) / step) - q_base).astype(np.int16),
                     _SHORT, np.int16)
    return _Grid(False, np.zeros(3), 0.0, (base * metres).astype(np.float32),
                 (frames * metres - base * metres).astype(np.float32), _FLOAT, np.float32)


def _animated_parts(tris: np.ndarray, part_of: np.ndarray, moving: np.ndarray, W: int,
                    part_names: list[str]) -> tuple[list[int], list[int]]:
    """Split the parts into those with a moving vertex and those that never move."""
    moving_set = np.zeros(W, bool)
    moving_set[moving] = True
    animated = [i for i in range(len(part_names)) if moving_set[tris[part_of == i]].any()]
    still = [i for i in range(len(part_names)) if i not in animated]
    return animated, still


def _mesh_accessors(buf: "_Bin", grid: _Grid, tris: np.ndarray, part_of: np.ndarray,
                    n_parts: int) -> tuple[int, list[int]]:
    """Write the neutral positions and each part's triangle indices; their accessors."""
    W = len(grid.base)
    pos_view = buf.view(_vec3_rows(grid.base, grid.dtype), target=_ARRAY_BUFFER,
                        stride=8 if grid.quantized else 12)
    lo_b, hi_b = _minmax(grid.base, grid.quantized)
    pos_acc = buf.accessor(bufferView=pos_view, componentType=grid.ctype, count=W, type="VEC3",
                           min=lo_b, max=hi_b)

    index_dtype, index_ctype = (np.uint16, _USHORT) if W < 65535 else (np.uint32, _UINT)
    index_view = buf.view(np.concatenate(
        [tris[part_of == i].ravel() for i in range(n_parts)]).astype(index_dtype).tobytes(),
        target=_ELEMENT_ARRAY_BUFFER)
    index_acc, offset = [], 0
    for i in range(n_parts):
        n = int((part_of == i).sum()) * 3
        index_acc.append(buf.accessor(bufferView=index_view, byteOffset=offset,
                                      componentType=index_ctype, count=n, type="SCALAR"))
        offset += n * np.dtype(index_dtype).itemsize
    return pos_acc, index_acc


def _morph_targets(buf: "_Bin", grid: _Grid, moving: np.ndarray) -> tuple[list[dict], int]:
    """Write one sparse morph target a frame; the targets and one target's stored bytes."""
    F, W = grid.deltas.shape[:2]
    targets: list[dict] = []
    if not len(moving):
        return targets, 0
    vdtype, deltas = grid.dtype, grid.deltas
    # one index list, the moving vertices, serves every target
    sp_dtype, sp_ctype = (np.uint16, _USHORT) if W <= 65535 else (np.uint32, _UINT)
    sp_view = buf.view(moving.astype(sp_dtype).tobytes())
    per_frame = len(moving) * 3 * np.dtype(vdtype).itemsize
    val_view = buf.view(np.ascontiguousarray(deltas[:, moving], vdtype).tobytes())
    for k in range(F):
        d = deltas[k, moving]
        lo_d, hi_d = _minmax(np.vstack([d, np.zeros((1, 3), vdtype)]) if len(moving) < W
                             else d, grid.quantized)
        targets.append({"POSITION": buf.accessor(
            componentType=grid.ctype, count=W, type="VEC3", min=lo_d, max=hi_d,
            sparse={"count": int(len(moving)),
                    "indices": {"bufferView": sp_view, "componentType": sp_ctype},
                    "values": {"bufferView": val_view, "byteOffset": k * per_frame}})})
    return targets, per_frame


def _materials(part_names: list[str]) -> list[dict]:
    """One PBR material a part, in the part's render colour."""
    materials = []
    for pname in part_names:
        m = material_for(pname)
        materials.append({"name": pname, "doubleSided": True, "pbrMetallicRoughness": {
            "baseColorFactor": [*map(float, m.rgb), 1.0], "metallicFactor": 0.0,
            "roughnessFactor": float(min(1.0, max(m.alpha, 0.05) ** 0.5))}})
    return materials


def _meshes_and_nodes(name: str, parts: tuple[list[int], list[int]], pos_acc: int,
                      index_acc: list[int], targets: list[dict], grid: _Grid,
                      metres: float) -> tuple[list[dict], list[dict]]:
    """The animated and the still mesh, a node each, under a root that holds the grid."""
    animated, still = parts

    def primitive(i: int, with_targets: bool) -> dict:
        prim = {"attributes": {"POSITION": pos_acc}, "indices": index_acc[i], "material": i,
                "mode": 4}
        if with_targets:
            prim["targets"] = targets
        return prim

    meshes, nodes, children = [], [], []
    if animated:
        mesh = {"name": "animated parts", "primitives": [primitive(i, bool(targets))
                                                         for i in animated]}
        if targets:
            F = len(targets)
            mesh["weights"] = [0.0] * F
            mesh["extras"] = {"targetNames": [f"frame {k}" for k in range(F)]}
        meshes.append(mesh)
    if still:
        meshes.append({"name": "still parts", "primitives": [primitive(i, False) for i in still]})
    for mi, mesh in enumerate(meshes):
        nodes.append({"name": mesh["name"], "mesh": mi})
        children.append(mi)
    root = {"name": name, "children": children}
    if grid.quantized:
        root["translation"] = [float(x * metres) for x in grid.origin]
        root["scale"] = [float(grid.step * metres)] * 3
    nodes.append(root)
    return meshes, nodes


def _animation(buf: "_Bin", times: np.ndarray) -> list[dict]:
    """Write the keys and the weights (1 on target k at key k, sparse); the one animation."""
    F = len(times)
    t = (times - times[0]).astype(np.float32)
    t_acc = buf.accessor(bufferView=buf.view(t.tobytes()), componentType=_FLOAT, count=F,
                         type="SCALAR", min=[float(t[0])], max=[float(t[-1])])
    diag = np.arange(F, dtype=np.uint64) * (F + 1)   # key k: weight 1 on target k
    w_acc = buf.accessor(componentType=_FLOAT, count=F * F, type="SCALAR", sparse={
        "count": F,
        "indices": {"bufferView": buf.view(diag.astype(np.uint32).tobytes()),
                    "componentType": _UINT},
        "values": {"bufferView": buf.view(np.ones(F, np.float32).tobytes())}})
    return [{"name": "task", "samplers": [
        {"input": t_acc, "output": w_acc, "interpolation": "LINEAR"}],
        "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}]


def _glb(text: bytes, binary: bytes) -> bytes:
    text += b" " * (-len(text) % 4)       # the JSON chunk pads with spaces, BIN with zeros
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    return b"".join([struct.pack("<III", _GLB_MAGIC, 2, total),
                     struct.pack("<II", len(text), _JSON_CHUNK), text,
                     struct.pack("<II", len(binary), _BIN_CHUNK), binary])


def write_glb(path: str | os.PathLike, topology: RenderTopology, neutral: np.ndarray,
              positions: np.ndarray, times_s: np.ndarray, *, quantize: bool = True,
              name: str = "CASSI face", mm_per_unit: float = MM_PER_UNIT) -> GlbSummary:
    """Write :func:`glb_bytes` to ``path`` atomically."""
    data, summary = glb_bytes(topology, neutral, positions, times_s, quantize=quantize, name=name,
                              mm_per_unit=mm_per_unit)
    atomic_write_bytes(path, data)
    return summary
