"""Pictures for reports from a run's renders: copied thumbnails, contact sheets and
side-by-side animations of tasks 106 and 118. Reads image files only; never re-renders."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pandas as pd

from cassi.data.atomic import atomic_tmp_path


def copy_image(src: str | os.PathLike, dest: Path) -> Path:
    """Copy a render beside the report (so the report is self-contained), atomically."""
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_tmp_path(dest)
    shutil.copyfile(src, tmp)
    os.replace(tmp, dest)
    return dest


def read_rgb8(path) -> np.ndarray:
    """An image file as 8-bit RGB (grey expanded, alpha dropped)."""
    img = np.asarray(iio.imread(path))
    if img.ndim == 2:
        img = np.stack([img] * 3, axis=-1)
    return img[..., :3].astype(np.uint8)


def tile(images: list[np.ndarray], *, columns: int, gap: int = 4) -> np.ndarray:
    """Images (same height; widths may differ per column) laid out in a grid on white."""
    if not images:
        raise ValueError("no images to tile")
    h = max(im.shape[0] for im in images)
    w = max(im.shape[1] for im in images)
    rows = -(-len(images) // columns)
    sheet = np.full((rows * h + (rows - 1) * gap, columns * w + (columns - 1) * gap, 3), 255, np.uint8)
    for i, im in enumerate(images):
        r, c = divmod(i, columns)
        sheet[r * (h + gap): r * (h + gap) + im.shape[0], c * (w + gap): c * (w + gap) + im.shape[1]] = im
    return sheet


def contact_sheet(paths: list[str], dest: Path, *, columns: int = 4) -> Path:
    """One PNG with the given renders in a grid (e.g. the four views at a check's frame)."""
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_tmp_path(dest)
    iio.imwrite(tmp, tile([read_rgb8(p) for p in paths], columns=columns), extension=".png")
    os.replace(tmp, dest)
    return dest


def side_by_side_animation(renders: pd.DataFrame, dest: Path, *, fps: int = 12) -> Path | None:
    """An MP4 of one task with every version side by side (columns) per frame rendered by all.

    ``renders`` holds one subject, task and view. Returns None when fewer than two frames were
    rendered by every version (nothing to animate).
    """
    versions = list(dict.fromkeys(renders["version"]))
    by_frame = renders.groupby("frame")
    frames = [f for f, g in by_frame if set(g["version"]) >= set(versions)]
    if len(frames) < 2:
        return None
    import imageio_ffmpeg  # noqa: PLC0415 - only needed here

    first = tile([read_rgb8(p) for p in by_frame.get_group(frames[0]).set_index("version")
                  .loc[versions, "path"]], columns=len(versions))
    h, w = (first.shape[0] // 2) * 2, (first.shape[1] // 2) * 2  # yuv420p wants even sizes
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = atomic_tmp_path(dest)
    writer = imageio_ffmpeg.write_frames(str(tmp), (w, h), fps=fps, codec="libx264",
                                         pix_fmt_out="yuv420p", macro_block_size=1)
    writer.send(None)
    try:
        for f in frames:
            g = by_frame.get_group(f).set_index("version")
            img = tile([read_rgb8(p) for p in g.loc[versions, "path"]], columns=len(versions))
            writer.send(np.ascontiguousarray(img[:h, :w]))
    finally:
        writer.close()
    os.replace(tmp, dest)
    return dest
