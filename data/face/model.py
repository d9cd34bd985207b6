"""The Parke-compatible face model: :class:`FaceModel` and :func:`build_face`.

Conventions (thesis 3.1.1): X forward, Y to the face's left, Z up, Parke units
(:data:`cassi.data.face.numbering.MM_PER_UNIT` mm each). ``vertices[i]`` is vertex ``i + 1``. The
polygons describe the LEFT half (plus both eyes, which Parke does not mirror); the right half is
the mirror y -> -y (see :mod:`cassi.data.face.topology`). Numbering: :mod:`cassi.data.face.numbering`.

Files: ``st1.pts`` (base vertices: eyelids open), ``st2.pts`` (the second extremes used by
interpolation: eyelids closed) and ``stt.top`` (polygons), in Parke's formats
(:mod:`cassi.data.xrmb.parke_io`). Parke's own files load unchanged with :meth:`FaceModel.read`.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from os import PathLike
from pathlib import Path

import numpy as np

from cassi.data.face import numbering as N
from cassi.common.errors import CassiInputError
from cassi.data.face.build import (EYE_CENTRE, EYEBALL_RADIUS, MATERIAL_NAMES,
                                   PARKE_MATERIAL_NAMES, UNMIRRORED_MATERIALS, build_layout)
from cassi.data.xrmb.parke_io import (Polygon, PtsFile, TopFile, read_pts, read_top, write_pts,
                                 write_top)
from cassi.data.face.eyes import (SIDES, VERTS_PER_EYE, WHITE_RINGS_DEG, EyeParams,
                                  default_gaze_target, eyeball_polygons, place_eye)
from cassi.data.face.params import apply_parameters
from cassi.data.face.topology import RenderTopology, render_topology  # noqa: F401  (re-export)
from cassi.common.atomic import atomic_write_text

__all__ = ["FaceModel", "Material", "build_face", "parke_parameters", "RenderTopology",
           "render_topology", "default_gaze_target", "jaw_pellet_sites", "jaw_length_units",
           "subject_units_per_mm"]


def jaw_pellet_sites(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the face carries the jaw pellets (thesis 4.1.1): (x, z) of MANi (vertex 258) and of
    the MANm site (the midpoint of 281 and 286), each float (..., 2) for vertices (..., V, 3)."""
    v = np.asarray(vertices, np.float64)
    mani = v[..., N.MANI - 1, :][..., [0, 2]]
    a, b = (v[..., n - 1, :][..., [0, 2]] for n in N.MANM_PAIR)
    return mani, 0.5 * (a + b)


def jaw_length_units(vertices: np.ndarray) -> float:
    """Parke's jaw distance p (4.1.1): MANi to the MANm site in the x-z plane, as the XRMB
    pellets are measured; Parke units, for vertices (V, 3)."""
    mani, manm = jaw_pellet_sites(vertices)
    return float(np.hypot(*(mani - manm)))


def subject_units_per_mm(vertices: np.ndarray, jaw_length_mm: float) -> float:
    """p / d (thesis 4.1.1): Parke units per millimetre of a subject whose jaw length is d mm,
    on the face ``vertices`` (V, 3) whose jaw distance is p; the scale the pellets are mapped by
    (:class:`cassi.versions.mapping.XrmbToParke`)."""
    return jaw_length_units(vertices) / float(jaw_length_mm)


def parke_parameters(face: "FaceModel", values: dict[int, float] | None = None, *,
                     clamp: bool = False, gaze_target=None) -> "FaceModel":
    """``face`` with Parke's parameters (thesis Table 3.1 numbers -> values) applied; see
    :func:`cassi.data.face.params.apply_parameters`."""
    return apply_parameters(face, values or {}, clamp=clamp, gaze_target=gaze_target)


@dataclass(frozen=True)
class Material:
    """A material number's meaning: ``name`` is the render part (skin, lips, ...; the ``teeth``
    material renders as two parts, ``teeth_upper`` and ``teeth_lower``, see
    :mod:`cassi.data.face.topology`), ``parke_name`` Parke's word for it where he had one."""

    number: int
    name: str
    parke_name: str | None = None
    mirrored: bool = True


