"""A speaker directory of EMA recordings, as :class:`cassi.data.corpus.disk.SubjectData` reads it.

- The coil map is the speaker directory's ``ema.yaml``, else the corpus root's.
- Recordings are the files with the map's suffix (``.ema``, ``.pos``, ``.tsv``, ``.csv``) other
  than the files the map names (bite plane, palate trace).
- Task numbers: ``task_offset`` (default 1000) plus the utterance number, the last run of digits
  in the file's stem: ``fsew0_001.ema`` is task 1001, ``mngu0_s1_0123.ema`` task 1123. The
  offset keeps utterances off XRMB's task numbers, whose 106 and 118 are the oral-motor tasks
  the rubric's Tables D and E judge. Repetition 1.
- The palate (XRMB subjects have PAL.DAT): the file the map names, in PAL.DAT's format, or
  ``{file, coil}``: a palate trace recorded with that coil, in the head frame, front to back,
  the highest point per millimetre of x; else PAL.DAT in the speaker directory; else an error.
"""
from __future__ import annotations

import re
from functools import cached_property
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.ema.coilmap import MAP_FILE, CoilMap, read_coil_map
from cassi.data.ema.derive import describe
from cassi.data.ema.recording import in_head_frame, read_track, to_recording
from cassi.data.ema.track import CoilTrack
from cassi.data.xrmb.files import PELLETS, TaskRecording, check_palate_length, read_pal

_DIGITS = re.compile(r"([0-9]+)(?!.*[0-9])")


def map_path(root: Path, directory: Path) -> Path | None:
    """The coil map that applies to ``directory``: its own ``ema.yaml``, else the root's."""
    for where in (directory, root):
        path = where / MAP_FILE
        if path.is_file():
            return path
    return None


class EmaSubject:
    """The EMA side of one speaker directory (see the module docstring)."""

    def __init__(self, map_file: Path, directory: Path):
        self.map_file = map_file
        self.directory = directory
        self.map: CoilMap = read_coil_map(map_file)

    def is_recording(self, name: str) -> bool:
        return (name.lower().endswith(self.map.suffix) and not name.startswith(".")
                and name not in self.map.extra_files())

    def task_key(self, name: str) -> tuple[int, int]:
        """``(task, 1)`` from a recording's file name (CassiInputError without a number)."""
        m = _DIGITS.search(Path(name).stem)
        if not m:
            raise CassiInputError("no utterance number in the file name", path=name)
        task = self.map.task_offset + int(m.group(1))
        if not 1 <= task <= 9999:
            raise CassiInputError(f"task number {task} (task_offset {self.map.task_offset} + "
                                  f"{int(m.group(1))}) is outside 1-9999", path=name)
        return task, 1

    def _extra(self, name: str) -> Path:
        path = self.directory / name
        if not path.is_file():
            raise self.map.error(f"no file {name} in {self.directory}", "palate") \
                if name not in (self.map.head_frame.get("occlusal") or {}).values() else \
                self.map.error(f"no file {name} in {self.directory}", "head_frame", "occlusal")
        return path

    @cached_property
    def bite(self) -> CoilTrack | None:
        """The bite-plane recording the map names, read once."""
        name = (self.map.head_frame.get("occlusal") or {}).get("file")
        return None if name is None else read_track(self._extra(name), self.map)

    def derived_rules(self) -> list[str]:
        """One line per pellet the map derives (XRMB's pellet order), for the reports."""
        return [describe(p, self.map.derive[p]) for p in sorted(self.map.derive, key=PELLETS.index)]

    def files(self) -> list[Path]:
        """The map and the files it names: what a recording read here depends on."""
        return [self.map_file] + [self._extra(n) for n in self.map.extra_files()]

    def read(self, path: Path, *, subject: str, task: int, rep: int = 1,
             require_valid: bool = True) -> TaskRecording:
        return to_recording(read_track(path, self.map), self.map, subject=subject, task=task,
                            rep=rep, bite=self.bite, require_valid=require_valid)

    def palate_mm(self) -> np.ndarray | None:
        """The palate the map names (mm, front to back), None when it names none."""
        pal = self.map.palate
        if pal is None:
            return None
        if isinstance(pal, str):
            return read_pal(self._extra(pal))
        path = self._extra(pal["file"])
        track = read_track(path, self.map)
        xy = in_head_frame(track, self.map, self.map.coil_names() + [pal["coil"]],
                           bite=self.bite)[pal["coil"]]
        xy = xy[np.isfinite(xy).all(axis=1)]
        if not len(xy):
            raise CassiInputError(f"coil {pal['coil']} is never valid in the palate trace",
                                  path=path)
        bins = np.floor(xy[:, 0]).astype(np.int64)
        top = np.array([xy[bins == b][np.argmax(xy[bins == b, 1])] for b in np.unique(bins)])
        outline = top[::-1]  # front (largest x) to back
        check_palate_length(outline, path=path)
        return outline
