"""Label files beside TextGrids: xwaves/ESPS ``.lab`` and HTK label files (``.lab``, ``.rec``,
master label files ``.mlf``), read into the one :class:`~cassi.data.xrmb.alignment.Alignment`.

xwaves/ESPS (MOCHA-TIMIT, mngu0): a header ending with a line ``#``, then one label a line,
``time colour label``: ``time`` is the label's *end* in seconds; each label starts where the one
before ends (the first at 0). HTK: ``start end label [score ...]`` a line, times in 100 ns
units; a master label file holds several, each after a quoted name (``"*/fsew0_001.lab"``) and
ending with a line ``.``. Both formats carry one tier: it becomes the alignment's phones (the
words stay empty), as MOCHA's and mngu0's phone labels are.

Every reader refuses bad input with :class:`CassiInputError` naming the file, the line and the
problem; :func:`check_within` refuses labels that run past the recording.
"""
from __future__ import annotations

import math
import os
import re
from pathlib import Path

import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.alignment import ROUNDING_S, Alignment, decode_text, read_alignment
from cassi.data.xrmb.textlines import parse_num, read_bytes, split_lines

__all__ = ["parse_xwaves_lab", "parse_htk_lab", "parse_mlf", "read_labels", "check_within",
           "LABEL_SUFFIXES", "LABEL_SLACK_S", "HTK_UNIT_S"]

#: HTK's time unit: 100 ns.
HTK_UNIT_S = 1e-7
#: The label files a task's labels may be, in the order they are looked for beside it.
LABEL_SUFFIXES = (".TextGrid", ".lab", ".rec")
_MLF_NAME = re.compile(r'^"(?P<name>[^"]+)"$')


def _text(data: bytes | str, path) -> str:
    return data if isinstance(data, str) else decode_text(data, path)


def _seconds(token: str, *, what: str, path, line: int) -> float:
    value = parse_num(token, what=what, path=path, line=line)
    if not math.isfinite(value) or value < 0:
        raise CassiInputError(f"{what}: {token[:40]!r} is not a time from 0 on", path=path,
                              line=line)
    return value


def _alignment(rows: list[tuple[float, float, str]], *, path) -> Alignment:
    phones = pd.DataFrame(rows, columns=["start_s", "end_s", "label"]).astype(
        {"start_s": "float64", "end_s": "float64", "label": "object"})
    words = phones.iloc[0:0].copy()
    end = float(phones["end_s"].iloc[-1]) if len(phones) else 0.0
    return Alignment(phones=phones, words=words, xmin_s=0.0, xmax_s=end,
                     path=None if path is None else Path(path))


def parse_xwaves_lab(data: bytes | str, *, path: str | os.PathLike | None = None) -> Alignment:
    """An xwaves/ESPS label file: header up to a line ``#``, then ``end_s colour label`` lines.
    The labels tile the time from 0: each starts where the one before ends."""
    lines = split_lines(_text(data, path))
    head = next((i for i, s in enumerate(lines) if s.strip() == "#"), None)
    if head is None:
        raise CassiInputError("no header end (a line '#'): not an xwaves/ESPS label file",
                              path=path)
    rows, prev = [], 0.0
    for i in range(head + 1, len(lines)):
        toks = lines[i].split(None, 2)
        if not toks:
            continue
        if len(toks) < 2:
            raise CassiInputError(f"expected 'time colour label', found {lines[i].strip()[:60]!r}",
                                  path=path, line=i + 1)
        end = _seconds(toks[0], what="time", path=path, line=i + 1)
        if end < prev - ROUNDING_S:
            raise CassiInputError(f"time {end} s before the label before it ends ({prev} s)",
                                  path=path, line=i + 1)
        label = toks[2].strip() if len(toks) > 2 else ""
        rows.append((prev, max(end, prev), label))
        prev = max(end, prev)
    if not rows:
        raise CassiInputError("no label after the header", path=path)
    return _alignment(rows, path=path)


