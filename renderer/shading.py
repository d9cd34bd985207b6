"""The raycast preview's colour, computed from the one ``aov`` pass that also gives mask and depth.

Why: a path-traced 4-spp preview costs 10-20 times the aov pass and its Monte Carlo noise is not
reproducible across processes, so golden images could only be compared after a blur. Shading
the aov pass (part id and shading normal through each pixel centre) gives colour, mask and depth
from one ray per pixel, exactly aligned, with no sampling at all: the same bytes in every run,
process and machine of one variant.

The formula is written once (:func:`shade_terms`) over an array namespace: :func:`shade` runs it
in numpy on the aov pass's outputs (scalar variants), :mod:`cassi.renderer.raycast` inside its
Dr.Jit kernel (llvm, cuda), where the same numbers come out without a pass over numpy arrays.

The model is the fixed-function one of the thesis's SGI display: per part a Lambert term plus a
Blinn-Phong highlight (:class:`~cassi.renderer.views.Material`), the view's studio lights as
directional lights (no shadows) and the view's ambient level, with smooth (interpolated vertex
normals) or flat (one normal per triangle) look. Surfaces are two-sided: a normal facing away
from the camera is flipped, as the path tracer's two-sided BSDFs do.

Light strength: a rectangle light of side ``size * d`` and radiance ``L`` at distance
``|offset| * d`` from the camera target subtends about ``size^2 / |offset|^2`` sr there, so it
gives the irradiance ``L * size^2 / |offset|^2`` (W m^-2, linear RGB) along its direction; the
preview is therefore about as bright as the path-traced ``final`` preset, without its shadows and
interreflections.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.renderer.views import Material, Preset, View, material_for

__all__ = ["ShadingTables", "shading_tables", "shade", "shade_terms", "columns", "NumpyOps",
           "pixel_directions"]


def pixel_directions(view: View, preset: Preset) -> np.ndarray:
    """float32 (H, W, 3): the unit direction of the ray through each pixel centre, world space."""
    h, w = preset.height, preset.width
    tan = np.tan(np.radians(view.camera.fov) / 2.0)  # fov_axis = y
    sx = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * tan * (w / h)
    sy = (1.0 - (np.arange(h) + 0.5) / h * 2.0) * tan
    right, up, back = view.camera.basis()
    d = (sx[None, :, None] * right + sy[:, None, None] * up - back).astype(np.float64)
    d /= np.linalg.norm(d, axis=2, keepdims=True)
    return d.astype(np.float32)


@dataclass(frozen=True)
class ShadingTables:
    """Everything of a (view, preset, parts) that is the same for every frame.

    Attributes
    ----------
    diffuse : float32 (P, 3)
        Diffuse reflectance / pi per part index (row 0 = background, unused).
    ambient_rgb : float32 (P, 3)
        Ambient level times reflectance per part.
    specular, shininess : float32 (P,)
        Blinn-Phong weight (energy-normalised: ``(n + 8) / (8 pi)``) and exponent per part.
    light_dirs : float32 (L, 3)
        Unit directions towards the lights.
    light_rgb : float32 (L, 3)
        Irradiance each light gives a surface facing it.
    view_dirs : float32 (H, W, 3)
        Unit vectors from the surface towards the camera (minus the ray directions).
    half_norm : float32 (H, W, L)
        ``1 / |l + v|`` per pixel and light, so ``n . h = (n . l + n . v) * half_norm``.
    background : float32 (3,)
        Linear colour where no surface is hit (the ambient environment, as in the path tracer).
    """

    diffuse: np.ndarray
    ambient_rgb: np.ndarray
    specular: np.ndarray
    shininess: np.ndarray
    light_dirs: np.ndarray
    light_rgb: np.ndarray
    view_dirs: np.ndarray
    half_norm: np.ndarray
    background: np.ndarray


def shading_tables(view: View, preset: Preset, part_names: tuple[str, ...]) -> ShadingTables:
    """The per-frame constants of :func:`shade` (``part_names[0]`` is the background)."""
    mats: list[Material] = [material_for(p) for p in part_names]
    rgb = np.array([m.rgb for m in mats], np.float64)
    shin = np.array([m.shininess for m in mats], np.float64)
    spec = np.array([m.specular for m in mats], np.float64) * (shin + 8.0) / (8.0 * np.pi)
    right, up, back = view.camera.basis()
    dirs, irr = [], []
    for light in view.lights:
        off = np.asarray(light.offset, float)
        d = off[0] * right + off[1] * up + off[2] * back
        dirs.append(d / np.linalg.norm(d))
        irr.append(np.asarray(light.radiance, float) * light.size ** 2 / float(off @ off))
    dirs = np.asarray(dirs, np.float64).reshape(-1, 3)
    v = -pixel_directions(view, preset).astype(np.float64)
    half = v[:, :, None, :] + dirs[None, None, :, :]
    half_norm = 1.0 / np.maximum(np.linalg.norm(half, axis=3), 1e-6)
    return ShadingTables(
        diffuse=(rgb / np.pi).astype(np.float32),
        ambient_rgb=(view.ambient * rgb).astype(np.float32),
        specular=spec.astype(np.float32), shininess=shin.astype(np.float32),
        light_dirs=dirs.astype(np.float32), light_rgb=np.asarray(irr, np.float32).reshape(-1, 3),
        view_dirs=v.astype(np.float32), half_norm=half_norm.astype(np.float32),
        background=np.full(3, view.ambient, np.float32))


class NumpyOps:
    """Array operations of :func:`shade_terms` on numpy arrays (float32 kept float32)."""

    @staticmethod
    def take(column: np.ndarray, part: np.ndarray) -> np.ndarray:
        return column[part]

    @staticmethod
    def select(cond, a: float, b) -> np.ndarray:
        return np.where(cond, np.float32(a), np.asarray(b, np.float32))

    maximum, clip, power, abs = (staticmethod(np.maximum), staticmethod(np.clip),
                                 staticmethod(np.power), staticmethod(np.abs))


def shade_terms(ops, tables, part, normal, view, half_norm):
    """The shading formula, written once for numpy (:class:`NumpyOps`) and Dr.Jit arrays
    (:class:`cassi.renderer.raycast.DrJitOps`).

    Parameters
    ----------
    ops
        The array operations (``take``, ``select``, ``maximum``, ``clip``, ``power``, ``abs``).
    tables
        Per-part columns in the backend's arrays: ``ambient_rgb`` and ``diffuse`` (3 columns
        each), ``specular``, ``shininess``; and ``light_dirs``, ``light_rgb`` (L, 3) numbers.
    part : int (N,)
        Part index per pixel (only hit pixels are meaningful).
    normal, view : 3 arrays (N,)
        World-space unit surface normal and direction towards the camera, per component.
    half_norm : L arrays (N,)
        ``1 / |l + v|`` per light.

    Returns
    -------
    list of 3 arrays (N,)
        Linear R, G, B.
    """
    nx, ny, nz = normal
    ndv = nx * view[0] + ny * view[1] + nz * view[2]
    # two-sided: a normal facing away from the camera is flipped (n -> -n flips every n . x)
    sign = ops.select(ndv < 0, -1.0, 1.0)
    ndv = ops.abs(ndv)
    shininess = ops.take(tables.shininess, part)
    diffuse_e, glossy_e = [0.0] * 3, [0.0] * 3
    for (lx, ly, lz), rgb, hn in zip(tables.light_dirs, tables.light_rgb, half_norm):
        ndl = (nx * float(lx) + ny * float(ly) + nz * float(lz)) * sign
        lit = ops.maximum(ndl, 0.0)
        ndh = ops.clip((ndl + ndv) * hn, 0.0, 1.0)
        glossy = ops.power(ndh, shininess) * lit
        for c in range(3):
            diffuse_e[c] = diffuse_e[c] + lit * float(rgb[c])
            glossy_e[c] = glossy_e[c] + glossy * float(rgb[c])
    specular = ops.take(tables.specular, part)
    return [ops.take(tables.ambient_rgb[c], part) + ops.take(tables.diffuse[c], part) * diffuse_e[c]
            + specular * glossy_e[c] for c in range(3)]


@dataclass(frozen=True)
class _Columns:
    """Per-part tables as columns (what :func:`shade_terms` reads)."""

    ambient_rgb: tuple
    diffuse: tuple
    specular: object
    shininess: object
    light_dirs: np.ndarray
    light_rgb: np.ndarray


def columns(tables: ShadingTables, convert=np.ascontiguousarray) -> _Columns:
    """The per-part tables of ``tables`` as columns, each passed through ``convert`` (e.g. a
    Dr.Jit array type)."""
    return _Columns(ambient_rgb=tuple(convert(tables.ambient_rgb[:, c]) for c in range(3)),
                    diffuse=tuple(convert(tables.diffuse[:, c]) for c in range(3)),
                    specular=convert(tables.specular), shininess=convert(tables.shininess),
                    light_dirs=tables.light_dirs, light_rgb=tables.light_rgb)


def shade(tables: ShadingTables, mask: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Linear RGB of one frame, in numpy (scalar variants; JIT variants shade inside their
    Dr.Jit kernel, :mod:`cassi.renderer.raycast`, with the same :func:`shade_terms`).

    Parameters
    ----------
    tables
        :func:`shading_tables` of the view, preset and parts.
    mask : int (H, W)
        Part index per pixel, 0 = background.
    normals : float32 (H, W, 3)
        World-space unit normal of the surface at each pixel (shading or geometric normal).

    Returns
    -------
    float32 (H, W, 3)
        Linear RGB radiance, the background at mask 0.
    """
    h, w = mask.shape
    flat = mask.ravel()
    out = np.empty((h * w, 3), np.float32)
    out[...] = tables.background
    hit = np.flatnonzero(flat)
    if not hit.size:
        return out.reshape(h, w, 3)
    n = normals.reshape(-1, 3)[hit]
    view = tables.view_dirs.reshape(-1, 3)[hit]
    half = tables.half_norm.reshape(h * w, -1)[hit]
    rgb = shade_terms(NumpyOps, columns(tables), flat[hit], (n[:, 0], n[:, 1], n[:, 2]),
                      (view[:, 0], view[:, 1], view[:, 2]),
                      [half[:, k] for k in range(half.shape[1])])
    out[hit] = np.stack(rgb, axis=1)
    return out.reshape(h, w, 3)
