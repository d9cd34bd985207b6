"""The ``cassi render``, ``cassi animate`` and ``cassi export`` command lines, given where positions come from.

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

import numpy as np


from cassi.common.cliargs import ascii_int, positive_number
from cassi.renderer.views import PRESET_NAMES, VIEW_NAMES

__all__ = ["register", "NEUTRAL"]

log = logging.getLogger(__name__)
#: The version name that stands for the subject's neutral face in every frame.
NEUTRAL = "neutral"

#: ``(corpus, subject, task, rep, version) -> (face, rows, positions[, time_us])``: without the
#: rows' times the rows are taken as XRMB's, 6866 us apart.
PositionsProvider = Callable[..., tuple]


def _task(p: argparse.ArgumentParser) -> None:
    p.add_argument("--corpus", default=None,
                   help="corpus directory (see cassi corpus; default: the embedded synthetic one)")
    p.add_argument("--subject", required=True, help="subject name, e.g. JW45")
    p.add_argument("--task", required=True, type=ascii_int, help="task number")
    p.add_argument("--rep", type=ascii_int, default=1, help="repetition (default 1)")
    p.add_argument("--version", required=True,
                   help=f"'{NEUTRAL}' (the subject's neutral face) or a registered version "
                        "(cassi versions)")


def _common(p: argparse.ArgumentParser) -> None:
    _task(p)
    p.add_argument("--preset", default="preview", choices=PRESET_NAMES, help="quality preset")
    p.add_argument("--variant", default=None,
                   help="Mitsuba variant (cuda_ad_rgb, llvm_ad_rgb, scalar_rgb; default: "
                        "$CASSI_VARIANT or the fastest usable)")


def register(sub, *, positions_provider: PositionsProvider | str) -> None:
    """Add ``render``, ``animate`` and ``export`` to the ``cassi`` subcommands, animating through
    ``positions_provider`` (or the ``"module:function"`` that names it)."""
    provider = positions_provider

    p = sub.add_parser("render", help="render one frame of a task in one view (PNG or EXR)",
                       description="Render one frame with Mitsuba 3; writes the image, a JSON "
                                   "sidecar with the render metadata and optionally the mask.")
    _common(p)
    p.add_argument("--view", required=True, choices=VIEW_NAMES)
    p.add_argument("--frame", required=True, type=ascii_int, help="recording row to render")
    p.add_argument("--out", required=True, help="output file, .png (sRGB) or .exr (linear)")
    p.add_argument("--mask", action="store_true", help="also write <out stem>.mask.png")
    p.set_defaults(func="cassi.renderer.actions:cmd_render", positions_provider=provider)

    a = sub.add_parser("animate", help="render a task as MP4 or GIF, views side by side",
                       description="Render every STRIDE-th animated frame of a task in the "
                                   "given views, side by side, as an MP4 or GIF.")
    _common(a)
    a.add_argument("--views", default="front,side", help="comma-separated views (front,side)")
    a.add_argument("--stride", type=ascii_int, default=5, help="render every Nth frame (default 5)")
    a.add_argument("--start", type=ascii_int, default=None, help="first recording row")
    a.add_argument("--end", type=ascii_int, default=None, help="last recording row")
    a.add_argument("--fps", type=positive_number, default=None, help="frames per second (default: real time)")
    a.add_argument("--out", required=True, help="output .mp4 or .gif")
    a.set_defaults(func="cassi.renderer.actions:cmd_animate", positions_provider=provider)

    e = sub.add_parser("export", help="write a task's animated face as glTF 2.0 (.glb)",
                       description="Write the mirrored face of a task as binary glTF 2.0: one "
                                   "mesh, a primitive and material per part, one morph target "
                                   "per kept frame keyed at the recording's own times (its "
                                   "period x STRIDE: 6866 us on XRMB). Opens in Blender (File > Import > glTF 2.0) and "
                                   "any glTF viewer.")
    _task(e)
    e.add_argument("--format", default="gltf", choices=("gltf",), help="output format (gltf)")
    e.add_argument("--stride", type=ascii_int, default=1, help="keep every Nth frame (default 1)")
    e.add_argument("--positions", default="int16", choices=("int16", "float32"),
                   help="int16: quantised (KHR_mesh_quantization, the default); float32: exact")
    e.add_argument("--out", required=True, help="output .glb")
    e.set_defaults(func="cassi.renderer.actions:cmd_export", positions_provider=provider)
