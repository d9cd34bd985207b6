"""``FaceRenderer``: one Mitsuba scene per (topology, view, preset), loaded once; per frame only the
vertex positions change.

Why: ``mi.load_dict`` per frame leaks memory and recompiles kernels (mitsuba issues 1890, 703);
writing ``<mesh id>.vertex_positions`` (and normals) through ``mi.traverse`` and calling ``params.update()``
once keeps the scene, the film, the sensors and hence the compiled kernels fixed, so a frame costs
a BVH refit plus the render itself.

Each frame gives the colour image (linear RGB), the part shown at each pixel and its distance
from the camera, from one pass of the ``aov`` integrator through the pixel centres (part id,
depth, surface normal). The ``preview`` preset shades its colour from that pass
(:mod:`cassi.renderer.shading`): one ray per pixel, no noise, the same bytes in every process.
In JIT variants one Dr.Jit kernel (:mod:`cassi.renderer.raycast`) traces the same rays and gives
part, depth, colour and its 8-bit sRGB encoding at once.
The ``final`` preset path-traces the colour in a second pass (same camera, same pixel grid).
"""
from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError

from cassi.renderer import raycast, scenes, shading
from cassi.renderer.variant import activate_variant, choose_variant
from cassi.renderer.views import Preset, View, mouth_box, preset as _preset, project, view as _view
from cassi.renderer.images import to_srgb8
from cassi.renderer.images import write_result

__all__ = ["RenderResult", "FaceRenderer", "part_triangles", "BACKGROUND"]

BACKGROUND = "background"


@dataclass(frozen=True)
class RenderResult:
    """One rendered frame of one view.

    Attributes
    ----------
    rgb : float32 (H, W, 3)
        Linear RGB radiance (scene-referred; 1.0 ~ diffuse white under the key light).
    mask : int32 (H, W)
        Part index per pixel: ``part_names[mask[i, j]]`` is the part the ray through the pixel
        centre hits first; 0 = background.
    depth : float32 (H, W)
        Distance along that ray from the camera to the surface, Parke units; ``inf`` where the
        ray hits nothing.
    part_names : tuple of str
        ``("background", part1, part2, ...)``.
    view, preset, variant : str
        What produced the image (recorded in every file written from it).
    srgb : uint8 (H, W, 3) or None
        ``images.to_srgb8(rgb)`` when the renderer computed it with the colour (raycast
        presets in JIT variants); read it through :meth:`srgb8`.
    """

    rgb: np.ndarray
    mask: np.ndarray
    depth: np.ndarray
    part_names: tuple[str, ...]
    view: str
    preset: str
    variant: str
    spp: int
    seed: int
    render_s: float = 0.0
    extra: dict = field(default_factory=dict)
    srgb: np.ndarray | None = None

    def srgb8(self) -> np.ndarray:
        """uint8 (H, W, 3): the colour sRGB-encoded, ``images.to_srgb8(rgb)`` (the renderer's
        kernel gives it in JIT variants; else it is computed here)."""
        if self.srgb is not None:
            return self.srgb
        return to_srgb8(self.rgb)

    def part_mask(self, part: str) -> np.ndarray:
        """bool (H, W): where ``part`` is the visible surface."""
        if part not in self.part_names:
            raise KeyError(f"no part {part!r}; parts: {', '.join(self.part_names[1:])}")
        return self.mask == self.part_names.index(part)

    def coverage(self) -> dict[str, float]:
        """Fraction of the image each part covers (background included)."""
        counts = np.bincount(self.mask.ravel(), minlength=len(self.part_names))
        return {name: float(c) / self.mask.size for name, c in zip(self.part_names, counts)}

    def metadata(self) -> dict:
        """What gets recorded with every image written from this result."""
        import mitsuba as mi
        return {"renderer": "cassi.renderer", "mitsuba": mi.__version__, "variant": self.variant,
                "view": self.view, "preset": self.preset, "spp": self.spp, "seed": self.seed,
                "width": int(self.rgb.shape[1]), "height": int(self.rgb.shape[0]),
                "part_names": list(self.part_names), **self.extra}


