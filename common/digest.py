"""SHA-256 of source trees: what the farm's job digests and the synthetic corpus's cache check
read to tell that code changed."""
from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Iterable

__all__ = ["source_files", "tree_digest"]

_SKIP_DIRS = {"__pycache__"}


def source_files(root: Path, exclude: Iterable[Path] = ()) -> list[Path]:
    """Every file under ``root`` (or ``root`` itself), sorted, less byte code and the files under
    ``exclude``."""
    exclude = [e.resolve() for e in exclude]
    if root.is_file():
        return [root]
    return sorted(p for p in root.rglob("*") if p.is_file() and not _SKIP_DIRS & set(p.parts)
                  and p.suffix not in (".pyc", ".pyo")
                  and not any(p.resolve().is_relative_to(e) for e in exclude))


def tree_digest(paths: Iterable[Path], *, exclude: Iterable[Path] = ()) -> str:
    """SHA-256 over the relative names and bytes of every file under ``paths`` (sorted), less
    the files under ``exclude``."""
    exclude = list(exclude)
    h = hashlib.sha256()
    for root in paths:
        for path in source_files(root, exclude):
            rel = path.name if path == root else path.relative_to(root).as_posix()
            h.update(f"{root.name}/{rel}\0".encode())
            h.update(path.read_bytes())
            h.update(b"\0")
    return h.hexdigest()
