"""What the report's task viewer draws of one job: the animated face and the pellets, small.

The geometry stage writes it (output ``viewer``) from the positions it animated, so the report
never animates again and the viewer shows exactly the geometry the checks judged. One blob per
job (subject, task file, version), a deterministic ``.npz``:

- ``frames``, ``time_us`` int64 (K,): the recording rows kept (:func:`viewer_frames`);
- ``base`` float32 (V, 3): every vertex at the first kept frame, Parke units (face numbering);
- ``moving`` int32 (M,): the vertices that move in some kept frame; ``step`` float64: the
  quantisation step (Parke units); ``q0`` int16 (M, 3) their first frame and ``dq`` int16
  (K - 1, M, 3) frame-to-frame changes, both in steps, so that frame k is
  ``(q0 + dq[:k].sum(0)) * step`` to within half a step (0.008 mm at :data:`STEP_UNITS`);
  small changes deflate well, which is what makes the data small (docs/reports.md, the task viewer);
- ``gather`` int32 (W,), ``sign`` int8 (W,), ``triangles`` int32 (T, 3), ``part_of`` int16 (T,)
  and ``parts`` (P,) str: the render topology of the face the version animated, merged as in
  :meth:`cassi.data.face.topology.RenderTopology.mesh` (vertex w is face row gather[w], y times
  sign[w]);
- ``measured``, ``model`` float32 (K, 8, 2): the recorded pellets (NaN where not valid) and the
  model's pellet sites (:func:`cassi.harness.rubric.fidelity.virtual_pellets`), XRMB frame, mm,
  pellets in :data:`cassi.data.xrmb.files.PELLETS` order;
- ``units_per_mm`` float64 and ``xrmb_origin`` float64 (2,): the version's map from the XRMB
  frame to its face (:class:`cassi.versions.mapping.XrmbToParke`: Parke (x, z) = XRMB (x, y) *
  units_per_mm + xrmb_origin), which places the pellets in 3D and turns Parke units into mm
  (format 3; a format 2 blob has neither and reads as None).

The large arrays (:data:`DEFLATED`: ``dq``, ``triangles``, ``measured``, ``model``) are
stored as zlib streams of their little-endian bytes (``<name>_z`` uint8, ``<name>_shape``), made
once by the worker that animated the task: the report hands those bytes to the page as they are
(the browser's DecompressionStream("deflate") inflates them), so a night's report compresses
nothing again.
"""
from __future__ import annotations

import io
import zlib
from dataclasses import dataclass

import numpy as np

from cassi.data.face.topology import render_topology
from cassi.data.xrmb.files import PELLETS
from cassi.harness.farm.jobs import npz_bytes
from cassi.harness.rubric.fidelity import virtual_pellets
from cassi.versions.mapping import XrmbToParke

__all__ = ["VIEWER_FORMAT", "READABLE_FORMATS", "STEP_UNITS", "DEFLATED", "ViewerData",
           "viewer_blob", "read_viewer_blob"]

#: Bumped when the blob's arrays change meaning (it is part of the stage's outputs' digest
#: through the code hash; readers refuse other formats).
VIEWER_FORMAT = 3
#: Formats this reader still reads: 2 lacks the map (``units_per_mm``, ``xrmb_origin``).
READABLE_FORMATS = (2, VIEWER_FORMAT)
#: Quantisation step, Parke units: 1/16 unit = 0.016 mm (a tenth of XRMB's pellet noise), so
#: a kept frame is within 0.008 mm of the animated one; int16 then holds +-2048 units, more
#: than the head (about 925 units from chin to crown).
STEP_UNITS = 1.0 / 16.0
#: Arrays stored deflated, with their dtypes (little-endian).
DEFLATED = {"dq": "<i2", "triangles": "<i4", "measured": "<f4", "model": "<f4"}
#: zlib level of the deflated arrays: 6 is zlib's default, 16 % smaller than 1 on ``dq``.
ZLIB_LEVEL = 6


