"""Per-subject preprocessing for CASSI 2.x (thesis 4.2.1, 4.2.3 and Appendix B).

For each subject, up to :data:`MAX_FILES` error-free task files are selected (task 118, maximum lip
protrusion, always when it is error-free; then the lowest-numbered error-free tasks, one repetition
per task). From each selected file, at its first valid row (all eight pellets valid):

- the jaw length ``d`` = distance MNI-MNM (mm);
- the resting x of the upper and lower lip pellets, ``UL.x / d`` and ``LL.x / d``;
- the lip thickness, distance UL-LL divided by ``d``;

and over that row and all later rows, the largest and smallest x of UL and LL, divided by ``d``.
The subject's profile is

- ``rest_ul``, ``rest_ll``, ``lipthick``: means over the selected files;
- ``max_ul``, ``max_ll`` / ``min_ul``, ``min_ll``: the largest / smallest per-file value (the
  extreme over files: the published maxprotru.txt uses it, not a mean of per-file extremes);
- ``jaw_length_mm``: the mean of ``d`` (mm) over the selected files.

``maxprotru.txt`` (thesis Figure 4.16) and ``lipthick.txt`` (Figure 4.25) are read and written in
the thesis's formats::

    Subject REST_UL REST_LL MAX_UL MAX_LL MIN_UL MIN_LL
    JW11 0.345274 0.228690 0.519758 0.439836 0.009925 0.003348

    JW27 0.442891
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_write_text
from cassi.data.corpus.disk import SUBJECT_FILES, Corpus, SubjectData, natural_key
from cassi.common.errors import CassiInputError
from cassi.data.subject_name import SUBJECT_NAME_RE
from cassi.data.xrmb.headmeasures import HeadMeasures
from cassi.data.xrmb.textlines import decode_ascii, numbered_rows, parse_num, read_bytes
from cassi.data.xrmb.files import MAX_PROTRUSION_TASK, PELLETS, TaskRecording

log = logging.getLogger(__name__)

MAX_FILES = 20
MAXPROTRU_COLUMNS = ("REST_UL", "REST_LL", "MAX_UL", "MAX_LL", "MIN_UL", "MIN_LL")
_UL, _LL, _MNI, _MNM = (PELLETS.index(p) for p in ("UL", "LL", "MNI", "MNM"))


class MaxProtru(NamedTuple):
    """One row of maxprotru.txt (all values divided by the jaw length)."""

    rest_ul: float
    rest_ll: float
    max_ul: float
    max_ll: float
    min_ul: float
    min_ll: float


@dataclass(frozen=True, eq=False)
class SubjectProfile:
    """What CASSI 2.x needs to know about one subject.

    Attributes
    ----------
    subject : str
    jaw_length_mm : float
        Mean XRMB jaw length (MNI-MNM at the first valid row) over the selected files, mm.
    rest_ul, rest_ll, max_ul, max_ll, min_ul, min_ll : float
        The maxprotru.txt row: lip pellet x positions divided by the jaw length (dimensionless).
    lipthick : float
        The lipthick.txt value: UL-LL distance at the first valid row divided by the jaw length.
    palate_mm : float64 (P, 2) or None
        PAL.DAT, mm, front to back.
    pharynx_mm : float64 (P, 2) or None
        PHA.DAT (the posterior pharyngeal wall), mm, as the file lists it; for versions that
        place the back of the tongue along it (None where the subject has no PHA.DAT).
    head_measures : HeadMeasures or None
    selected : tuple of (task, rep)
        The files the values came from (thesis Table B.1).
    per_file : pandas.DataFrame
        One row per selected file (thesis Figure B.1): task, rep, jaw_length_mm, rest_ul, rest_ll,
        max_ul, max_ll, min_ul, min_ll, lipthick.
    """

    subject: str
    jaw_length_mm: float
    rest_ul: float
    rest_ll: float
    max_ul: float
    max_ll: float
    min_ul: float
    min_ll: float
    lipthick: float
    palate_mm: np.ndarray | None = None
    head_measures: HeadMeasures | None = None
    pharynx_mm: np.ndarray | None = None
    selected: tuple[tuple[int, int], ...] = ()
    per_file: pd.DataFrame = field(default_factory=pd.DataFrame)

    @property
    def maxprotru(self) -> MaxProtru:
        return MaxProtru(self.rest_ul, self.rest_ll, self.max_ul, self.max_ll, self.min_ul,
                         self.min_ll)


def file_measures(rec: TaskRecording) -> dict[str, float]:
    """Appendix B's per-file values for one recording (a row of Figure B.1).

    Raises :class:`CassiInputError` when the file has no valid row or a zero jaw length.
    """
    i = rec.first_valid_index
    if i is None:
        raise CassiInputError("no row has all eight pellets valid", path=rec.path)
    row = rec.xy_mm[i]
    d = float(np.hypot(*(row[_MNI] - row[_MNM])))
    if not d > 0:
        raise CassiInputError("jaw length (MNI-MNM) is zero at the first valid row", path=rec.path)
    ul_x = rec.xy_mm[i:, _UL, 0]
    ll_x = rec.xy_mm[i:, _LL, 0]
    return {
        "task": rec.task, "rep": rec.rep, "jaw_length_mm": d,
        "rest_ul": row[_UL, 0] / d, "rest_ll": row[_LL, 0] / d,
        "max_ul": np.nanmax(ul_x) / d, "max_ll": np.nanmax(ll_x) / d,
        "min_ul": np.nanmin(ul_x) / d, "min_ll": np.nanmin(ll_x) / d,
        "lipthick": float(np.hypot(*(row[_UL] - row[_LL]))) / d,
    }


def select_files(subject: SubjectData, *, max_files: int = MAX_FILES,
                 problems: list[str] | None = None
                 ) -> list[tuple[TaskRecording, tuple[int, int]]]:
    """Pick up to ``max_files`` error-free files (task 118 first when error-free).

    Tasks listed in Mis.dat are skipped without reading; one repetition per task (the lowest
    error-free one). A malformed file is left out with a logged warning, or, when ``problems``
    is a list, appended to it (``file:line: reason``) for the caller to refuse. Returns
    ``[(recording, (task, rep)), ...]`` in task order.
    """
    by_task: dict[int, list[int]] = {}
    for task, rep in subject.tasks():
        by_task.setdefault(task, []).append(rep)
    listed = subject.mistracked_tasks
    order = sorted(by_task)
    if MAX_PROTRUSION_TASK in by_task:
        order.remove(MAX_PROTRUSION_TASK)
        order.insert(0, MAX_PROTRUSION_TASK)
    chosen: list[tuple[TaskRecording, tuple[int, int]]] = []
    for task in order:
        if len(chosen) >= max_files:
            break
        if task in listed:
            continue
        for rep in sorted(by_task[task]):
            try:
                rec = subject.load(task, rep, require_valid=False)
            except CassiInputError as err:
                if problems is None:
                    log.warning("%s", err)
                else:
                    problems.append(str(err))
                continue
            if subject.usability(task, rep, recording=rec).error_free:
                chosen.append((rec, (task, rep)))
                break
    chosen.sort(key=lambda c: c[1])
    return chosen


def _pharynx(subject: SubjectData) -> np.ndarray | None:
    """The subject's PHA.DAT (mm), None where it has none; a malformed file raises."""
    if not any(f.name.upper() == SUBJECT_FILES["pha"] for f in subject.subject_files()):
        return None
    return subject.pharynx_mm


