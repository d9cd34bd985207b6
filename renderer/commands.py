"""The ``cassi render`` and ``cassi animate`` command lines, given where positions come from.

The renderer takes vertex positions only: it may import ``cassi.data`` but not the versions or
the harness. The harness registers these commands (:mod:`cassi.harness.render_commands`) with a
*positions provider* that answers
``(corpus, subject, task, rep, version) -> (face, frames int64 (F,), positions float32 (F, V, 3))``
through the same corpus -> profile -> face -> version path as ``cassi run``.
"""
from __future__ import annotations

import argparse
import logging
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError

from .views import PRESET_NAMES, VIEW_NAMES

__all__ = ["register", "NEUTRAL"]

log = logging.getLogger(__name__)
#: The version name that stands for the subject's neutral face in every frame.
NEUTRAL = "neutral"

PositionsProvider = Callable[..., tuple[object, np.ndarray, np.ndarray]]


def _frame_index(frames: np.ndarray, frame: int) -> int:
    hits = np.flatnonzero(frames == frame)
    if not hits.size:
        lo, hi = (int(frames[0]), int(frames[-1])) if frames.size else (None, None)
        raise CassiInputError(f"frame {frame} is not animated (frames {lo}..{hi})")
    return int(hits[0])


def _cmd_render(args, provider: PositionsProvider) -> int:
    from cassi.data.face.model import render_topology

    from .images import write_exr, write_mask_png, write_png, write_sidecar
    from .render import FaceRenderer

    out = Path(args.out)
    if out.suffix.lower() not in (".png", ".exr"):
        raise CassiInputError("--out must end in .png or .exr", path=out)
    face, frames, positions = provider(args.corpus, args.subject, args.task, args.rep, args.version)
    k = _frame_index(frames, args.frame)
    renderer = FaceRenderer(render_topology(face, half=(args.view == "half")), args.view,
                            args.preset, args.variant)
    res = renderer.render(positions[k])
    meta = {**res.metadata(), "subject": args.subject, "task": args.task, "rep": args.rep,
            "version": args.version, "frame": int(args.frame)}
    if out.suffix.lower() == ".exr":
        write_exr(out, res.rgb, depth=res.depth, mask=res.mask, metadata=meta)
    else:
        write_png(out, res.rgb, metadata=meta)
    written = [out]
    if args.mask:
        written.append(write_mask_png(out.with_name(out.stem + ".mask.png"), res.mask, metadata=meta))
    written.append(write_sidecar(out.with_name(out.name + ".json"), meta))
    for p in written:
        print(p)
    log.info("rendered %s %s frame %d with %s", args.view, args.version, args.frame, res.variant)
    return 0


def _cmd_animate(args, provider: PositionsProvider) -> int:
    from .animate import animate_positions

    views = [v.strip() for v in args.views.split(",") if v.strip()]
    face, frames, positions = provider(args.corpus, args.subject, args.task, args.rep, args.version)
    if args.start is not None or args.end is not None:
        keep = (frames >= (args.start if args.start is not None else frames.min())) & \
               (frames <= (args.end if args.end is not None else frames.max()))
        positions = positions[keep]
        if not len(positions):
            raise CassiInputError("no animated frame in the --start/--end range")
    if args.version == NEUTRAL:
        positions = positions[:1]  # a still face: one frame is the whole animation
    summary = animate_positions(face, positions, args.out, views=views, stride=args.stride,
                                preset=args.preset, variant=args.variant, fps=args.fps)
    print(summary["path"])
    log.info("animation: %s", summary)
    return 0


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--corpus", default=None,
                   help="corpus directory (see cassi corpus; default: the embedded synthetic one)")
    p.add_argument("--subject", required=True, help="subject name, e.g. JW45")
    p.add_argument("--task", required=True, type=int, help="task number")
    p.add_argument("--rep", type=int, default=1, help="repetition (default 1)")
    p.add_argument("--version", required=True,
                   help=f"'{NEUTRAL}' (the subject's neutral face) or a registered version "
                        "(cassi versions)")
    p.add_argument("--preset", default="preview", choices=PRESET_NAMES, help="quality preset")
    p.add_argument("--variant", default=None,
                   help="Mitsuba variant (cuda_ad_rgb, llvm_ad_rgb, scalar_rgb; default: "
                        "$CASSI_VARIANT or the fastest usable)")


def register(sub, *, positions_provider: PositionsProvider) -> None:
    """Add ``render`` and ``animate`` to the ``cassi`` subcommands, animating through
    ``positions_provider``."""
    provider = positions_provider

    p = sub.add_parser("render", help="render one frame of a task in one view (PNG or EXR)",
                       description="Render one frame with Mitsuba 3; writes the image, a JSON "
                                   "sidecar with the render metadata and optionally the mask.")
    _common(p)
    p.add_argument("--view", required=True, choices=VIEW_NAMES)
    p.add_argument("--frame", required=True, type=int, help="recording row to render")
    p.add_argument("--out", required=True, help="output file, .png (sRGB) or .exr (linear)")
    p.add_argument("--mask", action="store_true", help="also write <out stem>.mask.png")
    p.set_defaults(func=lambda a: _cmd_render(a, provider))

    a = sub.add_parser("animate", help="render a task as MP4 or GIF, views side by side",
                       description="Render every STRIDE-th animated frame of a task in the "
                                   "given views, side by side, as an MP4 or GIF.")
    _common(a)
    a.add_argument("--views", default="front,side", help="comma-separated views (front,side)")
    a.add_argument("--stride", type=int, default=5, help="render every Nth frame (default 5)")
    a.add_argument("--start", type=int, default=None, help="first recording row")
    a.add_argument("--end", type=int, default=None, help="last recording row")
    a.add_argument("--fps", type=float, default=None, help="frames per second (default: real time)")
    a.add_argument("--out", required=True, help="output .mp4 or .gif")
    a.set_defaults(func=lambda a_: _cmd_animate(a_, provider))