def part_triangles(topology) -> dict[str, np.ndarray]:
    """The per-part triangles of a render topology, as int (T, 3) zero-based into the part's
    expanded vertex array.

    Accepts ``topology.triangles`` (a mapping part -> triangles) or ``topology.parts`` (a mapping
    part -> object with ``.triangles``), which is how ``cassi.data.face.model.RenderTopology`` and the
    test meshes describe themselves.
    """
    tri = getattr(topology, "triangles", None)
    if isinstance(tri, Mapping):
        items = tri.items()
    else:
        parts = getattr(topology, "parts", None)
        if isinstance(parts, Mapping):
            items = ((k, getattr(v, "triangles", v)) for k, v in parts.items())
        else:
            raise TypeError("topology has neither a .triangles nor a .parts mapping")
    out = {}
    for name, t in items:
        t = np.asarray(t)
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"part {name!r}: triangles must be (T, 3), not {t.shape}")
        out[str(name)] = t.astype(np.int64)
    return out


def _near_offset(view: View, preset: Preset) -> np.ndarray:
    """float32 (H, W): distance from the eye to the near-clip plane along each pixel-centre ray."""
    h, w = preset.height, preset.width
    tan = np.tan(np.radians(view.camera.fov) / 2.0)  # fov_axis = y
    sx = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * tan * (w / h)
    sy = (1.0 - (np.arange(h) + 0.5) / h * 2.0) * tan
    cos = 1.0 / np.sqrt(1.0 + sx[None, :] ** 2 + sy[:, None] ** 2)
    return (view.camera.near_clip / cos).astype(np.float32)


#: Pixels around the projected vertices of :meth:`FaceRenderer.render_region`'s parts: a part's
#: pixels lie within its vertices' projection, and two pixels more hold the ring the image
#: measures keep around them (:func:`cassi.harness.rubric.image.read_box`) with a pixel to spare.
REGION_MARGIN = 2


