"""argparse types every layer's commands share."""
from __future__ import annotations

import argparse
import re

_INT = re.compile(r"[+-]?[0-9]{1,18}", re.ASCII)


def ascii_int(text: str) -> int:
    """An integer written in ASCII digits. ``int()`` also reads ``'٣'`` (Arabic-Indic three),
    ``'1_0'`` and padded text, which a command line should refuse, not reinterpret."""
    if not _INT.fullmatch(text):
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not an integer (ASCII digits)")
    return int(text)
