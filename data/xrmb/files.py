"""Readers and writers for the Wisconsin X-ray Microbeam (XRMB) files CASSI uses.

Task files (thesis 3.2.5, Figure 3.9)
-------------------------------------
``tpNNN.txy``, ``tpNNN_R.txy`` (repetition R) or the thesis's ``SUBJ_NNN.TXY`` (any case): one row
per sample, 17 whitespace-separated integer columns::

    time_us ULx ULy LLx LLy T1x T1y T2x T2y T3x T3y T4x T4y MNIx MNIy MNMx MNMy

Time in microseconds (XRMB's nominal period 6866 us; other recordings, such as EMA at 200-500 Hz,
keep their own: :func:`recording_period_us` is a recording's period wherever one is needed),
coordinates in micrometres in the XRMB head frame
(thesis 3.2.3: origin between the tips of the central maxillary incisors, x along the maxillary
occlusal plane with positive x out of the mouth, y normal to it with positive y toward the roof of
the mouth). ``1000000`` marks a bad value (mistracked, missing or not yet tracked pellet); it
becomes ``valid == False`` and NaN coordinates, never a coordinate. Tabs or spaces, CRLF or LF,
with or without a final newline are all read.

Outline files (thesis Figure 3.11)
----------------------------------
``PAL.DAT`` (palate, front to back) and ``PHA.DAT`` (pharynx): one ``x y`` pair per line in
micrometres; returned as float64 ``(P, 2)`` millimetres.

Mis.dat and the head-measures file live in :mod:`cassi.data.xrmb.mis` and
:mod:`cassi.data.xrmb.headmeasures` and are re-exported here.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.data.xrmb.headmeasures import (  # noqa: F401  (re-exported: contract names them here)
    HeadMeasures, parse_head_measures, read_head_measures, write_head_measures,
    format_head_measures)
from cassi.data.xrmb.mis import (  # noqa: F401
    MISTRACK_PELLET_CODES, MistrackEntry, format_mis, parse_mis, read_mis, write_mis)
from cassi.data.xrmb.textlines import (decode_ascii, numbered_rows, parse_int, parse_num, read_bytes,
                                  split_lines, tokens)

__all__ = [
    "PELLETS", "BAD_VALUE", "NOMINAL_PERIOD_US", "JAW_WAGGING_TASK", "MAX_PROTRUSION_TASK",
    "ORAL_MOTOR_TASKS",
    "N_COLUMNS", "COLUMN_NAMES", "TaskRecording", "recording_period_us", "rows_spanning",
    "parse_task_name", "task_stem", "task_file_name", "parse_txy", "read_txy", "format_txy", "write_txy",
    "parse_outline", "format_outline", "read_pal", "write_pal", "check_palate_length",
    "MIN_PALATE_LENGTH_MM", "read_pha", "write_pha",
    "MistrackEntry", "MISTRACK_PELLET_CODES", "parse_mis", "read_mis", "format_mis", "write_mis",
    "HeadMeasures", "parse_head_measures", "read_head_measures", "format_head_measures",
    "write_head_measures",
]

PELLETS = ("UL", "LL", "T1", "T2", "T3", "T4", "MNI", "MNM")
BAD_VALUE = 1000000
NOMINAL_PERIOD_US = 6866
#: The two oral-motor tasks the thesis evaluates on their own (section 5.3): jaw wagging (its
#: Table 5.9) and maximum lip protrusion (Table 5.8, and the file 2.x's rounding is read from).
JAW_WAGGING_TASK = 106
MAX_PROTRUSION_TASK = 118
#: Both, in the thesis's order: tasks judged by their own tables, not by the speech tables.
ORAL_MOTOR_TASKS = (JAW_WAGGING_TASK, MAX_PROTRUSION_TASK)
N_COLUMNS = 1 + 2 * len(PELLETS)
COLUMN_NAMES = ("time",) + tuple(f"{p}{c}" for p in PELLETS for c in "xy")

# Every column is a whole number (time in us, coordinates in um; the real files have no
# fraction). At most 12 digits: exact in int64, and a coordinate of 10^12 um is already absurd.
_NUM = r"[+-]?[0-9]{1,12}"
_SEP = r"[ \t\f\v]+"
# One well-formed row; rows that do not match are diagnosed field by field (the slow path).
_ROW_RE = re.compile(rf"[ \t\f\v]*[0-9]{{1,15}}(?:{_SEP}{_NUM}){{16}}[ \t\f\v\r]*", re.ASCII)
# A whole file of nothing but rows (what every real file is): checked without a string per
# line; possessive (*+) so the engine keeps no backtracking state per row (2.8 GB an hour).
_FILE_RE = re.compile(rf"(?:{_ROW_RE.pattern}\n)*+(?:{_ROW_RE.pattern})?", re.ASCII)
_TASK_NAME_RE = re.compile(
    r"^(?:tp|(?P<subject>[a-z]+[0-9]+)_)(?P<task>[0-9]{1,4})(?:_(?P<rep>[0-9]{1,3}))?\.txy$",
    re.IGNORECASE | re.ASCII)
# Largest plausible coordinate (micrometres): 0.5 m from the incisors is certainly wrong data.
_MAX_ABS_UM = 500_000


def recording_period_us(time_us) -> float:
    """The sample period of a recording, us: the median interval of its sample times ``time_us``
    (int (F,), increasing), so a few dropped or late rows do not change it; XRMB's nominal
    :data:`NOMINAL_PERIOD_US` when fewer than two samples say otherwise.

    The one home of "the period of a recording": every figure, window, video frame rate and
    export time that depends on the rate reads it from here (6866.0 on an XRMB file, 2000.0 on
    MOCHA-TIMIT's 500 Hz EMA)."""
    t = np.asarray(time_us)
    if t.shape[0] < 2:
        return float(NOMINAL_PERIOD_US)
    return float(np.median(np.diff(t)))


def rows_spanning(duration_us: float, period_us: float, *, odd: bool = False) -> int:
    """How many rows of ``period_us`` span ``duration_us`` (rounded, at least 1; with ``odd`` the
    next odd number, for a centred window). A window stated in time gives the same count on
    XRMB as the per-row constant it replaces: 62 ms at 6866 us is 9 rows, at 2000 us 31."""
    n = max(1, int(round(float(duration_us) / float(period_us))))
    return n | 1 if odd else n


def parse_task_name(name: str) -> tuple[str | None, int, int]:
    """Subject (if the name carries it), task and repetition from a task file name.

    ``tp013.txy`` -> ``(None, 13, 1)``; ``tp015_2.txy`` -> ``(None, 15, 2)``;
    ``JW45_013.TXY`` -> ``("JW45", 13, 1)``. Raises :class:`CassiInputError` otherwise.
    """
    m = _TASK_NAME_RE.match(name)
    if not m:
        raise CassiInputError(
            "not a task file name (expected tpNNN.txy, tpNNN_R.txy or SUBJ_NNN.txy)", path=name)
    subject = m.group("subject")
    rep = int(m.group("rep")) if m.group("rep") else 1
    task = int(m.group("task"))
    if task < 1 or rep < 1:
        raise CassiInputError("task and repetition numbers start at 1", path=name)
    return (subject.upper() if subject else None), task, rep


def task_stem(task: int, rep: int = 1) -> str:
    """A task file's name without its suffix, ``tpNNN`` or ``tpNNN_R``: the stem its labels
    and sound share (``tpNNN.TextGrid``, ``tpNNN.wav``)."""
    return f"tp{task:03d}" if rep == 1 else f"tp{task:03d}_{rep}"


def task_file_name(task: int, rep: int = 1) -> str:
    """The canonical file name for a task: ``tpNNN.txy`` or ``tpNNN_R.txy``."""
    return task_stem(task, rep) + ".txy"


@dataclass(frozen=True, eq=False)
class TaskRecording:
    """One XRMB task file.

    Attributes
    ----------
    path : Path or None
        Where it was read from (None when built in memory).
    subject : str
    task : int
        XRMB task (record) number, 1..118.
    rep : int
        Repetition: 1 for ``tpNNN.txy``, R for ``tpNNN_R.txy``.
    time_us : int64 (F,)
        Sample times in microseconds, strictly increasing.
    xy_mm : float64 (F, 8, 2)
        Pellet x, y in millimetres in the XRMB frame, pellets in :data:`PELLETS` order; NaN where
        the pellet is invalid.
    valid : bool (F, 8)
        False where the file had the bad value 1000000.
    warnings : tuple of str
        Problems found that did not stop reading (``file:line: reason``).
    derived : tuple of str
        Pellets not measured but derived by a rule the EMA coil map declares
        (:mod:`cassi.data.ema.derive`); empty for XRMB files.
    """

    path: Path | None
    subject: str
    task: int
    rep: int
    time_us: np.ndarray
    xy_mm: np.ndarray
    valid: np.ndarray
    warnings: tuple[str, ...] = field(default=())
    derived: tuple[str, ...] = field(default=())

    @property
    def n_frames(self) -> int:
        return int(self.time_us.shape[0])

    @property
    def period_us(self) -> float:
        """The recording's sample period, us (:func:`recording_period_us`)."""
        return recording_period_us(self.time_us)

    @property
    def all_valid(self) -> np.ndarray:
        """bool (F,): rows where all eight pellets are valid."""
        return self.valid.all(axis=1)

    @property
    def first_valid_index(self) -> int | None:
        """Index of the first row with all eight pellets valid, or None (thesis 3.2.5)."""
        rows = np.flatnonzero(self.all_valid)
        return int(rows[0]) if rows.size else None

    @property
    def first_valid_time_us(self) -> int | None:
        i = self.first_valid_index
        return None if i is None else int(self.time_us[i])

    def pellet(self, name: str) -> np.ndarray:
        """float64 (F, 2) mm for one pellet by name (``"UL"`` ... ``"MNM"``)."""
        return self.xy_mm[:, PELLETS.index(name)]


def _diagnose_row(toks: list[str], *, path, line) -> None:
    """Raise the precise error for a row that failed the fast pattern."""
    if len(toks) != N_COLUMNS:
        raise CassiInputError(f"expected {N_COLUMNS} columns, found {len(toks)}", path=path, line=line)
    t = toks[0]
    if not re.fullmatch(r"[0-9]+", t, re.ASCII):
        parse_int(t, what="column 1 (time)", path=path, line=line)  # raises if not an integer
        raise CassiInputError(f"column 1 (time): {t[:40]!r} must be a non-negative integer",
                              path=path, line=line)
    if len(t) > 15:
        raise CassiInputError(f"column 1 (time): {t[:40]!r} is too large", path=path, line=line)
    for k, tok in enumerate(toks[1:], start=2):
        what = f"column {k} ({COLUMN_NAMES[k - 1]})"
        parse_num(tok, what=what, path=path, line=line)
        if re.fullmatch(r"[+-]?(?:[0-9]*\.[0-9]*|[0-9.]+[eE][+-]?[0-9]+)", tok, re.ASCII):
            raise CassiInputError(f"{what}: {tok[:40]!r} is not a whole number of micrometres "
                                  "(XRMB coordinates are integers)", path=path, line=line)
        if not re.fullmatch(_NUM, tok, re.ASCII):
            raise CassiInputError(f"{what}: {tok[:40]!r} has too many digits", path=path,
                                  line=line)
    raise CassiInputError("malformed row", path=path, line=line)  # pragma: no cover - defensive


def parse_txy(data: bytes | str, *, path: str | os.PathLike | None = None,
              subject: str | None = None, task: int | None = None, rep: int | None = None,
              require_valid: bool = True) -> TaskRecording:
    """Parse the text of a task file.

    Parameters
    ----------
    data : bytes or str
        The file's content.
    path : path-like, optional
        Used in messages; subject/task/rep are taken from its name when not given.
    subject, task, rep : optional
        Override what the file name says. ``task`` is required when the name is not a task name.
    require_valid : bool
        When True (default) a file with no row where all eight pellets are valid is an error;
        when False it is a recorded warning (used to report why a file is unusable).

    Raises
    ------
    CassiInputError
        Empty file, wrong column count, non-numeric field, time not increasing, no valid row.
    """
    subject, task, rep = _recording_names(path, subject, task, rep)
    warnings: list[str] = []

    def warn(msg: str, line: int | None = None) -> None:
        line = None if line is None else int(line)
        warnings.append(str(CassiInputError(msg, path=path, line=line)))

    values, line_numbers = _table(decode_ascii(data, path=path), path=path, warn=warn)
    time_us = values[:, 0].astype(np.int64)
    _check_times(time_us, line_numbers, path=path, warn=warn)
    xy_mm, valid = _pellet_samples(values, line_numbers, warn=warn)
    _check_valid_rows(valid, time_us, line_numbers, path=path, warn=warn,
                      require_valid=require_valid)
    return TaskRecording(path=None if path is None else Path(path), subject=str(subject),
                         task=int(task), rep=int(rep), time_us=time_us, xy_mm=xy_mm,
                         valid=valid, warnings=tuple(warnings))


def _recording_names(path, subject, task, rep) -> tuple[str, int, int]:
    """Subject, task and repetition: as given, else from the file's name (and its folder's)."""
    name_subject, name_task, name_rep = None, None, None
    if path is not None:
        try:
            name_subject, name_task, name_rep = parse_task_name(Path(path).name)
        except CassiInputError:
            if task is None:
                raise
    task = task if task is not None else name_task
    if task is None:
        raise CassiInputError("task number unknown (pass task=...)", path=path)
    rep = rep if rep is not None else (name_rep or 1)
    if subject is None:
        subject = name_subject
        if subject is None and path is not None:
            subject = Path(path).resolve().parent.name.upper() or None
    return subject or "UNKNOWN", task, rep


def _table(text: str, *, path, warn) -> tuple[np.ndarray, np.ndarray]:
    """The integer table int64 (N, N_COLUMNS) and each row's line number (1-based)."""
    # NumPy's C text reader parses the table without a Python string per number (an hour-long
    # file has ten million of them); every row has matched _ROW_RE (integers only) first.
    if text.strip() and _FILE_RE.fullmatch(text):
        flat = np.fromstring(text, dtype=np.int64, sep=" ")
        line_numbers = np.arange(1, flat.size // N_COLUMNS + 1)
    else:  # a header, blank lines or a bad row: line by line, to say which line is wrong
        rows, line_numbers = _table_rows(split_lines(text), path=path, warn=warn)
        flat = np.fromstring(" ".join(rows), dtype=np.int64, sep=" ")
    if flat.size != len(line_numbers) * N_COLUMNS:  # pragma: no cover - defensive: rows matched
        raise CassiInputError("malformed rows", path=path)
    return flat.reshape(len(line_numbers), N_COLUMNS), line_numbers


def _check_times(time_us: np.ndarray, line_numbers: np.ndarray, *, path, warn) -> None:
    """Refuse a time that does not increase; warn of intervals off the file's own period (its
    median interval: 6866 us on XRMB, 2000 us on a 500 Hz recording)."""
    dt = np.diff(time_us)
    bad_dt = np.flatnonzero(dt <= 0)
    if bad_dt.size:
        k = int(bad_dt[0]) + 1
        raise CassiInputError(
            f"time not increasing: {time_us[k]} us after {time_us[k - 1]} us",
            path=path, line=int(line_numbers[k]))
    if dt.size:
        period = recording_period_us(time_us)
        off = np.flatnonzero(np.abs(dt - period) > 2)
        if off.size:
            k = int(off[0]) + 1
            warn(f"{off.size} sample interval(s) differ from the nominal {period:g} us "
                 f"(first: {int(dt[k - 1])} us)", line_numbers[k])


def _pellet_samples(values: np.ndarray, line_numbers: np.ndarray, *,
                    warn) -> tuple[np.ndarray, np.ndarray]:
    """The pellets in mm (NaN where invalid) and which samples are valid."""
    coords = values[:, 1:].reshape(len(line_numbers), len(PELLETS), 2)
    bad = coords == BAD_VALUE
    valid = ~bad.any(axis=2)
    half = np.argwhere(bad.any(axis=2) & ~bad.all(axis=2))
    if half.size:
        r, p = half[0]
        warn(f"{len(half)} pellet sample(s) with only one coordinate 1000000 treated as invalid "
             f"(first: {PELLETS[p]})", line_numbers[r])
    far = valid & (np.abs(coords) > _MAX_ABS_UM).any(axis=2)
    if far.any():
        # mistracked as surely as the bad value: kept valid, one such sample became a lip
        # protrusion of 26 km in preprocessing, in a file counted as error-free
        r, p = np.argwhere(far)[0]
        warn(f"{int(far.sum())} pellet sample(s) farther than {_MAX_ABS_UM // 1000} mm from the "
             f"origin treated as invalid (first: {PELLETS[p]})", line_numbers[r])
        valid &= ~far
    xy_mm = coords.astype(np.float64)  # in place from here: no temporary of the whole table
    xy_mm /= 1000.0
    xy_mm[~valid] = np.nan
    return xy_mm, valid


def _check_valid_rows(valid: np.ndarray, time_us: np.ndarray, line_numbers: np.ndarray, *,
                      path, warn, require_valid: bool) -> None:
    """Refuse (or warn of) a file with no all-valid row; warn of pellets lost after the first."""
    all_valid = valid.all(axis=1)
    if not all_valid.any():
        never = [PELLETS[p] for p in range(len(PELLETS)) if not valid[:, p].any()]
        why = f" (never valid: {', '.join(never)})" if never else ""
        msg = f"no row has all eight pellets valid{why}"
        if require_valid:
            raise CassiInputError(msg, path=path, line=int(line_numbers[-1]))
        warn(msg)
        return
    first = int(np.flatnonzero(all_valid)[0])
    # A pellet lost part-way and never recovered (the thesis's JW29/JW32 cases): record it.
    for p, name in enumerate(PELLETS):
        after = valid[first:, p]
        if not after.all():
            lost = first + int(np.flatnonzero(~after)[0])
            if not valid[lost:, p].any():
                warn(f"pellet {name} invalid from time {time_us[lost]} us to the end",
                     line_numbers[lost])
            else:
                n = int((~after).sum())
                warn(f"pellet {name} invalid in {n} row(s) after the first valid row",
                     line_numbers[lost])


def _table_rows(lines: list[str], *, path, warn) -> tuple[list[str], np.ndarray]:
    """The data rows of a task file and their line numbers (1-based), line by line: a header
    line is skipped with a warning, blank lines between rows are warned about, anything else
    that is not a row is an error naming its line."""
    rows: list[str] = []
    line_numbers: list[int] = []
    blank_inside: list[int] = []
    for i, line in enumerate(lines, start=1):
        if _ROW_RE.fullmatch(line):
            rows.append(line)
            line_numbers.append(i)
            continue
        toks = tokens(line)
        if not toks:
            blank_inside.append(i)
            continue
        if not rows and len(toks) == N_COLUMNS and [t.lower() for t in toks] == [
                c.lower() for c in COLUMN_NAMES]:
            warn("column header line skipped (real .txy files have none)", i)
            continue
        _diagnose_row(toks, path=path, line=i)
    if not rows:
        raise CassiInputError("empty file: no data rows", path=path,
                              line=None if not lines else 1)
    # Blank lines after the last row are harmless; blank lines between rows are worth a warning.
    inner = [b for b in blank_inside if line_numbers[0] < b < line_numbers[-1]]
    if inner:
        warn(f"{len(inner)} blank line(s) between rows (first at line {inner[0]})", inner[0])
    return rows, np.asarray(line_numbers)


def read_txy(path: str | os.PathLike, *, subject: str | None = None, task: int | None = None,
             rep: int | None = None, require_valid: bool = True) -> TaskRecording:
    """Read a task file (see :func:`parse_txy`)."""
    return parse_txy(read_bytes(path), path=path, subject=subject, task=task, rep=rep,
                     require_valid=require_valid)


def format_txy(rec: TaskRecording) -> str:
    """The text of a task file: tab-separated integers, LF line ends, final newline.

    Invalid pellets (``valid`` False or NaN coordinates) are written as 1000000 for x and y.
    Coordinates are rounded to whole micrometres, as in the real files.
    """
    t = np.asarray(rec.time_us)
    xy = np.asarray(rec.xy_mm, dtype=np.float64)
    valid = np.asarray(rec.valid, dtype=bool)
    if t.ndim != 1 or xy.shape != (t.shape[0], len(PELLETS), 2) or valid.shape != xy.shape[:2]:
        raise CassiInputError(f"inconsistent shapes time {t.shape}, xy {xy.shape}, valid "
                              f"{valid.shape}")
    if t.size == 0:
        raise CassiInputError("a task file needs at least one row")
    if (t < 0).any() or (np.diff(t) <= 0).any():
        raise CassiInputError("time must be non-negative and strictly increasing")
    valid = valid & np.isfinite(xy).all(axis=2)
    um = np.rint(np.where(valid[:, :, None], xy, 0.0) * 1000.0)
    if (np.abs(um[valid]) >= BAD_VALUE).any():
        raise CassiInputError("a valid coordinate would collide with the bad value 1000000 um")
    um = np.where(valid[:, :, None], um, BAD_VALUE).astype(np.int64).reshape(len(t), -1)
    table = np.column_stack([t.astype(np.int64), um])
    # One %-format over the whole table: the per-row loop is done in C (about 3x faster than
    # joining str() per row, which took half the synthetic corpus's generation time); "%d" of a
    # Python int is exactly its str(), so the bytes are unchanged.
    row_format = "\t".join(["%d"] * table.shape[1]) + "\n"
    return (row_format * table.shape[0]) % tuple(table.ravel().tolist())


def write_txy(path: str | os.PathLike, rec: TaskRecording) -> None:
    """Write ``rec`` as a task file (atomic)."""
    atomic_write_text(path, format_txy(rec))


# ----------------------------------------------------------------------------- outlines
def parse_outline(data: bytes | str, *, path: str | os.PathLike | None = None,
                  what: str = "outline") -> np.ndarray:
    """Parse ``PAL.DAT`` / ``PHA.DAT`` text: ``x y`` micrometres per line -> float64 (P, 2) mm."""
    text = decode_ascii(data, path=path)
    pts: list[tuple[float, float]] = []
    for line, toks in numbered_rows(text):
        if len(toks) != 2:
            raise CassiInputError(f"expected 2 columns (x y), found {len(toks)}", path=path,
                                  line=line)
        x = parse_num(toks[0], what="column 1 (x)", path=path, line=line)
        y = parse_num(toks[1], what="column 2 (y)", path=path, line=line)
        if BAD_VALUE in (x, y):
            raise CassiInputError(f"bad value {BAD_VALUE} in a {what}", path=path, line=line)
        if abs(x) > _MAX_ABS_UM or abs(y) > _MAX_ABS_UM:
            raise CassiInputError(f"point ({x:g}, {y:g}) um is implausibly far from the origin",
                                  path=path, line=line)
        pts.append((x, y))
    if not pts:
        raise CassiInputError(f"empty file: no {what} points", path=path)
    return np.asarray(pts, dtype=np.float64) / 1000.0


def format_outline(points_mm: np.ndarray) -> str:
    pts = np.asarray(points_mm, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] == 0:
        raise CassiInputError(f"outline must be a non-empty (P, 2) array, not {pts.shape}")
    if not np.isfinite(pts).all():
        raise CassiInputError("outline has non-finite points")
    um = np.rint(pts * 1000.0).astype(np.int64)
    return "".join(f"{x} {y}\n" for x, y in um.tolist())


#: The shortest palatal outline a face can be given (mm along the outline): two points or an
#: outline shorter than this cannot place the palate (the real outlines run 50-60 mm).
MIN_PALATE_LENGTH_MM = 5.0


def check_palate_length(points_mm: np.ndarray, *, path: str | os.PathLike | None = None) -> None:
    """:class:`CassiInputError` (naming ``path``) unless the outline has two points or more and
    runs at least :data:`MIN_PALATE_LENGTH_MM`."""
    pts = np.asarray(points_mm, dtype=np.float64)
    length = float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0
    if not length >= MIN_PALATE_LENGTH_MM:  # NaN too
        raise CassiInputError(f"the palate outline runs {length:.2f} mm over {len(pts)} point(s), "
                              f"shorter than the {MIN_PALATE_LENGTH_MM:g} mm a face needs", path=path)


def read_pal(path: str | os.PathLike) -> np.ndarray:
    """Palatal outline ``PAL.DAT``: float64 (P, 2) mm, front to back (thesis Figure 3.11)."""
    pts = parse_outline(read_bytes(path), path=path, what="palate outline")
    check_palate_length(pts, path=path)
    return pts


def write_pal(path: str | os.PathLike, points_mm: np.ndarray) -> None:
    atomic_write_text(path, format_outline(points_mm))


def read_pha(path: str | os.PathLike) -> np.ndarray:
    """Pharynx outline ``PHA.DAT``: float64 (P, 2) mm."""
    return parse_outline(read_bytes(path), path=path, what="pharynx outline")


def write_pha(path: str | os.PathLike, points_mm: np.ndarray) -> None:
    atomic_write_text(path, format_outline(points_mm))
