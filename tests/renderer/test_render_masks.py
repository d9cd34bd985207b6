"""Masks and depth from the aov pass: exact per pixel centre, aligned with the colour image, and
the shape-index mapping right on both the scalar and the llvm variant (shape_index is the scene
order + 1 in scalar variants but a registry id in JIT ones)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from render_meshes import SimpleTopology, quad
from cassi.renderer import views
from cassi.renderer.render import FaceRenderer
from cassi.renderer.variant import choose_variant

pytestmark = pytest.mark.render

W = H = 48
CAM = views.Camera(origin=(1000.0, 0.0, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov=30.0)
VIEW = views.View("test", CAM, lights=views.VIEWS["front"].lights)
PRESET = views.Preset("tiny", W, H, spp=4, seed=3, max_depth=2)

# Three axis-aligned quads facing the camera (+X): a big "skin" backdrop at x = 0, "teeth" on the
# image right (+Y side... the face's left, i.e. image right from the front) at x = 100 and a
# "tongue" lower down at x = 200 overlapping the teeth. (y0, y1, z0, z1, x) in Parke units.
QUADS = {"skin": (-200, 200, -200, 200, 0.0), "teeth": (10, 150, -60, 120, 100.0),
         "tongue": (-120, 60, -160, -20, 200.0)}


def _scene():
    positions, parts, off = [], {}, 0
    for name, (y0, y1, z0, z1, x) in QUADS.items():
        v, t = quad((x, y0, z0), (x, y1, z0), (x, y1, z1), (x, y0, z1))
        positions.append(v)
        parts[name] = (np.arange(off, off + 4), t)
        off += 4
    return SimpleTopology(parts), np.vstack(positions)


def _expected():
    """Part index and distance of the ray through each pixel centre, by hand."""
    right, up, back = CAM.basis()
    o = np.asarray(CAM.origin)
    tan = math.tan(math.radians(CAM.fov) / 2)
    jj, ii = np.meshgrid(np.arange(W), np.arange(H))
    sx = ((jj + 0.5) / W * 2 - 1) * tan
    sy = (1 - (ii + 0.5) / H * 2) * tan
    d = -back[None, None] + sx[..., None] * right + sy[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    mask = np.zeros((H, W), int)
    depth = np.full((H, W), np.inf)
    edge = np.zeros((H, W), bool)  # pixel centres within 0.02 px of an edge: not compared
    px = 2 * tan * (o[0] - 0) / W
    for k, (name, (y0, y1, z0, z1, x)) in enumerate(QUADS.items(), start=1):
        t = (x - o[0]) / d[..., 0]
        y, z = o[1] + t * d[..., 1], o[2] + t * d[..., 2]
        inside = (y >= y0) & (y <= y1) & (z >= z0) & (z <= z1)
        near = np.minimum.reduce([abs(y - y0), abs(y - y1), abs(z - z0), abs(z - z1)]) < 0.02 * px
        edge |= near
        closer = inside & (t < depth)
        mask[closer] = k
        depth[closer] = t[closer]
    return mask, depth, edge


def _variants():
    out = ["scalar_rgb"]
    try:
        auto = choose_variant("llvm")
        out.append(auto)
    except Exception:  # noqa: BLE001 - no usable libLLVM: scalar only
        pass
    return out


@pytest.mark.parametrize("variant", _variants())
def test_mask_and_depth_exact_at_pixel_centres(variant):
    topo, pos = _scene()
    r = FaceRenderer(topo, VIEW, PRESET, variant)
    res = r.render(pos)
    assert res.variant == variant
    assert res.part_names == ("background", "skin", "teeth", "tongue")
    mask, depth, edge = _expected()
    ok = ~edge
    assert np.array_equal(res.mask[ok], mask[ok]), np.argwhere((res.mask != mask) & ok)[:5]
    hit = ok & (mask > 0)
    np.testing.assert_allclose(res.depth[hit], depth[hit], rtol=1e-4)
    assert np.all(np.isinf(res.depth[mask == 0]))
    # every part appears, the tongue hides part of the teeth, the background shows at the corners
    assert set(np.unique(res.mask)) == {0, 1, 2, 3}


@pytest.mark.parametrize("variant", _variants())
def test_mask_aligned_with_colour(variant):
    """The bright enamel in the colour image sits exactly where the mask says teeth (raycast
    colour: deterministic, so the comparison is exact; path-traced colour is noise around it)."""
    import dataclasses

    topo, pos = _scene()
    raycast = dataclasses.replace(PRESET, shading="raycast", spp=1)
    res = FaceRenderer(topo, VIEW, raycast, variant).render(pos)
    lum = res.rgb.mean(axis=2)
    teeth = res.part_mask("teeth")
    tongue = res.part_mask("tongue")
    # interior pixels (not on a part boundary) of each part
    def interior(m):
        e = m.copy()
        e[1:] &= m[:-1]; e[:-1] &= m[1:]; e[:, 1:] &= m[:, :-1]; e[:, :-1] &= m[:, 1:]
        return e
    t_in, g_in = interior(teeth), interior(tongue)
    assert t_in.sum() > 20 and g_in.sum() > 20
    # colour of each part's interior matches its material: enamel pale and neutral, tongue red
    t_rgb = res.rgb[t_in].mean(axis=0)
    g_rgb = res.rgb[g_in].mean(axis=0)
    assert t_rgb[2] > 1.5 * g_rgb[2] and g_rgb[0] > 2 * g_rgb[2]
    # the teeth/tongue boundary in the colour image lies where the mask's does: threshold the
    # blue channel half-way between the two materials and compare with the mask
    thr = 0.5 * (t_rgb[2] + g_rgb[2])
    region = t_in | g_in
    colour_says_teeth = res.rgb[..., 2] > thr
    assert np.mean(colour_says_teeth[region] == teeth[region]) == 1.0
    assert np.isfinite(lum).all()


def test_scalar_and_llvm_masks_agree():
    variants = _variants()
    if len(variants) < 2:
        pytest.skip("no JIT variant usable here")
    topo, pos = _scene()
    masks = [FaceRenderer(topo, VIEW, PRESET, v).render(pos).mask for v in variants]
    assert np.array_equal(masks[0], masks[1])
