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


def decode_text(data: bytes, path) -> str:
    """Label text as UTF-16 (with its byte-order mark) or UTF-8; a bad byte names its line."""
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


_LONG_ITEM = re.compile(r"^[ \t]*item[ \t]*\[\d+\][ \t]*:?[ \t]*\r?$", re.M)
_LONG_FIELD = re.compile(r'^[ \t]*(?P<key>class|name)[ \t]*=[ \t]*"(?P<value>(?:[^"\n]|"")*)"[ \t]*\r?$', re.M)
_LONG_INTERVAL = re.compile(r"^[ \t]*intervals[ \t]*\[\d+\][ \t]*:?[ \t]*\r?$", re.M)


def _unquote(value: str) -> str:
    """A Praat string's text: the doubled quotes inside it read as one."""
    return value.replace('""', '"')


_LONG_SIZE = re.compile(r"^[ \t]*intervals[ \t]*:[ \t]*size[ \t]*=[ \t]*(?P<n>[0-9]+)[ \t]*\r?$",
                        re.M | re.ASCII)


def _long_tier_span(text: str, want: str) -> tuple[int, int] | None:
    """Long form: the text span of the last interval tier named ``want`` (case aside, as the
    parsed tiers are keyed)."""
    items = [m.start() for m in _LONG_ITEM.finditer(text)] + [len(text)]
    found = None
    for a, b in zip(items, items[1:]):
        fields = {m.group("key"): _unquote(m.group("value"))
                  for m in _LONG_FIELD.finditer(text, a, b)}
        if fields.get("class") == "IntervalTier" and fields.get("name", "").lower() == want:
            found = (a, b)
    return found


def _long_interval_line(text: str, want: str, index: int) -> int | None:
    """Long form: the line of ``intervals [index + 1]:`` in tier ``want``."""
    span = _long_tier_span(text, want)
    if span is None:
        return None
    starts = [m.start() for m in _LONG_INTERVAL.finditer(text, *span)]
    return text.count("\n", 0, starts[index]) + 1 if index < len(starts) else None


def _short_tier_head(lines: list[str], want: str) -> int | None:
    """Short form: the index of the "IntervalTier" row of the last interval tier named
    ``want``; its rows are "IntervalTier", name, xmin, xmax, size, then xmin, xmax, label per
    interval."""
    found = None
    for i in range(len(lines) - 1):
        name = lines[i + 1].strip()
        if lines[i].strip() == '"IntervalTier"' and len(name) >= 2 and name.startswith('"') \
                and name.endswith('"') and _unquote(name[1:-1]).lower() == want:
            found = i
    return found


def _short_interval_line(text: str, want: str, index: int) -> int | None:
    """Short form: the xmin line of interval ``index`` in tier ``want`` (a label may run over
    several lines, until its quotes pair up)."""
    lines = text.split("\n")
    head = _short_tier_head(lines, want)
    if head is None:
        return None
    row, k = head + 5, 0
    while row < len(lines):
        if k == index:
            return row + 1
        row += 2                                   # xmin, xmax
        quotes = 0
        while row < len(lines):                    # the label, until its quotes pair up
            quotes += lines[row].count('"')
            row += 1
            if quotes and quotes % 2 == 0:
                break
        k += 1
    return None


def _declared_size(text: str | None, tier: str) -> tuple[str, int] | None:
    """The interval count tier ``tier`` declares (``intervals: size = N``; the short form's
    fifth row), as its ASCII digits without leading zeros (never through ``int()``, which
    refuses more than 4300 digits), and its 1-based line; None when the text does not say."""
    if text is None:
        return None
    want = tier.lower()
    if _LONG_ITEM.search(text):
        span = _long_tier_span(text, want)
        m = _LONG_SIZE.search(text, *span) if span else None
        return (m.group("n").lstrip("0") or "0", text.count("\n", 0, m.start()) + 1) if m else None
    lines = text.split("\n")
    head = _short_tier_head(lines, want)
    row = None if head is None else head + 4
    if row is None or row >= len(lines) or not re.fullmatch(r"[0-9]+", lines[row].strip(), re.ASCII):
        return None
    return lines[row].strip().lstrip("0") or "0", row + 1


def _interval_line(text: str | None, tier: str, index: int) -> int | None:
    """The 1-based line where interval ``index`` (0-based) of ``tier`` starts in TextGrid
    ``text``: its ``intervals [k]:`` line (long form) or its xmin line (short form); None when
    the text is not laid out so (praatio's parser gives no lines)."""
    if text is None:
        return None
    want = tier.lower()
    if _LONG_ITEM.search(text):
        return _long_interval_line(text, want, index)
    return _short_interval_line(text, want, index)


