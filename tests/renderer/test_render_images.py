"""Image writers: sRGB transfer, EXR/PNG round trips through OpenImageIO, atomicity, sheets."""
from __future__ import annotations

import numpy as np
import pytest

from cassi.common.errors import CassiInputError
from cassi.renderer import images
from cassi.renderer.animate import realtime_fps, side_by_side, write_animation


def test_srgb_reference_values():
    # IEC 61966-2-1: 0.0031308 is the linear/power knee; 0.18 grey -> 0.4614; 1 -> 1
    enc = images.srgb_encode(np.array([0.0, 0.0031308, 0.18, 1.0, 2.0]))
    np.testing.assert_allclose(enc, [0.0, 0.04045, 0.46135, 1.0, 1.0], atol=2e-5)
    x = np.linspace(0, 1, 101, dtype=np.float32)
    np.testing.assert_allclose(images.srgb_decode(images.srgb_encode(x)), x, atol=1e-5)


def test_exr_round_trip_exact_with_metadata(tmp_path):
    rng = np.random.default_rng(0)
    rgb = rng.random((12, 20, 3), dtype=np.float32) * 4
    depth = rng.random((12, 20), dtype=np.float32) * 1000
    depth[0, 0] = np.inf
    mask = rng.integers(0, 7, (12, 20))
    p = images.write_exr(tmp_path / "a.exr", rgb, depth=depth, mask=mask,
                         metadata={"variant": "scalar_rgb", "part_names": ["background", "skin"]})
    back = images.read_image(p)
    np.testing.assert_array_equal(back[..., :3], rgb)
    np.testing.assert_array_equal(back[..., 3], depth)
    np.testing.assert_array_equal(back[..., 4], mask)
    assert images.read_metadata(p) == {"variant": "scalar_rgb", "part_names": ["background", "skin"]}
    assert [f.name for f in tmp_path.iterdir()] == ["a.exr"]


def test_png_and_mask_png(tmp_path):
    rgb = np.linspace(0, 1, 8 * 6 * 3, dtype=np.float32).reshape(8, 6, 3)
    images.write_png(tmp_path / "a.png", rgb, metadata={"view": "front"})
    np.testing.assert_array_equal(images.read_image(tmp_path / "a.png"), images.to_srgb8(rgb))
    assert images.read_metadata(tmp_path / "a.png")["view"] == "front"
    mask = np.arange(48).reshape(8, 6) % 7  # not symmetric under a layout mix-up
    images.write_mask_png(tmp_path / "m.png", mask)
    np.testing.assert_array_equal(images.read_image(tmp_path / "m.png")[..., 0], mask)
    with pytest.raises(CassiInputError):
        images.write_mask_png(tmp_path / "bad.png", mask + 300)
    with pytest.raises(CassiInputError):
        images.write_png(tmp_path / "bad.png", rgb[..., 0])


def test_failed_write_leaves_old_file(tmp_path):
    target = tmp_path / "keep.png"
    images.write_png(target, np.zeros((4, 4, 3), np.float32))
    before = target.read_bytes()
    with pytest.raises(Exception):
        images.write_png(target, np.zeros((4, 4, 3), np.float32), metadata={"x": object()})
    assert target.read_bytes() == before
    assert sorted(f.name for f in tmp_path.iterdir()) == ["keep.png"]


def test_contact_sheet_layout(tmp_path):
    tiles = [np.full((10, 8, 3), 40 * k, np.uint8) for k in range(5)]
    sheet = images.tile(tiles, columns=3, gap=2)
    assert sheet.shape == (2 * 10 + 3 * 2, 3 * 8 + 4 * 2, 3)
    assert (sheet[2:12, 2:10] == 0).all() and (sheet[14:24, 12:20] == 160).all()
    images.write_contact_sheet(tmp_path / "s.png", tiles)
    assert images.read_image(tmp_path / "s.png").shape[2] == 3
    with pytest.raises(CassiInputError):
        images.tile([])


def test_animation_mp4_and_gif(tmp_path):
    import imageio_ffmpeg

    frames = [side_by_side([np.full((16, 16, 3), 30 * k, np.uint8)] * 2) for k in range(6)]
    for name in ("a.mp4", "a.gif"):
        write_animation(tmp_path / name, iter(frames), fps=10)
        reader = imageio_ffmpeg.read_frames(str(tmp_path / name))
        meta = next(reader)
        assert tuple(meta["size"]) == (32, 16)
        assert sum(1 for _ in reader) == 6
    with pytest.raises(CassiInputError):
        write_animation(tmp_path / "a.avi", iter(frames), fps=10)
    with pytest.raises(CassiInputError):
        write_animation(tmp_path / "b.mp4", iter([]), fps=10)
    assert not (tmp_path / "b.mp4").exists()
    before = (tmp_path / "a.mp4").read_bytes()
    odd = iter(frames[:3] + [np.zeros((8, 8, 3), np.uint8)])   # fails after ffmpeg started
    with pytest.raises(ValueError, match="same size"):
        write_animation(tmp_path / "a.mp4", odd, fps=10)
    assert (tmp_path / "a.mp4").read_bytes() == before          # the old video kept whole
    assert sorted(f.name for f in tmp_path.iterdir()) == ["a.gif", "a.mp4"]   # no .tmp left
    assert realtime_fps(1) == 50.0 and abs(realtime_fps(5) - 1e6 / (6866 * 5)) < 1e-9


@pytest.mark.parametrize("shape", [(37, 53, 3), (16, 9)])
def test_png_bytes_decode_exactly_in_pillow_and_openimageio(tmp_path, shape):
    """png_bytes writes its own rows (Up filter, zlib): readers other than ours must agree."""
    import io

    from PIL import Image

    rng = np.random.default_rng(3)
    pixels = rng.integers(0, 256, shape, dtype=np.uint8)
    pixels[5:9] = 250  # flat rows next to noisy ones: both byte wrap-arounds of the filter
    meta = {"view": "front", "part_names": ["background", "skin"], "subject": "JW11 é ✓"}
    data = images.png_bytes(pixels, metadata=meta, linear=False)
    assert data == images.png_bytes(pixels.copy(), metadata=dict(meta), linear=False)
    with Image.open(io.BytesIO(data)) as im:
        im.load()
        np.testing.assert_array_equal(np.asarray(im), pixels)
        assert im.text["cassi:subject"] == "JW11 é ✓"
    (tmp_path / "a.png").write_bytes(data)
    back = images.read_image(tmp_path / "a.png")
    np.testing.assert_array_equal(back if back.ndim == len(shape) else back[..., 0], pixels)
    assert images.read_metadata(tmp_path / "a.png") == meta
