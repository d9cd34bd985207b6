"""Edinburgh Speech Tools track files (``EST_File Track``), as MOCHA-TIMIT and mngu0 ship EMA.

Layout (Edinburgh Speech Tools, ``EST_Track`` ``est`` format; a MOCHA-TIMIT header is quoted in
eecqin/TongueReconstruction, ``corpus`` reader)::

    EST_File Track
    DataType binary            ascii or binary
    ByteOrder 01               binary only: 01 least significant byte first, 10 most
    NumFrames 1548
    NumChannels 20
    EqualSpace 1
    BreaksPresent true
    CommentChar ;
    Channel_0 ui_x             one line per channel, 0-based
    ...
    EST_Header_End

then one frame per sample: its time (s), a break flag when ``BreaksPresent`` is true (0: no
data at that frame), and the channels. ASCII: one frame per line, whitespace-separated. Binary:
float32 in the declared byte order, ``4 * (1 + breaks + NumChannels)`` bytes per frame. The
header is read first and the file's size checked against it, so a truncated binary file is
refused without reading its samples.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.ema.track import CoilTrack, check_times, sample

MAGIC = b"EST_File Track"
_END = b"EST_Header_End"
#: The most header bytes read to find its end (a header of a thousand channels fits).
_MAX_HEADER = 1 << 16


def _header(path: Path) -> tuple[dict[str, tuple[str, int]], int, int, list[str]]:
    """``({key: (value, line)}, data offset in bytes, the data's first line, channel names)``."""
    with open(path, "rb") as f:
        head = f.read(_MAX_HEADER)
    if not head.startswith(MAGIC):
        raise CassiInputError(f"not an EST track file (expected {MAGIC.decode()!r} on line 1)",
                              path=path, line=1)
    end = head.find(b"\n" + _END)
    if end < 0:
        raise CassiInputError(f"no {_END.decode()} line in the first {_MAX_HEADER} bytes",
                              path=path)
    stop = head.find(b"\n", end + 1 + len(_END))
    offset = len(head) if stop < 0 else stop + 1
    try:
        text = head[:end].decode("ascii")
    except UnicodeDecodeError as err:
        raise CassiInputError(f"header byte {err.start} is not ASCII", path=path) from None
    keys: dict[str, tuple[str, int]] = {}
    for i, line in enumerate(text.split("\n")[1:], start=2):
        parts = line.strip().split(None, 1)
        if parts:
            keys[parts[0]] = (parts[1].strip() if len(parts) > 1 else "", i)
    n = _int(keys, "NumChannels", path)
    names = []
    for c in range(n):
        name, _ = keys.get(f"Channel_{c}", (f"channel_{c}", 0))
        names.append(name)
    if len(set(names)) != len(names):
        dup = next(x for x in names if names.count(x) > 1)
        raise CassiInputError(f"channel name {dup!r} used twice", path=path,
                              line=next(ln for k, (v, ln) in keys.items()
                                        if k.startswith("Channel_") and v == dup))
    return keys, offset, head[:offset].count(b"\n") + 1, names


def _int(keys, key: str, path) -> int:
    if key not in keys:
        raise CassiInputError(f"header has no {key}", path=path)
    value, line = keys[key]
    if not value.isdigit():
        raise CassiInputError(f"{key} {value[:40]!r} is not a whole number", path=path, line=line)
    return int(value)


def _choice(keys, key: str, options: dict, default, path):
    if key not in keys:
        return default
    value, line = keys[key]
    if value.lower() not in options:
        raise CassiInputError(f"{key} {value[:40]!r}: expected one of {', '.join(options)}",
                              path=path, line=line)
    return options[value.lower()]


def read_est(path: str | os.PathLike) -> CoilTrack:
    """Read an EST track file (ASCII or binary, either byte order); see the module docstring."""
    path = Path(path)
    keys, offset, first_line, names = _header(path)
    frames = _int(keys, "NumFrames", path)
    binary = _choice(keys, "DataType", {"ascii": False, "binary": True}, False, path)
    breaks = _choice(keys, "BreaksPresent", {"true": True, "false": False, "1": True,
                                             "0": False}, False, path)
    if binary:
        if "ByteOrder" not in keys:
            raise CassiInputError("a binary track needs ByteOrder (01 or 10)", path=path)
        order = _choice(keys, "ByteOrder", {"01": "<", "10": ">"}, None, path)
        table = _binary_frames(path, offset, frames, 1 + breaks + len(names), order)
        line_of = None
    else:
        table, line_numbers = _ascii_frames(path, offset, first_line, frames, len(names), breaks)
        line_of = lambda k: int(line_numbers[k])  # noqa: E731
    time_s = table[:, 0].astype(np.float64)
    check_times(time_s, path=path, line_of=line_of)
    valid = table[:, 1] != 0 if breaks else np.ones(len(time_s), dtype=bool)
    values = table[:, 1 + breaks:].astype(np.float64)
    equal = _choice(keys, "EqualSpace", {"1": True, "0": False, "true": True, "false": False},
                    False, path)
    rate = 1.0 / float(np.median(np.diff(time_s))) if equal and len(time_s) > 1 else None
    return CoilTrack(path=path, channels=tuple(names), values=values, time_s=time_s,
                     valid=valid, rate_hz=rate)


def _binary_frames(path: Path, offset: int, frames: int, width: int, order: str) -> np.ndarray:
    size = path.stat().st_size
    frame_bytes = 4 * width
    need = offset + frames * frame_bytes
    if size < need:
        whole = (size - offset) // frame_bytes
        raise CassiInputError(
            f"truncated: NumFrames {frames} of {frame_bytes} bytes need {need} bytes, the file "
            f"ends at byte {size} (in frame {whole + 1})", path=path)
    if size > need:
        raise CassiInputError(f"{size - need} bytes after the last of NumFrames {frames} frames "
                              f"(from byte {need}): NumFrames or NumChannels is wrong", path=path)
    data = np.fromfile(path, dtype=f"{order}f4", count=frames * width, offset=offset)
    return data.reshape(frames, width)


def _ascii_frames(path: Path, offset: int, first_line: int, frames: int, n: int,
                  breaks: bool) -> tuple[np.ndarray, np.ndarray]:
    with open(path, "rb") as f:
        f.seek(offset)
        body = f.read()
    try:
        text = body.decode("ascii")
    except UnicodeDecodeError as err:
        raise CassiInputError(f"byte {offset + err.start} is not ASCII", path=path) from None
    widths = {n + 2: True, n + 1: False} if not breaks else {n + 2: True}
    rows, line_numbers = [], []
    for i, line in enumerate(text.splitlines(), start=first_line):
        toks = line.split()
        if not toks:
            continue
        if len(toks) not in widths:
            raise CassiInputError(f"expected {n + 2} columns (time, break flag, {n} channels), "
                                  f"found {len(toks)}", path=path, line=i)
        row = [sample(t, what=f"column {k + 1}", path=path, line=i) for k, t in enumerate(toks)]
        if not widths[len(toks)]:
            row.insert(1, 1.0)
        rows.append(row)
        line_numbers.append(i)
        if len(rows) > frames:
            raise CassiInputError(f"more frames than NumFrames {frames}", path=path, line=i)
    if len(rows) < frames:
        raise CassiInputError(f"truncated: {len(rows)} frames of NumFrames {frames}", path=path,
                              line=line_numbers[-1] if line_numbers else None)
    table = np.asarray(rows, dtype=np.float64).reshape(frames, n + 2)
    if not breaks:
        table = np.delete(table, 1, axis=1)
    return table, np.asarray(line_numbers)

