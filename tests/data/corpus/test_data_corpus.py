"""Corpus discovery, subject files, usability (thesis 3.2.5), tidy/array views, alignments."""
from __future__ import annotations

import os
import shutil

import numpy as np
import pandas as pd
import pytest
from data_helpers import FIXTURES, recording, write_metadata, write_subject

from cassi.data.corpus.disk import Corpus, check_corpus, natural_key, read_alignment
from cassi.common.errors import CassiInputError
from cassi.harness.cli import main as cli_main
from cassi.data.xrmb.files import PELLETS, write_txy


@pytest.fixture
def corpus_dir(tmp_path):
    root = tmp_path / "corpus"
    write_subject(root, "JW11", {(1, 1): recording(task=1), (2, 1): recording(task=2),
                                 (2, 2): recording(task=2, rep=2),
                                 (3, 1): recording(task=3, lost=("MNM", 20)),
                                 (4, 1): recording(task=4)},
                  mis=[(4, "TB2"), (9, "MAX G")])
    write_subject(root, "JW502", {(1, 1): recording(task=1)})
    write_subject(root, "JW45", {(13, 1): recording(task=13)})
    (root / "notes").mkdir()  # not a subject: no task files
    write_metadata(root, synthetic=True, generator="test")
    return root


def test_discovery_in_natural_order_and_metadata(corpus_dir):
    c = Corpus(corpus_dir)
    assert c.subjects == ["JW11", "JW45", "JW502"]
    assert c.is_synthetic and c.metadata["generator"] == "test"
    assert any("notes" in w for w in c.warnings)
    s = c.subject("jw11")  # case-insensitive
    assert s.name == "JW11"
    assert list(s.task_files()) == [(1, 1), (2, 1), (2, 2), (3, 1), (4, 1)]
    assert s.palate_mm.shape == (4, 2) and s.pharynx_mm.shape == (2, 2)
    assert s.mistracked_tasks == {4, 9}
    assert s.head_measures is None


def test_not_synthetic_without_metadata(tmp_path):
    write_subject(tmp_path, "JW12", {(1, 1): recording()})
    c = Corpus(tmp_path)
    assert c.metadata == {} and not c.is_synthetic


def test_usability_per_thesis(corpus_dir):
    s = Corpus(corpus_dir).subject("JW11")
    u = s.usability(1)
    assert u.usable and u.error_free and u.reasons == ()
    u = s.usability(3)  # MNM lost part-way, not logged (the thesis's JW29/JW32 case)
    assert u.usable and not u.error_free and "MNM" in u.reasons[0]
    u = s.usability(4)
    assert u.usable and not u.error_free and u.reasons == ("listed in Mis.dat (TB2)",)
    assert s.error_free_tasks() == [(1, 1), (2, 1), (2, 2)]


def test_unreadable_file_is_reported_unusable_with_reason(corpus_dir):
    (corpus_dir / "JW11" / "tp005.txy").write_text("0 1 2\n")
    s = Corpus(corpus_dir).subject("JW11")
    u = s.usability(5)
    assert not u.usable and "tp005.txy:1: expected 17 columns" in u.reasons[0]


def test_views_tidy_and_array(corpus_dir):
    c = Corpus(corpus_dir)
    arr = c.array("JW11", 2, rep=2)
    assert arr.shape == (40, 8, 2) and np.isnan(arr[:3]).all()
    df = c.tidy("JW11", 2, rep=2)
    assert list(df.columns) == ["subject", "task", "rep", "frame", "time_us", "pellet", "x", "y",
                                "valid"]
    assert len(df) == 40 * 8
    assert list(df["pellet"].cat.categories) == list(PELLETS)
    assert (df["rep"] == 2).all() and (df["subject"] == "JW11").all()
    row = df[(df.frame == 5) & (df.pellet == "LL")].iloc[0]
    assert row.x == pytest.approx(arr[5, 1, 0]) and row.y == pytest.approx(arr[5, 1, 1])
    assert row.time_us == 5 * 6866 and bool(row.valid)
    assert not df[df.frame < 3]["valid"].any() and df[df.frame < 3]["x"].isna().all()
    back = df.pivot_table(index="frame", columns="pellet", values="x", observed=False,
                          dropna=False).to_numpy()
    np.testing.assert_array_equal(np.nan_to_num(back), np.nan_to_num(arr[:, :, 0]))


