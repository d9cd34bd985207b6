"""The raycast presets' one pass on JIT variants (llvm, cuda): one Dr.Jit kernel per frame.

Why: Mitsuba's ``aov`` integrator gives part id, depth and normal, but the colour, the sRGB
encoding and the part lookup were then computed in numpy, each a pass over the image and a copy
(about 7 ms of a 20 ms preview frame). Here the rays through the pixel centres (the same rays
the ``aov`` pass traces: :func:`pixel_centre_rays`) are built once per view, and each frame one
kernel intersects them with the scene and computes, per pixel, the part, the depth, the linear
colour (:func:`cassi.renderer.shading.shade_terms`, the formula the numpy path uses) and its
8-bit sRGB value (the table of :func:`cassi.renderer.images.to_srgb8`, so the bytes equal
``to_srgb8(rgb)`` exactly). The 8-bit colour and the part id travel packed in one 32-bit word
per pixel, so numpy receives them without a further pass.

Mask and depth are bit-identical to the ``aov`` pass's (same rays, same intersection routine);
the colour agrees with the numpy shading within float32 rounding (Dr.Jit's ``power`` differs
from libm's in the last bits), i.e. the same 8-bit values or one level apart.
"""
from __future__ import annotations

import numpy as np

from cassi.renderer import shading
from cassi.renderer.images import _LUT_STEPS, _SRGB8_LUT

__all__ = ["DrJitOps", "RaycastPass", "pixel_centre_rays"]


class DrJitOps:
    """Array operations of :func:`cassi.renderer.shading.shade_terms` on Dr.Jit arrays."""

    def __init__(self, active):
        import drjit as dr

        self._dr, self._active = dr, active

    def take(self, column, part):
        return self._dr.gather(type(column), column, part, self._active)

    def select(self, cond, a, b):
        return self._dr.select(cond, a, b)

    def maximum(self, a, b):
        return self._dr.maximum(a, b)

    def clip(self, a, lo, hi):
        return self._dr.clip(a, lo, hi)

    def power(self, a, b):
        return self._dr.power(a, b)

    def abs(self, a):
        return self._dr.abs(a)


