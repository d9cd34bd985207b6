"""``Mis.dat``: a subject's log of mistracked pellets (thesis 3.2.5, Figure 3.10).

Format: one entry per line, whitespace separated::

    TASK  PELLET-CODE  ONSET  OFFSET  [NOTE]
    011   TD           2330   -1      k;j
    105   MAN M        1018   1224

- ``TASK``: record (task) number, usually written with three digits.
- ``PELLET-CODE``: ``TT, TB1, TB2, TD`` (tongue tip to dorsum = T1..T4), ``UL``, ``LL``,
  ``MAN I``/``MAN M`` (mandible incisor/molar = MNI/MNM) and ``MAX x`` (reference pellets, not in
  the task files). A code may contain a space; it is stored with single spaces (``"MAN M"``).
- ``ONSET``, ``OFFSET``: start and end of the episode in milliseconds from the start of the record
  (the thesis does not name the unit; the values, up to ~15000 for records of ~15 s, are
  milliseconds); ``OFFSET = -1`` means to the end of the file.
- ``NOTE``: optional raster-hop note such as ``k;j`` (the tracker followed another pellet).

An empty Mis.dat is valid: the subject has no logged mistracking.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.data.xrmb.textlines import INT_RE, decode_ascii, numbered_rows, read_bytes

#: Mis.dat pellet code -> task-file pellet name (None: a reference pellet, not in the .txy files).
MISTRACK_PELLET_CODES: dict[str, str | None] = {
    "TT": "T1", "TB1": "T2", "TB2": "T3", "TD": "T4",
    "T1": "T1", "T2": "T2", "T3": "T3", "T4": "T4",
    "UL": "UL", "LL": "LL",
    "MAN I": "MNI", "MAN M": "MNM", "MANI": "MNI", "MANM": "MNM", "MNI": "MNI", "MNM": "MNM",
}
_REFERENCE_RE = re.compile(r"MAX ?[A-Z]?", re.ASCII)
_CODE_TOKEN_RE = re.compile(r"[A-Za-z][A-Za-z0-9]*", re.ASCII)


@dataclass(frozen=True)
class MistrackEntry:
    """One Mis.dat line.

    Attributes
    ----------
    task : int
    pellet : str
        The code as written, spaces normalised (``"TB2"``, ``"MAN M"``, ``"MAX G"``).
    onset_ms : int
        Start of the episode, milliseconds from the start of the record.
    offset_ms : int
        End of the episode in milliseconds; -1 = to the end of the file.
    note : str or None
        Raster-hop note such as ``"k;j"``.
    line : int or None
        Line number in the file it came from.
    """

    task: int
    pellet: str
    onset_ms: int
    offset_ms: int
    note: str | None = None
    line: int | None = None

    @property
    def to_end(self) -> bool:
        return self.offset_ms == -1

    @property
    def onset_us(self) -> int:
        return self.onset_ms * 1000

    @property
    def offset_us(self) -> int:
        """End in microseconds; -1 stays -1 (to the end of the file)."""
        return -1 if self.offset_ms == -1 else self.offset_ms * 1000

    @property
    def xrmb_pellet(self) -> str | None:
        """The task-file pellet (``"T3"`` for ``TB2``), or None for reference pellets."""
        return pellet_for_code(self.pellet)


def pellet_for_code(code: str) -> str | None:
    """Map a Mis.dat pellet code to the task-file pellet name (None for ``MAX`` references).

    Raises :class:`CassiInputError` for an unknown code.
    """
    norm = " ".join(code.upper().split())
    if norm in MISTRACK_PELLET_CODES:
        return MISTRACK_PELLET_CODES[norm]
    if _REFERENCE_RE.fullmatch(norm):
        return None
    raise CassiInputError(f"unknown pellet code {code!r}")


def parse_mis(data: bytes | str, *, path: str | os.PathLike | None = None) -> list[MistrackEntry]:
    """Parse Mis.dat text into entries in file order (see the module docstring)."""
    text = decode_ascii(data, path=path)
    entries: list[MistrackEntry] = []
    for line, toks in numbered_rows(text):
        if len(toks) < 4:
            raise CassiInputError(
                f"expected TASK PELLET ONSET OFFSET [NOTE], found {len(toks)} field(s)",
                path=path, line=line)
        if not INT_RE.fullmatch(toks[0]) or toks[0].startswith(("-", "+")) or len(toks[0]) > 4:
            raise CassiInputError(f"task number {toks[0][:40]!r} is not a positive integer",
                                  path=path, line=line)
        task = int(toks[0])
        # The code runs up to the first integer field (codes like "MAN M" hold a space).
        k = 1
        while k < len(toks) and not INT_RE.fullmatch(toks[k]):
            k += 1
        code_toks = toks[1:k]
        if not code_toks:
            raise CassiInputError("missing pellet code", path=path, line=line)
        if len(code_toks) > 2 or not all(_CODE_TOKEN_RE.fullmatch(t) for t in code_toks):
            raise CassiInputError(f"malformed pellet code {' '.join(code_toks)[:40]!r}",
                                  path=path, line=line)
        code = " ".join(t.upper() for t in code_toks)
        try:
            pellet_for_code(code)
        except CassiInputError as err:
            raise CassiInputError(err.reason, path=path, line=line) from None
        if k + 1 >= len(toks) or not INT_RE.fullmatch(toks[k + 1]):
            raise CassiInputError("expected integer ONSET and OFFSET after the pellet code",
                                  path=path, line=line)
        if len(toks[k]) > 9 or len(toks[k + 1]) > 9:
            raise CassiInputError("onset/offset too large", path=path, line=line)
        onset, offset = int(toks[k]), int(toks[k + 1])
        if task < 1:
            raise CassiInputError(f"task number {task} must be at least 1", path=path, line=line)
        if onset < 0:
            raise CassiInputError(f"onset {onset} is negative", path=path, line=line)
        if offset != -1 and offset < onset:
            raise CassiInputError(f"offset {offset} before onset {onset}", path=path, line=line)
        rest = toks[k + 2:]
        note = " ".join(rest) if rest else None
        entries.append(MistrackEntry(task, code, onset, offset, note, line))
    return entries


def read_mis(path: str | os.PathLike) -> list[MistrackEntry]:
    """Read a subject's Mis.dat (see the module docstring)."""
    return parse_mis(read_bytes(path), path=path)


def format_mis(entries) -> str:
    """Mis.dat text in the thesis's layout (``010 TB1 0 767``), one entry per line."""
    out = []
    for e in entries:
        pellet_for_code(e.pellet)
        if e.offset_ms != -1 and e.offset_ms < e.onset_ms:
            raise CassiInputError(f"task {e.task}: offset before onset")
        note = f" {e.note}" if e.note else ""
        out.append(f"{e.task:03d} {' '.join(e.pellet.split())} {e.onset_ms} {e.offset_ms}{note}\n")
    return "".join(out)


def write_mis(path: str | os.PathLike, entries) -> None:
    """Write Mis.dat (atomic)."""
    atomic_write_text(path, format_mis(entries))