def test_missing_subject_files_and_unknown_subject(corpus_dir):
    (corpus_dir / "JW45" / "PAL.DAT").unlink()
    (corpus_dir / "JW45" / "Mis.dat").unlink()
    c = Corpus(corpus_dir)
    with pytest.raises(CassiInputError, match="missing subject file PAL.DAT"):
        c.subject("JW45").palate_mm
    u = None
    with pytest.raises(CassiInputError, match="Mis.dat"):
        u = c.subject("JW45").usability(13)
    assert u is None
    with pytest.raises(CassiInputError, match="no subject JW99"):
        c.subject("JW99")
    for bad in ["..", "../JW11", "JW11/..", "/etc", ""]:
        with pytest.raises(CassiInputError, match="bad subject name"):
            c.subject(bad)
    reports, errors = check_corpus(c)
    assert any("missing subject file PAL.DAT" in e for e in errors)
    assert any("missing subject file Mis.dat" in e for e in errors)


def test_symlinks_that_escape_the_corpus_are_errors(corpus_dir, tmp_path):
    outside = tmp_path / "outside"
    write_subject(tmp_path, "outside", {(1, 1): recording()})
    os.symlink(outside, corpus_dir / "JW99")
    os.symlink(outside / "tp001.txy", corpus_dir / "JW45" / "tp007.txy")
    os.symlink(outside / "PAL.DAT", corpus_dir / "JW502" / "pal.dat.lnk")
    (corpus_dir / "JW502" / "PAL.DAT").unlink()
    os.symlink(outside / "PAL.DAT", corpus_dir / "JW502" / "PAL.DAT")
    c = Corpus(corpus_dir)
    assert "JW99" not in c.subjects
    assert any("leads outside the corpus directory" in p for p in c.problems)
    s = c.subject("JW45")
    assert (7, 1) not in s.task_files()
    assert any("tp007.txy" in p and "outside" in p for p in s.problems)
    with pytest.raises(CassiInputError, match="leads outside"):
        c.subject("JW502").palate_mm
    reports, errors = check_corpus(c)
    assert sum("leads outside" in e for e in errors) >= 3


def test_symlink_inside_the_corpus_is_fine(corpus_dir):
    os.symlink(corpus_dir / "JW11" / "tp001.txy", corpus_dir / "JW45" / "tp001.txy")
    assert (1, 1) in Corpus(corpus_dir).subject("JW45").task_files()


def test_link_loops_and_fifos_are_named_not_followed(corpus_dir):
    """A symbolic link loop (in the root or as a task file) and a FIFO where a file belongs are
    named (exit 2 for the files the corpus needs), never a traceback or a read that blocks."""
    os.symlink("loop", corpus_dir / "loop")                                    # loops on itself
    os.symlink("tp007.txy", corpus_dir / "JW45" / "tp007.txy")
    os.mkfifo(corpus_dir / "JW45" / "tp008.txy")
    (corpus_dir / "corpus.json").unlink(missing_ok=True)
    os.mkfifo(corpus_dir / "corpus.json")
    c = Corpus(corpus_dir)
    assert any("loop" in w and "skipped" in w for w in c.warnings)
    with pytest.raises(CassiInputError, match="is not a regular file") as info:
        c.metadata
    assert info.value.path.endswith("corpus.json")
    reports, errors = check_corpus(Corpus(corpus_dir))
    assert any("tp007.txy" in e and "symbolic link loop" in e for e in errors), errors
    assert "tp008.txy: is not a regular file" in " ".join(errors) + str(reports)


def test_bad_metadata_names_file_and_line(corpus_dir):
    (corpus_dir / "corpus.json").write_text('{\n "synthetic": true,\n}\n')
    with pytest.raises(CassiInputError) as info:
        Corpus(corpus_dir).metadata
    assert info.value.line == 3 and info.value.path.endswith("corpus.json")


def test_duplicate_task_names_and_stray_files_are_warnings(corpus_dir):
    shutil.copy(corpus_dir / "JW45" / "tp013.txy", corpus_dir / "JW45" / "JW45_013.TXY")
    (corpus_dir / "JW45" / "notes.txy").write_text("x")
    (corpus_dir / "JW45" / ".tp014.txy").write_text("x")
    s = Corpus(corpus_dir).subject("JW45")
    s.task_files()
    assert list(s.task_files()) == [(13, 1)]
    joined = "\n".join(s.warnings)
    assert "already read" in joined and "not a task file name" in joined
    assert ".tp014.txy: hidden file ignored" in joined