@dataclass(frozen=True)
class ViewerData:
    """A viewer blob, decoded (the arrays of the module docstring)."""

    frames: np.ndarray
    time_us: np.ndarray
    base: np.ndarray
    moving: np.ndarray
    step: float
    q0: np.ndarray
    dq: np.ndarray
    gather: np.ndarray
    sign: np.ndarray
    triangles: np.ndarray
    part_of: np.ndarray
    parts: tuple[str, ...]
    measured: np.ndarray
    model: np.ndarray
    #: The zlib streams of :data:`DEFLATED` arrays as stored (the report's page reads these).
    deflated: dict
    #: The version's XRMB -> Parke map: scale (Parke units per mm) and where the XRMB origin
    #: lands (Parke x, z); None in a format 2 blob.
    units_per_mm: float | None = None
    xrmb_origin: np.ndarray | None = None

    def positions(self) -> np.ndarray:
        """float32 (K, V, 3): every kept frame's vertices, dequantised."""
        q = np.concatenate([self.q0[None].astype(np.int64),
                            self.dq.astype(np.int64)]).cumsum(axis=0)
        out = np.repeat(self.base[None], len(self.frames), axis=0)
        out[:, self.moving] = (q * self.step).astype(np.float32)
        return out


def viewer_blob(face, positions: np.ndarray, frames: np.ndarray, time_us: np.ndarray,
                measured_mm: np.ndarray, valid: np.ndarray, jaw_length_mm: float) -> bytes:
    """The blob of one job.

    Parameters
    ----------
    face : FaceModel
        The face the version animated (its topology and the 4.1.1 mapping).
    positions : float (K, V, 3)
        The kept frames' vertices, Parke units.
    frames, time_us : int (K,)
        Their recording rows and times.
    measured_mm : float (K, 8, 2)
        The recording's pellets at those rows; ``valid`` bool (K,) whether each row's pellets
        are valid.
    jaw_length_mm : float
        The subject's jaw length (the mapping's scale, as Table F uses it).
    """
    pos = np.asarray(positions, np.float32)
    q = np.rint(pos.astype(np.float64) / STEP_UNITS)
    if np.abs(q).max(initial=0) > np.iinfo(np.int16).max:
        raise ValueError("positions beyond the viewer's int16 grid (+-2048 Parke units)")
    moving = np.flatnonzero(np.any(q != q[:1], axis=(0, 2))).astype(np.int32)
    qm = q[:, moving].astype(np.int16)
    topo = render_topology(face)
    _, tris, part_of = topo.mesh(np.asarray(face.vertices, np.float64))
    gather, sign = topo.merged_gather()
    mapping = XrmbToParke.from_face(face.vertices, jaw_length_mm)
    measured = np.asarray(measured_mm, np.float32).copy()
    measured[~np.asarray(valid, bool)] = np.nan
    big = {"dq": np.diff(qm, axis=0), "triangles": tris, "measured": measured,
           "model": virtual_pellets(pos, mapping)}
    packed = {}
    for name, a in big.items():
        a = np.ascontiguousarray(a, DEFLATED[name])
        packed[f"{name}_z"] = np.frombuffer(zlib.compress(a.tobytes(), ZLIB_LEVEL), np.uint8)
        packed[f"{name}_shape"] = np.asarray(a.shape, np.int64)
    return npz_bytes(
        format=np.int64(VIEWER_FORMAT),
        frames=np.asarray(frames, np.int64), time_us=np.asarray(time_us, np.int64),
        base=pos[0], moving=moving, step=np.float64(STEP_UNITS), q0=qm[0],
        units_per_mm=np.float64(mapping.scale), xrmb_origin=np.asarray(mapping.origin, np.float64),
        gather=gather.astype(np.int32), sign=sign.astype(np.int8),
        part_of=part_of.astype(np.int16), parts=np.asarray(topo.part_names, dtype=str),
        **packed)


def read_viewer_blob(data: bytes) -> ViewerData:
    """Decode :func:`viewer_blob`'s bytes (ValueError for a format not in
    :data:`READABLE_FORMATS`)."""
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        fmt = int(z["format"])
        if fmt not in READABLE_FORMATS:
            raise ValueError(f"viewer data format {fmt}, this cassi-farm reads "
                             f"{', '.join(map(str, READABLE_FORMATS))}")
        a = {k: z[k] for k in z.files if k != "format"}
    deflated = {}
    for name, dtype in DEFLATED.items():
        stream = a.pop(f"{name}_z").tobytes()
        shape = tuple(int(n) for n in a.pop(f"{name}_shape"))
        deflated[name] = stream
        a[name] = np.frombuffer(zlib.decompress(stream), dtype).reshape(shape)
    if a["model"].shape[1:] != (len(PELLETS), 2):
        raise ValueError(f"viewer data pellets are {a['model'].shape[1:]}, not ({len(PELLETS)}, 2)")
    scale = a.pop("units_per_mm", None)
    return ViewerData(**{**a, "step": float(a["step"]), "parts": tuple(str(p) for p in a["parts"]),
                         "deflated": deflated,
                         "units_per_mm": None if scale is None else float(scale)})
