"""Commands name their handlers as ``"module:function"`` strings, imported when the command
runs: ``cassi --help`` and every command start without the others' dependencies (pandas,
Mitsuba, matplotlib, the versions), and each handler module keeps its imports at its top."""
from __future__ import annotations

import importlib
from typing import Any


def resolve(target: Any) -> Any:
    """``"package.module:attr"`` -> that object (anything else is returned as it is)."""
    if not isinstance(target, str):
        return target
    module, sep, attr = target.partition(":")
    if not sep or not attr:
        raise ValueError(f"not a 'module:attr' target: {target!r}")
    return getattr(importlib.import_module(module), attr)