#: Interval bounds that miss each other (or the grid's span) by less than this are the same
#: time: 1 us, the XRMB files' time unit. The forced alignments of the XRMB tasks write bounds
#: rounded apart by ~1e-7 s (45 of the 1,700 files have one such overlap).
ROUNDING_S = 1e-6
#: A time field (long form ``xmin = -0.1``, or a bare unquoted number of the short form) below 0.
_NEGATIVE_TIME = re.compile(r"^[ \t]*(?:(?:xmin|xmax|number|time)[ \t]*=[ \t]*)?-[ \t]*\.?[0-9][^\n]*",
                            re.M)


def _tier_frame(tier: dict, *, path, text: str | None = None,
                span: tuple[float, float] = (-math.inf, math.inf)) -> pd.DataFrame:
    rows = []
    prev_end = -math.inf
    name = tier.get("name")
    entries = tier.get("entries", [])
    if not isinstance(entries, (list, tuple)):
        raise CassiInputError(f"tier {name!r}: its entries are not a list", path=path)
    declared = _declared_size(text, str(name))
    if declared is not None and declared[0] != str(len(entries)):
        # praatio reads what is there; Praat reads exactly the declared count, so a file cut
        # short (or one with intervals pasted in) is not what its header says
        digits = declared[0]
        count = digits if len(digits) <= 20 else f"{digits[:20]}... ({len(digits)} digits)"
        raise CassiInputError(f"tier {name!r} declares {count} intervals but holds "
                              f"{len(entries)}: the file is cut short or was edited by hand",
                              path=path, line=declared[1])
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
        if start < prev_end - ROUNDING_S:
            raise refuse(f"overlaps the one before: starts at {start} s, before {prev_end} s")
        start = max(start, prev_end)  # a rounding overlap: the intervals still tile the time
        if end < start:
            raise refuse(f"bad interval {start}..{end} (it ends inside the one before)")
        if start < span[0] - ROUNDING_S or end > span[1] + ROUNDING_S:
            raise refuse(f"{start}..{end} s lies outside the grid's {span[0]}..{span[1]} s")
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

    text = data if isinstance(data, str) else decode_text(data, path)
    if not text.strip():
        raise CassiInputError("empty file", path=path)
    # quoted labels blanked (lines kept): a label's own "-5 dB" is not a time
    unquoted = re.sub(r'"(?:[^"]|"")*"', lambda m: re.sub(r"[^\n]", " ", m.group()), text)
    negative = _NEGATIVE_TIME.search(unquoted)
    if negative:  # praatio reads "-0.1" as 0.1: refuse it before it does
        raise CassiInputError(f"a negative time {negative.group(0).strip()!r}: a recording's "
                              f"times start at 0", path=path,
                              line=text.count("\n", 0, negative.start()) + 1)
    try:
        tg = textgrid_io.parseTextgridStr(text, includeEmptyIntervals=True)
        tiers = {str(t["name"]).lower(): t for t in tg["tiers"]}
        xmin, xmax = float(tg["xmin"]), float(tg["xmax"])
    except CassiInputError:
        raise
    except Exception as err:  # noqa: BLE001 - praatio raises many kinds on malformed text
        raise CassiInputError(f"not a readable TextGrid ({type(err).__name__}: "
                              f"{str(err)[:120]})", path=path) from None
    if not (math.isfinite(xmin) and math.isfinite(xmax)) or xmax < xmin or xmin < 0:
        raise CassiInputError(f"the grid's time range {xmin}..{xmax} s is not a finite span "
                              f"from 0 on",
                              path=path)

    def pick(names):
        for n in names:
            if n in tiers:
                return tiers[n]
        raise CassiInputError(f"no {names[0]!r} tier (tiers: {', '.join(sorted(tiers)) or 'none'})",
                              path=path)

    return Alignment(phones=_tier_frame(pick(PHONE_TIERS), path=path, text=text, span=(xmin, xmax)),
                     words=_tier_frame(pick(WORD_TIERS), path=path, text=text, span=(xmin, xmax)),
                     xmin_s=xmin, xmax_s=xmax, path=None if path is None else Path(path))


def read_alignment(path: str | os.PathLike) -> Alignment:
    """Read a task's TextGrid -> :class:`Alignment` (``.phones``, ``.words`` tables)."""
    return parse_alignment(read_bytes(path), path=path)