def profile_subject(subject: SubjectData, *, max_files: int = MAX_FILES,
                    problems: list[str] | None = None) -> SubjectProfile:
    """Preprocess one subject (see the module docstring; ``problems``: :func:`select_files`)."""
    chosen = select_files(subject, max_files=max_files, problems=problems)
    if not chosen:
        raise CassiInputError(f"subject {subject.name} has no error-free task file to preprocess",
                              path=subject.directory)
    per_file = pd.DataFrame([file_measures(rec) for rec, _ in chosen])
    palate = subject.palate_mm
    return SubjectProfile(
        subject=subject.name,
        jaw_length_mm=float(per_file["jaw_length_mm"].mean()),
        rest_ul=float(per_file["rest_ul"].mean()), rest_ll=float(per_file["rest_ll"].mean()),
        max_ul=float(per_file["max_ul"].max()), max_ll=float(per_file["max_ll"].max()),
        min_ul=float(per_file["min_ul"].min()), min_ll=float(per_file["min_ll"].min()),
        lipthick=float(per_file["lipthick"].mean()),
        palate_mm=palate, head_measures=subject.head_measures, pharynx_mm=_pharynx(subject),
        selected=tuple(key for _, key in chosen), per_file=per_file)


def preprocess(corpus: Corpus, subjects=None, *, max_files: int = MAX_FILES,
               skipped: list[str] | None = None,
               problems: list[str] | None = None) -> dict[str, SubjectProfile]:
    """Profiles of ``subjects`` (default: all subjects of the corpus).

    When ``subjects`` is None, a subject that cannot be preprocessed (no error-free file, like the
    thesis's JW29) is left out with a logged warning that is also appended to ``skipped``; a
    subject named explicitly raises :class:`CassiInputError` instead. ``problems`` collects the
    malformed task files met (:func:`select_files`) instead of logging them.
    """
    explicit = subjects is not None
    names = list(subjects) if explicit else corpus.subjects
    out: dict[str, SubjectProfile] = {}
    for name in names:
        subj = corpus.subject(name)
        try:
            out[subj.name] = profile_subject(subj, max_files=max_files, problems=problems)
        except CassiInputError as err:
            if explicit:
                raise
            msg = f"{subj.name} skipped: {err}"
            log.warning("%s", msg)
            if skipped is not None:
                skipped.append(msg)
    return out


