"""Commands name their handlers as ``"module:function"`` strings, imported when the command
runs: ``cassi --help`` and every command start without the others' dependencies (pandas,
Mitsuba, matplotlib, the versions), and each handler module keeps its imports at its top."""
from __future__ import annotations

import importlib
from typing import Any


def resolve(target: Any) -> Any:
    """``"package.module:attr"`` (``attr`` may be dotted) -> that object; anything else is
    returned as it is. The version registry's lazy entries resolve the same way."""
    if not isinstance(target, str):
        return target
    module, sep, attr = target.partition(":")
    if not sep or not module or not attr:
        raise ValueError(f"lazy target must read 'module:attr', got {target!r}")
    obj: Any = importlib.import_module(module)
    for part in attr.split("."):
        obj = getattr(obj, part)
    return obj
