"""What ``cassi render``, ``cassi animate`` and ``cassi export`` do (parsers: :mod:`cassi.renderer.commands`),
with the positions provider the harness named there."""
from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.common.lazy import resolve
from cassi.data.face.topology import render_topology
from cassi.data.xrmb.files import NOMINAL_PERIOD_US, recording_period_us
from cassi.renderer.animate import animate_positions
from cassi.renderer.commands import NEUTRAL
from cassi.renderer.gltf import write_glb
from cassi.renderer.images import write_exr, write_mask_png, write_png, write_sidecar
from cassi.renderer.render import FaceRenderer

log = logging.getLogger(__name__)


def _frame_index(frames: np.ndarray, frame: int) -> int:
    hits = np.flatnonzero(frames == frame)
    if not hits.size:
        lo, hi = (int(frames[0]), int(frames[-1])) if frames.size else (None, None)
        raise CassiInputError(f"frame {frame} is not animated (frames {lo}..{hi})")
    return int(hits[0])


def _animated(args):
    """(face, recording rows, positions, sample times us) from the command's positions provider.
    A provider may leave the times out (three values): its rows are then XRMB's, 6866 us
    apart."""
    provider = resolve(args.positions_provider)
    face, frames, positions, *times = provider(args.corpus, args.subject, args.task, args.rep,
                                               args.version)
    frames = np.asarray(frames, np.int64)
    time_us = np.asarray(times[0], np.int64) if times else frames * NOMINAL_PERIOD_US
    return face, frames, positions, time_us


def cmd_render(args) -> int:
    out = Path(args.out)
    if out.suffix.lower() not in (".png", ".exr"):
        raise CassiInputError("--out must end in .png or .exr", path=out)
    face, frames, positions, _ = _animated(args)
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


def cmd_animate(args) -> int:
    views = [v.strip() for v in args.views.split(",") if v.strip()]
    face, frames, positions, time_us = _animated(args)
    if args.start is not None or args.end is not None:
        keep = (frames >= (args.start if args.start is not None else frames.min())) & \
               (frames <= (args.end if args.end is not None else frames.max()))
        positions = positions[keep]
        if not len(positions):
            raise CassiInputError("no animated frame in the --start/--end range")
    if args.version == NEUTRAL:
        positions = positions[:1]  # a still face: one frame is the whole animation
    summary = animate_positions(face, positions, args.out, views=views, stride=args.stride,
                                preset=args.preset, variant=args.variant, fps=args.fps,
                                period_us=recording_period_us(time_us))
    print(summary["path"])
    log.info("animation: %s", summary)
    return 0


def cmd_export(args) -> int:
    out = Path(args.out)
    if out.suffix.lower() != ".glb":
        raise CassiInputError("--out must end in .glb (binary glTF 2.0)", path=out)
    if out.is_dir():
        raise CassiInputError("--out is a directory", path=out)
    if args.stride < 1:
        raise CassiInputError(f"--stride must be at least 1, not {args.stride}")
    face, frames, positions, time_us = _animated(args)
    if args.version == NEUTRAL:
        frames, positions = frames[:1], positions[:1]  # a still face: no animation
    frames, positions = frames[::args.stride], positions[::args.stride]
    time_us = time_us[::args.stride][:len(frames)]
    if not len(frames):
        raise CassiInputError("the task has no animated frame")
    summary = write_glb(out, render_topology(face), face.vertices, positions,
                        time_us * 1e-6, quantize=args.positions == "int16",
                        name=f"{args.subject} task {args.task} rep {args.rep} {args.version}",
                        mm_per_unit=1.0 / face.units_per_mm)  # the subject's size (d / p)
    print(out)
    log.info("glTF: %d frame(s), %d vertices (%d moving), %d bytes, %d bytes of deltas per "
             "frame, %.0f bytes per frame in all", summary.frames, summary.vertices,
             summary.moving_vertices, summary.bytes, summary.target_bytes_per_frame,
             summary.bytes_per_frame)
    return 0
