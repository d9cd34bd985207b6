"""The one rule by which two renders of a frame count as the same picture: the golden tests
(tests/renderer/test_render_golden.py) and the nightly's image gates (cassi.reports.gates) both use it.

Why a tolerance at all: a preview frame is the same bytes in every run of one build on one
machine (checked separately, tests/renderer/test_render_golden.py::test_render_is_reproducible), but
Dr.Jit compiles its LLVM kernels for the CPU it runs on (vector width, fused multiply-add,
instruction choice), so a golden image made on one machine and a frame rendered on another
differ: scalar_rgb, and llvm at another vector width, by at most one 8-bit level where the parts
agree; a machine with another CPU in up to 107 pixels (0.16%) at the edge of the eye's specular
highlight, by up to 38 levels, where ``(n . h) ** shininess`` turns last-bit differences of the
normal into visible ones. The rule is Blender's for its render tests: a per-pixel threshold and
a largest share of pixels beyond it, plus, where part masks are given, their agreement.

Measured on the neutral face (256 x 256 preview, share of pixels beyond one level against the
llvm render): another code path 0 to 0.002%; the jaw lowered by 4 Parke units (0.5 degrees)
1.1% (side) to 3.5% (top); the skin 2% darker 9.9% to 18%; the lights mirrored 29% to 48%.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PIXEL_LEVELS", "MAX_CHANGED_SHARE", "MASK_AGREEMENT_MIN", "ImageComparison",
           "compare_images"]

#: A pixel has changed when a channel differs by more than this many 8-bit levels: code paths
#: differ by one level at most (float rounding that crosses an 8-bit boundary), while a 2%
#: darker material moves 10-18% of the pixels by two levels, so the threshold cannot be higher.
PIXEL_LEVELS = 1
#: Largest share of pixels that may change: three times the 0.16% that another CPU changes at
#: the eye's highlight, and half of the smallest real change measured (the jaw lowered by 4 Parke
#: units: 1.1% in the side view). A change confined to fewer pixels passes (the jaw lowered by 2
#: units changes 0.34% of the side view); the part masks (below) still catch geometry.
MAX_CHANGED_SHARE = 0.005
#: Least share of pixels whose part ids agree: llvm and scalar_rgb differ in one silhouette pixel
#: (0.0015%) where a ray grazes an edge; the jaw lowered by 2 Parke units leaves 0.9978 in the
#: half view and 0.9988 in the top view (0.9996 in the front and side views, which pass).
MASK_AGREEMENT_MIN = 0.999


@dataclass(frozen=True)
class ImageComparison:
    """How a render differs from its reference, and whether that is within the rule.

    ``changed_px`` pixels (of ``pixels``) differ by more than ``levels`` in a channel, among the
    pixels whose part ids agree when masks were given; ``max_levels`` is the largest difference
    there; ``mask_agreement`` is None without masks.
    """

    pixels: int
    changed_px: int
    max_levels: int
    mask_agreement: float | None
    levels: int
    max_share: float
    mask_agreement_min: float

    @property
    def changed_share(self) -> float:
        return self.changed_px / self.pixels if self.pixels else 0.0

    @property
    def colour_ok(self) -> bool:
        return self.changed_share <= self.max_share

    @property
    def mask_ok(self) -> bool:
        return self.mask_agreement is None or self.mask_agreement >= self.mask_agreement_min

    @property
    def passed(self) -> bool:
        return self.colour_ok and self.mask_ok

    @property
    def reason(self) -> str:
        text = (f"{self.changed_px} px ({100 * self.changed_share:.3f}%) differ by more than "
                f"{self.levels} level (max {self.max_levels}; allowed "
                f"{100 * self.max_share:.2f}%)")
        if self.mask_agreement is not None:
            text += (f"; part masks agree on {self.mask_agreement:.5f} of the pixels "
                     f"(least {self.mask_agreement_min})")
        return text


def compare_images(rendered: np.ndarray, reference: np.ndarray, *,
                   rendered_mask: np.ndarray | None = None,
                   reference_mask: np.ndarray | None = None,
                   levels: int = PIXEL_LEVELS, max_share: float = MAX_CHANGED_SHARE,
                   mask_agreement_min: float = MASK_AGREEMENT_MIN) -> ImageComparison:
    """Compare two 8-bit RGB images of one shape (uint8 (H, W, >=3); alpha ignored) and,
    optionally, their part-id masks (int (H, W), both or neither).

    Raises
    ------
    ValueError
        When the shapes differ or only one mask is given.
    """
    rendered, reference = np.asarray(rendered)[..., :3], np.asarray(reference)[..., :3]
    if rendered.shape != reference.shape:
        raise ValueError(f"image shapes differ: {rendered.shape} vs {reference.shape}")
    if (rendered_mask is None) != (reference_mask is None):
        raise ValueError("give both part masks or neither")
    diff = np.abs(rendered.astype(np.int16) - reference.astype(np.int16)).max(axis=2)
    agreement = None
    if rendered_mask is not None:
        rendered_mask, reference_mask = np.asarray(rendered_mask), np.asarray(reference_mask)
        if rendered_mask.shape != diff.shape or reference_mask.shape != diff.shape:
            raise ValueError(f"mask shapes {rendered_mask.shape}, {reference_mask.shape} do not "
                             f"match the image {diff.shape}")
        same_part = rendered_mask == reference_mask
        agreement = float(same_part.mean())
        diff = diff[same_part]
    return ImageComparison(pixels=int(rendered.shape[0] * rendered.shape[1]),
                           changed_px=int((diff > levels).sum()),
                           max_levels=int(diff.max(initial=0)), mask_agreement=agreement,
                           levels=int(levels), max_share=float(max_share),
                           mask_agreement_min=float(mask_agreement_min))
