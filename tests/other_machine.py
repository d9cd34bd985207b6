"""Renders as another machine makes them, to test the golden tolerance against them.

:func:`llvm_target` renders with Dr.Jit's LLVM backend compiled for another CPU target (vector
width, features), the way another machine's kernels come out; :func:`as_another_cpu` changes a
render the way the reported AMD EPYC (AVX-512) machine changed the half view's golden image.

drjit-core has ``jit_llvm_set_target(cpu, features, vector_width)`` (documented in its
``include/drjit-core/jit.h``: "Override the target CPU, features, and vector width of the LLVM
backend") but the Python package does not bind it, so it is called through ctypes; its symbol is
C++-mangled in drjit 1.x. Kernels already compiled for the old target are flushed, and the old
target is restored on exit, so later tests render as before.
"""
from __future__ import annotations

import ctypes
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from cassi.renderer.variant import activate_variant

_SYMBOLS = {"set": "_Z19jit_llvm_set_targetPKcS0_j", "cpu": "_Z19jit_llvm_target_cpuv",
            "features": "_Z24jit_llvm_target_featuresv", "width": "_Z21jit_llvm_vector_widthv",
            "flush": "_Z22jit_flush_kernel_cachev"}


def _core():
    import drjit as dr  # noqa: PLC0415 - Mitsuba's Dr.Jit, loaded on first render as elsewhere

    lib = ctypes.CDLL(str(Path(dr.__file__).parent / "libdrjit-core.so"))
    fns = {}
    for name, symbol in _SYMBOLS.items():
        fn = getattr(lib, symbol, None)
        if fn is None:
            pytest.skip(f"this drjit ({dr.__version__}) does not export {symbol}")
        fns[name] = fn
    fns["set"].argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    fns["cpu"].restype = fns["features"].restype = ctypes.c_char_p
    fns["width"].restype = ctypes.c_uint32
    return fns


@contextmanager
def llvm_target(cpu: str, features: str | None, vector_width: int):
    """Within the block, llvm_ad_rgb kernels are compiled for ``cpu`` with ``features`` (LLVM
    names, e.g. "haswell", "+avx2,+fma") and ``vector_width`` lanes. Yields the previous
    (cpu, features, width), so a test can check that the target really changed."""
    import drjit as dr  # noqa: PLC0415 - loaded on first render, as the renderer does
    import mitsuba as mi  # noqa: PLC0415

    activate_variant("llvm_ad_rgb")
    dr.eval(dr.arange(mi.Float, 4))  # the backend sets its native target when it starts
    core = _core()
    before = (core["cpu"](), core["features"](), int(core["width"]()))
    core["set"](cpu.encode(), features.encode() if features else None, vector_width)
    core["flush"]()
    try:
        yield before
    finally:
        core["set"](before[0], before[1], before[2])
        core["flush"]()


#: The reported failure: 107 pixels differed by more than one level, up to 38, all in rows 0-22,
#: columns 91-123 of the 256 x 256 half view (the edge of the eye's specular highlight).
CPU_BOX = (0, 23, 91, 124)
CPU_PIXELS = 107
CPU_LEVELS = 38


def as_another_cpu(srgb: np.ndarray, box=CPU_BOX, pixels: int = CPU_PIXELS,
                   levels: int = CPU_LEVELS) -> np.ndarray:
    """uint8 (H, W, 3): ``srgb`` with the ``pixels`` pixels of steepest brightness inside ``box``
    (the highlight's edge, where last-bit differences of the normal show) moved by up to
    ``levels`` levels in proportion to their slope: bright ones darker, dark ones brighter, as
    when the highlight comes out a little smaller or larger."""
    r0, r1, c0, c1 = box
    lum = srgb[..., :3].astype(np.float64).mean(axis=2)
    gy, gx = np.gradient(lum)
    slope = np.hypot(gx, gy)[r0:r1, c0:c1]
    order = np.argsort(slope, axis=None)[::-1][:pixels]
    rows, cols = np.unravel_index(order, slope.shape)
    step = np.maximum(2, np.rint(levels * slope[rows, cols] / slope[rows[0], cols[0]]))
    rows, cols = rows + r0, cols + c0
    sign = np.where(lum[rows, cols] > np.median(lum[r0:r1, c0:c1]), -1.0, 1.0)
    out = srgb[..., :3].astype(np.int16)
    out[rows, cols] += (sign * step).astype(np.int16)[:, None]
    return np.clip(out, 0, 255).astype(np.uint8)
