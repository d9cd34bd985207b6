"""The default evaluation set: thesis Table 5.1 plus tasks 106 and 118.

The thesis evaluated every version on two error-free task files per subject (Table 5.1, chapter
5.1: "arbitrarily selected so that each of the 15 sample subjects had two error-free files
corresponding to two different tasks"), and, in section 5.3, task 118 (maximum lip protrusion)
and task 106 (jaw wagging) for the subjects with a usable file of them.

On a corpus whose subjects are not in Table 5.1, the first two error-free tasks of each subject
(other than 106 and 118) stand in for the table's.
"""
from __future__ import annotations

from typing import Iterable

from cassi.data.xrmb.files import ORAL_MOTOR_TASKS
from cassi.harness.farm.runner import TaskSpec

#: Thesis Table 5.1: subject -> the two tasks used for evaluation (task descriptions in comments).
TABLE_5_1: dict[str, tuple[int, int]] = {
    "JW11": (19, 21),    # sentences; citation words
    "JW12": (2, 5),      # citation words; citation words
    "JW15": (9, 10),     # citation words; sentences
    "JW16": (3, 6),      # number sequences; citation words
    "JW18": (4, 14),     # citation words; citation vowels
    "JW19": (1, 23),     # citation words; citation words
    "JW21": (7, 12),     # sentences; paragraph
    "JW24": (17, 18),    # sentences; citation words
    "JW25": (15, 16),    # vowel sequences; citation VCV
    "JW27": (20, 22),    # sentences; citation words
    "JW32": (13, 15),    # citation sVd's; vowel sequences
    "JW40": (5, 8),      # citation words; citation words
    "JW41": (1, 11),     # citation words; paragraph
    "JW45": (3, 13),     # number sequences; citation sVd's
    "JW502": (21, 22),   # citation words; citation words
}

#: Section 5.3: jaw wagging and maximum lip protrusion, where a usable file exists.
EXTRA_TASKS = ORAL_MOTOR_TASKS


def _task_numbers(subject_data) -> list[tuple[int, int]]:
    """(task, rep) pairs of a subject's task files, whatever shape ``task_files()`` returns."""
    files = subject_data.task_files()
    pairs = []
    items = files.items() if isinstance(files, dict) else files
    for item in items:
        if isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], tuple):
            task, rep = item[0]                     # {(task, rep): path}
        elif isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], int):
            task, rep = item[0], 1                  # {task: path}
        elif isinstance(item, tuple) and len(item) >= 2 and isinstance(item[1], int):
            task, rep = item[0], item[1]            # [(task, rep, path)]
        else:
            task = getattr(item, "task", None)      # [TaskFile(task, rep, path)]
            rep = getattr(item, "rep", 1)
            if task is None:
                continue
        pairs.append((int(task), int(rep)))
    return sorted(set(pairs))


def _usable(subject_data, task: int, rep: int = 1) -> tuple[bool, bool, str]:
    """(usable, error_free, reason) from the corpus, never raising for one bad file."""
    try:
        u = subject_data.usability(task, rep)
    except Exception as err:  # noqa: BLE001 - an unreadable file is a skipped job, not a crash
        return False, False, f"{type(err).__name__}: {err}"
    reasons = "; ".join(getattr(u, "reasons", ()) or ())
    return bool(u.usable), bool(getattr(u, "error_free", u.usable)), reasons


def task_catalog(corpus) -> dict[str, tuple[int, ...]]:
    """subject -> task numbers that have a file in ``corpus``."""
    return {s: tuple(sorted({t for t, _ in _task_numbers(corpus.subject(s))}))
            for s in corpus.subjects}


def default_tasks(corpus, subjects: Iterable[str] | None = None) -> list[TaskSpec]:
    """The thesis's evaluation set on ``corpus`` (see the module docstring).

    Table 5.1 files that are missing or unusable stay in the set as unusable
    :class:`TaskSpec` (their jobs are skipped with the reason); tasks 106 and 118 are added
    only where usable, as in the thesis.
    """
    specs: list[TaskSpec] = []
    for subject in (list(subjects) if subjects is not None else corpus.subjects):
        data = corpus.subject(subject)
        present = _task_numbers(data)
        have = {t for t, _ in present}
        if subject in TABLE_5_1:
            chosen = list(TABLE_5_1[subject])
        else:
            chosen = []
            for task, rep in present:
                if task in EXTRA_TASKS or rep != 1 or len(chosen) == 2:
                    continue
                usable, error_free, _ = _usable(data, task, rep)
                if usable and error_free:
                    chosen.append(task)
        for task in chosen:
            if task not in have:
                specs.append(TaskSpec(subject, task, 1, False, f"no file for task {task}"))
                continue
            usable, error_free, why = _usable(data, task, 1)
            if not usable:
                specs.append(TaskSpec(subject, task, 1, False, why or "task file not usable"))
            else:
                specs.append(TaskSpec(subject, task, 1, True,
                                      "" if error_free else f"not error-free: {why}"))
        for task in EXTRA_TASKS:
            if task in have and _usable(data, task, 1)[0]:
                specs.append(TaskSpec(subject, task, 1))
    return specs


def explicit_tasks(corpus, subjects: Iterable[str], tasks: Iterable[int]) -> list[TaskSpec]:
    """Every (subject, task) asked for; files that do not exist or are unusable are skipped
    jobs with the reason (all repetitions of a task are included)."""
    specs = []
    for subject in subjects:
        data = corpus.subject(subject)
        present = _task_numbers(data)
        for task in tasks:
            reps = [r for t, r in present if t == task]
            if not reps:
                specs.append(TaskSpec(subject, task, 1, False, f"no file for task {task}"))
            for rep in reps:
                usable, _, why = _usable(data, task, rep)
                specs.append(TaskSpec(subject, task, rep, usable,
                                      "" if usable else (why or "task file not usable")))
    return specs


def full_tasks(corpus, subjects: Iterable[str] | None = None) -> list[TaskSpec]:
    """Every task file (every repetition) of every subject: the whole corpus; unusable files
    stay in the set as skipped jobs with the reason, as in :func:`explicit_tasks`."""
    subjects = list(subjects) if subjects is not None else corpus.subjects
    specs = []
    for subject in subjects:
        tasks = sorted({t for t, _ in _task_numbers(corpus.subject(subject))})
        specs += explicit_tasks(corpus, [subject], tasks)
    return specs
