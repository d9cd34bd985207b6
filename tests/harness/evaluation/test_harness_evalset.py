"""The default evaluation set (thesis Table 5.1 + tasks 106 and 118) on generated corpora, and
unusable task files turning into skipped jobs with their reason."""
from __future__ import annotations

import shutil

import pytest

from cassi.data.corpus.disk import Corpus
from cassi.data.synth.corpus import make_corpus
from cassi.harness.evaluation.evalset import (EXTRA_TASKS, TABLE_5_1, default_tasks, explicit_tasks,
                                             full_tasks, task_catalog)


@pytest.fixture(scope="module")
def small_corpus(tmp_path_factory):
    root = make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW12"], seed=0)
    # JW12's Table 5.1 task 2 becomes unreadable, task 5 disappears; a subject outside the table
    # (a copy of JW12 named XY01) gets the first two error-free tasks instead.
    (root / "JW12" / "tp002.txy").write_text("this is not a task file\n")
    (root / "JW12" / "tp005.txy").unlink()
    shutil.copytree(root / "JW12", root / "XY01")
    return Corpus(root)


def test_table_tasks_missing_or_unusable_are_kept_with_reasons(small_corpus):
    specs = {(s.subject, s.task): s for s in default_tasks(small_corpus, ["JW12"])}
    assert not specs[("JW12", 2)].usable and specs[("JW12", 2)].reason
    assert not specs[("JW12", 5)].usable and specs[("JW12", 5)].reason == "no file for task 5"
    for task in EXTRA_TASKS:  # added only where usable
        if ("JW12", task) in specs:
            assert specs[("JW12", task)].usable
    assert [t for s, t in specs if s == "JW12"][:2] == [2, 5]


def test_subject_outside_table_gets_two_error_free_tasks(small_corpus):
    specs = default_tasks(small_corpus, ["XY01"])
    main = [s for s in specs if s.task not in EXTRA_TASKS]
    assert len(main) == 2 and all(s.usable and not s.reason for s in main)
    subject = small_corpus.subject("XY01")
    assert all(subject.usability(s.task).error_free for s in main)
    assert main[0].task < main[1].task and 2 not in {s.task for s in main}


def test_explicit_tasks_skip_what_is_not_there(small_corpus):
    specs = explicit_tasks(small_corpus, ["JW12"], [2, 5, 19])
    by_task = {s.task: s for s in specs}
    assert not by_task[2].usable and not by_task[5].usable
    assert by_task[19].usable
    assert 19 in task_catalog(small_corpus)["JW12"] and 5 not in task_catalog(small_corpus)["JW12"]


def test_default_corpus_follows_table_5_1():
    from cassi.data.synth.corpus import default_corpus

    corpus = Corpus(default_corpus())
    specs = default_tasks(corpus)
    for subject in corpus.subjects:
        mine = [s.task for s in specs if s.subject == subject]
        if subject in TABLE_5_1:
            assert mine[:2] == list(TABLE_5_1[subject])
        assert set(mine[2:]) <= set(EXTRA_TASKS)
        for s in specs:
            if s.subject == subject and s.task in EXTRA_TASKS:
                assert corpus.subject(subject).usability(s.task).usable


def test_the_full_set_is_every_task_file_of_every_subject(small_corpus):
    specs = full_tasks(small_corpus)
    files = {(s.subject, s.task, s.rep) for s in specs}
    on_disk = {(name, t, r) for name in small_corpus.subjects
               for (t, r) in small_corpus.subject(name).task_files()}
    assert files == on_disk and len(specs) == len(files)
    bad = {(s.subject, s.task): s for s in specs}[("JW12", 2)]   # kept, with its reason
    assert not bad.usable and bad.reason
    assert len(specs) > len(default_tasks(small_corpus))
