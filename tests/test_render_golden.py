"""Golden images of the neutral face (cassi.data.face.model.build_face()) in all four views, preview preset.

References live in tests/golden/: ``neutral_<view>.png`` (sRGB colour) and
``neutral_<view>.mask.png`` (part ids). They are regenerated only on purpose, after looking at
them:

    CASSI_REGEN_GOLDEN=1 python -m pytest tests/test_render_golden.py

(then the test skips, saying what it wrote). A missing reference skips, never passes. A failure
writes the rendered, reference and difference images and names the folder (``CASSI_GOLDEN_OUT``
or pytest's tmp_path).

What is compared, and why: the preview preset shades its colour from one ray through each pixel
centre (no sampling), so a render is the same bytes in every run and process of a variant.

- the mask: agreement >= 0.999 (it catches geometry and camera changes: lowering the jaw by 15
  Parke units leaves 0.996 in the front view and 0.986 in the half view); llvm and scalar differ
  in one silhouette pixel of the half and top views (the ray grazes an edge);
- the colour, exactly up to one 8-bit level on every pixel where the masks agree (llvm against
  scalar_rgb: at most one level; a skin 2% darker or the lights mirrored already fail).
"""
from __future__ import annotations

import importlib
import os
from pathlib import Path

import numpy as np
import pytest

from cassi.renderer.images import read_image, to_srgb8, write_mask_png, write_png

pytestmark = pytest.mark.render

GOLDEN = Path(__file__).resolve().parent / "golden"
LEVELS = 1
MASK_AGREEMENT_MIN = 0.999
REGEN = os.environ.get("CASSI_REGEN_GOLDEN", "") not in ("", "0")


@pytest.fixture(scope="module")
def neutral():
    face_mod = importlib.import_module("cassi.data.face.model")
    face = face_mod.build_face()
    return face, np.asarray(face.vertices)


def colour_difference(ref: np.ndarray, img: np.ndarray, same_part: np.ndarray) -> tuple[int, int]:
    """(largest difference in 8-bit levels, pixels beyond LEVELS) of two uint8 (H, W, 3) images
    over the pixels where ``same_part`` (bool (H, W)) is true."""
    d = np.abs(ref.astype(int) - img.astype(int)).max(axis=2)[same_part]
    return int(d.max(initial=0)), int((d > LEVELS).sum())


def _failure_dir(tmp_path: Path) -> Path:
    out = Path(os.environ.get("CASSI_GOLDEN_OUT", tmp_path))
    out.mkdir(parents=True, exist_ok=True)
    return out


@pytest.mark.parametrize("view", ["front", "side", "half", "top"])
def test_neutral_face_matches_golden(neutral, view, tmp_path):
    from cassi.data.face.model import render_topology
    from cassi.renderer.render import FaceRenderer

    face, pos = neutral
    r = FaceRenderer(render_topology(face, half=(view == "half")), view, "preview")
    res = r.render(pos)
    img = to_srgb8(res.rgb)
    colour_ref = GOLDEN / f"neutral_{view}.png"
    mask_ref = GOLDEN / f"neutral_{view}.mask.png"
    if REGEN:
        write_png(colour_ref, img, linear=False, metadata=res.metadata())
        write_mask_png(mask_ref, res.mask, metadata=res.metadata())
        pytest.skip(f"regenerated {colour_ref.name} and {mask_ref.name}")

    problems = []
    out = None
    ref_mask = read_image(mask_ref)[..., 0].astype(int) if mask_ref.exists() else res.mask
    if mask_ref.exists():
        agree = float(np.mean(ref_mask == res.mask))
        if agree < MASK_AGREEMENT_MIN:
            problems.append(f"mask agreement {agree:.5f} < {MASK_AGREEMENT_MIN}")
            out = _failure_dir(tmp_path)
            write_mask_png(out / f"{view}.mask.rendered.png", res.mask)
            diff = np.where(ref_mask != res.mask, 255, 0)
            write_png(out / f"{view}.mask.diff.png", np.repeat(diff[..., None], 3, 2).astype(np.uint8),
                      linear=False)
    if colour_ref.exists():
        ref = read_image(colour_ref)[..., :3]
        worst, n_bad = colour_difference(ref, img, ref_mask == res.mask)
        if n_bad:
            problems.append(f"{n_bad} pixel(s) differ by more than {LEVELS} level (up to {worst})")
            out = _failure_dir(tmp_path)
            write_png(out / f"{view}.rendered.png", img, linear=False)
            write_png(out / f"{view}.reference.png", ref, linear=False)
            diff = np.clip(np.abs(img.astype(int) - ref.astype(int)) * 4, 0, 255).astype(np.uint8)
            write_png(out / f"{view}.difference.png", diff, linear=False)
    if problems:
        pytest.fail(f"{view}: {'; '.join(problems)}; images in {out}")
    if not colour_ref.exists() or not mask_ref.exists():
        missing = [p.name for p in (colour_ref, mask_ref) if not p.exists()]
        pytest.skip(f"no golden reference {', '.join(missing)} (CASSI_REGEN_GOLDEN=1 makes it)")


