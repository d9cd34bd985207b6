"""The files beside a recording: its labels and its sound, found by the recording's stem.

An XRMB task ``tp013.txy`` has ``tp013.TextGrid`` (or ``.lab``, ``.rec``) and ``tp013.wav``
beside it; an EMA utterance ``fsew0_001.ema`` has ``fsew0_001.lab`` and ``fsew0_001.wav``. Names
match in any case; a master label file (``*.mlf``) in the directory is read for a stem that has
no label file of its own. :class:`cassi.data.corpus.disk.SubjectData` finds a task's files so,
and so can any reader with its own stems (the EMA corpus adapter)::

    alignment_for_stem(Path("mocha/fsew0"), "fsew0_001")   # Alignment or None
    audio_for_stem(Path("mocha/fsew0"), "fsew0_001")       # Path or None

Label times and the sound's time 0 are the recording's clock: the times of its samples.
"""
from __future__ import annotations

from pathlib import Path

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.alignment import Alignment
from cassi.data.xrmb.labels import LABEL_SUFFIXES, parse_mlf, read_labels
from cassi.data.xrmb.textlines import read_bytes

__all__ = ["file_for_stem", "alignment_path_for_stem", "alignment_for_stem", "audio_for_stem"]


def _listing(directory: Path) -> dict[str, Path]:
    """The directory's files by lower-case name (none when it cannot be listed)."""
    try:
        return {p.name.lower(): p for p in sorted(Path(directory).iterdir())}
    except OSError:
        return {}


def file_for_stem(directory: str | Path, stem: str, suffixes, *,
                  files: dict[str, Path] | None = None) -> Path | None:
    """The first of ``stem`` + each of ``suffixes`` in ``directory``, names in any case
    (``files``: the directory's files by lower-case name, when the caller has listed it)."""
    files = _listing(Path(directory)) if files is None else files
    for suffix in suffixes:
        path = files.get((stem + suffix).lower())
        if path is not None:
            return path
    return None


def _mlf_with(directory: Path, stem: str, files: dict[str, Path] | None) -> Path | None:
    """The master label file in ``directory`` that labels ``stem``, if one does."""
    for name, path in (_listing(directory) if files is None else files).items():
        if name.endswith(".mlf") and stem in parse_mlf(read_bytes(path), path=path):
            return path
    return None


def alignment_path_for_stem(directory: str | Path, stem: str, *,
                            files: dict[str, Path] | None = None) -> Path | None:
    """The file that holds ``stem``'s labels: ``stem.TextGrid``, ``stem.lab``, ``stem.rec``
    (:data:`~cassi.data.xrmb.labels.LABEL_SUFFIXES`, in that order), else a master label file
    of the directory that names it; None when there is none (``files``: as
    :func:`file_for_stem`)."""
    return (file_for_stem(directory, stem, LABEL_SUFFIXES, files=files)
            or _mlf_with(Path(directory), stem, files))


def alignment_for_stem(directory: str | Path, stem: str) -> Alignment | None:
    """``stem``'s labels as an :class:`Alignment` (phone and word tiers; a ``.lab``'s one tier
    is the phones), or None when the directory has none for it."""
    path = alignment_path_for_stem(directory, stem)
    return None if path is None else read_labels(path, stem=stem)


def audio_for_stem(directory: str | Path, stem: str, *,
                   files: dict[str, Path] | None = None) -> Path | None:
    """``stem.wav`` (any case, any sample rate) in ``directory``, or None (``files``: as
    :func:`file_for_stem`)."""
    path = file_for_stem(directory, stem, (".wav",), files=files)
    if path is not None and not path.is_file():
        raise CassiInputError("is not a regular file", path=path)
    return path
