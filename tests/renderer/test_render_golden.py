"""Golden images of the neutral face (cassi.data.face.model.build_face()) in all four views, preview preset.

References live in tests/golden/: ``neutral_<view>.png`` (sRGB colour) and
``neutral_<view>.mask.png`` (part ids). They are regenerated only on purpose, after looking at
them:

    CASSI_REGEN_GOLDEN=1 python -m pytest tests/renderer/test_render_golden.py

(then the test skips, saying what it wrote). A missing reference skips, never passes. A failure
writes the rendered, reference and difference images and names the folder (``CASSI_GOLDEN_OUT``
or pytest's tmp_path).

What is compared, and why: the preview preset shades its colour from one ray through each pixel
centre (no sampling), so a render is the same bytes in every run and process of one build on one
machine (test_render_is_reproducible checks that exactly). Another machine compiles Dr.Jit's
LLVM kernels for its own CPU, so a golden image made on one machine is compared with a render
from another by the renderer's one rule (:func:`cassi.renderer.compare.compare_images`, the rule
the nightly's image gates use; its module gives each tolerance's reason and measurement): part
masks agree on >= 99.9% of the pixels, and at most 0.5% of the pixels differ by more than one
8-bit level where they do. Renders from other code paths (scalar_rgb, llvm built for AVX2 with 8
lanes) and the reported AVX-512 machine's highlight difference pass; a jaw lowered by 4 Parke
units, a skin 2% darker and mirrored lights fail.
"""
from __future__ import annotations

import dataclasses
import importlib
import os
from pathlib import Path

import numpy as np
import pytest

from testpaths import GOLDEN
from cassi.data.face.model import render_topology
from cassi.data.face.params import jaw_rotation
from cassi.renderer import views
from cassi.renderer.compare import compare_images
from cassi.renderer.images import png_bytes, read_image, to_srgb8, write_mask_png, write_png
from cassi.renderer.render import FaceRenderer
from other_machine import CPU_LEVELS, CPU_PIXELS, as_another_cpu, llvm_target

pytestmark = pytest.mark.render

REGEN = os.environ.get("CASSI_REGEN_GOLDEN", "") not in ("", "0")
VIEWS = ("front", "side", "half", "top")
#: The jaw opened by 0.5 degrees moves its farthest vertex (the chin) by 4.0 Parke units: the
#: smallest geometric change the rule is meant to catch in every view ("a few Parke units").
JAW_DEGREES = 0.5


@pytest.fixture(scope="module")
def neutral():
    face_mod = importlib.import_module("cassi.data.face.model")
    face = face_mod.build_face()
    return face, np.asarray(face.vertices)


def _failure_dir(tmp_path: Path) -> Path:
    out = Path(os.environ.get("CASSI_GOLDEN_OUT", tmp_path))
    out.mkdir(parents=True, exist_ok=True)
    return out


@pytest.mark.parametrize("view", VIEWS)
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

    if not colour_ref.exists() or not mask_ref.exists():
        missing = [p.name for p in (colour_ref, mask_ref) if not p.exists()]
        pytest.skip(f"no golden reference {', '.join(missing)} (CASSI_REGEN_GOLDEN=1 makes it)")
    ref, ref_mask = read_image(colour_ref)[..., :3], read_image(mask_ref)[..., 0].astype(int)
    c = compare_images(img, ref, rendered_mask=res.mask, reference_mask=ref_mask)
    if not c.passed:
        out = _failure_dir(tmp_path)
        write_png(out / f"{view}.rendered.png", img, linear=False)
        write_png(out / f"{view}.reference.png", ref, linear=False)
        diff = np.clip(np.abs(img.astype(int) - ref.astype(int)) * 4, 0, 255).astype(np.uint8)
        write_png(out / f"{view}.difference.png", diff, linear=False)
        write_mask_png(out / f"{view}.mask.rendered.png", res.mask)
        pytest.fail(f"{view}: {c.reason}; images in {out}")


def _golden(view: str) -> tuple[np.ndarray, np.ndarray]:
    colour_ref, mask_ref = GOLDEN / f"neutral_{view}.png", GOLDEN / f"neutral_{view}.mask.png"
    if not colour_ref.exists() or not mask_ref.exists():
        pytest.skip(f"no golden reference for the {view} view")
    return read_image(colour_ref)[..., :3], read_image(mask_ref)[..., 0].astype(int)


