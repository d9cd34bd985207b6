"""Every Mitsuba scene dictionary of the renderer, built in this one module.

The ids chosen here become the keys of ``mi.traverse``; they are fixed on purpose:

- ``mesh_<part>``: one triangle mesh per face part in path-traced presets (each with its
  material), or one ``mesh_parts`` holding every part in raycast presets (no BSDF is evaluated
  there; the aov pass's triangle index says the part); ``.vertex_positions`` and
  ``.vertex_normals`` are what the renderer rewrites each frame;
- ``sensor_colour``: the camera with the preset's film and an ``multijitter`` sampler (its seed
  is the preset's, so a render is reproducible);
- ``sensor_mask``: the same camera and film size with a ``stratified`` sampler, one sample per
  pixel and ``jitter=False``, i.e. exactly one ray through each pixel's centre, and a box filter:
  the mask and depth it gives are exact per pixel and aligned with the colour image (same camera,
  same pixel grid);
- ``light_key``, ``light_fill``, ``light_rim``: rectangular area lights; ``ambient``: a dim
  constant environment (also the image background). The raycast preview shades with the same
  lights as directional ones (:mod:`cassi.renderer.shading`).

All functions need Mitsuba's variant to be set already (``variant.activate_variant``).
"""
from __future__ import annotations

import numpy as np

from cassi.renderer.views import Preset, View, material_for

__all__ = ["mesh_id", "part_mesh", "vertex_normals", "sensor_dict", "emitter_dicts",
           "colour_integrator_dict", "mask_integrator_dict", "scene_dict", "SENSOR_COLOUR",
           "SENSOR_MASK"]

SENSOR_COLOUR = "sensor_colour"
#: The one mesh of the raycast presets, holding every part (the triangle index says which).
MERGED = "parts"
SENSOR_MASK = "sensor_mask"
_MESH_PREFIX = "mesh_"


def mesh_id(part: str) -> str:
    """The scene id (and ``mi.traverse`` key prefix) of a part's mesh."""
    return _MESH_PREFIX + part


def vertex_normals(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """float32 (W, 3) unit vertex normals: the area-weighted mean of the adjacent triangles'
    normals; (0, 0, 1) for a vertex no triangle uses.

    Computed here rather than by Mitsuba, whose recomputation in JIT variants sums in parallel
    and varies in the last bits from frame to frame; this sum has a fixed order, so a frame
    renders to the same bits however often and in whatever order it is rendered.
    """
    p = np.asarray(positions, np.float64)
    t = np.asarray(triangles, np.int64)
    face = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])  # length = 2 x area
    idx = t.ravel()
    w = np.repeat(face, 3, axis=0)
    n = np.stack([np.bincount(idx, weights=w[:, k], minlength=len(p)) for k in range(3)], axis=1)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    out = np.where(length > 0, n / np.where(length > 0, length, 1.0), (0.0, 0.0, 1.0))
    return out.astype(np.float32)


def part_mesh(part: str, positions: np.ndarray, triangles: np.ndarray):
    """A Mitsuba mesh for one part, with smooth vertex normals (:func:`vertex_normals`).

    Parameters
    ----------
    positions : float (W, 3)
        Vertex positions in Parke units.
    triangles : int (T, 3)
        Zero-based indices into ``positions``; T >= 1.

    The renderer writes the normals with the positions every frame (``<mesh id>.vertex_normals``).
    """
    import mitsuba as mi

    props = mi.Properties()
    props["bsdf"] = mi.load_dict(material_for(part).bsdf())
    mesh = mi.Mesh(mesh_id(part), int(len(positions)), int(len(triangles)), props=props,
                   has_vertex_normals=True)
    params = mi.traverse(mesh)
    vp, fc, vn = params["vertex_positions"], params["faces"], params["vertex_normals"]
    params["vertex_positions"] = type(vp)(np.ascontiguousarray(positions, np.float32).ravel())
    params["faces"] = type(fc)(np.ascontiguousarray(triangles, np.uint32).ravel())
    params["vertex_normals"] = type(vn)(vertex_normals(positions, triangles).ravel())
    params.update()
    return mesh