def _htk_rows(lines: list[str], first: int, *, path) -> list[tuple[float, float, str]]:
    """``start end label [score ...]`` lines from index ``first`` up to a line ``.`` or the end
    (a master label file's entry ends so)."""
    rows, prev = [], 0.0
    for i in range(first, len(lines)):
        s = lines[i].strip()
        if s == ".":
            break
        if not s:
            continue
        toks = s.split()
        if len(toks) < 3:
            raise CassiInputError(f"expected 'start end label [score]', found {s[:60]!r}",
                                  path=path, line=i + 1)
        for t in toks[:2]:
            if not t.isdigit():
                raise CassiInputError(f"time {t[:40]!r} is not a whole number of 100 ns",
                                      path=path, line=i + 1)
        start, end = int(toks[0]) * HTK_UNIT_S, int(toks[1]) * HTK_UNIT_S
        if end < start:
            raise CassiInputError(f"label ends ({end} s) before it starts ({start} s)",
                                  path=path, line=i + 1)
        if start < prev - ROUNDING_S:
            raise CassiInputError(f"label starts at {start} s, before the one before ends "
                                  f"({prev} s)", path=path, line=i + 1)
        rows.append((start, end, toks[2]))
        prev = end
    if not rows:
        raise CassiInputError("no label", path=path, line=first + 1 if first else None)
    return rows


def parse_htk_lab(data: bytes | str, *, path: str | os.PathLike | None = None) -> Alignment:
    """An HTK label file: ``start end label [score]`` a line, times in 100 ns units."""
    return _alignment(_htk_rows(split_lines(_text(data, path)), 0, path=path), path=path)


def parse_mlf(data: bytes | str, *,
              path: str | os.PathLike | None = None) -> dict[str, Alignment]:
    """An HTK master label file (``#!MLF!#``, then per file a quoted name, its labels and a line
    ``.``) -> ``{stem: Alignment}`` (the name's last part without its suffix)."""
    lines = split_lines(_text(data, path))
    if not lines or lines[0].strip() != "#!MLF!#":
        raise CassiInputError("no '#!MLF!#' first line: not an HTK master label file",
                              path=path, line=1)
    out: dict[str, Alignment] = {}
    i = 1
    while i < len(lines):
        s = lines[i].strip()
        if not s:
            i += 1
            continue
        m = _MLF_NAME.match(s)
        if m is None:
            raise CassiInputError(f"expected a quoted file name, found {s[:60]!r}", path=path,
                                  line=i + 1)
        stem = Path(m.group("name").replace("\\", "/").rsplit("/", 1)[-1]).stem
        if stem in out:
            raise CassiInputError(f"{stem!r} is labelled twice", path=path, line=i + 1)
        rows = _htk_rows(lines, i + 1, path=path)
        out[stem] = _alignment(rows, path=path)
        i += 1
        while i < len(lines) and lines[i].strip() != ".":
            i += 1
        if i == len(lines):
            raise CassiInputError(f"the labels of {stem!r} do not end with a line '.'",
                                  path=path, line=len(lines))
        i += 1
    return out


def _is_xwaves(text: str) -> bool:
    """An xwaves file has a header closed by a line ``#``; an HTK file starts with labels."""
    return any(s.strip() == "#" for s in split_lines(text)[:200])


def read_labels(path: str | os.PathLike, *, stem: str | None = None) -> Alignment:
    """The alignment in ``path``, by its suffix: a TextGrid; ``.lab`` (xwaves/ESPS when it has
    the ``#`` header line, else HTK); ``.rec`` (HTK); ``.mlf`` (the entry for ``stem``)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".textgrid":
        return read_alignment(path)
    if suffix not in (".lab", ".rec", ".mlf"):
        raise CassiInputError("not a label file (.TextGrid, .lab, .rec or .mlf)", path=path)
    text = _text(read_bytes(path), path)
    if suffix == ".mlf":
        entries = parse_mlf(text, path=path)
        if stem not in entries:
            raise CassiInputError(f"no labels for {stem!r}", path=path)
        return entries[stem]
    if suffix == ".lab" and _is_xwaves(text):
        return parse_xwaves_lab(text, path=path)
    return parse_htk_lab(text, path=path)


#: How far labels may run past a recording's last sample: the sound the labels were made on
#: may go on a little after the articulatory samples stop (a frame or two, 7-14 ms on XRMB).
LABEL_SLACK_S = 0.05


def check_within(alignment: Alignment, duration_s: float, *, path=None) -> None:
    """Refuse labels that end more than :data:`LABEL_SLACK_S` after the recording's end
    (``duration_s``, its last sample's time): they belong to another recording, or to its
    samples read at the wrong rate."""
    for name, tier in (("phone", alignment.phones), ("word", alignment.words)):
        late = tier[tier["end_s"] > duration_s + LABEL_SLACK_S]
        if len(late):
            row = late.iloc[0]
            raise CassiInputError(
                f"{name} {row['label']!r} ends at {row['end_s']:.3f} s, after the recording's "
                f"end at {duration_s:.3f} s", path=path or alignment.path)