def _render(face, view, positions, variant=None, view_obj=None):
    topo = render_topology(face, half=(view == "half"))
    return FaceRenderer(topo, view_obj or view, "preview", variant).render(positions)


def test_render_is_reproducible(neutral):
    """Same-machine determinism, kept exact (the golden tolerance is for other machines): a new
    renderer, and the same renderer after another frame, give the same bits and the same PNG
    bytes (vertex normals are summed in a fixed order, see scenes.vertex_normals)."""
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
        assert png_bytes(a.srgb8(), linear=False) == png_bytes(other.srgb8(), linear=False)


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


def test_other_code_paths_pass_against_the_goldens(neutral):
    """Renders from other code paths than the goldens' pass the rule in every view: scalar_rgb
    (no JIT), and llvm compiled for an AVX2 CPU with 8 lanes (here AVX-512 with 16). Both really
    differ from the goldens somewhere, so the rule, not luck, lets them through."""
    face, pos = neutral
    goldens = {view: _golden(view) for view in VIEWS}
    differing = {"scalar": 0, "llvm avx2 x8": 0}
    renders = {("scalar", v): _render(face, v, pos, "scalar") for v in VIEWS}
    with llvm_target("haswell", "+avx2,+fma", 8) as before:
        assert before[2] != 8, "the native target already has 8 lanes: nothing would change"
        renders.update({("llvm avx2 x8", v): _render(face, v, pos, "llvm") for v in VIEWS})
    for (path, view), res in renders.items():
        ref, ref_mask = goldens[view]
        c = compare_images(res.srgb8(), ref, rendered_mask=res.mask, reference_mask=ref_mask)
        assert c.passed, (path, view, c.reason)
        differing[path] += int(np.any(res.srgb8() != ref))
    assert all(differing.values()), differing


def test_another_cpus_highlight_passes_and_real_changes_still_fail(neutral):
    """The reported failure, simulated: the half view's eye highlight changed as the AVX-512
    machine changed it (107 pixels beyond one level, up to 38) fails the old exact rule and
    passes the new one; with the jaw lowered or the skin darker as well, it fails."""
    face, pos = neutral
    base = _render(face, "half", pos)
    cpu = as_another_cpu(base.srgb8())
    c = compare_images(cpu, base.srgb8(), rendered_mask=base.mask, reference_mask=base.mask)
    assert c.changed_px == CPU_PIXELS and c.max_levels == CPU_LEVELS  # the old rule's failure
    assert c.passed, c.reason
    lowered = _render(face, "half", jaw_rotation(pos, JAW_DEGREES))
    c = compare_images(as_another_cpu(lowered.srgb8()), base.srgb8(),
                       rendered_mask=lowered.mask, reference_mask=base.mask)
    assert not c.colour_ok and not c.mask_ok, c.reason


def test_real_changes_fail(neutral, monkeypatch):
    """The jaw lowered by 4 Parke units (every view), a skin 2% darker and the lights mirrored
    (front view) fail the rule, each through the colour."""
    face, pos = neutral
    lowered = jaw_rotation(pos, JAW_DEGREES)
    assert np.linalg.norm(lowered - pos, axis=1).max() == pytest.approx(4.0, abs=0.05)
    for view in VIEWS:
        base, moved = _render(face, view, pos), _render(face, view, lowered)
        c = compare_images(moved.srgb8(), base.srgb8(), rendered_mask=moved.mask,
                           reference_mask=base.mask)
        assert not c.colour_ok, (view, c.reason)

    base = _render(face, "front", pos)
    skin = views.MATERIALS["skin"]
    monkeypatch.setitem(views.MATERIALS, "skin",
                        dataclasses.replace(skin, rgb=tuple(0.98 * c for c in skin.rgb)))
    darker = _render(face, "front", pos)
    monkeypatch.setitem(views.MATERIALS, "skin", skin)
    c = compare_images(darker.srgb8(), base.srgb8(), rendered_mask=darker.mask,
                       reference_mask=base.mask)
    assert c.mask_ok and not c.passed and c.max_levels <= 2, c.reason  # small, but everywhere

    front = views.VIEWS["front"]
    lights = tuple(dataclasses.replace(l, offset=(-l.offset[0], l.offset[1], l.offset[2]))
                   for l in front.lights)
    relit = _render(face, "front", pos, view_obj=dataclasses.replace(front, lights=lights))
    c = compare_images(relit.srgb8(), base.srgb8(), rendered_mask=relit.mask,
                       reference_mask=base.mask)
    assert not c.passed, c.reason


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
