"""The report's copies of renders: lossless, content-addressed, each picture stored once."""
from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

import numpy as np
import pandas as pd
from PIL import Image

from reports_fixtures import image, results_rows, write_run
from cassi.renderer.images import png_bytes
from cassi.reports import media
from cassi.reports.report import _image_store, _viewer_images, write_report
from cassi.reports.runio import load_run

VIEWS = ("front", "side")


def _run(tmp_path: Path) -> Path:
    """cassi-1.0 and cassi-2.0 fire on JW11 task 19 at frame 7; their front renders there have
    the same pixels (cassi-2.0's PNG carries text chunks, so the files differ)."""
    res = results_rows({("cassi-1.0", "JW11", "lip_gap_start"): 2,
                        ("cassi-2.0", "JW11", "lip_gap_start"): 1}, subjects=("JW11",))
    keys = [("JW11", 19, v, view, f) for v in ("cassi-1.0", "cassi-2.0") for view in VIEWS
            for f in (0, 7)]
    images = {k: image(seed) for seed, k in enumerate(keys)}
    images[("JW11", 19, "cassi-2.0", "front", 7)] = images[("JW11", 19, "cassi-1.0", "front", 7)]
    run = write_run(tmp_path / "run", res, images=images)
    rend = pd.read_parquet(run / "renders.parquet")
    same = rend[(rend["version"] == "cassi-2.0") & (rend["view"] == "front") & (rend["frame"] == 7)]
    path = run / same["path"].iloc[0]
    path.write_bytes(png_bytes(images[("JW11", 19, "cassi-2.0", "front", 7)], linear=False,
                               metadata={"version": "cassi-2.0"}))
    return run


def _pixels(path) -> np.ndarray:
    with Image.open(path) as img:
        return np.asarray(img.convert("RGBA" if "A" in img.getbands() else "RGB"))


def _linked(report: Path) -> dict[Path, Path]:
    """Every image a subject page shows -> the page."""
    found = {}
    for page in (report / "subjects").glob("*.html"):
        for ref in re.findall(r'<img src="([^"]+)"', page.read_text()):
            found[(page.parent / ref).resolve()] = page
    return found


def _folder(path: Path) -> dict[str, bytes]:
    return {p.relative_to(path).as_posix(): p.read_bytes()
            for p in sorted(path.rglob("*")) if p.is_file()}


def test_images_are_the_renders_pixels_stored_once_by_content(tmp_path):
    run = _run(tmp_path)
    report = write_report(run, tmp_path / "report").parent
    linked = _linked(report)
    assert linked, "the subject page shows no render"
    rend = pd.read_parquet(run / "renders.parquet")
    shown = rend[rend["frame"] == 7]  # the four views of each fired version's frame
    pictures = {hashlib.sha256(_pixels(run / p).tobytes()).hexdigest() for p in shown["path"]}
    assert len(pictures) == len(shown) - 1  # two renders, one picture
    for path in linked:
        assert path.is_file(), path
        assert path.suffix == ".webp" and path.parent.parent == (report / "images").resolve()
        assert path.stem == hashlib.sha256(path.read_bytes()).hexdigest()
        assert path.parent.name == path.stem[:2]
    # every render shown decodes to exactly its PNG's pixels (lossless), each picture once
    decoded = {hashlib.sha256(_pixels(p).tobytes()).hexdigest(): p for p in linked}
    assert set(decoded) == pictures
    stored = list((report / "images").glob("*/*.webp"))
    assert len(stored) == len(pictures)
    for p in shown["path"]:
        digest = hashlib.sha256(_pixels(run / p).tobytes()).hexdigest()
        assert np.array_equal(_pixels(decoded[digest]), _pixels(run / p))


def test_a_report_made_twice_has_the_same_image_folder(tmp_path):
    run = _run(tmp_path)
    one = write_report(run, tmp_path / "one").parent / "images"
    two = write_report(run, tmp_path / "two").parent / "images"
    assert _folder(one) and _folder(one) == _folder(two)


def test_webp_keeps_every_pixel_and_alpha(tmp_path):
    """Lossless and exact: colour under transparent pixels and every alpha level survive."""
    rng = np.random.default_rng(3)
    rgba = rng.integers(0, 256, (37, 53, 4), dtype=np.uint8)
    rgba[::3, ::2, 3] = 0
    Image.fromarray(rgba).save(tmp_path / "a.png")
    dest = media.store_image(tmp_path / "a.png", tmp_path / "images")
    assert np.array_equal(_pixels(dest), rgba)


def test_a_large_runs_fast_webp_keeps_every_pixel_too_and_is_cached_apart(tmp_path):
    rng = np.random.default_rng(4)
    rgba = rng.integers(0, 256, (37, 53, 4), dtype=np.uint8)
    Image.fromarray(rgba).save(tmp_path / "a.png")
    cache = tmp_path / "media"
    fast = media.store_image(tmp_path / "a.png", tmp_path / "f", cache, fast=True)
    slow = media.store_image(tmp_path / "a.png", tmp_path / "s", cache)
    assert np.array_equal(_pixels(fast), rgba) and np.array_equal(_pixels(slow), rgba)
    assert fast.read_bytes() != slow.read_bytes() and len(list(cache.iterdir())) == 2


def test_an_encoding_in_the_media_cache_is_linked_not_made_again(tmp_path, monkeypatch):
    src = tmp_path / "r.png"
    Image.fromarray(image(5)).save(src)
    cache = tmp_path / "media"
    first = media.store_image(src, tmp_path / "a" / "images", cache)
    [cached] = cache.iterdir()
    assert cached.read_bytes() == first.read_bytes()

    def refuse(*_, **__):
        raise AssertionError("encoded again")
    monkeypatch.setattr(media, "webp_bytes", refuse)
    second = media.store_image(src, tmp_path / "b" / "images", cache)
    assert second.read_bytes() == first.read_bytes() and cached.stat().st_nlink >= 3
    assert second.relative_to(tmp_path / "b") == first.relative_to(tmp_path / "a")


def test_the_viewer_carries_the_first_frame_and_the_frames_checks_point_at(tmp_path):
    """A grid render no check points at stays in the run; the frames that earned negatives
    (every view) and the first frame are in the report, each link naming a stored picture."""
    res = results_rows({("cassi-1.0", "JW11", "lip_gap_start"): 2}, subjects=("JW11",))
    images = {("JW11", 19, "cassi-1.0", view, f): image(10 * f + i)
              for i, view in enumerate(VIEWS) for f in (0, 3, 7)}
    run = load_run(write_run(tmp_path / "run", res, images=images))
    out = tmp_path / "report"
    shown = _viewer_images(run, out, _image_store(out, None))("JW11", 19, 1, "cassi-1.0")
    assert sorted((r["frame"], r["view"]) for r in shown) == \
        sorted((f, view) for f in (0, 7) for view in VIEWS)
    for r in shown:
        path = os.path.normpath(out / "viewer" / "JW11" / r["href"])  # no viewer page here
        assert np.array_equal(_pixels(path), images[("JW11", 19, "cassi-1.0", r["view"],
                                                     r["frame"])])
