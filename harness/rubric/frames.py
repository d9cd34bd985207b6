"""An animation's positions as the rubric reads them: a chunk of frames at a time.

The geometric measures are per-frame series (a gap, a penetration, an angle per frame) and a
few single frames (the first, the frame of maximum protrusion). :class:`Frames` gives both
without the whole (F, V, 3) array in memory: :meth:`Frames.series` applies a per-frame function
to consecutive chunks and joins the results, with ``halo`` frames on each side for functions
that look at neighbouring frames (a smoothing window, a frame-to-frame step) so that every
value is the one the whole array would give. Positions come from an array
(:class:`ArrayFrames`) or a float32 file written a chunk at a time (:class:`FileFrames`).
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

import numpy as np

#: Frames per chunk: 4,096 frames of a 570-vertex face are 56 MB in float64.
CHUNK_FRAMES = 4096


class Frames:
    """Base: ``n_frames``, ``n_vertices``, :meth:`read` (a chunk in float64), :meth:`frame`."""

    n_frames: int
    n_vertices: int
    chunk: int = CHUNK_FRAMES

    def read(self, start: int, stop: int) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def frame(self, i: int) -> np.ndarray:
        """float64 (V, 3): frame ``i`` (negative counts from the end)."""
        i = int(i) + (self.n_frames if int(i) < 0 else 0)
        return self.read(i, i + 1)[0]

    def series(self, fn: Callable, *args, halo: int = 0, **kwargs):
        """``fn(positions, *args, **kwargs)`` over every frame, a chunk at a time.

        ``fn`` maps float64 (n, V, 3) to per-frame results with n as the leading axis: an
        array, a tuple of arrays or a dict of arrays; the chunks' results are joined the same
        way. ``halo`` frames of context on each side are read and cut off again.
        """
        parts = []
        for a in range(0, self.n_frames, self.chunk):
            b = min(self.n_frames, a + self.chunk)
            lo, hi = max(0, a - halo), min(self.n_frames, b + halo)
            out = fn(self.read(lo, hi), *args, **kwargs)
            parts.append(_cut(out, a - lo, b - lo))
        return _join(parts)


def _cut(out, a: int, b: int):
    if isinstance(out, tuple):
        return tuple(_cut(o, a, b) for o in out)
    if isinstance(out, dict):
        return {k: _cut(v, a, b) for k, v in out.items()}
    # a copy: a view would keep the whole chunk it was cut from alive until the join
    return np.array(np.asarray(out)[a:b])


def _join(parts: list):
    first = parts[0]
    if isinstance(first, tuple):
        return tuple(_join([p[i] for p in parts]) for i in range(len(first)))
    if isinstance(first, dict):
        return {k: _join([p[k] for p in parts]) for k in first}
    return np.concatenate(parts) if len(parts) > 1 else first


class LastRead(Frames):
    """Another source's frames with its last read kept (read-only), so the many series and
    single frames of one animation's checks read a task of one chunk once, not once each:
    memory still holds one chunk."""

    def __init__(self, source: Frames):
        self.source = source
        self.n_frames, self.n_vertices = source.n_frames, source.n_vertices
        self.chunk = source.chunk
        self._start, self._data = 0, None

    def read(self, start: int, stop: int) -> np.ndarray:
        start, stop = max(0, start), min(self.n_frames, stop)
        if self._data is None or start < self._start or stop > self._start + len(self._data):
            self._data = self.source.read(start, stop)
            self._data.flags.writeable = False    # shared by every reader: none may change it
            self._start = start
        return self._data[start - self._start:stop - self._start]


class ArrayFrames(Frames):
    """Positions held in memory (float (F, V, 3) Parke units)."""

    def __init__(self, positions: np.ndarray, *, chunk: int = CHUNK_FRAMES):
        self.positions = np.asarray(positions)
        if self.positions.ndim != 3 or self.positions.shape[2] != 3:
            raise ValueError(f"positions must be (F, V, 3), got {self.positions.shape}")
        self.n_frames, self.n_vertices = self.positions.shape[:2]
        self.chunk = int(chunk)

    def read(self, start: int, stop: int) -> np.ndarray:
        return np.asarray(self.positions[start:stop], dtype=np.float64)


class FileFrames(Frames):
    """float32 (F, V, 3) positions in a raw file, frame after frame, appended a chunk at a
    time (:meth:`append`) and read back a chunk at a time: memory holds one chunk."""

    def __init__(self, path: str | os.PathLike, n_vertices: int, *, chunk: int = CHUNK_FRAMES):
        self.path = Path(path)
        self.n_vertices = int(n_vertices)
        self.n_frames = 0
        self.chunk = int(chunk)
        self._frame_bytes = self.n_vertices * 3 * 4
        self.path.write_bytes(b"")

    def append(self, positions: np.ndarray) -> None:
        arr = np.ascontiguousarray(positions, dtype=np.float32)
        if arr.ndim != 3 or arr.shape[1:] != (self.n_vertices, 3):
            raise ValueError(f"positions must be (n, {self.n_vertices}, 3), got {arr.shape}")
        try:
            with open(self.path, "ab") as fh:
                arr.tofile(fh)
        except OSError as err:  # numpy's message names neither the file nor its directory
            raise OSError(err.errno, f"cannot write {arr.nbytes} bytes of positions to "
                          f"{self.path} ({err.strerror or err}); a full temporary "
                          f"directory? set TMPDIR to one with room", str(self.path)) from err
        self.n_frames += arr.shape[0]

    def read(self, start: int, stop: int) -> np.ndarray:
        start, stop = max(0, start), min(self.n_frames, stop)
        n = max(0, stop - start)
        with open(self.path, "rb") as fh:
            fh.seek(start * self._frame_bytes)
            arr = np.fromfile(fh, dtype=np.float32, count=n * self.n_vertices * 3)
        return arr.reshape(n, self.n_vertices, 3).astype(np.float64)

    def take(self, frames) -> np.ndarray:
        """float32 (K, V, 3): the given frames (0-based indices), as stored; read a chunk of
        frames at a time (a viewer keeps hundreds of frames: not a read each)."""
        frames = np.asarray(frames, np.int64).reshape(-1)
        out = np.empty((len(frames), self.n_vertices, 3), np.float32)
        if len(frames) and (frames.min() < 0 or frames.max() >= self.n_frames):
            raise IndexError(f"frames {frames.min()}..{frames.max()} of {self.n_frames}")
        with open(self.path, "rb") as fh:
            for a in range(0, self.n_frames, self.chunk):
                mine = np.flatnonzero((frames >= a) & (frames < a + self.chunk))
                if not mine.size:
                    continue
                lo, hi = int(frames[mine].min()), int(frames[mine].max()) + 1
                fh.seek(lo * self._frame_bytes)
                arr = np.fromfile(fh, dtype=np.float32, count=(hi - lo) * self.n_vertices * 3)
                out[mine] = arr.reshape(hi - lo, self.n_vertices, 3)[frames[mine] - lo]
        return out
