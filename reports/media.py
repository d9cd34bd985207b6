"""Pictures for reports from a run's renders: lossless content-addressed copies, contact
sheets, a four-view video of every task file and side-by-side version comparisons (front
view), each panel labelled, in real time, with the task's sound when the corpus has it. Reads
image files (and the corpus's WAV files) only; never re-renders."""
from __future__ import annotations

import functools
import hashlib
import importlib.metadata as md
import io
import json
import os
import sys
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_write_bytes, link_or_copy
from cassi.harness.farm.store import sha256_file
from cassi.renderer import animate, images
from cassi.data.xrmb.files import NOMINAL_PERIOD_US
from cassi.renderer.animate import write_animation
from cassi.renderer.images import tile
from cassi.harness.evaluation.frames import video_grid


#: A report's copies of renders: lossless WebP (``exact``: every pixel kept, under transparent
#: alpha too). Measured on 300 of a run's 256-px renders (mostly front): method 1 gives 0.63 of
#: the PNGs' bytes in 5.9 ms a render, method 0 0.76 in 2.5 ms, method 2 0.62 in 8.0 ms; on 150
#: of a default night's report images, against method 1 at quality 0 (lossless: quality is the
#: effort, never a loss): method 2 quality 50 0.918 of the bytes in 14 ms, method 4 quality 50
#: 0.853 in 40 ms, method 6 quality 100 0.819 in 600 ms. Method 2 at 50 keeps a night's report
#: under 150 MB for about 30 s more encoding on the first night (later nights link the cache).
WEBP_OPTIONS = {"lossless": True, "exact": True, "method": 2, "quality": 50}
#: A large run's (a full set's: about 9,000 pictures a subject, on its viewer pages), where
#: encoding was most of the report: on 200 renders of JW11's full set, method 0 takes 1.2 ms a
#: render against method 2's 9.1 ms, for 0.74 of the PNGs' bytes against 0.58. Still lossless.
WEBP_FAST_OPTIONS = {"lossless": True, "exact": True, "method": 0, "quality": 0}
IMAGE_SUFFIX = ".webp"


@functools.lru_cache(maxsize=None)
def _webp_code(fast: bool = False) -> str:
    """What a report image's bytes depend on besides the pixels: the options, Pillow and libwebp."""
    from PIL import __version__ as pillow, features  # noqa: PLC0415 - Pillow comes with imageio

    doc = {"options": WEBP_FAST_OPTIONS if fast else WEBP_OPTIONS, "pillow": pillow,
           "libwebp": features.version("webp")}
    return json.dumps(doc, sort_keys=True)


def webp_bytes(src: str | os.PathLike, *, fast: bool = False) -> bytes:
    """The image file ``src`` (a render's PNG: RGB, or RGBA) as lossless WebP: the same pixels,
    none of the PNG's text chunks, so renders with the same pixels give the same bytes.
    ``fast``: :data:`WEBP_FAST_OPTIONS`."""
    from PIL import Image  # noqa: PLC0415

    with Image.open(src) as img:
        img.load()
        if img.mode not in ("RGB", "RGBA"):
            img = img.convert("RGBA" if "A" in img.getbands() else "RGB")
        buf = io.BytesIO()
        img.save(buf, "WEBP", **(WEBP_FAST_OPTIONS if fast else WEBP_OPTIONS))
    return buf.getvalue()


def store_image(src: str | os.PathLike, images: Path, cache: Path | None = None, *,
                fast: bool = False) -> Path:
    """A render beside the report, content-addressed: ``images/<ab>/<sha256>.webp``, named by
    the SHA-256 of its lossless WebP bytes (:func:`webp_bytes`, ``fast`` for a large run), so a
    picture that several renders, pages or versions show is stored once. With ``cache`` (a
    nightly store's media), an encoding made before from the same PNG bytes and codec is
    linked, not made again."""
    cached = None
    if cache is not None:
        key = hashlib.sha256(f"{sha256_file(src)} {_webp_code(fast)}".encode()).hexdigest()
        cached = cache / f"{key}{IMAGE_SUFFIX}"
    if cached is not None and cached.is_file():
        data = cached.read_bytes()
    else:
        data = webp_bytes(src, fast=fast)
    digest = hashlib.sha256(data).hexdigest()
    dest = images / digest[:2] / f"{digest}{IMAGE_SUFFIX}"
    if not dest.is_file():
        dest.parent.mkdir(parents=True, exist_ok=True)
        if cached is not None and cached.is_file():
            link_or_copy(cached, dest)
        else:
            atomic_write_bytes(dest, data, durable=False)
    if cached is not None and not cached.is_file():
        cache.mkdir(parents=True, exist_ok=True)
        link_or_copy(dest, cached)
    return dest


