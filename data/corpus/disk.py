"""An XRMB corpus on disk: a directory of subject directories (thesis 3.2.5).

Layout::

    CORPUS/
      corpus.json            optional metadata; generated corpora say {"synthetic": true, ...}
      Headmeasures.txt       optional, all subjects (format: cassi.data.xrmb.headmeasures)
      JW12/
        tp001.txy ... tp118.txy, tp015_2.txy    task files (any case; JW12_001.TXY also read)
        PAL.DAT  PHA.DAT  Mis.dat               subject files (any case)
        Headmeasures.txt                        optional, this subject (overrides the root one)
        tp001.TextGrid ...                      optional labels (phone and word tiers; or
                                                tp001.lab xwaves/ESPS or HTK, .rec, *.mlf)
        tp001.wav ...                           optional sound, any sample rate

A directory with a coil map (``ema.yaml``, in it or in the corpus root) holds EMA recordings
instead: :mod:`cassi.data.ema.subject` says how they become task recordings.

Two files of one task (``tp003.txy`` and ``JW12_003.txy``, or names equal up to case) are read
only when their bytes are equal; otherwise every reader refuses, naming both.

Every path the corpus opens is checked to stay inside the corpus directory (a symlink or a name
that leads outside is an error), and every problem met is either raised as
:class:`~cassi.common.errors.CassiInputError` or recorded in ``problems``/``warnings``.
"""
from __future__ import annotations

import filecmp
import json
import os
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from cassi.data.corpus.beside import alignment_path_for_stem, audio_for_stem
from cassi.data.xrmb.alignment import Alignment, read_alignment  # noqa: F401 (re-exported)
from cassi.data.xrmb.labels import read_labels
from cassi.common.errors import CassiInputError
from cassi.data.xrmb.headmeasures import HEAD_MEASURES_FILE, HeadMeasures, read_head_measures
from cassi.data.xrmb.mis import MistrackEntry, read_mis
from cassi.data.xrmb.textlines import read_bytes
from cassi.data.xrmb.files import (PELLETS, TaskRecording, parse_task_name, parse_txy, read_pha,
                                   read_pal, read_txy, task_stem)
from cassi.data.subject_name import SUBJECT_NAME_RE
from cassi.data.ema.subject import EmaSubject, map_path

METADATA_FILE = "corpus.json"
SUBJECT_FILES = {"pal": "PAL.DAT", "pha": "PHA.DAT", "mis": "Mis.dat"}


def natural_key(name: str):
    return [int(p) if p.isdecimal() else p.lower() for p in re.split(r"(\d+)", name)]


def _same_bytes(a: Path, b: Path) -> bool:
    try:
        return filecmp.cmp(a, b, shallow=False)
    except OSError as err:
        raise CassiInputError(f"cannot read: {err.strerror or err}", path=err.filename or b) \
            from None


def ensure_inside(root: Path, path: Path) -> Path:
    """Resolve ``path`` and make sure it lies inside ``root`` (symlinks followed).

    Raises :class:`CassiInputError` naming the path when it would escape the corpus directory.
    """
    try:
        real_root = root.resolve()
        real = path.resolve()
    except (RuntimeError, OSError) as err:  # Python 3.11 raises RuntimeError on a link loop
        raise CassiInputError(f"cannot resolve (a symbolic link loop?): {err}", path=path) from None
    if real != real_root and real_root not in real.parents:
        link = "is a symbolic link that " if path.is_symlink() else ""
        raise CassiInputError(f"{link}leads outside the corpus directory {root} (to {real}): "
                              f"not read; copy it into the corpus", path=path)
    return real


@dataclass(frozen=True)
class Usability:
    """Whether a task file can be used (thesis 3.2.5 and 4.2.1).

    ``usable``: readable, with at least one row where all eight pellets are valid.
    ``error_free``: usable, not listed in Mis.dat, and no pellet missing after the first valid row
    (the preprocessing selection of thesis 4.2.1 takes only error-free files).
    ``reasons``: why not (empty when error-free).
    """

    usable: bool
    error_free: bool
    reasons: tuple[str, ...] = ()


