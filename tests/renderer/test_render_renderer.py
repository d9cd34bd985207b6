"""FaceRenderer on a toy head: one scene per renderer, per-frame vertex updates, files and
metadata, input errors. Real Mitsuba renders at a small film."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from render_meshes import toy_head
from cassi.common.errors import CassiInputError
from cassi.renderer import images, views
from cassi.renderer.images import FrameWriter, read_image, read_metadata
from cassi.renderer.render import FaceRenderer

pytestmark = pytest.mark.render

SMALL = dataclasses.replace(views.PRESETS["preview"], name="small", width=64, height=64, spp=2)


@pytest.fixture(scope="module")
def head():
    return toy_head()


@pytest.fixture(scope="module")
def front(head):
    return FaceRenderer(head[0], "front", SMALL)


def test_scene_loaded_once_and_vertices_move(front, head):
    topo, pos = head
    a = front.render(pos)
    moved = pos.copy()
    moved[:, 2] -= 150.0  # the whole head 150 units down
    b = front.render(moved)
    c = front.render(pos)
    assert front.loads == 1
    rows = lambda m: np.nonzero((m > 0).any(axis=1))[0]  # noqa: E731
    # the head's image moves down (rows grow downward)
    assert rows(b.mask)[0] > rows(a.mask)[0] + 3
    # back to the start: identical image (fixed seed, same scene)
    # back to the start: the same mask exactly and the same colour up to render noise (llvm
    # renders in one process usually agree to 1e-7 but now and then differ at noise level)
    assert np.array_equal(a.mask, c.mask)
    assert float(np.abs(a.rgb - c.rgb).mean()) < 0.02


def test_render_result_fields(front, head):
    res = front.render(head[1])
    assert res.rgb.shape == (64, 64, 3) and res.rgb.dtype == np.float32
    assert res.mask.shape == (64, 64) and res.depth.shape == (64, 64)
    assert res.part_names[0] == "background" and "skin" in res.part_names
    assert res.variant == front.variant and res.view == "front" and res.preset == "small"
    cov = res.coverage()
    assert abs(sum(cov.values()) - 1.0) < 1e-9 and cov["skin"] > 0.1
    # the closed mouth hides the tongue from the front
    assert cov["tongue"] == 0.0
    assert np.all(np.isfinite(res.depth[res.mask > 0])) and np.all(np.isinf(res.depth[res.mask == 0]))
    with pytest.raises(KeyError):
        res.part_mask("nose")


def test_bad_positions_are_input_errors(front, head):
    pos = head[1].copy()
    pos[3, 1] = np.nan
    with pytest.raises(CassiInputError, match="NaN"):
        front.render(pos)
    with pytest.raises(CassiInputError, match=r"\(V, 3\)"):
        front.render(pos[:, :2])


def test_view_and_topology_must_match(head):
    with pytest.raises(CassiInputError, match="half"):
        FaceRenderer(head[0], "half", SMALL)
    with pytest.raises(CassiInputError, match="unknown view"):
        FaceRenderer(head[0], "back", SMALL)
    with pytest.raises(CassiInputError, match="unknown preset"):
        FaceRenderer(head[0], "front", "draft")


def test_half_view_shows_the_inside_of_the_mouth():
    topo, pos = toy_head(half=True)
    res = FaceRenderer(topo, "half", SMALL).render(pos)
    cov = res.coverage()
    for part in ("teeth", "tongue", "palate"):
        assert cov[part] > 0.002, (part, cov)


def test_top_view_hides_the_skull_and_shows_the_palate(head):
    topo, pos = head
    res = FaceRenderer(topo, "top", SMALL).render(pos)
    cov = res.coverage()
    assert cov["palate"] > 0.02, cov
    # no skin above the palate's top + margin: every skin pixel lies farther than the palate top
    palate_top = pos[topo._gather["palate"]][:, 2].max()
    cam_z = views.VIEWS["top"].camera.origin[2]
    assert np.nanmin(res.depth[res.part_mask("skin")]) > (cam_z - palate_top - 25.0) - 1.0


def test_files_carry_the_variant(front, head, tmp_path):
    res = front.render_to_files(head[1], tmp_path / "f.0001", exr=True, extra={"subject": "JW99"})
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["f.0001.exr", "f.0001.json", "f.0001.mask.png", "f.0001.png"]
    exr = read_image(tmp_path / "f.0001.exr")
    assert exr.shape == (64, 64, 5)
    np.testing.assert_array_equal(exr[..., :3], res.rgb)
    np.testing.assert_array_equal(exr[..., 4].astype(int), res.mask)
    png = read_image(tmp_path / "f.0001.png")
    np.testing.assert_array_equal(png, images.to_srgb8(res.rgb))
    mask = read_image(tmp_path / "f.0001.mask.png")
    np.testing.assert_array_equal(mask[..., 0], res.mask)
    for f in ("f.0001.exr", "f.0001.png", "f.0001.mask.png"):
        meta = read_metadata(tmp_path / f)
        assert meta["variant"] == front.variant and meta["view"] == "front"
        assert meta["subject"] == "JW99" and meta["part_names"][0] == "background"
    side = json.loads((tmp_path / "f.0001.json").read_text())
    assert side["variant"] == front.variant and side["spp"] == 2 and side["seed"] == SMALL.seed


def test_background_writer_matches_synchronous_writes(front, head, tmp_path):
    res = front.render(head[1])
    with FrameWriter(exr=True) as w:
        for k in range(5):
            w.submit(res, tmp_path / f"bg{k}")
    images.write_result(res, tmp_path / "sync", exr=True)
    assert len(w.written) == 20
    for ext in (".exr", ".png", ".mask.png"):
        assert np.array_equal(read_image(tmp_path / f"bg4{ext}"), read_image(tmp_path / f"sync{ext}"))
    assert not list(tmp_path.glob(".*tmp*"))  # atomic writes leave no temporaries


@pytest.mark.slow
def test_bench_render_quick_on_toy_head():
    """The benchmark runs end to end and reports the figures cassi bench expects."""
    from cassi.harness.bench.render import bench_render

    topo_full, pos = toy_head()
    topo_half, pos_half = toy_head(half=True)
    assert np.array_equal(pos, pos_half)
    out = bench_render(True, topology_for=lambda half: topo_half if half else topo_full,
                       positions=pos)
    assert out["variant"] in ("cuda_ad_rgb", "llvm_ad_rgb", "scalar_rgb")
    assert set(out["render_per_s"]) >= {"front/preview", "side/preview", "half/preview",
                                        "top/preview", "front/final"}
    assert all(v > 0 for v in out["render_per_s"].values())
    assert 0 < out["render_pipeline_efficiency"] <= 1.5
    # a ratio of two timings on one machine: others sharing it move it either way (1.1 seen)
    assert 0 < out["render_pipeline_efficiency_vs_own_pass"] <= 1.5
    assert out["render_rss_growth_mb"] < 50
    assert all(n == 1 for n in out["scene_loads"].values())


@pytest.mark.parametrize("view,look", [("front", "smooth"), ("side", "flat"), ("top", "smooth")])
def test_kernel_equals_aov_pass_with_numpy_shading(head, view, look):
    """JIT variants render raycast presets in one Dr.Jit kernel (renderer.raycast); Mitsuba's aov
    pass with the numpy shading is the path it replaces (and scalar_rgb's). Same rays: the same
    mask and depth bits; same formula: the same 8-bit colour, which is to_srgb8 of the linear one."""
    topo, pos = head
    r = FaceRenderer(topo, view, dataclasses.replace(SMALL, look=look))
    moved = pos.copy()
    moved[:, 0] += 7.0
    res = r.render(moved)
    if r._raycast is None:
        pytest.skip("scalar variant: the aov pass is the only path")
    kernel, r._raycast = r._raycast, None
    try:
        mask, depth, rgb, srgb = r._one_pass()
    finally:
        r._raycast = kernel
    assert srgb is None and res.srgb is not None
    np.testing.assert_array_equal(res.mask, mask)
    np.testing.assert_array_equal(res.depth, depth)
    np.testing.assert_array_equal(res.srgb, images.to_srgb8(res.rgb))
    np.testing.assert_array_equal(res.srgb8(), images.to_srgb8(rgb))
    assert float(np.abs(res.rgb - rgb).max()) < 1e-4
