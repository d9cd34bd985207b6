"""Animations of a task: every ``stride``-th frame, the chosen views side by side, written as MP4
(H.264) or GIF through imageio-ffmpeg. One ``FaceRenderer`` per view renders all frames (scene
loaded once per view); frames stream to ffmpeg, so memory stays flat however long the task.
"""
from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path

import numpy as np

from cassi.common.atomic import replacing
from cassi.common.errors import CassiInputError
from cassi.data.xrmb.files import NOMINAL_PERIOD_US  # XRMB's period: the default, us

from cassi.renderer.views import VIEW_NAMES
from cassi.data.face.model import render_topology
from cassi.renderer.render import FaceRenderer
from cassi.renderer.images import tile, write_contact_sheet

__all__ = ["side_by_side", "animation_frames", "write_animation", "animate_positions", "views_sheet",
           "realtime_fps"]



def realtime_fps(stride: int, *, period_us: float = NOMINAL_PERIOD_US, cap: float = 50.0) -> float:
    """Frames per second that play a recording at its own speed at ``stride``, capped (GIF
    players round delays to 1/100 s; 50 fps is the fastest they keep)."""
    return float(min(cap, 1e6 / (period_us * max(1, stride))))


#: x264's speed preset. Measured on 354 five-panel report frames (1280x256): "medium" (the
#: default) 2.04 s of encoder CPU and 732 KB, "veryfast" 1.13 s and 918 KB, "superfast" 0.89 s
#: and 1.7 MB. A night encodes about 18,000 such panels; its videos are 5 MB of 150.
X264_SPEED = ("-preset", "veryfast")


def side_by_side(images: Sequence[np.ndarray], gap: int = 0) -> np.ndarray:
    """uint8 (H, sum W, 3) of equal-height images (linear float images are sRGB-encoded)."""
    if len({i.shape[0] for i in images}) != 1:
        raise ValueError("side_by_side needs images of equal height")
    return tile(images, columns=len(images), gap=gap, background=(0, 0, 0), border=False)


def animation_frames(renderers: Sequence, positions: Iterable[np.ndarray]) -> Iterator[np.ndarray]:
    """For each (V, 3) positions array, the views of all ``renderers`` side by side (uint8)."""
    for pos in positions:
        yield side_by_side([r.render(pos).rgb for r in renderers])


def write_animation(path: str | os.PathLike, frames: Iterable[np.ndarray], *, fps: float,
                    quality: float = 7, audio: Path | None = None, audio_start_s: float = 0.0,
                    duration_s: float | None = None) -> Path:
    """Stream uint8 (H, W, 3) frames to ``path`` (``.mp4``: H.264 yuv420p; ``.gif``), atomically:
    the one video writer (``cassi animate`` and the report's task videos).

    ``quality`` is imageio-ffmpeg's 0-10 scale. With ``audio`` (a WAV; MP4 only), its part from
    ``audio_start_s`` for ``duration_s`` is muxed in (AAC), so sound and picture start together.
    Returns the path. Raises CassiInputError for another suffix or no frames.
    """
    import imageio_ffmpeg

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".mp4":
        kw = dict(codec="libx264", pix_fmt_out="yuv420p", quality=quality,
                  output_params=list(X264_SPEED))
        if audio is not None:
            trim = f"atrim=start={audio_start_s:.6f}"
            if duration_s is not None:
                trim += f":end={audio_start_s + duration_s:.6f}"
            kw.update(audio_path=str(audio), audio_codec="aac",
                      output_params=[*X264_SPEED, "-af", trim + ",asetpts=PTS-STARTPTS"])
    elif suffix == ".gif":
        kw = dict(codec="gif", pix_fmt_out="rgb8")
    else:
        raise CassiInputError("animation file must end in .mp4 or .gif", path=path)
    with replacing(path) as tmp:   # renamed onto path at the end, removed on any failure
        writer = None
        try:
            for frame in frames:
                frame = np.ascontiguousarray(frame, np.uint8)
                h, w = frame.shape[:2]
                if writer is None:
                    if suffix == ".mp4" and (h % 2 or w % 2):
                        raise ValueError("MP4 frames need even width and height")
                    writer = imageio_ffmpeg.write_frames(str(tmp), (w, h), fps=fps,
                                                         macro_block_size=2,
                                                         ffmpeg_log_level="error", **kw)
                    writer.send(None)
                    size = (h, w)
                elif (h, w) != size:
                    raise ValueError("all animation frames must have the same size")
                writer.send(frame.tobytes())
        except BaseException:
            if writer is not None:   # stop ffmpeg before its file goes
                with contextlib.suppress(Exception):
                    writer.close()
            raise
        if writer is None:
            raise CassiInputError("no frames to animate", path=path)
        writer.close()
    return path


def animate_positions(face, positions: np.ndarray, out: str | os.PathLike, *,
                      views: Sequence[str] = ("front", "side"), stride: int = 1,
                      preset: str = "preview", variant: str | None = None,
                      fps: float | None = None, period_us: float = NOMINAL_PERIOD_US) -> dict:
    """Render frames 0, stride, 2*stride, ... of ``positions`` (float (F, V, 3), Parke units) in
    ``views`` side by side and write the animation ``out`` (.mp4 or .gif), by default in real
    time for rows ``period_us`` apart (the recording's period).

    ``face`` is the ``cassi.data.face.model.FaceModel`` whose topology the positions follow.
    Returns a summary dict (frames written, views, fps, variant, path).
    """
    positions = np.asarray(positions)
    if positions.ndim != 3 or positions.shape[2] != 3 or len(positions) == 0:
        raise CassiInputError(f"positions must be (F, V, 3) with F >= 1, not {positions.shape}")
    if stride < 1:
        raise CassiInputError(f"stride must be >= 1, not {stride}")
    bad = [v for v in views if v not in VIEW_NAMES]
    if bad or not views:
        raise CassiInputError(f"unknown view(s) {bad or views}; choose from {', '.join(VIEW_NAMES)}")
    renderers = [FaceRenderer(render_topology(face, half=(v == "half")), v, preset, variant)
                 for v in views]
    picked = positions[::stride]
    fps = fps or realtime_fps(stride, period_us=period_us)
    path = write_animation(out, animation_frames(renderers, picked), fps=fps)
    return {"path": str(path), "frames": int(len(picked)), "views": list(views), "fps": fps,
            "stride": stride, "preset": preset, "variant": renderers[0].variant}


def views_sheet(face, positions: np.ndarray, *, views: Sequence[str] = VIEW_NAMES,
                preset: str = "preview", variant: str | None = None,
                out: str | os.PathLike | None = None) -> np.ndarray:
    """All ``views`` of one frame (positions (V, 3)) side by side as a uint8 contact sheet; also
    written as PNG to ``out`` when given (metadata: views, preset, variant)."""
    results = [FaceRenderer(render_topology(face, half=(v == "half")), v, preset, variant)
               .render(positions) for v in views]
    sheet = side_by_side([r.rgb for r in results], gap=4)
    if out is not None:
        write_contact_sheet(out, [sheet], columns=1,
                            metadata={"views": list(views), "preset": preset,
                                      "variant": results[0].variant})
    return sheet