def default_materials() -> dict[int, Material]:
    return {n: Material(n, name, PARKE_MATERIAL_NAMES.get(n), n not in UNMIRRORED_MATERIALS)
            for n, name in MATERIAL_NAMES.items()}


@dataclass(frozen=True, eq=False)
class FaceModel:
    """A face in Parke's structure.

    Attributes
    ----------
    vertices : float64 (V, 3)
        The face as displayed (parameters applied), Parke units; row i is vertex i + 1.
    polygons : tuple[Polygon, ...]
        Material, 1-based vertex numbers (Parke's order: clockwise seen from outside), crease
        flags.
    materials : dict[int, Material]
    st1, st2 : float64 (V, 3)
        The two vertex sets of Parke's interpolation: st1 the base (eyelids open), st2 the
        second extremes (eyelids closed); equal where nothing is interpolated.
    eye_centres : float64 (2, 3)
        Left and right eyeball centres (empty (0, 3) for a model without eyes).
    eyes_first : int | None
        First vertex number of the eyeballs (left eye, then right), None without eyes.
    parameters : dict[int, float]
        Parke parameter values applied to get ``vertices`` (thesis Table 3.1 numbering).
    palate_mm : float64 (P, 2) | None
        The PAL.DAT outline the palate was built from (XRMB mm), None for the default palate.
    head_measures : object | None
        The subject's head measures as given (used by the versions' chin adjustment).
    jaw_length_mm : float | None
        The subject's jaw length d (MNI-MNM, mm) the face was built for, None for the model's
        own scale; :attr:`units_per_mm` follows from it.
    regions : dict[str, tuple[int, ...]]
        Vertex groups the generator names for the parameters (eyelid, eyelid_lip, brow,
        eye_socket, forehead, cheek, mouth_expression); empty for Parke's own files, where the
        parameters acting on them have no effect.
    """

    vertices: np.ndarray
    polygons: tuple[Polygon, ...]
    materials: dict[int, Material] = field(default_factory=default_materials)
    st1: np.ndarray | None = None
    st2: np.ndarray | None = None
    eye_centres: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    eyes_first: int | None = None
    parameters: dict[int, float] = field(default_factory=dict)
    palate_mm: np.ndarray | None = None
    head_measures: object | None = None
    jaw_length_mm: float | None = None
    description: str = "cassi-farm face"
    regions: dict[str, tuple[int, ...]] = field(default_factory=dict)

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices must be (V, 3), not {v.shape}")
        object.__setattr__(self, "vertices", v)
        for name in ("st1", "st2"):
            a = getattr(self, name)
            object.__setattr__(self, name, v.copy() if a is None else np.asarray(a, np.float64))
        object.__setattr__(self, "polygons", tuple(self.polygons))

    @property
    def vertex_count(self) -> int:
        return int(self.vertices.shape[0])

    @property
    def units_per_mm(self) -> float:
        """Parke units per millimetre of this face: p / d for a subject's face
        (:func:`subject_units_per_mm`), the model's nominal
        :data:`~cassi.data.face.numbering.UNITS_PER_MM` without a jaw length."""
        if self.jaw_length_mm is None:
            return float(N.UNITS_PER_MM)
        return subject_units_per_mm(self.vertices, self.jaw_length_mm)

    def vertex(self, number: int) -> np.ndarray:
        """Position (3,) of vertex ``number`` (1-based)."""
        if not 1 <= number <= self.vertex_count:
            raise IndexError(f"vertex {number} outside 1..{self.vertex_count}")
        return self.vertices[number - 1]

    def with_vertices(self, vertices: np.ndarray) -> "FaceModel":
        """The same face with other vertex positions (same numbering)."""
        v = np.asarray(vertices, np.float64)
        if v.shape != self.vertices.shape:
            raise ValueError(f"expected {self.vertices.shape}, got {v.shape}")
        return replace(self, vertices=v)

    def material_name(self, number: int) -> str:
        m = self.materials.get(number)
        return m.name if m is not None else f"material{number}"

    def polygons_of(self, name: str) -> list[Polygon]:
        return [p for p in self.polygons if self.material_name(p.material) == name]

    @property
    def jaw_length(self) -> float:
        """Parke's jaw distance p (4.1.1): from MANi (258) to the MANm site (midpoint of 281 and
        286), measured in the x-z plane as the XRMB pellets are."""
        return jaw_length_units(self.vertices)

    # --- files ------------------------------------------------------------------------------
    def write(self, directory: str | PathLike, *, st1_name="st1.pts", st2_name="st2.pts",
              top_name="stt.top") -> dict[str, Path]:
        """Write ``st1.pts``, ``st2.pts`` and ``stt.top`` into ``directory`` (atomically), plus
        ``cassi-face.json`` with what Parke's formats cannot hold (the named regions the
        parameters act on, the eyes, the subject's jaw length); :meth:`read` picks it up when it
        sits beside stt.top."""
        import json


        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        paths = {"st1": d / st1_name, "st2": d / st2_name, "top": d / top_name,
                 "meta": d / SIDECAR}
        write_pts(paths["st1"], PtsFile(f"st1.pts - {self.description}", self.st1))
        write_pts(paths["st2"], PtsFile(f"st2.pts - {self.description}", self.st2))
        write_top(paths["top"], TopFile(f"stt.top - {self.description}", self.polygons))
        meta = {"format": 1, "regions": {k: list(map(int, v)) for k, v in self.regions.items()},
                "eyes_first": self.eyes_first,
                "eye_centres": np.asarray(self.eye_centres).tolist(),
                "jaw_length_mm": self.jaw_length_mm}
        atomic_write_text(paths["meta"], json.dumps(meta, indent=1) + "\n")
        return paths

    @classmethod
    def read(cls, st1: str | PathLike, top: str | PathLike,
             st2: str | PathLike | None = None) -> "FaceModel":
        """Load a face from Parke-format files (Parke's own or ones written by :meth:`write`).

        Undefined vertices (Parke's st1.pts defines 275 of 287) stay NaN in ``st1``; in
        ``vertices`` they take st2's value where st2 defines them, else NaN. Polygons may not
        use a vertex that neither file defines.
        """
        p1 = read_pts(st1)
        t = read_top(top, vertex_count=p1.count)
        v2 = None
        if st2 is not None:
            p2 = read_pts(st2)
            if p2.count != p1.count:
                raise CassiInputError(f"st2 has {p2.count} vertices, st1 {p1.count}", path=st2)
            v2 = p2.vertices
        verts = p1.vertices.copy()
        if v2 is not None:
            fill = ~p1.defined & ~np.isnan(v2).any(axis=1)
            verts[fill] = v2[fill]
        used = np.unique(np.concatenate([np.asarray(p.vertices) for p in t.polygons])) \
            if t.polygons else np.zeros(0, int)
        missing = [int(u) for u in used if np.isnan(verts[u - 1]).any()]
        if missing:
            raise CassiInputError(f"polygons use undefined vertices {missing[:10]}", path=top)
        if v2 is None:
            v2 = p1.vertices.copy()
        else:
            v2 = np.where(np.isnan(v2), p1.vertices, v2)
        eyes_first = N.EYES_FIRST if p1.count >= N.EYES_FIRST - 1 + 2 * _verts_per_eye() \
            else None
        centres = np.zeros((0, 3))
        if eyes_first is not None:
            back = 1 + SIDES * (3 + len(WHITE_RINGS_DEG))
            cs = []
            for k in range(2):
                base = eyes_first - 1 + k * VERTS_PER_EYE
                cs.append(0.5 * (verts[base] + verts[base + back]))
            centres = np.array(cs)
        desc = p1.description
        regions, jaw = {}, None
        side = Path(top).parent / SIDECAR
        if side.is_file():
            regions, eyes_first, centres, jaw = _read_sidecar(side, p1.count, eyes_first, centres)
        return cls(verts, t.polygons, st1=p1.vertices, st2=v2, eye_centres=centres,
                   eyes_first=eyes_first, description=desc, regions=regions, jaw_length_mm=jaw)


