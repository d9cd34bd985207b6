"""The versions' unstated constants with their plausible ranges, and setting one for a while.

Each constant's range lives beside its value (``RANGES`` of :mod:`.constants` and
:mod:`.lips_constants`); this module only gathers them and sets one value in place for the
sensitivity analysis, which animates with it. The versions read these constants when they
animate, never when they are imported (``tests/versions/test_versions_ranges.py`` checks), so
a value set here reaches every version built while it holds.
"""
from __future__ import annotations

import threading
from contextlib import contextmanager
from dataclasses import dataclass
from types import ModuleType
from typing import Iterator

from cassi.common.errors import CassiInputError
from cassi.versions import constants, lips_constants

__all__ = ["RANGED_MODULES", "RangedConstant", "ranged_constants", "constant_set"]

#: The modules whose ``RANGES`` are gathered, by the short name settings are called with.
RANGED_MODULES: dict[str, ModuleType] = {"constants": constants, "lips_constants": lips_constants}

_lock = threading.RLock()  # a block may set a second constant inside the first


@dataclass(frozen=True)
class RangedConstant:
    """One ranged constant: ``name`` is ``module.NAME`` (``lips_constants.RHO``)."""

    name: str
    value: float
    low: float
    high: float
    reason: str


def ranged_constants() -> dict[str, RangedConstant]:
    """Every ranged constant, ``module.NAME`` -> :class:`RangedConstant`, in declaration order."""
    out = {}
    for short, module in RANGED_MODULES.items():
        for name, (low, high, reason) in module.RANGES.items():
            out[f"{short}.{name}"] = RangedConstant(f"{short}.{name}", float(getattr(module, name)),
                                                    float(low), float(high), reason)
    return out


@contextmanager
def constant_set(name: str, value: float) -> Iterator[None]:
    """Set the ranged constant ``name`` (``module.NAME``) to ``value`` in this process while the
    block runs; other threads wait (the modules are the process's own)."""
    known = ranged_constants()
    if name not in known:
        raise CassiInputError(f"no ranged constant {name!r}; known: {', '.join(known)}")
    short, attr = name.split(".", 1)
    module = RANGED_MODULES[short]
    with _lock:
        old = getattr(module, attr)
        setattr(module, attr, type(old)(value))
        try:
            yield
        finally:
            setattr(module, attr, old)