class SubjectData:
    """One subject directory of a :class:`Corpus`."""

    def __init__(self, corpus: "Corpus", name: str, directory: Path):
        self.corpus = corpus
        self.name = name
        self.directory = directory
        self.warnings: list[str] = []
        self.problems: list[str] = []
        self._task_paths: list[Path] = []  # every *.txy, case twins included
        ema_map = map_path(corpus.root, directory)
        #: The EMA side (coil map, readers) where a coil map applies, else None.
        self.ema = None if ema_map is None else EmaSubject(ema_map, directory)
        self._files = self._scan()

    def __repr__(self) -> str:
        return f"SubjectData({self.name!r}, {self.directory})"

    # ------------------------------------------------------------------ files
    def _scan(self) -> dict[str, Path]:
        files: dict[str, Path] = {}
        try:
            entries = sorted(os.scandir(self.directory), key=lambda e: e.name)
        except OSError as err:
            raise CassiInputError(f"cannot list subject directory: {err.strerror or err}",
                                  path=self.directory) from None
        for e in entries:
            if e.name.startswith("."):
                if e.name.lower().endswith((".txy", ".dat", ".txt", ".textgrid")):
                    self.warnings.append(f"{self.directory / e.name}: hidden file ignored")
                continue
            key = e.name.lower()
            if self.ema is not None:
                if self.ema.is_recording(e.name):
                    self._task_paths.append(self.directory / e.name)
            elif key.endswith(".txy"):  # twins up to case are two files of one task: the index's
                self._task_paths.append(self.directory / e.name)
            if key in files:
                if not key.endswith(".txy"):
                    self.warnings.append(f"{self.directory / e.name}: same name as "
                                         f"{files[key].name} up to case; ignored")
                continue
            files[key] = self.directory / e.name
        return files

    def _file(self, name: str, *, required: bool = True) -> Path | None:
        path = self._files.get(name.lower())
        if path is None:
            if required:
                raise CassiInputError(f"missing subject file {name}", path=self.directory)
            return None
        return self._checked(path)

    def _checked(self, path: Path) -> Path:
        """``path``, a regular file inside the corpus (else CassiInputError naming it)."""
        ensure_inside(self.corpus.root, path)
        if not path.is_file():
            raise CassiInputError("is not a regular file", path=path)
        return path

    @property
    def _task_index(self) -> dict[tuple[int, int], Path]:
        """``{(task, rep): path}``. Two files of one task (``tp003.txy`` and ``JW16_003.txy``,
        or names equal up to case) are read as one only when their bytes are equal; otherwise
        which one is the recording is not ours to guess: CassiInputError naming both."""
        index, ambiguous = self._task_scan
        if ambiguous:
            raise CassiInputError("\n".join(ambiguous.values()))
        return index

    @cached_property
    def _task_scan(self) -> tuple[dict[tuple[int, int], Path], dict[tuple[int, int], str]]:
        """The task index and, per task read from two different files, the error naming both."""
        index: dict[tuple[int, int], Path] = {}
        ambiguous: dict[tuple[int, int], str] = {}
        for path in sorted(self._task_paths, key=lambda p: natural_key(p.name)):
            try:
                if self.ema is not None:
                    subj, (task, rep) = None, self.ema.task_key(path.name)
                else:
                    subj, task, rep = parse_task_name(path.name)
            except CassiInputError as err:
                self.warnings.append(f"{path}: {err.reason}; ignored")
                continue
            if subj is not None and subj != self.name.upper():
                self.warnings.append(f"{path}: names subject {subj} but is in {self.name}; "
                                     f"read as {self.name}")
            try:
                ensure_inside(self.corpus.root, path)
            except CassiInputError as err:
                self.problems.append(str(err))
                continue
            if (task, rep) in index:
                first = index[(task, rep)]
                if _same_bytes(first, path):
                    self.warnings.append(f"{path}: task {task} repetition {rep} already read "
                                         f"from {first.name} (the same bytes); ignored")
                else:
                    error = CassiInputError(
                        f"task {task} repetition {rep} is also {first}, and the two differ: "
                        f"remove the one that is not the recording", path=path)
                    ambiguous[(task, rep)] = "\n".join(filter(None, [ambiguous.get((task, rep)),
                                                                     str(error)]))
                continue
            index[(task, rep)] = path
        return dict(sorted(index.items())), ambiguous

    def task_files(self) -> dict[tuple[int, int], Path]:
        """``{(task, rep): path}`` for every task file, sorted by task then repetition."""
        return dict(self._task_index)

    def tasks(self) -> list[tuple[int, int]]:
        return list(self._task_index)

    def task_path(self, task: int, rep: int = 1) -> Path:
        try:
            return self._task_index[(task, rep)]
        except KeyError:
            raise CassiInputError(f"subject {self.name} has no task {task}"
                                  + (f" repetition {rep}" if rep != 1 else ""),
                                  path=self.directory) from None

    def _stem(self, task: int, rep: int) -> str:
        """The name its side files share: ``tpNNN[_R]``, an EMA recording's own stem."""
        if self.ema is not None:
            return self.task_path(task, rep).stem
        return task_stem(task, rep)

    def alignment_path(self, task: int, rep: int = 1) -> Path | None:
        """The file of the task's labels beside it (``tpNNN.TextGrid``, ``.lab``, ``.rec`` or a
        master label file naming it: :func:`~cassi.data.corpus.beside.alignment_path_for_stem`)
        or None."""
        path = alignment_path_for_stem(self.directory, self._stem(task, rep), files=self._files)
        return None if path is None else self._checked(path)

    def audio_path(self, task: int, rep: int = 1) -> Path | None:
        """The task's audio recording (``tpNNN.wav`` as XRMB distributes it, any case, any
        sample rate) or None."""
        path = audio_for_stem(self.directory, self._stem(task, rep), files=self._files)
        return None if path is None else self._checked(path)

    def alignment(self, task: int, rep: int = 1) -> Alignment | None:
        """The task's phone/word labels if the subject directory has them (a TextGrid, an
        xwaves/ESPS or HTK label file: :func:`~cassi.data.xrmb.labels.read_labels`)."""
        path = self.alignment_path(task, rep)
        return None if path is None else read_labels(path, stem=self._stem(task, rep))

    # ------------------------------------------------------------------ subject files
    @cached_property
    def palate_mm(self) -> np.ndarray:
        """float64 (P, 2) mm: PAL.DAT, front to back (EMA: the palate the coil map names first)."""
        named = None if self.ema is None else self.ema.palate_mm()
        if named is not None:
            return named
        if self.ema is not None and self._file(SUBJECT_FILES["pal"], required=False) is None:
            raise CassiInputError(f"no palate: the coil map {self.ema.map_file} names none "
                                  f"('palate: ...') and there is no PAL.DAT", path=self.directory)
        return read_pal(self._file(SUBJECT_FILES["pal"]))

    @cached_property
    def pharynx_mm(self) -> np.ndarray:
        """float64 (P, 2) mm: PHA.DAT (EMA speakers: None without one)."""
        if self.ema is not None and self._file(SUBJECT_FILES["pha"], required=False) is None:
            return None
        return read_pha(self._file(SUBJECT_FILES["pha"]))

    @cached_property
    def mistracking(self) -> list[MistrackEntry]:
        """Entries of Mis.dat (an error if the file is missing: usability needs it; EMA speakers
        have none: their missing samples are NaN in the files)."""
        if self.ema is not None and self._file(SUBJECT_FILES["mis"], required=False) is None:
            return []
        return read_mis(self._file(SUBJECT_FILES["mis"]))

    @cached_property
    def mistracked_tasks(self) -> frozenset[int]:
        return frozenset(e.task for e in self.mistracking)

    @cached_property
    def head_measures(self) -> HeadMeasures | None:
        """Gonion and gnathion from the subject's or the corpus's head-measures file, or None."""
        own = self._file(HEAD_MEASURES_FILE, required=False)
        if own is not None:
            table = read_head_measures(own)
            if self.name.upper() in table:
                return table[self.name.upper()]
            if len(table) == 1:
                self.warnings.append(f"{own}: names subject {next(iter(table))}, used for "
                                     f"{self.name}")
                return next(iter(table.values()))
            raise CassiInputError(f"does not list subject {self.name}", path=own)
        return self.corpus.head_measures_table.get(self.name.upper())

    def subject_files(self) -> list[Path]:
        """The subject-level files that exist (PAL.DAT, PHA.DAT, Mis.dat, and the head-measures
        file that applies: the subject's own, else the corpus's)."""
        files = [self._file(name, required=False) for name in SUBJECT_FILES.values()]
        own = self._file(HEAD_MEASURES_FILE, required=False)
        files.append(own if own is not None else self.corpus.head_measures_path())
        if self.ema is not None:
            files.extend(self.ema.files())
        return [f for f in files if f is not None]

    # ------------------------------------------------------------------ tasks
    def load(self, task: int, rep: int = 1, *, require_valid: bool = True) -> TaskRecording:
        """Read one task file (see :func:`cassi.data.xrmb.files.read_txy`)."""
        return self.read_task(self.task_path(task, rep), task=task, rep=rep,
                              require_valid=require_valid)

    def read_task(self, path: Path, *, data: bytes | None = None, task: int | None = None,
                  rep: int | None = None, require_valid: bool = True) -> TaskRecording:
        """One of this subject's task files (``data``: its bytes as already read, XRMB files
        only; an EMA recording is read through its coil map, from ``path``)."""
        if self.ema is not None:
            if task is None:
                task, rep = self.ema.task_key(path.name)
            return self.ema.read(path, subject=self.name, task=task, rep=rep or 1,
                                 require_valid=require_valid)
        if data is not None:
            return parse_txy(data, path=path, subject=self.name, task=task, rep=rep,
                             require_valid=require_valid)
        return read_txy(path, subject=self.name, task=task, rep=rep, require_valid=require_valid)

    def usability(self, task: int, rep: int = 1, *,
                  recording: TaskRecording | None = None) -> Usability:
        """Usable / error-free per thesis 3.2.5 and 4.2.1, with the reasons."""
        reasons: list[str] = []
        if recording is None:
            try:
                recording = self.load(task, rep, require_valid=False)
            except CassiInputError as err:
                return Usability(False, False, (str(err),))
        usable = recording.first_valid_index is not None
        if not usable:
            reasons.append("no row with all eight pellets valid")
        if task in self.mistracked_tasks:
            codes = sorted({e.pellet for e in self.mistracking if e.task == task})
            reasons.append(f"listed in Mis.dat ({', '.join(codes)})")
        if usable:
            first = recording.first_valid_index
            missing = [PELLETS[p] for p in range(len(PELLETS))
                       if not recording.valid[first:, p].all()]
            if missing:
                reasons.append(f"pellet(s) missing after the first valid row: {', '.join(missing)}")
        return Usability(usable, usable and not reasons, tuple(reasons))

    def error_free_tasks(self) -> list[tuple[int, int]]:
        """``(task, rep)`` of every error-free task file, in task order."""
        return [key for key in self._task_index if self.usability(*key).error_free]