#: Beside stt.top: what Parke's formats cannot hold (regions, eyes, the jaw length).
SIDECAR = "cassi-face.json"


def _read_sidecar(path: Path, count: int, eyes_first, centres):
    import json

    try:
        meta = json.loads(path.read_text())
        regions = {str(k): tuple(int(n) for n in v) for k, v in meta.get("regions", {}).items()}
        ef = meta.get("eyes_first", eyes_first)
        ef = None if ef is None else int(ef)
        ec = np.asarray(meta.get("eye_centres", centres), np.float64).reshape(-1, 3)
        jaw = meta.get("jaw_length_mm")
    except (ValueError, TypeError, AttributeError) as exc:
        raise CassiInputError(f"malformed face sidecar: {exc}", path=path) from None
    bad = [n for v in regions.values() for n in v if not 1 <= n <= count]
    if bad:
        raise CassiInputError(f"region vertex numbers outside 1..{count}: {bad[:5]}", path=path)
    if jaw is not None:
        if isinstance(jaw, bool) or not isinstance(jaw, (int, float)) or not (np.isfinite(jaw) and jaw > 0):
            raise CassiInputError(f"jaw_length_mm must be a positive number of mm or null, not {jaw!r}",
                                  path=path)
        jaw = float(jaw)
    return regions, ef, ec, jaw


