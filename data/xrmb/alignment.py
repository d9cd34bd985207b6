"""Praat TextGrid alignments of a task (phone and word tiers), read with praatio.

The XRMB annotations (rsprouse/xray_microbeam_database) name them ``SUBJECT/tpNNN[_R].TextGrid``
with interval tiers ``phone`` and ``word``, times in seconds from the start of the recording.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.textlines import read_bytes

PHONE_TIERS = ("phone", "phones")
WORD_TIERS = ("word", "words")
_COLUMNS = ["start_s", "end_s", "label"]


@dataclass(frozen=True, eq=False)
class Alignment:
    """Phone and word intervals of one task.

    Attributes
    ----------
    phones, words : pandas.DataFrame
        Columns ``start_s, end_s, label`` (seconds, float64; label str), in time order; silence
        intervals (``sp``, ``sil`` or empty) are kept so durations add up.
    xmin_s, xmax_s : float
        The TextGrid's time domain in seconds.
    path : Path or None
    """

    phones: pd.DataFrame
    words: pd.DataFrame
    xmin_s: float
    xmax_s: float
    path: Path | None = None


def _decode(data: bytes, path) -> str:
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return data.decode("utf-16")
        except UnicodeDecodeError:
            raise CassiInputError("not valid UTF-16 text", path=path) from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        raise CassiInputError("not valid UTF-8 text", path=path, line=line) from None


_LONG_NAME = re.compile(r'^\s*name\s*=\s*"(?P<name>(?:[^"]|"")*)"\s*$', re.M)
_LONG_INTERVAL = re.compile(r"^\s*intervals\s*\[\d+\]\s*:?\s*$", re.M)
_LONG_ITEM = re.compile(r"^\s*item\s*\[\d+\]\s*:?\s*$", re.M)


def _interval_line(text: str | None, tier: str, index: int) -> int | None:
    """The 1-based line where interval ``index`` (0-based) of ``tier`` starts in TextGrid
    ``text``: its ``intervals [k]:`` line (long form) or its xmin line (short form); None when
    the text is not laid out so (praatio's parser gives no lines)."""
    if text is None:
        return None
    want = tier.lower()
    for m in _LONG_NAME.finditer(text):
        if m.group("name").replace('""', '"').lower() != want:
            continue
        nxt = _LONG_ITEM.search(text, m.end())
        end = nxt.start() if nxt else len(text)
        starts = [i.start() for i in _LONG_INTERVAL.finditer(text, m.end(), end)]
        return text.count("\n", 0, starts[index]) + 1 if index < len(starts) else None
    lines = text.splitlines()
    for i in range(len(lines) - 1):  # short form: "IntervalTier", "name", xmin, xmax, size
        if lines[i].strip() == '"IntervalTier"' and lines[i + 1].strip().strip('"').lower() == want:
            line = i + 6 + 3 * index
            return line if line <= len(lines) else None
    return None


def _tier_frame(tier: dict, *, path, text: str | None = None) -> pd.DataFrame:
    rows = []
    prev_end = -math.inf
    name = tier.get("name")
    entries = tier.get("entries", [])
    if not isinstance(entries, (list, tuple)):
        raise CassiInputError(f"tier {name!r}: its entries are not a list", path=path)
    for k, entry in enumerate(entries):
        def refuse(reason: str) -> CassiInputError:
            return CassiInputError(f"tier {name!r}, interval {k + 1}: {reason}", path=path,
                                   line=_interval_line(text, str(name), k))
        if not isinstance(entry, (list, tuple)) or len(entry) != 3:
            raise CassiInputError(f"tier {name!r}: not an interval tier", path=path)
        start, end, label = entry
        try:
            start, end = float(start), float(end)
        except (TypeError, ValueError):
            raise refuse("non-numeric time") from None
        if not (math.isfinite(start) and math.isfinite(end)) or end < start:
            raise refuse(f"bad interval {start}..{end}")
        if start < prev_end - 1e-9:
            raise refuse(f"overlaps the one before: starts at {start} s, before {prev_end} s")
        prev_end = end
        rows.append((start, end, str(label)))
    return pd.DataFrame(rows, columns=_COLUMNS).astype({"start_s": "float64", "end_s": "float64",
                                                        "label": "object"})


def parse_alignment(data: bytes | str, *, path: str | os.PathLike | None = None) -> Alignment:
    """Parse TextGrid text (long, short or praatio JSON form) into an :class:`Alignment`.

    Raises :class:`CassiInputError` for anything praatio cannot read or a grid without a phone
    and a word interval tier.
    """
    from praatio.utilities import textgrid_io  # praatio's own parser (long/short/JSON forms)

    text = data if isinstance(data, str) else _decode(data, path)
    if not text.strip():
        raise CassiInputError("empty file", path=path)
    try:
        tg = textgrid_io.parseTextgridStr(text, includeEmptyIntervals=True)
        tiers = {str(t["name"]).lower(): t for t in tg["tiers"]}
        xmin, xmax = float(tg["xmin"]), float(tg["xmax"])
    except CassiInputError:
        raise
    except Exception as err:  # noqa: BLE001 - praatio raises many kinds on malformed text
        raise CassiInputError(f"not a readable TextGrid ({type(err).__name__}: "
                              f"{str(err)[:120]})", path=path) from None
    if not (math.isfinite(xmin) and math.isfinite(xmax)) or xmax < xmin:
        raise CassiInputError(f"the grid's time range {xmin}..{xmax} s is not a finite span",
                              path=path)

    def pick(names):
        for n in names:
            if n in tiers:
                return tiers[n]
        raise CassiInputError(f"no {names[0]!r} tier (tiers: {', '.join(sorted(tiers)) or 'none'})",
                              path=path)

    return Alignment(phones=_tier_frame(pick(PHONE_TIERS), path=path, text=text),
                     words=_tier_frame(pick(WORD_TIERS), path=path, text=text),
                     xmin_s=xmin, xmax_s=xmax, path=None if path is None else Path(path))


def read_alignment(path: str | os.PathLike) -> Alignment:
    """Read a task's TextGrid -> :class:`Alignment` (``.phones``, ``.words`` tables)."""
    return parse_alignment(read_bytes(path), path=path)