class Corpus:
    """A directory of subject directories.

    Parameters
    ----------
    root : path-like
        The corpus directory. A directory that itself holds task files is read as a one-subject
        corpus named after the directory.
    """

    def __init__(self, root: str | os.PathLike):
        root = Path(root)
        if not root.exists():
            raise CassiInputError("corpus directory not found", path=root)
        if not root.is_dir():
            raise CassiInputError("not a directory", path=root)
        self.root = root
        self.warnings: list[str] = []
        self.problems: list[str] = []
        self._subjects: dict[str, Path] = self._discover()
        self._cache: dict[str, SubjectData] = {}

    def __repr__(self) -> str:
        return f"Corpus({str(self.root)!r}, subjects={len(self._subjects)})"

    def _discover(self) -> dict[str, Path]:
        found: dict[str, Path] = {}
        try:
            entries = list(os.scandir(self.root))
        except OSError as err:
            raise CassiInputError(f"cannot list corpus directory: {err.strerror or err}",
                                  path=self.root) from None
        if any(e.name.lower().endswith(".txy") for e in entries) or self._ema_subject(self.root):
            # A single subject directory given directly.
            return {self.root.resolve().name: self.root}
        for e in sorted(entries, key=lambda e: natural_key(e.name)):
            if e.name.startswith("."):
                continue
            path = self.root / e.name
            try:
                if not e.is_dir():
                    continue
            except OSError as err:  # a symbolic link loop: not a subject directory either
                self.warnings.append(f"{path}: cannot tell what it is ({err.strerror or err}); "
                                     f"skipped")
                continue
            try:
                ensure_inside(self.root, path)
            except CassiInputError as err:
                self.problems.append(str(err))
                continue
            if not SUBJECT_NAME_RE.fullmatch(e.name):
                self.warnings.append(f"{path}: not a subject name; skipped")
                continue
            try:
                has_task = any(n.lower().endswith(".txy") for n in os.listdir(path)) or \
                    self._ema_subject(path)
            except OSError as err:
                self.problems.append(str(CassiInputError(
                    f"cannot list subject directory: {err.strerror or err}", path=path)))
                continue
            if not has_task:
                self.warnings.append(f"{path}: no task files; not a subject directory")
                continue
            if e.name.upper() in {k.upper() for k in found}:
                self.problems.append(f"{path}: subject name differs from another only in case")
                continue
            found[e.name] = path
        return found

    def _ema_subject(self, directory: Path) -> bool:
        """Whether ``directory`` holds EMA recordings under a coil map (the map is read)."""
        found = map_path(self.root, directory)
        if found is None:
            return False
        try:
            ema = EmaSubject(found, directory)
        except CassiInputError as err:
            self.problems.append(str(err))
            return False
        return any(ema.is_recording(n) for n in os.listdir(directory))

    @cached_property
    def metadata(self) -> dict:
        """Contents of ``corpus.json`` ({} when absent)."""
        path = self.root / METADATA_FILE
        if not path.exists():
            return {}
        ensure_inside(self.root, path)
        raw = read_bytes(path)
        try:
            meta = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError:
            raise CassiInputError("not UTF-8 text", path=path) from None
        except json.JSONDecodeError as err:
            raise CassiInputError(f"invalid JSON: {err.msg}", path=path, line=err.lineno) from None
        if not isinstance(meta, dict):
            raise CassiInputError("must hold a JSON object", path=path, line=1)
        return meta

    @property
    def is_synthetic(self) -> bool:
        """True when ``corpus.json`` says ``"synthetic": true`` (generated corpora do)."""
        return self.metadata.get("synthetic") is True

    @cached_property
    def head_measures_table(self) -> dict[str, HeadMeasures]:
        """The corpus-level head-measures file ({} when absent)."""
        path = self.head_measures_path()
        return {} if path is None else read_head_measures(path)

    def head_measures_path(self) -> Path | None:
        """The corpus-level head-measures file, if there is one."""
        for e in os.scandir(self.root):
            if e.name.lower() == HEAD_MEASURES_FILE.lower():
                path = self.root / e.name
                ensure_inside(self.root, path)
                return path
        return None

    @property
    def subjects(self) -> list[str]:
        """Subject names in natural order (JW11, JW12, ..., JW502)."""
        return list(self._subjects)

    def subject(self, name: str) -> SubjectData:
        """The subject named ``name`` (case-insensitive)."""
        if not isinstance(name, str) or not SUBJECT_NAME_RE.fullmatch(name):
            raise CassiInputError(f"bad subject name {str(name)[:40]!r}")
        match = next((k for k in self._subjects if k.upper() == name.upper()), None)
        if match is None:
            raise CassiInputError(f"no subject {name} in the corpus (subjects: "
                                  f"{', '.join(self._subjects) or 'none'})", path=self.root)
        if match not in self._cache:
            self._cache[match] = SubjectData(self, match, self._subjects[match])
        return self._cache[match]

    def __iter__(self):
        return (self.subject(s) for s in self._subjects)

    def load(self, subject: str, task: int, rep: int = 1) -> TaskRecording:
        return self.subject(subject).load(task, rep)

    def array(self, subject: str, task: int, rep: int = 1) -> np.ndarray:
        """Fast array view: float64 (F, 8, 2) mm, NaN where invalid (pellets in PELLETS order)."""
        return self.load(subject, task, rep).xy_mm

    def tidy(self, subject: str, task: int, rep: int = 1) -> pd.DataFrame:
        """Long table of one task: one row per frame and pellet.

        Columns: ``subject, task, rep, frame, time_us, pellet, x, y, valid`` (x, y in mm, NaN
        where invalid; pellet a categorical in PELLETS order).
        """
        return tidy_recording(self.load(subject, task, rep))