def _verts_per_eye() -> int:
    return VERTS_PER_EYE


def build_face(*, palate_mm: np.ndarray | None = None, palate_xz: np.ndarray | None = None,
               head_measures=None, jaw_length_mm: float | None = None,
               parameters: dict[int, float] | None = None, clamp: bool = False) -> FaceModel:
    """The neutral face: Parke's structure generated from code, start parameter values applied.

    A subject's face comes from :func:`cassi.versions.mapping.subject_face`, which maps the
    subject's PAL.DAT outline onto the model with the one XRMB -> Parke mapping (thesis 4.1.1)
    and passes both forms here.

    Parameters
    ----------
    palate_mm : float (P, 2), optional
        The subject's PAL.DAT outline (XRMB mm), kept on the model for the versions.
    palate_xz : float (P, 2), optional
        The same outline on the model (Parke x, z), front to back, resampled to the fixed
        palate size; given with ``palate_mm``. Default: the generator's typical palate.
    head_measures : optional
        Stored on the model for the versions' chin and jaw adjustment (4.1.1); the neutral
        geometry does not use it.
    jaw_length_mm : float, optional
        The subject's jaw length d, kept on the model (:attr:`FaceModel.units_per_mm`); the
        geometry does not use it.
    parameters : dict[int, float], optional
        Parke parameters (Table 3.1 numbers) overriding the start values.
    clamp : bool
        Clamp out-of-range parameters instead of raising :class:`CassiInputError`.

    Returns
    -------
    FaceModel
        ``vertices`` float64 (V, 3) with V = 360 + two eyeballs.
    """
    if (palate_mm is None) != (palate_xz is None):
        raise CassiInputError("palate_mm and palate_xz go together (the outline and its place on "
                              "the model: cassi.versions.mapping.subject_face)")
    pal = None if palate_mm is None else np.asarray(palate_mm, dtype=np.float64)
    if palate_xz is not None:
        palate_xz = np.asarray(palate_xz, dtype=np.float64)
        if palate_xz.ndim != 2 or palate_xz.shape[1] != 2 or not np.isfinite(palate_xz).all():
            raise CassiInputError("palate_xz must be a finite (P, 2) array of Parke x, z")
    base = _base_face(palate_xz)
    face = replace(base, palate_mm=pal, head_measures=head_measures,
                   jaw_length_mm=None if jaw_length_mm is None else float(jaw_length_mm))
    return apply_parameters(face, parameters or {}, clamp=clamp)


