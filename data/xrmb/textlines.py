"""Shared helpers for the small whitespace-separated ASCII formats of the XRMB corpus.

Real files differ in small ways that must be tolerated: CRLF or LF line ends, no newline after the
last row, tabs or runs of spaces. Anything else odd (non-ASCII bytes, control characters, numbers
written in ways Python would accept but a C reader would not, such as ``1_000``) is an error that
names the file and line.
"""
from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from typing import Iterator

from cassi.common.errors import CassiInputError

#: A field separator: spaces, tabs, form feed, vertical tab. (Not ``str.split()``, which also
#: splits on ``\x1c``..``\x1f`` and Unicode spaces.)
_TOKEN = re.compile(r"[^ \t\f\v\r]+")
INT_RE = re.compile(r"[+-]?[0-9]+", re.ASCII)
#: A decimal number without exponent, as the corpus files write them (coordinates are integers in
#: the real data; decimals are tolerated so that hand-made files still read).
NUM_RE = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)", re.ASCII)

#: Refuse files larger than this: a task file of the real corpus is well under 1 MB.
MAX_FILE_BYTES = 64 * 1024 * 1024


def read_bytes(path: str | os.PathLike) -> bytes:
    """Read a whole file, turning OS errors into :class:`CassiInputError` naming the file."""
    path = Path(path)
    try:
        st = path.stat()
        if stat.S_ISDIR(st.st_mode):
            raise CassiInputError("is a directory, not a file", path=path)
        if not stat.S_ISREG(st.st_mode):  # a FIFO or a device would block or never end
            raise CassiInputError("is not a regular file", path=path)
        size = st.st_size
        if size > MAX_FILE_BYTES:
            raise CassiInputError(f"file is too large ({size} bytes)", path=path)
        with open(path, "rb") as fh:
            return fh.read(MAX_FILE_BYTES + 1)
    except CassiInputError:
        raise
    except FileNotFoundError:
        raise CassiInputError("file not found", path=path) from None
    except PermissionError:
        raise CassiInputError("permission denied", path=path) from None
    except OSError as err:
        raise CassiInputError(f"cannot read: {err.strerror or err}", path=path) from None


def decode_ascii(data: bytes | str, *, path=None) -> str:
    """Decode ``data`` as ASCII; a non-ASCII or NUL byte is an error naming its line."""
    if isinstance(data, str):
        text = data
    else:
        try:
            text = data.decode("ascii")
        except UnicodeDecodeError as err:
            line = data.count(b"\n", 0, err.start) + 1
            raise CassiInputError(f"non-ASCII byte 0x{data[err.start]:02x} (not a text file?)",
                                  path=path, line=line) from None
    bad = re.search(r"[^\x09-\x0d\x20-\x7e]", text)
    if bad:
        line = text.count("\n", 0, bad.start()) + 1
        raise CassiInputError(f"unexpected character {bad.group()!r} (not a text file?)",
                              path=path, line=line)
    return text


def split_lines(text: str) -> list[str]:
    """Split on LF, drop a CR before it; a missing final newline is fine.

    ``str.splitlines`` is not used because it also splits on ``\\v``, ``\\f`` and ``\\x1c``.
    """
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return [ln[:-1] if ln.endswith("\r") else ln for ln in lines]


def tokens(line: str) -> list[str]:
    """Whitespace-separated fields of one line."""
    return _TOKEN.findall(line)


def numbered_rows(text: str) -> Iterator[tuple[int, list[str]]]:
    """Yield ``(line_number, fields)`` for each non-blank line (1-based line numbers)."""
    for i, line in enumerate(split_lines(text), start=1):
        toks = tokens(line)
        if toks:
            yield i, toks


def parse_int(tok: str, *, what: str, path=None, line=None) -> int:
    if not INT_RE.fullmatch(tok):
        raise CassiInputError(f"{what}: {tok[:40]!r} is not an integer", path=path, line=line)
    return int(tok)


def parse_num(tok: str, *, what: str, path=None, line=None) -> float:
    if not NUM_RE.fullmatch(tok) or len(tok) > 40:
        raise CassiInputError(f"{what}: {tok[:40]!r} is not a number", path=path, line=line)
    return float(tok)
