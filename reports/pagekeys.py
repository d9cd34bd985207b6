"""What each reusable part of a report is made of: the documents :class:`~.memo.Memo` keys
them by. One place for it: a page that reads something not named here must add it here.

Every aggregation of the rubric is per subject (rule 1 counts over a subject's files, Table
C's rule compares a subject's versions; :mod:`cassi.harness.rubric.tables`), and a task
file's events are its own rows', so a subject page is keyed by its subject's rows and a viewer
page by its task file's; the thesis tables, counted over every subject, by all rows.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from cassi.reports.memo import RowDigests, by_content, content_ids, frame_digest
from cassi.reports.runio import Run
from cassi.reports.sensitivity import section_digest

_FILE = ["subject", "task", "rep"]


class PageKeys:
    """Key documents of one run's pages; ``audio_for(subject, task, rep)``: the task's WAV or
    None, ``labels_for(subject, task, rep)``: the file of its phone and word labels or None
    (both as the viewer pages find them; the labels are read from that file alone);
    ``renders_note``: the sentence a large run's viewer pages carry, or None."""

    def __init__(self, run: Run, *, audio_for=None, labels_for=None, renders_note=None):
        self.run = run
        self._audio_for, self._labels_for = audio_for, labels_for
        #: what a large run's viewer pages say their renders leave out (it reads the run's
        #: count of task files, which a page's own rows do not say)
        self._renders_note = renders_note
        res = RowDigests(run.results)
        rend = RowDigests(by_content(run.renders))
        self._results = res.whole()
        self._results_of = {"subject": res.groups(["subject"]), "file": res.groups(_FILE)}
        self._renders_of = {"subject": rend.groups(["subject"]), "file": rend.groups(_FILE)}
        self._attachments_of = {"file": RowDigests(by_content(run.attachments)).groups(_FILE)}

    def _common(self, subject: str) -> dict:
        return {"synthetic": self.run.synthetic, "derived": self.run.derived.get(str(subject), [])}

    def viewer(self, subject: str, task: int, rep: int) -> dict | None:
        """A task file's viewer page (its data, sound, renders and mask overlays); None (made
        anew) when the file has no result row."""
        file = (subject, int(task), int(rep))
        results = self._results_of["file"].get(file)
        if results is None:
            return None
        doc = {"file": list(file), **self._common(subject), "results": results,
               "renders": self._renders_of["file"].get(file, ""),
               "attachments": self._attachments_of["file"].get(file, ""),
               "audio": self._file(self._audio_for, file),
               "labels": self._file(self._labels_for, file)}
        return doc if self._renders_note is None else {**doc, "renders_note": self._renders_note}

    @staticmethod
    def _file(find, file: tuple):
        """A corpus file found by ``find(*file)``: its path and content, or None."""
        path = find(*file) if find else None
        if path is None or not Path(path).is_file():
            return None
        return [str(path), content_ids([path])[0]]

    def subject(self, subject: str, viewers) -> dict | None:
        """A subject's page; ``viewers``: the (subject, task, rep) with a viewer page. None
        (made anew) for a name no result row has (a missing subject reads as "")."""
        results = self._results_of["subject"].get((subject,))
        if results is None:
            return None
        return {"subject": subject, **self._common(subject), "results": results,
                "renders": self._renders_of["subject"].get((subject,), ""),
                "viewers": sorted([int(t), int(r)] for s, t, r in viewers if s == subject)}

    def tables(self, viewers) -> dict:
        """The thesis tables, their plots and files, the paired comparisons, the criterion,
        the judges' findings and the sensitivity section (all rows of the run; the viewers
        the tables' faults open)."""
        return {"results": self._results, "synthetic": self.run.synthetic,
                "viewers": sorted([s, int(t), int(r)] for s, t, r in viewers),
                "sensitivity": section_digest(self.run.root)}

    @staticmethod
    def trend(history: pd.DataFrame, synthetic: bool) -> dict:
        """The nightly history's plot."""
        return {"history": frame_digest(history), "synthetic": synthetic}
