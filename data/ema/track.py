"""What every EMA reader returns: named channels sampled at known times."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError

#: How exports write a missing sample (an empty cell, NaN, NA): it stays missing.
MISSING = {"", "nan", "-nan", "+nan", "na", "n/a"}


@dataclass(frozen=True, eq=False)
class CoilTrack:
    """One EMA recording as read, before any coil map.

    Attributes
    ----------
    path : Path
    channels : tuple of str
        Channel names (EST ``Channel_N`` names, table column names, ``.pos``: ``"<n>_x"``,
        ``"<n>_y"``, ``"<n>_z"``... with n the 1-based channel number).
    values : float64 (F, C)
        Samples in the file's own units; NaN where missing.
    time_s : float64 (F,)
        Sample times in seconds, strictly increasing.
    valid : bool (F,)
        False for frames the file marks as a break (EST ``BreaksPresent``).
    rate_hz : float or None
        The rate the file declares (``.pos`` header, EST equal spacing), None if it declares none.
    """

    path: Path
    channels: tuple[str, ...]
    values: np.ndarray
    time_s: np.ndarray
    valid: np.ndarray
    rate_hz: float | None = None

    @property
    def n_frames(self) -> int:
        return int(self.time_s.shape[0])

    def column(self, name: str) -> np.ndarray:
        """float64 (F,) of one channel by name."""
        return self.values[:, self.channels.index(name)]


def check_times(time_s: np.ndarray, *, path, line_of=None) -> None:
    """Refuse non-finite or non-increasing sample times (``line_of(k)``: row k's line)."""
    bad = np.flatnonzero(~np.isfinite(time_s))
    if bad.size:
        k = int(bad[0])
        raise CassiInputError(f"sample {k + 1}: time is not a number", path=path,
                              line=line_of(k) if line_of else None)
    back = np.flatnonzero(np.diff(time_s) <= 0)
    if back.size:
        k = int(back[0]) + 1
        raise CassiInputError(f"sample {k + 1}: time {time_s[k]:.6g} s does not increase "
                              f"(after {time_s[k - 1]:.6g} s)", path=path,
                              line=line_of(k) if line_of else None)
    if time_s.size and time_s[0] < 0:
        raise CassiInputError(f"sample 1: negative time {time_s[0]:.6g} s", path=path,
                              line=line_of(0) if line_of else None)


def sample(tok: str, *, what: str, path, line: int) -> float:
    """One number of a text recording; NaN for a missing sample (:data:`MISSING`)."""
    tok = tok.strip()
    if tok.lower() in MISSING:
        return float("nan")
    try:
        value = float(tok)
    except ValueError:
        value = float("inf")
    if not np.isfinite(value):
        raise CassiInputError(f"{what}: {tok[:40]!r} is not a number", path=path, line=line)
    return value