def test_render_is_reproducible(neutral):
    """A new renderer, and the same renderer after another frame, give the same bits (vertex
    normals are summed in a fixed order, see scenes.vertex_normals)."""
    from cassi.data.face.model import render_topology
    from cassi.renderer.render import FaceRenderer

    face, pos = neutral
    topo = render_topology(face)
    r = FaceRenderer(topo, "front", "preview")
    a = r.render(pos)
    r.render(pos - np.array([0.0, 0.0, 5.0]))
    b = r.render(pos)
    c = FaceRenderer(topo, "front", "preview").render(pos)
    for other in (b, c):
        assert np.array_equal(a.mask, other.mask) and np.array_equal(a.depth, other.depth)
        assert np.array_equal(a.rgb, other.rgb)


def test_neutral_views_show_what_they_should(neutral):
    """The parts each view exists for are visible in it (what the rubric reads from masks)."""
    from cassi.data.face.model import render_topology
    from cassi.renderer.render import FaceRenderer

    face, pos = neutral
    want = {"front": ("skin", "lips", "eye_white", "iris", "pupil"),
            "side": ("skin", "lips"),
            "half": ("skin", "lips", "teeth", "tongue", "palate"),
            "top": ("palate", "teeth", "tongue")}
    for view, parts in want.items():
        res = FaceRenderer(render_topology(face, half=(view == "half")), view, "preview").render(pos)
        cov = res.coverage()
        # a part may be split (teeth -> teeth_upper, teeth_lower): count every part it prefixes
        missing = [p for p in parts if sum(c for k, c in cov.items() if k.startswith(p)) <= 0.0]
        assert not missing, (view, missing, cov)
        # the head fills a sensible part of the frame and is not cut by it on the sides
        assert 0.1 < 1 - cov["background"] < 0.8, (view, cov["background"])
        if view in ("front", "side"):
            assert (res.mask[:, 0] == 0).all() and (res.mask[:, -1] == 0).all()
            assert (res.mask[0] == 0).all()


def test_colour_comparison_fires_on_a_planted_defect(neutral, monkeypatch):
    """The other variant passes; a skin 2% darker, or the lights mirrored, does not."""
    import dataclasses

    from cassi.data.face.model import render_topology
    from cassi.renderer import views
    from cassi.renderer.render import FaceRenderer

    face, pos = neutral
    topo = render_topology(face)
    res = FaceRenderer(topo, "front", "preview").render(pos)
    base, mask = to_srgb8(res.rgb), res.mask
    other = FaceRenderer(topo, "front", "preview", "scalar").render(pos)
    assert colour_difference(base, to_srgb8(other.rgb), mask == other.mask)[1] == 0

    skin = views.MATERIALS["skin"]
    monkeypatch.setitem(views.MATERIALS, "skin",
                        dataclasses.replace(skin, rgb=tuple(0.98 * c for c in skin.rgb)))
    darker = to_srgb8(FaceRenderer(topo, "front", "preview").render(pos).rgb)
    monkeypatch.setitem(views.MATERIALS, "skin", skin)
    assert colour_difference(base, darker, np.ones_like(mask, bool))[1] > 100

    front = views.VIEWS["front"]
    lights = tuple(dataclasses.replace(l, offset=(-l.offset[0], l.offset[1], l.offset[2]))
                   for l in front.lights)
    mirrored = dataclasses.replace(front, lights=lights)
    relit = to_srgb8(FaceRenderer(topo, mirrored, "preview").render(pos).rgb)
    assert colour_difference(base, relit, np.ones_like(mask, bool))[1] > 100


def test_final_preset_path_traces(neutral):
    """``final`` stays path-traced (shadows, interreflection): its colour is not the raycast
    shading, while mask and depth come from the same kind of pass."""
    from cassi.data.face.model import render_topology
    from cassi.renderer import views
    from cassi.renderer.render import FaceRenderer
    import dataclasses

    face, pos = neutral
    topo = render_topology(face)
    small = dataclasses.replace(views.PRESETS["final"], width=128, height=128, spp=4)
    res = FaceRenderer(topo, "front", small).render(pos)
    assert res.extra["shading"] == "path" and res.spp == 4
    ray = dataclasses.replace(small, shading="raycast", spp=1)
    res2 = FaceRenderer(topo, "front", ray).render(pos)
    assert np.array_equal(res.mask, res2.mask)
    assert float(np.abs(res.rgb - res2.rgb)[res.mask > 0].mean()) > 0.01
