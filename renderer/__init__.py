"""cassi.renderer: Mitsuba 3 batch rendering of face mesh sequences from the front, side,
half-face and top-of-palate views, with masks for image metrics. Imports cassi.data only.

Public names: :class:`FaceRenderer`, :class:`RenderResult`, :func:`choose_variant`,
the writers in :mod:`cassi.renderer.images`, animations in :mod:`cassi.renderer.animate`,
views and presets in :mod:`cassi.renderer.views`. Mitsuba itself is imported on first use.
"""
from cassi.renderer.images import FrameWriter, tile, write_exr, write_mask_png, write_png, write_result
from cassi.renderer.render import FaceRenderer, RenderResult
from cassi.renderer.variant import choose_variant
from cassi.renderer.views import PRESET_NAMES, PRESETS, VIEW_NAMES, VIEWS

__all__ = ["FaceRenderer", "RenderResult", "choose_variant", "FrameWriter", "tile",
           "write_exr", "write_png", "write_mask_png", "write_result", "VIEWS", "VIEW_NAMES",
           "PRESETS", "PRESET_NAMES"]