def pixel_centre_rays(sensor, width: int, height: int):
    """The rays of ``sensor`` through every pixel centre, row-major, as Mitsuba's
    ``SamplingIntegrator`` makes them for a one-sample, unjittered ``stratified`` sampler
    (film position ``(pixel + 0.5) / size``, aperture sample 0.5, time 0)."""
    import drjit as dr
    import mitsuba as mi

    idx = dr.arange(mi.UInt32, width * height)
    pos = mi.Point2f(mi.Float(idx % width) + 0.5, mi.Float(idx // width) + 0.5)
    ray, _ = sensor.sample_ray(0.0, 0.0, pos * mi.ScalarVector2f(1.0 / width, 1.0 / height),
                               mi.Point2f(0.5))
    dr.eval(ray)
    return ray


class RaycastPass:
    """Part, depth and shaded colour of every pixel from one kernel (see the module docstring).

    Parameters
    ----------
    scene, sensor, mesh
        The loaded scene, its mask sensor and the one mesh that holds every part.
    tri_part : int (T,)
        Part index of each of the mesh's triangles.
    near_offset : float32 (H, W)
        Distance from the eye to the near-clip plane along each pixel's ray (Mitsuba starts
        camera rays there): added to the hit distance.
    tables
        :func:`cassi.renderer.shading.shading_tables` of the view, preset and parts.
    look : {"smooth", "flat"}
        Interpolated vertex normals or the triangle's own normal.
    """

    def __init__(self, scene, sensor, mesh, tri_part: np.ndarray, near_offset: np.ndarray,
                 tables: shading.ShadingTables, *, look: str = "smooth"):
        import drjit as dr
        import mitsuba as mi

        self.height, self.width = near_offset.shape
        if len(tables.diffuse) > 255:
            raise ValueError("more than 255 parts: the part id travels in 8 bits")
        self._scene, self._flat = scene, look == "flat"
        self._ray = pixel_centre_rays(sensor, self.width, self.height)
        self._mesh_id = int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(mesh))[0])
        f = mi.Float
        self._tri_part = mi.UInt32(np.asarray(tri_part, np.uint32))
        self._near = f(np.ascontiguousarray(near_offset, np.float32).ravel())
        self._view = tuple(f(np.ascontiguousarray(tables.view_dirs[..., k]).ravel()) for k in range(3))
        self._half = tuple(f(np.ascontiguousarray(tables.half_norm[..., k]).ravel())
                           for k in range(tables.half_norm.shape[2]))
        self._columns = shading.columns(tables, convert=lambda a: f(np.asarray(a, np.float32)))
        self._background = [float(c) for c in tables.background]
        self._lut = mi.UInt32(_SRGB8_LUT.astype(np.uint32))
        dr.eval(self._tri_part, self._near, self._view, self._half, self._lut,
                self._columns.ambient_rgb, self._columns.diffuse, self._columns.specular,
                self._columns.shininess)

    def kernel(self):
        """The frame's Dr.Jit outputs, evaluated: (packed UInt32 per pixel: sRGB R, G, B and the
        part id in its four bytes; depth Float; linear R, G, B Floats)."""
        import drjit as dr
        import mitsuba as mi

        si = self._scene.ray_intersect(self._ray, mi.RayFlags.All, coherent=True)
        hit = si.is_valid() & (dr.reinterpret_array(mi.UInt32, si.shape) == self._mesh_id)
        part = dr.select(hit, dr.gather(mi.UInt32, self._tri_part, si.prim_index, hit), 0)
        depth = dr.select(hit, si.t + self._near, dr.inf)
        n = si.n if self._flat else si.sh_frame.n
        rgb = shading.shade_terms(DrJitOps(hit), self._columns, part, (n.x, n.y, n.z),
                                  self._view, self._half)
        rgb = [dr.select(hit, v, b) for v, b in zip(rgb, self._background)]
        # to_srgb8's table, indexed exactly as it is (clip, scale, round half to even)
        q = [dr.gather(mi.UInt32, self._lut,
                       mi.UInt32(dr.round(dr.clip(v, 0.0, 1.0) * float(_LUT_STEPS))))
             for v in rgb]
        packed = q[0] | (q[1] << 8) | (q[2] << 16) | (part << 24)
        dr.eval(packed, depth, rgb)
        return packed, depth, rgb

    def region(self, rows: range, cols: range) -> tuple[np.ndarray, np.ndarray]:
        """(mask int32, depth float32) of the pixels ``rows`` x ``cols`` only: the same rays
        as the whole frame's (gathered from them), so the same values, without the shading."""
        import drjit as dr
        import mitsuba as mi

        idx = (np.arange(rows.start, rows.stop)[:, None] * self.width
               + np.arange(cols.start, cols.stop)[None, :]).ravel()
        shape = (len(rows), len(cols))
        if not idx.size:
            return np.zeros(shape, np.int32), np.full(shape, np.inf, np.float32)
        idx = mi.UInt32(idx.astype(np.uint32))
        ray = dr.gather(type(self._ray), self._ray, idx)
        pi = self._scene.ray_intersect_preliminary(ray, coherent=True)
        hit = pi.is_valid() & (dr.reinterpret_array(mi.UInt32, pi.shape) == self._mesh_id)
        part = dr.select(hit, dr.gather(mi.UInt32, self._tri_part, pi.prim_index, hit), 0)
        depth = dr.select(hit, pi.t + dr.gather(mi.Float, self._near, idx), dr.inf)
        dr.eval(part, depth)
        return (np.asarray(part).astype(np.int32).reshape(shape),
                np.asarray(depth).reshape(shape))

    def __call__(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(mask int32 (H, W), depth float32 (H, W), linear rgb float32 (H, W, 3),
        srgb uint8 (H, W, 3)) of the scene's current geometry."""
        packed, depth, rgb = self.kernel()
        h, w = self.height, self.width
        words = np.asarray(packed).astype("<u4", copy=False).view(np.uint8).reshape(h, w, 4)
        mask = words[..., 3].astype(np.int32)
        srgb = words[..., :3]  # a view (the PNG encoder copies it once, as it must)
        colour = np.stack([np.asarray(v) for v in rgb], axis=-1).reshape(h, w, 3)
        return mask, np.asarray(depth).reshape(h, w), colour, srgb