class FaceRenderer:
    """Renders frames of one face topology from one view at one preset.

    Parameters
    ----------
    topology
        A ``cassi.data.face.model.RenderTopology`` (use ``half=True`` for the ``half`` view): per part
        triangles and ``expand(positions (V, 3)) -> dict[part, float32 (W, 3)]``.
    view, preset
        Names from :mod:`cassi.renderer.views` (or the objects).
    variant
        Mitsuba variant or None for :func:`choose_variant`.

    The scene is built on the first frame (its vertex counts, and for the ``top`` view the
    triangles kept below the clip plane, come from that frame) and never reloaded.
    """

    def __init__(self, topology, view: str | View = "front", preset: str | Preset = "preview",
                 variant: str | None = None):
        self.view = _view(view) if isinstance(view, str) else view
        self.preset = _preset(preset) if isinstance(preset, str) else preset
        self.variant = choose_variant(variant)
        half = getattr(topology, "half", None)
        if half is not None and bool(half) != self.view.half:
            raise CassiInputError(
                f"view {self.view.name!r} needs a {'half' if self.view.half else 'full'}-head "
                f"topology (render_topology(face, half={self.view.half}))")
        self.topology = topology
        self._triangles = part_triangles(topology)
        self._scene = None
        self._uploaded: dict[str, np.ndarray] = {}  # float32 positions per part now in the scene
        self.loads = 0  # how many times a scene was loaded (stays 1: tests check it)
        self._mouth_box = list(mouth_box(self.view, self.preset))  # fixed per view and preset

    # -- scene ---------------------------------------------------------------------------
    def _clip(self, expanded: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Triangles per part after the view's clip (top view: hide everything above the
        palate's top + margin; the palate itself is never clipped)."""
        tris = self._triangles
        margin = self.view.clip_above_palate
        if margin is None:
            return tris
        palate = [p for p in expanded if p.startswith("palate")]
        if not palate:
            return tris
        z_cut = max(float(np.max(expanded[p][:, 2])) for p in palate) + margin
        out = {}
        for part, t in tris.items():
            if part.startswith("palate") or len(t) == 0:
                out[part] = t
                continue
            centroid_z = expanded[part][t][:, :, 2].mean(axis=1)
            out[part] = t[centroid_z <= z_cut]
        return out

    def _load(self, expanded: dict[str, np.ndarray]) -> None:
        import drjit as dr
        import mitsuba as mi

        activate_variant(self.variant)
        missing = set(self._triangles) - set(expanded)
        if missing:
            raise ValueError(f"topology.expand gave no positions for parts {sorted(missing)}")
        tris = self._clip(expanded)
        parts = [part for part, t in tris.items() if len(t)]
        self.part_names = (BACKGROUND, *parts)
        # Path presets: one mesh per part (each its own material). Raycast presets never
        # evaluate a BSDF, so every part goes into one mesh and the triangle index says the
        # part: one mesh to refit per frame, and scalar_rgb's aov pass costs per shape.
        if self.preset.shading == "raycast":
            groups = {scenes.MERGED: parts}
        else:
            groups = {part: [part] for part in parts}
        self._groups = groups
        self._group_triangles = {}
        tri_part = []
        for name, members in groups.items():
            offsets = np.cumsum([0] + [len(expanded[m]) for m in members])
            self._group_triangles[name] = np.concatenate(
                [tris[m] + off for m, off in zip(members, offsets)])
            tri_part += [np.full(len(tris[m]), self.part_names.index(m), np.int32) for m in members]
        self._tri_part = np.concatenate(tri_part)  # part index of each merged triangle
        meshes = {name: scenes.part_mesh(name, self._group_positions(name, expanded),
                                         self._group_triangles[name])
                  for name in groups}
        self._scene = mi.load_dict(scenes.scene_dict(meshes, self.view, self.preset))
        self.loads += 1
        sensors = {s.id(): s for s in self._scene.sensors()}
        self._sensor_colour = sensors[scenes.SENSOR_COLOUR]
        self._sensor_mask = sensors[scenes.SENSOR_MASK]
        self._mask_integrator = mi.load_dict(scenes.mask_integrator_dict(look=self.preset.look))
        params = mi.traverse(self._scene)
        self._keys = {name: scenes.mesh_id(name) + ".vertex_positions" for name in groups}
        self._normal_keys = {name: scenes.mesh_id(name) + ".vertex_normals" for name in groups}
        self._uploaded = {name: self._group_positions(name, expanded).ravel() for name in groups}
        params.keep([*self._keys.values(), *self._normal_keys.values()])
        self._params = params
        self._buffer_type = {name: type(params[key]) for name, key in self._keys.items()}
        # The aov integrator's shape_index is the scene order + 1 in scalar variants and the
        # shape's registry id in JIT variants; map either to our part index via a lookup table
        # (for the merged mesh: to -1, "a hit: read the triangle's part").
        shapes = list(self._scene.shapes())
        by_id = {s.id(): s for s in shapes}
        raw = {}
        for name in groups:
            shape = by_id[scenes.mesh_id(name)]
            k = -1 if name == scenes.MERGED else self.part_names.index(name)
            if mi.variant().startswith("scalar"):
                raw[k] = shapes.index(shape) + 1
            else:
                raw[k] = int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(shape))[0])
        lut = np.zeros(max([0, *raw.values()]) + 2, np.int32)
        for k, r in raw.items():
            lut[r] = k
        self._lut = lut
        self._near_offset = _near_offset(self.view, self.preset)
        self._tables = shading.shading_tables(self.view, self.preset, self.part_names)
        # JIT variants: colour, sRGB, part and depth from one Dr.Jit kernel (renderer.raycast);
        # scalar_rgb keeps the aov pass with numpy shading (its Dr.Jit arrays are scalars).
        self._raycast = None
        if self.preset.shading == "raycast" and not mi.variant().startswith("scalar"):
            self._raycast = raycast.RaycastPass(
                self._scene, self._sensor_mask, by_id[scenes.mesh_id(scenes.MERGED)],
                self._tri_part, self._near_offset, self._tables, look=self.preset.look)

    def _group_positions(self, name: str, expanded: dict[str, np.ndarray]) -> np.ndarray:
        """float32 (W, 3): the vertices of one scene mesh (its parts' vertices in order)."""
        members = self._groups[name]
        if len(members) == 1:
            return np.ascontiguousarray(expanded[members[0]], np.float32)
        return np.concatenate([expanded[m] for m in members]).astype(np.float32)

    # -- per frame -------------------------------------------------------------------------
    def update(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        """Move the mesh to ``positions`` (float (V, 3), Parke units, FaceModel numbering);
        returns the parts' vertices (``topology.expand``)."""
        positions = np.asarray(positions)
        if positions.ndim != 2 or positions.shape[1] != 3:
            raise CassiInputError(f"positions must be (V, 3), not {positions.shape}")
        if not np.all(np.isfinite(positions)):
            raise CassiInputError("positions contain NaN or infinite values")
        expanded = self.topology.expand(positions)
        if self._scene is None:
            self._load(expanded)
            return expanded
        activate_variant(self.variant)
        changed = False
        for name, key in self._keys.items():
            verts = self._group_positions(name, expanded)
            flat = verts.ravel()
            # Meshes that did not move (eyes, palate, upper teeth in speech) are not
            # re-uploaded: fewer meshes to refit and re-normal per frame.
            if np.array_equal(flat, self._uploaded.get(name)):
                continue
            self._params[key] = self._buffer_type[name](flat)
            self._params[self._normal_keys[name]] = self._buffer_type[name](
                scenes.vertex_normals(verts, self._group_triangles[name]).ravel())
            self._uploaded[name] = flat
            changed = True
        if changed:
            self._params.update()
        return expanded

    def render_pass(self) -> np.ndarray:
        """The preset's one colour-giving ``mi.render`` of the current geometry, as Mitsuba
        returns it (the bare call ``cassi bench`` compares the pipeline with): the aov pass for
        raycast presets (which JIT variants replace by the :mod:`~cassi.renderer.raycast`
        kernel: same rays, colour included), the path-traced image for path presets."""
        import mitsuba as mi
        if self.preset.shading == "raycast":
            return mi.render(self._scene, integrator=self._mask_integrator,
                             sensor=self._sensor_mask, seed=0, spp=1)
        return mi.render(self._scene, sensor=self._sensor_colour, seed=self.preset.seed,
                         spp=self.preset.spp)

    def render_colour(self) -> np.ndarray:
        """float32 (H, W, 3) linear RGB of the current geometry."""
        if self.preset.shading == "raycast":
            return self.render_aov()[2]
        return np.asarray(self.render_pass(), dtype=np.float32)[..., :3]

    def render_aov(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(mask int32 (H, W), depth float32 (H, W), colour) of the current geometry from the
        one pass through the pixel centres; colour is the raycast shading (float32 (H, W, 3)
        linear RGB), or None for path presets."""
        mask, depth, colour, _ = self._one_pass()
        return mask, depth, colour

    def _one_pass(self):
        """render_aov's results and the sRGB colour when the kernel gave it (else None)."""
        import mitsuba as mi
        if self._raycast is not None:
            return self._raycast()
        aov = np.asarray(mi.render(self._scene, integrator=self._mask_integrator,
                                   sensor=self._sensor_mask, seed=0, spp=1), dtype=np.float32)
        raw = np.rint(aov[..., 1]).astype(np.int64)
        raw[(raw < 0) | (raw >= len(self._lut))] = len(self._lut) - 1  # unknown -> background
        mask = self._lut[raw]
        merged = mask < 0
        if merged.any():
            prim = np.rint(aov[..., 5][merged]).astype(np.int64)
            mask[merged] = self._tri_part[np.clip(prim, 0, len(self._tri_part) - 1)]
        # Mitsuba starts camera rays on the near-clip plane, so the aov distance lacks the
        # stretch from the eye to that plane: near_clip / cos(angle to the optical axis).
        depth = aov[..., 0] + self._near_offset
        depth[mask == 0] = np.inf
        colour = None
        if self.preset.shading == "raycast":
            colour = shading.shade(self._tables, mask, aov[..., 2:5])
        return mask, depth, colour, None

    def render_mask(self) -> tuple[np.ndarray, np.ndarray]:
        """(mask int32 (H, W), depth float32 (H, W)) of the current geometry."""
        mask, depth, _ = self.render_aov()
        return mask, depth

    def render_region(self, positions: np.ndarray, parts) -> tuple[np.ndarray, np.ndarray,
                                                                   tuple[int, int]]:
        """Part mask and depth of the frame's region that holds the parts for which ``parts``
        (a test of a part name) is true: ``(mask int32, depth float32, (row, column) of the
        region in the frame)``. The region is the parts' vertices projected into the view
        with a margin of :data:`REGION_MARGIN` pixels, clipped to the film; its pixels hold
        the very values of a whole frame's (the same rays), and no pixel of those parts lies
        outside it. Only the region's rays are traced and nothing is shaded: a frame whose
        picture nobody looks at (JIT variants; scalar_rgb renders the frame and crops it)."""
        expanded = self.update(positions)
        points = [expanded[p] for p in self.part_names[1:] if p in expanded and parts(p)]
        if not points:
            return np.zeros((0, 0), np.int32), np.zeros((0, 0), np.float32), (0, 0)
        px = project(self.view, self.preset, np.concatenate(points))
        h, w = self.preset.height, self.preset.width
        c0, r0 = np.floor(px.min(axis=0)).astype(int) - REGION_MARGIN
        c1, r1 = np.ceil(px.max(axis=0)).astype(int) + REGION_MARGIN + 1
        rows = range(min(h, max(0, int(r0))), max(0, min(h, int(r1))))
        cols = range(min(w, max(0, int(c0))), max(0, min(w, int(c1))))
        if self._raycast is not None:
            mask, depth = self._raycast.region(rows, cols)
        else:
            mask, depth = self.render_mask()
            mask, depth = mask[rows.start:rows.stop, cols.start:cols.stop], \
                depth[rows.start:rows.stop, cols.start:cols.stop]
        return mask, depth, (rows.start, cols.start)

    def render(self, positions: np.ndarray) -> RenderResult:
        """Render one frame: colour, mask and depth (one pass for raycast presets)."""
        t0 = time.perf_counter()
        self.update(positions)
        mask, depth, rgb, srgb = self._one_pass()
        if rgb is None:
            rgb = self.render_colour()
        return RenderResult(rgb=rgb, mask=mask, depth=depth, part_names=self.part_names, srgb=srgb,
                            view=self.view.name, preset=self.preset.name, variant=self.variant,
                            spp=self.preset.spp, seed=self.preset.seed,
                            render_s=time.perf_counter() - t0,
                            extra={"shading": self.preset.shading, "look": self.preset.look,
                                   "mouth_box": list(self._mouth_box)})

    def render_to_files(self, positions: np.ndarray, stem: str | Path, *, exr: bool = False,
                        png: bool = True, mask_png: bool = True, sidecar: bool = True,
                        extra: dict | None = None) -> RenderResult:
        """Render one frame and write it (synchronously) with :func:`images.write_result`:
        ``<stem>.png``, ``<stem>.mask.png``, ``<stem>.json`` and, with ``exr=True``, ``<stem>.exr``."""
        res = self.render(positions)
        if extra:
            res = dataclasses.replace(res, extra={**res.extra, **extra})
        write_result(res, stem, exr=exr, png=png, mask_png=mask_png, sidecar=sidecar)
        return res
