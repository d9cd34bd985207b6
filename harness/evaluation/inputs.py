"""Check every corpus file a run reads before any job starts, and digest them.

A malformed file (a task file, PAL.DAT, PHA.DAT, Mis.dat, a head-measures file, corpus.json)
stops the run with ``file:line: reason`` (exit 2), exactly as ``cassi corpus check`` reports
it; a well-formed file that cannot be animated (no row with all eight pellets valid) stays a
skipped job with its reason. Each usable task file gets the digest of everything its jobs
read (:func:`cassi.harness.evaluation.provenance.task_inputs_digest`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from cassi.data.corpus.disk import check_task_file
from cassi.common.errors import CassiInputError

from cassi.harness.farm.plan import TaskSpec
from cassi.harness.evaluation.provenance import task_inputs_digest

#: Subject attributes that read (and parse) the subject's own files.
_SUBJECT_READS = ("palate_mm", "pharynx_mm", "mistracking", "head_measures")


@dataclass
class CheckedInputs:
    """The run's task files with their input digests, the warnings the files raised, and each
    file's number of rows (``(subject, task, rep) -> rows``)."""

    tasks: list[TaskSpec]
    warnings: list[str] = field(default_factory=list)
    rows: dict[tuple[str, int, int], int] = field(default_factory=dict)


def check_inputs(corpus, tasks: list[TaskSpec], *, get_profile) -> CheckedInputs:
    """Validate the files behind ``tasks`` and fill in each spec's ``inputs`` digest.

    Parameters
    ----------
    corpus : cassi.data.corpus.disk.Corpus
    tasks : list of TaskSpec
        The run's task files (unusable ones included; they stay as they are).
    get_profile : callable (corpus, subject) -> SubjectProfile
        The harness's cached profile (thesis 4.2), so that workers in this process reuse it.

    Raises
    ------
    CassiInputError
        Listing every malformed file, one ``file:line: reason`` per line.
    """
    errors: list[str] = list(corpus.problems)
    warnings: list[str] = list(corpus.warnings)
    try:
        corpus.metadata
        corpus.head_measures_table
    except CassiInputError as err:
        errors.append(str(err))
    subjects = {}
    for spec in tasks:
        if spec.subject not in subjects:
            subj = subjects[spec.subject] = corpus.subject(spec.subject)
            for attr in _SUBJECT_READS:
                try:
                    getattr(subj, attr)
                except CassiInputError as err:
                    errors.append(str(err))
            errors.extend(subj.problems)
    paths, rows = {}, {}
    for spec in tasks:
        subj = subjects[spec.subject]
        if (spec.task, spec.rep) not in subj.task_files():
            continue  # no file: a skipped job that says so
        path = paths[spec] = subj.task_path(spec.task, spec.rep)
        report = check_task_file(path, subject=subj)
        rows[(spec.subject, spec.task, spec.rep)] = report.frames or 0
        if report.error:
            errors.extend(report.problems)
        warnings.extend(report.warnings)
    if errors:
        raise CassiInputError("\n".join(dict.fromkeys(errors)))
    profiles, unprofiled = {}, {}
    for name in subjects:
        try:
            profiles[name] = get_profile(corpus, name)
        except CassiInputError as err:
            unprofiled[name] = f"subject cannot be preprocessed: {err}"
    checked = []
    for spec in tasks:
        if spec.usable and spec.subject in unprofiled:
            spec = dataclasses.replace(spec, usable=False, reason=unprofiled[spec.subject])
        if spec.usable and spec in paths:
            spec = dataclasses.replace(spec, inputs=task_inputs_digest(
                task_file=paths[spec], subject_files=subjects[spec.subject].subject_files(),
                profile=profiles[spec.subject]))
        checked.append(spec)
    return CheckedInputs(checked, list(dict.fromkeys(warnings)), rows)