def _to_world(origin, target, up):
    import mitsuba as mi
    return mi.ScalarTransform4f().look_at(origin=list(map(float, origin)),
                                          target=list(map(float, target)),
                                          up=list(map(float, up)))


def sensor_dict(view: View, preset: Preset, *, mask: bool) -> dict:
    """The camera of ``view`` with the film of ``preset``; ``mask=True`` for the mask sensor."""
    cam = view.camera
    film = {"type": "hdrfilm", "width": preset.width, "height": preset.height,
            "pixel_format": "rgb", "component_format": "float32",
            "rfilter": {"type": "box" if mask else preset.rfilter}}
    if mask:
        sampler = {"type": "stratified", "sample_count": 1, "jitter": False}
    else:
        # multijitter: half the noise of independent sampling at the same cost (4 spp).
        sampler = {"type": "multijitter", "sample_count": preset.spp, "seed": preset.seed}
    return {"type": "perspective", "fov": cam.fov, "fov_axis": "y",
            "near_clip": cam.near_clip, "far_clip": cam.far_clip,
            "to_world": _to_world(cam.origin, cam.target, cam.up),
            "film": film, "sampler": sampler}


def emitter_dicts(view: View) -> dict[str, dict]:
    """The view's studio lights (placed in its camera frame) and the ambient environment."""
    import mitsuba as mi

    cam = view.camera
    right, up, back = cam.basis()
    target = np.asarray(cam.target, float)
    out: dict[str, dict] = {}
    for light in view.lights:
        pos = target + cam.distance * (light.offset[0] * right + light.offset[1] * up
                                       + light.offset[2] * back)
        half = 0.5 * light.size * cam.distance
        # A rectangle emits along its local +z; look_at turns +z toward the camera target.
        to_world = _to_world(pos, target, up) @ mi.ScalarTransform4f().scale([half, half, 1.0])
        out["light_" + light.name] = {
            "type": "rectangle", "to_world": to_world,
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": list(light.radiance)}}}
    out["ambient"] = {"type": "constant",
                      "radiance": {"type": "rgb", "value": [view.ambient] * 3}}
    return out


def colour_integrator_dict(preset: Preset) -> dict:
    return {"type": "path", "max_depth": preset.max_depth}


#: Channels of the aov pass, in order: distance along the ray, shape index (a registry id in
#: JIT variants, scene order + 1 in scalar ones; 0 = no hit), surface normal x, y, z (world),
#: triangle index within the shape.
AOV_CHANNELS = ("depth", "shape_index", "nx", "ny", "nz", "prim_index")


def mask_integrator_dict(*, look: str = "smooth") -> dict:
    """The aov integrator of the one pass through the pixel centres: depth, shape index and the
    shading normal (``look="smooth"``) or the geometric one (``"flat"``); see AOV_CHANNELS."""
    normal = "sh_normal" if look == "smooth" else "geo_normal"
    return {"type": "aov", "aovs": f"dd.y:depth,si:shape_index,n:{normal},pi:prim_index"}


def scene_dict(meshes: dict[str, object], view: View, preset: Preset) -> dict:
    """The complete scene of one (topology, view, preset): part meshes, both sensors, lights.

    ``meshes`` maps part name -> Mitsuba mesh from :func:`part_mesh`.
    """
    scene: dict = {"type": "scene", "integrator": colour_integrator_dict(preset),
                   SENSOR_COLOUR: sensor_dict(view, preset, mask=False),
                   SENSOR_MASK: sensor_dict(view, preset, mask=True)}
    scene.update(emitter_dicts(view))
    for part, mesh in meshes.items():
        scene[mesh_id(part)] = mesh
    return scene