def tidy_recording(rec: TaskRecording) -> pd.DataFrame:
    """The long (tidy) table of a :class:`TaskRecording` (see :meth:`Corpus.tidy`)."""
    n, p = rec.n_frames, len(PELLETS)
    return pd.DataFrame({
        "subject": pd.Categorical([rec.subject] * (n * p)),
        "task": np.full(n * p, rec.task, dtype=np.int64),
        "rep": np.full(n * p, rec.rep, dtype=np.int64),
        "frame": np.repeat(np.arange(n, dtype=np.int64), p),
        "time_us": np.repeat(rec.time_us, p),
        "pellet": pd.Categorical.from_codes(np.tile(np.arange(p), n), categories=list(PELLETS)),
        "x": rec.xy_mm[:, :, 0].reshape(-1),
        "y": rec.xy_mm[:, :, 1].reshape(-1),
        "valid": rec.valid.reshape(-1),
    })


@dataclass
class FileReport:
    """One row of ``cassi corpus check``."""

    path: str
    subject: str | None
    task: int | None
    rep: int | None
    frames: int | None = None
    first_valid_us: int | None = None
    usable: bool = False
    error_free: bool = False
    problems: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    error: bool = False  # a malformed file (check exits 2), not merely unusable

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def check_task_file(path: Path, *, subject: SubjectData | None = None) -> FileReport:
    """Read one task file and report frames, first valid row, usability and problems."""
    try:
        subj, task, rep = parse_task_name(path.name)
    except CassiInputError:
        subj, task, rep = None, None, None
    name = subject.name if subject is not None else subj
    rep_obj = FileReport(path=str(path), subject=name, task=task, rep=rep)
    try:
        rec = subject.read_task(path, require_valid=False) if subject is not None else \
            read_txy(path, subject=name, require_valid=False)
    except CassiInputError as err:
        rep_obj.problems.append(str(err))
        rep_obj.error = True
        return rep_obj
    rep_obj.subject, rep_obj.task, rep_obj.rep = rec.subject, rec.task, rec.rep
    rep_obj.frames = rec.n_frames
    rep_obj.first_valid_us = rec.first_valid_time_us
    rep_obj.warnings.extend(rec.warnings)
    if rec.first_valid_index is None:
        # Well-formed but unusable (a pellet removed, as for the thesis's JW29 and JW32): reported
        # with its reason; read_txy raises on it, so nothing downstream can animate it.
        why = [w for w in rec.warnings if "no row has all eight pellets valid" in w]
        rep_obj.problems.extend(why or [str(CassiInputError(
            "no row has all eight pellets valid", path=path))])
        rep_obj.warnings = [w for w in rep_obj.warnings if w not in why]
        return rep_obj
    if subject is not None:
        try:
            use = subject.usability(rec.task, rec.rep, recording=rec)
        except CassiInputError as err:  # Mis.dat missing or malformed
            rep_obj.problems.append(str(err))
            rep_obj.error = True
            rep_obj.usable = True
            return rep_obj
        rep_obj.usable, rep_obj.error_free = use.usable, use.error_free
        rep_obj.problems.extend(use.reasons)
    else:
        first = rec.first_valid_index
        missing = [PELLETS[p] for p in range(len(PELLETS)) if not rec.valid[first:, p].all()]
        rep_obj.usable = True
        rep_obj.error_free = not missing
        if missing:
            rep_obj.problems.append(
                f"pellet(s) missing after the first valid row: {', '.join(missing)}")
    return rep_obj


def check_corpus(corpus: Corpus) -> tuple[list[FileReport], list[str]]:
    """Check every subject file and task file of a corpus.

    Returns ``(reports, errors)``: one report per task file, and the corpus-level errors
    (malformed or missing subject files, paths escaping the corpus, bad metadata) as
    ``file:line: reason`` strings.
    """
    errors: list[str] = list(corpus.problems)
    if not corpus.subjects:
        errors.append(str(CassiInputError("no subject directories (directories holding task "
                                          "files) found", path=corpus.root)))
    try:
        corpus.metadata
        corpus.head_measures_table
    except CassiInputError as err:
        errors.append(str(err))
    reports: list[FileReport] = []
    for name in corpus.subjects:
        subj = corpus.subject(name)
        for attr in ("palate_mm", "pharynx_mm", "mistracking", "head_measures"):
            try:
                getattr(subj, attr)
            except CassiInputError as err:
                errors.append(str(err))
        index, ambiguous = subj._task_scan  # the ambiguous tasks are errors, the rest checked
        errors.extend(ambiguous.values())
        for key, path in index.items():
            if key not in ambiguous:
                reports.append(check_task_file(path, subject=subj))
        errors.extend(subj.problems)
    return reports, errors
