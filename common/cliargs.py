"""argparse types every layer's commands share."""
from __future__ import annotations

import argparse
import math
import re

_INT = re.compile(r"[+-]?[0-9]{1,18}", re.ASCII)
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]{1,3})?", re.ASCII)


def ascii_int(text: str) -> int:
    """An integer written in ASCII digits. ``int()`` also reads ``'٣'`` (Arabic-Indic three),
    ``'1_0'`` and padded text, which a command line should refuse, not reinterpret."""
    if not _INT.fullmatch(text):
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not an integer (ASCII digits)")
    return int(text)


def seed_int(text: str) -> int:
    """A random seed: a non-negative integer in ASCII digits of any size numpy's SeedSequence
    takes (up to 2**128; ascii_int's 18 digits would refuse a valid 64-bit seed)."""
    if not re.fullmatch(r"\+?[0-9]{1,39}", text, re.ASCII) or int(text) >= 2 ** 128:
        raise argparse.ArgumentTypeError(
            f"{text[:40]!r} is not a seed: a non-negative integer below 2**128 in ASCII digits")
    return int(text)


def positive_number(text: str) -> float:
    """A finite number above 0 in ASCII digits (``float()`` also reads ``'nan'``, ``'inf'`` and
    ``'١.٥'``; a rate or a length of those only fails, if at all, after the work is done)."""
    value = float(text) if _NUMBER.fullmatch(text) else math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a positive number")
    return value


_TASK_RANGE = re.compile(r"([0-9]{1,3})(?:-([0-9]{1,3}))?", re.ASCII)


def task_range(text: str) -> list[int]:
    """Task numbers as people write them: ``105``, ``102-105`` (both ends included) or a
    comma-separated mix (``1-118`` is every XRMB task). ValueError names what is wrong."""
    out: list[int] = []
    for part in (p.strip() for p in str(text).split(",")):
        m = _TASK_RANGE.fullmatch(part)
        if not m or int(m.group(2) or m.group(1)) < int(m.group(1)):
            raise ValueError(f"bad task list {str(text)[:40]!r} (e.g. 105 or 102-105,13)")
        out.extend(range(int(m.group(1)), int(m.group(2) or m.group(1)) + 1))
    return out


def task_list(text: str) -> list[int]:
    """:func:`task_range` as an argparse type."""
    try:
        return task_range(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
