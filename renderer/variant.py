"""Choosing the Mitsuba variant: cuda on a GPU, else llvm with a usable libLLVM >= 16, else scalar.

The choice is made once per process (Mitsuba's variant is process-global) and recorded with every
image the renderer writes (EXR/PNG metadata and the JSON sidecar), so a result always says which
code path produced it. Order of precedence: the ``override`` argument, then the environment
variable ``CASSI_VARIANT``, then the automatic choice.
"""
from __future__ import annotations

import glob
import os
import re
from dataclasses import dataclass
from pathlib import Path

from cassi.common.errors import CassiInputError

__all__ = ["VARIANTS", "LLVMLibrary", "find_libllvm", "choose_variant", "activate_variant",
           "MIN_LLVM_VERSION"]

#: The three RGB variants the renderer supports, fastest first.
VARIANTS = ("cuda_ad_rgb", "llvm_ad_rgb", "scalar_rgb")
#: Dr.Jit's LLVM backend needs LLVM 16 or newer for the kernels Mitsuba 3.9 emits.
MIN_LLVM_VERSION = 16

# Where distributions put libLLVM; searched when DRJIT_LIBLLVM_PATH is unset or unusable.
_LLVM_GLOBS = (
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/lib/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM*.dylib",
    "/usr/local/opt/llvm/lib/libLLVM*.dylib",
)
_VERSION_RE = re.compile(r"libLLVM(?:-|\.so\.)(\d+)")
_DIR_VERSION_RE = re.compile(r"llvm-(\d+)")


@dataclass(frozen=True)
class LLVMLibrary:
    """A libLLVM shared library found on disk, with its major version (None when unknown)."""

    path: Path
    version: int | None


def _llvm_version(path: Path) -> int | None:
    m = _VERSION_RE.search(path.name) or _DIR_VERSION_RE.search(str(path))
    return int(m.group(1)) if m else None


def find_libllvm(*, min_version: int = MIN_LLVM_VERSION) -> LLVMLibrary | None:
    """Find a libLLVM of at least ``min_version``.

    ``DRJIT_LIBLLVM_PATH`` wins when it names an existing file whose version is at least
    ``min_version`` (or whose version cannot be read from its name: the user chose it on purpose).
    Otherwise the standard locations are searched and the newest usable library is returned.
    """
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    if env:
        p = Path(env)
        if p.is_file():
            v = _llvm_version(p)
            if v is None or v >= min_version:
                return LLVMLibrary(p, v)
    found: dict[Path, LLVMLibrary] = {}
    for pattern in _LLVM_GLOBS:
        for name in glob.glob(pattern):
            p = Path(name)
            v = _llvm_version(p)
            if p.is_file() and v is not None and v >= min_version:
                found.setdefault(p.resolve(), LLVMLibrary(p, v))
    if not found:
        return None
    # Newest first; among equal versions the shortest (canonical, e.g. libLLVM-19.so) name.
    return sorted(found.values(), key=lambda lib: (-(lib.version or 0), len(str(lib.path))))[0]


def _cuda_usable() -> bool:
    import drjit as dr
    try:
        return bool(dr.has_backend(dr.JitBackend.CUDA))
    except Exception:  # noqa: BLE001 - no driver, no device: simply not usable
        return False


def _llvm_usable() -> bool:
    lib = find_libllvm()
    if lib is None:
        return False
    # Dr.Jit reads the variable when its LLVM backend starts, so it must be set before then.
    os.environ["DRJIT_LIBLLVM_PATH"] = str(lib.path)
    import drjit as dr
    try:
        return bool(dr.has_backend(dr.JitBackend.LLVM))
    except Exception:  # noqa: BLE001
        return False


def choose_variant(override: str | None = None) -> str:
    """The Mitsuba variant to render with.

    Parameters
    ----------
    override
        A variant name (``cuda_ad_rgb``, ``llvm_ad_rgb``, ``scalar_rgb``) or a short form
        (``cuda``, ``llvm``, ``scalar``). When None, ``$CASSI_VARIANT`` is used if set.

    Returns
    -------
    str
        The full variant name. Automatic choice: ``cuda_ad_rgb`` when a CUDA device is usable,
        else ``llvm_ad_rgb`` when a libLLVM >= 16 is found (``DRJIT_LIBLLVM_PATH`` first, then
        the standard paths; the variable is set for Dr.Jit when found), else ``scalar_rgb``.

    Raises
    ------
    CassiInputError
        When the requested variant is unknown or cannot run on this machine.
    """
    import mitsuba as mi

    requested = override if override is not None else os.environ.get("CASSI_VARIANT") or None
    if requested is not None:
        name = requested.strip().lower()
        name = {"cuda": "cuda_ad_rgb", "llvm": "llvm_ad_rgb", "scalar": "scalar_rgb"}.get(name, name)
        if name not in VARIANTS:
            raise CassiInputError(f"unknown render variant {requested!r}; choose one of "
                                  f"{', '.join(VARIANTS)} (or cuda, llvm, scalar)")
        if name not in mi.variants():
            raise CassiInputError(f"this Mitsuba build has no variant {name!r}")
        usable = {"cuda_ad_rgb": _cuda_usable, "llvm_ad_rgb": _llvm_usable,
                  "scalar_rgb": lambda: True}[name]()
        if not usable:
            hint = (f" (no libLLVM >= {MIN_LLVM_VERSION}: set DRJIT_LIBLLVM_PATH)"
                    if name == "llvm_ad_rgb" else "")
            raise CassiInputError(f"render variant {name!r} is not usable on this machine{hint}")
        return name
    available = set(mi.variants())
    if "cuda_ad_rgb" in available and _cuda_usable():
        return "cuda_ad_rgb"
    if "llvm_ad_rgb" in available and _llvm_usable():
        return "llvm_ad_rgb"
    return "scalar_rgb"


def activate_variant(variant: str) -> None:
    """Make ``variant`` Mitsuba's current variant (a no-op when it already is)."""
    import mitsuba as mi

    if variant == "llvm_ad_rgb" and "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib = find_libllvm()
        if lib is not None:
            os.environ["DRJIT_LIBLLVM_PATH"] = str(lib.path)
    if mi.variant() != variant:
        mi.set_variant(variant)