def read_rgb8(path) -> np.ndarray:
    """An image file as 8-bit RGB (grey expanded, alpha dropped)."""
    from PIL import Image  # noqa: PLC0415 - Pillow comes with imageio

    with Image.open(path) as img:
        if img.mode in _PIL_TO_RGB:  # Pillow directly: imageio's wrapper decoded each PNG twice
            return np.asarray(img.convert("RGB"))
    img = np.asarray(iio.imread(path))
    if img.ndim == 2:
        img = np.stack([img] * 3, axis=-1)
    return img[..., :3].astype(np.uint8)


#: 8-bit modes whose conversion to RGB keeps the values (alpha dropped, grey expanded).
_PIL_TO_RGB = frozenset({"RGB", "RGBA", "RGBX", "L", "LA", "P", "PA"})
LABEL_PX = 14
_LABEL_BG = (24, 24, 24)


@functools.lru_cache(maxsize=256)
def _label_line(width: int, text: str) -> np.ndarray:
    """One line of label text on the band's colour, (LABEL_PX, width, 3): a video draws a
    panel's name once and each frame's time once for all its panels."""
    from PIL import Image, ImageDraw, ImageFont  # noqa: PLC0415 - Pillow comes with imageio

    font = ImageFont.load_default(size=LABEL_PX - 3)
    canvas = Image.new("RGB", (width, LABEL_PX), _LABEL_BG)
    ImageDraw.Draw(canvas).text((4, 1), text, fill=(235, 235, 235), font=font)
    out = np.asarray(canvas)
    out.flags.writeable = False
    return out


def label_panel(image: np.ndarray, lines: list[str]) -> np.ndarray:
    """``image`` (uint8 (H, W, 3)) with a dark band on top carrying ``lines`` of text."""
    width = image.shape[1]
    parts = [_label_line(width, line) for line in lines]
    parts.append(np.full((2, width, 3), _LABEL_BG, np.uint8))
    parts.append(np.ascontiguousarray(image[..., :3], np.uint8))
    return np.concatenate(parts, axis=0)


def video_frames(renders: pd.DataFrame, *, stride: int) -> list[int]:
    """The frames of ``renders`` that lie on the video grid (first frame + k * ``stride``) and
    were rendered in every (version, view) of the table, so all panels move together.
    Extreme frames off the grid are left out: they would break the time base."""
    if not len(renders) or stride < 1:
        return []
    panels = renders.groupby(["version", "view"])["frame"].apply(lambda f: set(int(x) for x in f))
    return video_grid(set.intersection(*panels.tolist()), first=int(renders["frame"].min()),
                      stride=stride)


@functools.lru_cache(maxsize=None)
def _media_code() -> str:
    """Digest of the code that composes a video (this module, the writer, the tiler) and of
    the encoder's version: a cached video is reused only when both are unchanged."""
    h = hashlib.sha256(md.version("imageio-ffmpeg").encode())
    for module in (sys.modules[__name__], animate, images):
        h.update(Path(module.__file__).read_bytes())
    return h.hexdigest()