# ----------------------------------------------------------------------------- table files
def _rows_of(table) -> dict[str, MaxProtru]:
    out = {}
    for name, v in table.items():
        out[name] = v.maxprotru if isinstance(v, SubjectProfile) else MaxProtru(*v)
    return out


def format_maxprotru(table) -> str:
    """maxprotru.txt text; ``table`` maps subject -> SubjectProfile or MaxProtru (6 values)."""
    rows = _rows_of(table)
    lines = ["Subject " + " ".join(MAXPROTRU_COLUMNS)]
    for name in sorted(rows, key=natural_key):
        vals = rows[name]
        if not all(np.isfinite(vals)):
            raise CassiInputError(f"{name}: non-finite maxprotru value")
        lines.append(name + " " + " ".join(f"{v:.6f}" for v in vals))
    return "\n".join(lines) + "\n"


def write_maxprotru(path: str | os.PathLike, table) -> None:
    """Write maxprotru.txt (atomic) in the thesis's format, subjects in natural order."""
    atomic_write_text(path, format_maxprotru(table))


def _subject_row(name: str, seen: dict[str, int], *, path, line: int) -> None:
    """Refuse a row's subject name that is not one (the corpus's rule for subject folders), or
    that repeats an earlier row's, up to case (the folders are matched up to case)."""
    if not SUBJECT_NAME_RE.fullmatch(name):
        raise CassiInputError(f"{name!r} is not a subject name (a letter, then letters, digits, "
                              f"_ or -)", path=path, line=line)
    first = seen.setdefault(name.upper(), line)
    if first != line:
        raise CassiInputError(f"subject {name} listed twice (line {first}, up to case)",
                              path=path, line=line)