@pytest.mark.parametrize("twin", ["JW45_013.txy", "TP013.TXY"])
def test_two_different_files_of_one_task_are_refused_naming_both(corpus_dir, twin, capsys):
    """Which of two files is task 13's recording is not for the corpus to guess: every reader
    refuses (``cassi corpus check`` lists the rest)."""
    first, other = corpus_dir / "JW45" / "tp013.txy", corpus_dir / "JW45" / twin
    write_subject(corpus_dir, "JW45", {(14, 1): recording(task=14)})
    write_txy(other, recording(task=13, lead=5))
    paths = sorted([first, other], key=lambda p: (natural_key(p.name), p.name))  # the index's order
    s = Corpus(corpus_dir).subject("JW45")
    for read in (s.task_files, s.tasks, lambda: s.task_path(14), lambda: s.load(13)):
        with pytest.raises(CassiInputError) as info:
            read()
        assert str(info.value) == (f"{paths[1]}: task 13 repetition 1 is also {paths[0]}, and "
                                   f"the two differ: remove the one that is not the recording")
    reports, errors = check_corpus(Corpus(corpus_dir))
    assert str(info.value) in errors
    assert {(r.subject, r.task) for r in reports} >= {("JW45", 14), ("JW11", 1)}
    assert ("JW45", 13) not in {(r.subject, r.task) for r in reports}
    for argv in (["corpus", "check", str(corpus_dir)], ["corpus", "stats", str(corpus_dir)],
                 ["run", "--corpus", str(corpus_dir), "--subjects", "JW45", "--tasks", "14",
                  "--out", str(corpus_dir.parent / "out")]):
        code = cli_main(argv)
        err = capsys.readouterr().err
        assert code == 2 and str(info.value) in err, (argv, err)
    assert not (corpus_dir.parent / "out").exists()


def test_single_subject_directory_is_a_corpus():
    c = Corpus(FIXTURES / "xrmb" / "JW99")
    assert c.subjects == ["JW99"]
    s = c.subject("JW99")
    assert list(s.task_files()) == [(5, 1), (6, 1), (7, 2), (8, 1)]
    assert [s.usability(*k).error_free for k in s.task_files()] == [True, True, False, False]
    np.testing.assert_allclose(s.head_measures.gonion_mm, [-80.5, -51.0])


def test_head_measures_from_corpus_root(corpus_dir):
    (corpus_dir / "Headmeasures.txt").write_text("JW11 -80000 -50000 -5000 -44000\n")
    c = Corpus(corpus_dir)
    np.testing.assert_allclose(c.subject("JW11").head_measures.gnathion_mm, [-5.0, -44.0])
    assert c.subject("JW45").head_measures is None


def test_corpus_root_errors(tmp_path):
    with pytest.raises(CassiInputError, match="not found"):
        Corpus(tmp_path / "nope")
    (tmp_path / "f").write_text("x")
    with pytest.raises(CassiInputError, match="not a directory"):
        Corpus(tmp_path / "f")


def test_read_alignment_fixture_and_corpus_lookup(corpus_dir):
    a = read_alignment(FIXTURES / "textgrid" / "tp001.TextGrid")
    assert list(a.phones["label"]) == ["sp", "S", "AY1", "D", ""]
    assert list(a.words["label"]) == ["sp", "SIDE", ""]
    assert a.phones["start_s"].is_monotonic_increasing and a.xmax_s == 1.5
    shutil.copy(FIXTURES / "textgrid" / "tp001.TextGrid", corpus_dir / "JW11" / "tp001.TextGrid")
    s = Corpus(corpus_dir).subject("JW11")
    assert s.alignment(1).words["label"].tolist() == ["sp", "SIDE", ""]
    assert s.alignment(2) is None


def test_alignment_errors(tmp_path):
    p = tmp_path / "tp001.TextGrid"
    text = (FIXTURES / "textgrid" / "tp001.TextGrid").read_text()
    p.write_text(text.replace('name = "word"', 'name = "syllable"'))
    with pytest.raises(CassiInputError, match="no 'word' tier"):
        read_alignment(p)
    p.write_text("")
    with pytest.raises(CassiInputError, match="empty"):
        read_alignment(p)


def test_real_annotations_read(annotations_dir):
    """The XRMB TextGrids (rsprouse/xray_microbeam_database), read in place."""
    a = read_alignment(annotations_dir / "JW11" / "tp001.TextGrid")
    assert len(a.phones) == 47 and a.phones.iloc[1]["label"] == "P"
    assert (a.words["end_s"] >= a.words["start_s"]).all()
    assert isinstance(a.words, pd.DataFrame)


def test_every_real_alignment_reads_and_tiles(annotations_dir):
    """All of the XRMB forced alignments read (45 of them have bounds rounded ~1e-7 s into the
    interval before, which 1 us of tolerance takes as the same time), and every tier's
    intervals follow one another within the grid's span (~5 s for the 1,700 files)."""
    files = sorted(annotations_dir.glob("*/*.TextGrid"))
    assert len(files) > 1000
    for f in files:
        a = read_alignment(f)
        for tier in (a.phones, a.words):
            assert (tier["start_s"].values[1:] >= tier["end_s"].values[:-1]).all(), f
            assert tier["start_s"].min() >= a.xmin_s - 1e-6 and tier["end_s"].max() <= a.xmax_s + 1e-6, f
