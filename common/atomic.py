"""Atomic file writes: write to a temporary file in the same directory, fsync, rename.

A reader never sees a half-written file, and a crash leaves the old file (or none) intact.
Files get the mode an ordinary ``open`` would give them (0666 less the umask), not the 0600 of
a temporary file, and an OS error names the file it was about.
"""
from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
from pathlib import Path
from typing import IO, Iterator

from cassi.common.errors import CassiInputError


def current_umask() -> int:
    """The process's umask, read without changing it (Linux), else by setting it back."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _with_path(err: OSError, path: Path) -> OSError:
    """``err`` naming ``path`` when it names no file (ENOSPC from write() names none)."""
    if not err.filename:
        err.filename = str(path)
    return err


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", *, durable: bool = True,
                read_only: bool = False, **kwargs) -> Iterator[IO]:
    """Open a temporary sibling of ``path`` for writing; rename it over ``path`` on success.

    ``mode`` is ``"w"`` (text, UTF-8 unless ``encoding`` is given) or ``"wb"``.
    On an exception the temporary file is removed and ``path`` is untouched.
    ``durable=False`` skips the ``fsync`` before the rename: the write stays atomic for every
    reader and against a killed process, but a power loss may leave the file empty or short.
    Only for files whose readers detect that (content-addressed blobs checked against their
    hash); an fsync costs about 2 ms on this machine's disk. ``read_only``: the file appears
    without write permission (0444 less the umask), for files nobody may write into again.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open mode must be 'w' or 'wb', not {mode!r}")
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise _with_path(err, path) from None
    if mode == "w":
        kwargs.setdefault("encoding", "utf-8")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as err:
        raise _with_path(err, path) from None
    try:
        os.fchmod(fd, (0o444 if read_only else 0o666) & ~current_umask())
        with os.fdopen(fd, mode, **kwargs) as fh:
            yield fh
            fh.flush()
            if durable:
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as err:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise _with_path(err, path) from None
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike, text: str, *, encoding: str = "utf-8") -> None:
    with atomic_open(path, "w", encoding=encoding, newline="") as fh:
        fh.write(text)


def atomic_write_bytes(path: str | os.PathLike, data: bytes, *, durable: bool = True,
                       read_only: bool = False) -> None:
    with atomic_open(path, "wb", durable=durable, read_only=read_only) as fh:
        fh.write(data)


def atomic_tmp_path(path: str | os.PathLike) -> Path:
    """A fresh temporary path beside ``path`` for writers that need a file name
    (OpenImageIO, pyarrow); the caller renames it with ``os.replace`` when done."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}",
                                   dir=path.parent)
        os.fchmod(fd, 0o666 & ~current_umask())
    except OSError as err:
        raise _with_path(err, path) from None
    os.close(fd)
    return Path(tmp)


@contextlib.contextmanager
def replacing(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path beside ``path`` for a writer that needs a file name; renamed onto
    ``path`` when the block ends, removed when it raises (no ``.tmp`` file is left behind)."""
    tmp = atomic_tmp_path(path)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def link_or_copy(src: str | os.PathLike, dest: str | os.PathLike) -> Path:
    """Put the file ``src`` at ``dest`` atomically: a hard link (no bytes copied, no disk used)
    where both lie on one file system, else a copy. Only for files nobody writes into again
    (content-addressed blobs, finished media).

    A new ``dest`` is linked directly (a link appears whole or not at all; a report's 20,548
    renders take about 1 s so against 5 s through a temporary name); an existing one is
    replaced through a temporary name, a copy goes through one and keeps ``src``'s
    permissions (a read-only blob stays read-only)."""
    dest = Path(dest)
    try:
        os.link(src, dest)
        return dest
    except FileExistsError:
        pass
    except FileNotFoundError:
        if not dest.parent.is_dir() and Path(src).is_file():
            dest.parent.mkdir(parents=True, exist_ok=True)
            return link_or_copy(src, dest)
    except OSError:
        pass  # another file system, or links not allowed: copy below
    tmp = atomic_tmp_path(dest)  # a fresh name; the link needs it free
    try:
        try:
            tmp.unlink()
            os.link(src, tmp)
        except OSError:
            shutil.copyfile(src, tmp)
            shutil.copymode(src, tmp)
        os.replace(tmp, dest)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
    return dest


def writable_dir(path: str | os.PathLike, what: str = "output directory",
                 subdirs: tuple[str, ...] = ()) -> Path:
    """Create ``path`` (with its parents and ``subdirs``) and prove it a writable directory
    before any work is done; otherwise a :class:`CassiInputError` naming it and why (the CLI's
    exit 2)."""
    root = Path(path)
    if root.exists() and not root.is_dir():
        raise CassiInputError(f"{what} exists and is not a directory", path=root)
    try:
        root.mkdir(parents=True, exist_ok=True)
        for sub in subdirs:
            (root / sub).mkdir(exist_ok=True)
        probe = root / f".write-probe-{os.getpid()}"
        probe.write_bytes(b"ok")
        probe.unlink()
    except OSError as err:
        why = "no space left on the device" if err.errno == errno.ENOSPC else (
            err.strerror or str(err))
        raise CassiInputError(f"{what} is not writable: {why}", path=root) from err
    return root