def _video_key(frames: list[int], paths: pd.Series, columns, stride: int, subject: str,
               task: int, audio: Path | None, period_us: float = NOMINAL_PERIOD_US) -> str:
    """What a task video is made of: the renders (content-addressed: their names are their
    SHA-256), the panels, the time base, the labels, the sound and the code."""
    doc = {"columns": [list(c) for c in columns], "stride": stride, "subject": subject,
           "task": task, "frames": [[v, w, f, Path(str(paths[(v, w, f)])).name]
                                    for f in frames for v, w in columns],
           "audio": sha256_file(audio) if audio is not None else None, "code": _media_code()}
    if period_us != NOMINAL_PERIOD_US:  # XRMB's keys stay those of the videos cached before
        doc["period_us"] = float(period_us)
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def _grid(renders: pd.DataFrame, columns, stride: int):
    """(frames on the video grid, paths by (version, view, frame)) of ``columns``' renders."""
    wanted = renders[[(v, w) in set(columns) for v, w in zip(renders["version"], renders["view"])]]
    return video_frames(wanted, stride=stride), wanted.set_index(["version", "view", "frame"])["path"]


def cached_video(renders: pd.DataFrame, *, stride: int, columns: list[tuple[str, str]],
                 audio: Path | None = None, cache: Path | None = None,
                 period_us: float = NOMINAL_PERIOD_US) -> Path | None:
    """The file in ``cache`` that :func:`task_video` would link for these arguments, or None
    when there is none (nothing cached, no cache, or too few grid frames for a video)."""
    if cache is None:
        return None
    frames, paths = _grid(renders, columns, stride)
    if len(frames) < 2:
        return None
    subject, task = renders["subject"].iloc[0], int(renders["task"].iloc[0])
    key = _video_key(frames, paths, columns, stride, subject, task, audio, period_us)
    path = cache / f"{key}.mp4"
    return path if path.is_file() else None


def task_video(renders: pd.DataFrame, dest: Path, *, stride: int, columns: list[tuple[str, str]],
               audio: Path | None = None, cache: Path | None = None,
               period_us: float = NOMINAL_PERIOD_US) -> dict | None:
    """A video of one task file: per frame, one labelled panel per (version, view) of
    ``columns``, side by side, played in real time (one frame per ``stride`` rows of
    ``period_us``, the recording's period: 6866 us on XRMB, 2000 us on 500 Hz EMA).

    ``renders`` holds one subject, task and rep (columns version, view, frame, path). Each panel
    is labelled with version, view, subject, task and time. With ``audio`` (the task's WAV, at
    any sample rate; time 0 = the recording's first row) the video carries the sound in sync. Returns a description
    (path, frames, fps, stride, audio) or None when fewer than two grid frames exist in every
    panel. With ``cache`` (a directory shared between reports, e.g. a nightly store's media),
    a video made of the same renders, sound and code before is linked, not encoded again.
    """
    frames, paths = _grid(renders, columns, stride)
    if len(frames) < 2:
        return None
    subject, task = renders["subject"].iloc[0], int(renders["task"].iloc[0])
    fps = 1e6 / (period_us * stride)

    def composed():
        for f in frames:
            t = f * period_us / 1e6
            panels = [label_panel(read_rgb8(paths[(v, w, f)]),
                                  [f"{v} | {w}", f"{subject} task {task} | t = {t:6.3f} s"])
                      for v, w in columns]
            sheet = tile(panels, columns=len(panels), gap=2, background=(255, 255, 255),
                         border=False)
            h, w = (sheet.shape[0] // 2) * 2, (sheet.shape[1] // 2) * 2  # yuv420p: even sizes
            yield sheet[:h, :w]

    duration = len(frames) / fps
    dest.parent.mkdir(parents=True, exist_ok=True)
    cached = None
    if cache is not None:
        key = _video_key(frames, paths, columns, stride, subject, task, audio, period_us)
        cached = cache / f"{key}.mp4"
    if cached is not None and cached.is_file():
        link_or_copy(cached, dest)
    else:
        write_animation(dest, composed(), fps=fps, quality=5, audio=audio,
                        audio_start_s=frames[0] * period_us / 1e6, duration_s=duration)
        if cached is not None:
            cache.mkdir(parents=True, exist_ok=True)
            link_or_copy(dest, cached)
    return {"path": dest, "frames": len(frames), "fps": round(fps, 3), "stride": stride,
            "audio": audio is not None, "seconds": round(duration, 2)}