_BASE_CACHE: dict = {}


def _base_face(palate_xz) -> FaceModel:
    """Geometry without parameters: st1 (eyelids open), st2 (closed), both eyes looking ahead."""
    key = None if palate_xz is None else np.asarray(palate_xz).tobytes()
    if key in _BASE_CACHE:
        return _BASE_CACHE[key]

    lay = build_layout(palate_xz=palate_xz)
    numbers = assign_numbers(lay)
    n_face = N.EYES_FIRST - 1
    V = n_face + 2 * VERTS_PER_EYE
    st1 = np.full((V, 3), np.nan)
    st2 = np.full((V, 3), np.nan)
    for key_, node in lay.nodes.items():
        n = numbers[key_]
        st1[n - 1] = node.pos
        st2[n - 1] = node.pos if node.closed is None else node.closed
    polys = [Polygon(m, tuple(numbers[k] for k in keys), cr) for m, keys, cr in lay.polys]
    centres = np.array([EYE_CENTRE, EYE_CENTRE * np.array([1.0, -1.0, 1.0])])
    target = default_gaze_target()
    for k in range(2):
        first = N.EYES_FIRST + k * VERTS_PER_EYE
        ev = place_eye(centres[k], target, EyeParams(radius=EYEBALL_RADIUS))
        st1[first - 1:first - 1 + VERTS_PER_EYE] = ev
        st2[first - 1:first - 1 + VERTS_PER_EYE] = ev
        polys += [Polygon(m, vs) for m, vs in eyeball_polygons(first)]
    if np.isnan(st1).any():
        missing = np.flatnonzero(np.isnan(st1).any(axis=1)) + 1
        raise AssertionError(f"face generator left vertices undefined: {missing.tolist()}")
    regions = {name: tuple(sorted(numbers[k] for k in keys))
               for name, keys in lay.regions.items()}
    # the cached base is shared by every build_face() call: never let a caller write into it
    st1.setflags(write=False)
    st2.setflags(write=False)
    centres.setflags(write=False)
    face = FaceModel(st1.copy(), tuple(polys), st1=st1, st2=st2, eye_centres=centres,
                     eyes_first=N.EYES_FIRST, regions=regions,
                     description="cassi-farm generated face (Parke's structure)")
    _BASE_CACHE[key] = face
    return face


#: Numbers the generator may use for vertices without a thesis name, in order.
FREE_NUMBERS = tuple(list(range(74, 80)) + list(range(102, 107)) + list(range(108, 223)))


def assign_numbers(lay) -> dict[str, int]:
    """Parke numbers for the layout's nodes: fixed ones as asked, pools in layout order.

    Raises AssertionError when the design does not use every number of a pool exactly (the
    numbering must be complete: every vertex 1..300 defined).
    """
    fixed = {k: n.want for k, n in lay.nodes.items() if isinstance(n.want, (int, np.integer))}
    used = set(fixed.values())
    if len(used) != len(fixed):
        dup = [v for v in used if list(fixed.values()).count(v) > 1]
        raise AssertionError(f"vertex numbers asked twice: {dup}")
    pools = {
        "jaw": [n for n in N.JAW if n not in used],
        "nose": [n for n in N.NOSE if n not in used],
        "free": [n for n in FREE_NUMBERS if n not in used],
    }
    out = dict(fixed)
    taken = {p: 0 for p in pools}
    for k, node in lay.nodes.items():
        if k in out:
            continue
        pool = node.want
        if pool not in pools:
            raise AssertionError(f"node {k}: unknown pool {pool!r}")
        i = taken[pool]
        if i >= len(pools[pool]):
            raise AssertionError(f"pool {pool!r} exhausted at node {k}")
        out[k] = pools[pool][i]
        taken[pool] = i + 1
    for pool, nums in pools.items():
        if taken[pool] != len(nums):
            raise AssertionError(f"pool {pool!r}: {len(nums) - taken[pool]} numbers unused "
                                 f"({nums[taken[pool]:][:8]}...)")
    return out
