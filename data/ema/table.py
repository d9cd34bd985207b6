"""Plain TSV / CSV exports with named columns (NDI Wave and others).

The first non-blank line names the columns; one of them is the time (``time`` unless the coil
map names another, in seconds or milliseconds as the map declares). Every other cell is a
number; an empty cell, ``NaN`` or ``NA`` is a missing sample and stays missing.
"""
from __future__ import annotations

import csv
import io
import os
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.ema.track import CoilTrack, check_times, sample
from cassi.data.xrmb.textlines import read_bytes

TIME_UNITS = {"s": 1.0, "ms": 1e-3}


def read_table(path: str | os.PathLike, *, delimiter: str | None = None, time_column: str = "time",
               time_unit: str = "s") -> CoilTrack:
    """Read a TSV (``delimiter`` tab, the default for ``.tsv``) or CSV (comma) export."""
    path = Path(path)
    if time_unit not in TIME_UNITS:
        raise CassiInputError(f"time unit {time_unit!r}: expected s or ms", path=path)
    if delimiter is None:
        delimiter = "," if path.suffix.lower() == ".csv" else "\t"
    try:
        text = read_bytes(path).decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise CassiInputError(f"byte {err.start} is not UTF-8 text", path=path) from None
    rows = [(i, r) for i, r in enumerate(csv.reader(io.StringIO(text), delimiter=delimiter),
                                         start=1) if any(c.strip() for c in r)]
    if not rows:
        raise CassiInputError("empty file: no header line", path=path)
    head_line, head = rows[0]
    names = [c.strip() for c in head]
    if time_column not in names:
        raise CassiInputError(f"no time column {time_column!r} (columns: "
                              f"{', '.join(names[:12])})", path=path, line=head_line)
    if len(set(names)) != len(names):
        dup = next(x for x in names if names.count(x) > 1)
        raise CassiInputError(f"column {dup!r} named twice", path=path, line=head_line)
    if len(rows) == 1:
        raise CassiInputError("no data rows", path=path, line=head_line)
    table = np.empty((len(rows) - 1, len(names)), dtype=np.float64)
    for k, (line, row) in enumerate(rows[1:]):
        if len(row) != len(names):
            raise CassiInputError(f"expected {len(names)} columns, found {len(row)}", path=path,
                                  line=line)
        for j, cell in enumerate(row):
            table[k, j] = sample(cell, what=f"column {names[j]!r}", path=path, line=line)
    t = names.index(time_column)
    time_s = table[:, t] * TIME_UNITS[time_unit]
    check_times(time_s, path=path, line_of=lambda k: rows[k + 1][0])
    keep = [j for j in range(len(names)) if j != t]
    return CoilTrack(path=path, channels=tuple(names[j] for j in keep), values=table[:, keep],
                     time_s=time_s, valid=np.ones(len(time_s), dtype=bool), rate_hz=None)

