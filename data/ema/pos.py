"""Carstens AG500 / AG501 ``.pos`` files.

Every frame holds, per channel (sensor), 7 float32 little-endian values: x, y, z (mm), phi,
theta (degrees), rms, extra. AG500 files are only that (no header: the channel count and the
rate are declared in the coil map). AG501 files may start with an ASCII header (the layout
Praat reads, ``sensors/EMA.cpp``, ``CarstensEMA_processHeader``)::

    AG50xDATA_V00n\\n        n = 1, 2 or 3
    00000070\\n              the header's length in bytes: the data start there
    NumberOfChannels=16\\n
    SamplingFrequencyHz=250\\n
    ...                      further lines, padding

Missing samples are NaN in the file and stay NaN. The size is checked against the channel count
before a sample is read: a truncated file is refused, naming the byte where it ends.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.ema.track import CoilTrack

VALUES = ("x", "y", "z", "phi", "theta", "rms", "extra")
_MAGIC = b"AG50xDATA_V00"
_HEADER_READ = 4096


def channel_names(n: int) -> tuple[str, ...]:
    """``1_x, 1_y, ..., 1_extra, 2_x, ...``: channel numbers from 1, as Carstens counts them."""
    return tuple(f"{c}_{v}" for c in range(1, n + 1) for v in VALUES)


def _header(path: Path) -> tuple[int, int | None, float | None]:
    """``(data offset, channels, rate)`` from an AG50x header, ``(0, None, None)`` without one."""
    with open(path, "rb") as f:
        head = f.read(_HEADER_READ)
    if not head.startswith(_MAGIC):
        return 0, None, None
    lines = head.split(b"\n")
    if len(lines) < 3 or not re.fullmatch(rb"[1-9]", lines[0][len(_MAGIC):]):
        raise CassiInputError(f"line 1 {lines[0][:20]!r}: expected AG50xDATA_V001 to V009",
                              path=path, line=1)
    if not re.fullmatch(rb"[0-9]{1,8}", lines[1].strip()):
        raise CassiInputError(f"line 2 {lines[1][:20]!r}: expected the header length in bytes",
                              path=path, line=2)
    offset = int(lines[1])
    fields = {}
    for i, raw in enumerate(lines[2:], start=3):
        m = re.fullmatch(rb"([A-Za-z]+)=([0-9.]+)\r?", raw)
        if m:
            fields[m.group(1).decode()] = (m.group(2).decode(), i)
    channels, rate = None, None
    if "NumberOfChannels" in fields:
        value, line = fields["NumberOfChannels"]
        if not value.isdigit() or int(value) < 1:
            raise CassiInputError(f"NumberOfChannels={value}: not a channel count", path=path,
                                  line=line)
        channels = int(value)
    if "SamplingFrequencyHz" in fields:
        value, line = fields["SamplingFrequencyHz"]
        try:
            rate = float(value)
        except ValueError:
            rate = 0.0
        if not rate > 0:
            raise CassiInputError(f"SamplingFrequencyHz={value}: not a rate", path=path,
                                  line=line)
    return offset, channels, rate


def read_pos(path: str | os.PathLike, *, channels: int | None = None,
             rate_hz: float | None = None) -> CoilTrack:
    """Read a ``.pos`` file.

    Parameters
    ----------
    channels, rate_hz : optional
        What the coil map declares; required where the file has no header, checked against the
        header where it has one.
    """
    path = Path(path)
    offset, head_channels, head_rate = _header(path)
    for what, declared, found in (("channels", channels, head_channels),
                                  ("rate_hz", rate_hz, head_rate)):
        if declared is not None and found is not None and float(declared) != float(found):
            raise CassiInputError(f"the coil map declares {what} {declared}, the file's header "
                                  f"{found}", path=path, line=3 if what == "channels" else 4)
    channels = head_channels if head_channels is not None else channels
    rate_hz = head_rate if head_rate is not None else rate_hz
    if channels is None or rate_hz is None:
        raise CassiInputError("a .pos file without a header: the coil map must declare "
                              "'channels' and 'rate_hz'", path=path)
    size = path.stat().st_size
    if size < offset:
        raise CassiInputError(f"truncated: the header says the data start at byte {offset}, the "
                              f"file ends at byte {size}", path=path)
    frame_bytes = 4 * len(VALUES) * channels
    frames, rest = divmod(size - offset, frame_bytes)
    if rest:
        raise CassiInputError(
            f"truncated or wrong channel count: {size - offset} data bytes are not a whole "
            f"number of {channels}-channel frames of {frame_bytes} bytes (frame {frames + 1} "
            f"ends early at byte {size})", path=path)
    if frames == 0:
        raise CassiInputError("no frames", path=path)
    values = np.fromfile(path, dtype="<f4", offset=offset).astype(np.float64)
    values = values.reshape(frames, channels * len(VALUES))
    time_s = np.arange(frames, dtype=np.float64) / float(rate_hz)
    return CoilTrack(path=path, channels=channel_names(channels), values=values, time_s=time_s,
                     valid=np.ones(frames, dtype=bool), rate_hz=float(rate_hz))