def parse_maxprotru(data: bytes | str, *, path=None) -> dict[str, MaxProtru]:
    """Parse maxprotru.txt text -> ``{subject: MaxProtru}`` in file order.

    The header is ``Subject REST_UL ... MIN_LL`` (or as printed, ``REST UL`` with spaces).
    """
    text = decode_ascii(data, path=path)
    out: dict[str, MaxProtru] = {}
    seen: dict[str, int] = {}
    header_seen = False
    for line, toks in numbered_rows(text):
        if not header_seen:
            joined = " ".join(toks[1:]).upper().replace("_", " ")
            if toks[0].upper() == "SUBJECT" and joined == " ".join(MAXPROTRU_COLUMNS).replace(
                    "_", " "):
                header_seen = True
                continue
            if toks[0].upper() == "SUBJECT":
                raise CassiInputError("unexpected header (expected Subject REST_UL REST_LL "
                                      "MAX_UL MAX_LL MIN_UL MIN_LL)", path=path, line=line)
        header_seen = True
        if len(toks) != 7:
            raise CassiInputError(f"expected 7 columns (subject and six values), found "
                                  f"{len(toks)}", path=path, line=line)
        name = toks[0]
        _subject_row(name, seen, path=path, line=line)
        vals = [parse_num(t, what=f"column {k} ({MAXPROTRU_COLUMNS[k - 2]})", path=path, line=line)
                for k, t in enumerate(toks[1:], start=2)]
        row = MaxProtru(*vals)
        for lip in ("ul", "ll"):
            lo, rest, hi = (getattr(row, f"{k}_{lip}") for k in ("min", "rest", "max"))
            if not lo <= rest <= hi:  # eq. 4.13 maps MIN..REST..MAX onto c: they must be ordered
                raise CassiInputError(f"{lip.upper()}: expected MIN <= REST <= MAX, got {lo:g}, "
                                      f"{rest:g}, {hi:g}", path=path, line=line)
        out[name] = row
    if not out:
        raise CassiInputError("empty file: no subject rows", path=path)
    return out


def read_maxprotru(path: str | os.PathLike) -> dict[str, MaxProtru]:
    return parse_maxprotru(read_bytes(path), path=path)


def format_lipthick(table) -> str:
    """lipthick.txt text; ``table`` maps subject -> SubjectProfile or float."""
    lines = []
    for name in sorted(table, key=natural_key):
        v = table[name]
        v = v.lipthick if isinstance(v, SubjectProfile) else float(v)
        if not np.isfinite(v):
            raise CassiInputError(f"{name}: non-finite lip thickness")
        lines.append(f"{name} {v:.6f}")
    return "\n".join(lines) + "\n"


def write_lipthick(path: str | os.PathLike, table) -> None:
    """Write lipthick.txt (atomic): ``SUBJECT value`` per line, six decimals."""
    atomic_write_text(path, format_lipthick(table))


def parse_lipthick(data: bytes | str, *, path=None) -> dict[str, float]:
    """Parse lipthick.txt text -> ``{subject: value}`` in file order."""
    text = decode_ascii(data, path=path)
    out: dict[str, float] = {}
    seen: dict[str, int] = {}
    for line, toks in numbered_rows(text):
        if len(toks) != 2:
            raise CassiInputError(f"expected 2 columns (subject value), found {len(toks)}",
                                  path=path, line=line)
        _subject_row(toks[0], seen, path=path, line=line)
        v = parse_num(toks[1], what="column 2 (lip thickness)", path=path, line=line)
        if not v > 0:  # the UL-LL pellet distance over the jaw length
            raise CassiInputError(f"lip thickness must be positive, got {v:g}", path=path, line=line)
        out[toks[0]] = v
    if not out:
        raise CassiInputError("empty file: no subject rows", path=path)
    return out


def read_lipthick(path: str | os.PathLike) -> dict[str, float]:
    return parse_lipthick(read_bytes(path), path=path)
