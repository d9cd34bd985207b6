"""Preprocessing (thesis 4.2.1, 4.2.3, Appendix B) and the maxprotru/lipthick tables."""
from __future__ import annotations

import math

import numpy as np
import pytest
from data_helpers import FIXTURES, JW45_EXCERPT, REST, recording, write_subject

from cassi.data.corpus.disk import Corpus
from cassi.common.errors import CassiInputError
from cassi.data.corpus.profile import (MaxProtru, file_measures, parse_lipthick, parse_maxprotru,
                                preprocess, read_lipthick, read_maxprotru, write_lipthick,
                                write_maxprotru)
from cassi.data.xrmb.files import read_txy

D_REST = math.hypot(*(REST[6] - REST[7]))  # MNI-MNM of the helper's rest posture, mm
LIP_REST = math.hypot(*(REST[0] - REST[1]))


def test_jw45_excerpt_file_measures_by_hand():
    """Thesis Figure 3.9 row 27464 us: UL (15757, 11596), LL (12175, -9772), MNI (-699, -7452),
    MNM (-34792, -9862) um; d = |MNI - MNM|."""
    m = file_measures(read_txy(JW45_EXCERPT))
    d = math.hypot(-699 + 34792, -7452 + 9862) / 1000
    assert m["jaw_length_mm"] == pytest.approx(d)
    assert m["rest_ul"] == pytest.approx(15.757 / d)
    assert m["rest_ll"] == pytest.approx(12.175 / d)
    assert m["max_ul"] == pytest.approx(15.786 / d)  # UL x rises to 15786 um in the excerpt
    assert m["min_ll"] == pytest.approx(12.107 / d)
    assert m["lipthick"] == pytest.approx(math.hypot(15.757 - 12.175, 11.596 + 9.772) / d)
    # The published JW45 REST UL (0.462957) is an average over 20 files; one file is close.
    assert m["rest_ul"] == pytest.approx(0.462957, abs=0.01)


@pytest.fixture
def subject_dir(tmp_path):
    recs = {}
    for task in range(1, 31):
        recs[(task, 1)] = recording(task=task, ul_dx=np.r_[np.zeros(20), np.full(20, 0.1 * task)])
    recs[(5, 1)] = recording(task=5, lost=("LL", 30))          # pellet lost: not error-free
    recs[(118, 1)] = recording(task=118, ul_dx=np.r_[np.zeros(10), np.full(30, 9.0)])
    # Task 2, a second repetition, with a different jaw size: one repetition per task is used.
    recs[(2, 2)] = recording(task=2, rest=REST * 1.5)
    write_subject(tmp_path, "JW90", recs, mis=[(3, "TB2"), (7, "MAN M")])
    return tmp_path


def test_selection_and_values(subject_dir):
    prof = preprocess(Corpus(subject_dir))["JW90"]
    expected = (1, 2, 4, 6, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 118)
    assert tuple(t for t, _ in prof.selected) == expected  # 19 lowest error-free + task 118
    assert all(rep == 1 for _, rep in prof.selected)
    assert len(prof.per_file) == 20
    assert prof.jaw_length_mm == pytest.approx(D_REST)
    assert prof.rest_ul == pytest.approx(REST[0, 0] / D_REST)
    assert prof.rest_ll == pytest.approx(REST[1, 0] / D_REST)
    assert prof.lipthick == pytest.approx(LIP_REST / D_REST)
    # Extreme over files (task 118's +9 mm), not the mean of per-file extremes.
    assert prof.max_ul == pytest.approx((REST[0, 0] + 9.0) / D_REST)
    mean_of_max = np.mean([(REST[0, 0] + 0.1 * t) for t in expected[:-1]] + [REST[0, 0] + 9]) / D_REST
    assert prof.max_ul > mean_of_max + 0.05
    assert prof.min_ul == pytest.approx(REST[0, 0] / D_REST)
    assert prof.palate_mm.shape == (4, 2)


def test_per_file_jaw_length_normalises_each_file(tmp_path):
    big = REST * 2.0  # every length doubles: the normalised values must not change
    write_subject(tmp_path, "JW91", {(1, 1): recording(task=1), (2, 1): recording(task=2, rest=big)})
    prof = preprocess(Corpus(tmp_path))["JW91"]
    assert prof.jaw_length_mm == pytest.approx(1.5 * D_REST)
    assert prof.rest_ul == pytest.approx(REST[0, 0] / D_REST)
    assert prof.lipthick == pytest.approx(LIP_REST / D_REST)


def test_max_files_and_118_not_error_free(tmp_path):
    recs = {(t, 1): recording(task=t) for t in range(1, 26)}
    recs[(118, 1)] = recording(task=118, lost=("UL", 20))
    write_subject(tmp_path, "JW92", recs)
    prof = preprocess(Corpus(tmp_path))["JW92"]
    assert tuple(t for t, _ in prof.selected) == tuple(range(1, 21))


def test_subject_without_error_free_files(tmp_path):
    write_subject(tmp_path, "JW29", {(t, 1): recording(task=t, lost=("MNM", 10))
                                     for t in range(1, 4)})
    write_subject(tmp_path, "JW32", {(2, 1): recording(task=2)})
    skipped = []
    profiles = preprocess(Corpus(tmp_path), skipped=skipped)
    assert list(profiles) == ["JW32"]
    assert len(skipped) == 1 and "JW29" in skipped[0] and "no error-free" in skipped[0]
    with pytest.raises(CassiInputError, match="no error-free task file"):
        preprocess(Corpus(tmp_path), ["JW29"])


def test_reference_maxprotru_reads_and_writes_back_identically(tmp_path):
    """Thesis Figure 4.16 (printing defects repaired in ../shared/reference)."""
    src = FIXTURES / "profiles" / "maxprotru.txt"
    table = read_maxprotru(src)
    assert len(table) == 15 and list(table)[0] == "JW11" and list(table)[-1] == "JW502"
    assert table["JW12"].min_ll == -0.102688 and table["JW502"].min_ll == -0.037349
    assert table["JW45"] == MaxProtru(0.462957, 0.355955, 0.692150, 0.564495, 0.010773, 0.008101)
    write_maxprotru(tmp_path / "maxprotru.txt", table)
    assert (tmp_path / "maxprotru.txt").read_bytes() == src.read_bytes()


def test_reference_lipthick_roundtrip(tmp_path):
    """Thesis Figure 4.25 (subjects in no particular order; we write natural order)."""
    table = read_lipthick(FIXTURES / "profiles" / "lipthick.txt")
    assert len(table) == 15 and table["JW11"] == 0.975998 and table["JW25"] == 0.414120
    write_lipthick(tmp_path / "lipthick.txt", table)
    back = read_lipthick(tmp_path / "lipthick.txt")
    assert back == table and list(back)[:2] == ["JW11", "JW12"]
    assert (tmp_path / "lipthick.txt").read_text().splitlines()[0] == "JW11 0.975998"


def test_printed_header_with_spaces_is_accepted():
    t = parse_maxprotru("Subject REST UL REST LL MAX UL MAX LL MIN UL MIN LL\r\n"
                        "JW11 0.345274 0.228690 0.519758 0.439836 0.009925 0.003348")
    assert t["JW11"].max_ll == 0.439836


_ROW = "0.3 0.2 0.5 0.4 0.01 0.0"    # REST_UL REST_LL MAX_UL MAX_LL MIN_UL MIN_LL, ordered


@pytest.mark.parametrize("text, reason, line", [
    ("Subject A B\n", "unexpected header", 1), ("JW1 1 2 3\n", "expected 7 columns", 1),
    ("JW1 1 2 3 4 5 x\n", "not a number", 1), ("", "empty file", None),
    (f"JW1 {_ROW}\nJW1 {_ROW}\n", r"listed twice \(line 1", 2),
    (f"JW1 {_ROW}\njw1 {_ROW}\n", r"jw1 listed twice \(line 1, up to case\)", 2),
    (f"!!! {_ROW}\n", "'!!!' is not a subject name", 1),
    ("JW1 0.3 0.2 0.5 0.4 0.6 0.0\n", r"UL: expected MIN <= REST <= MAX, got 0.6, 0.3, 0.5", 1),
    ("JW1 0.3 0.2 0.5 0.1 0.01 0.0\n", "LL: expected MIN <= REST <= MAX", 1),
])
def test_malformed_maxprotru(text, reason, line):
    with pytest.raises(CassiInputError, match=reason) as info:
        parse_maxprotru(text, path="maxprotru.txt")
    assert info.value.line == line


@pytest.mark.parametrize("text, reason, line", [
    ("JW1 0\n", "lip thickness must be positive, got 0", 1),
    ("JW1 0.5\nJW2 -0.4\n", "lip thickness must be positive, got -0.4", 2),
    ("JW1 0.5\njw1 0.6\n", "listed twice", 2), ("0.4 0.5\n", "not a subject name", 1),
])
def test_malformed_lipthick(text, reason, line):
    with pytest.raises(CassiInputError, match=reason) as info:
        parse_lipthick(text, path="lipthick.txt")
    assert info.value.line == line


def test_the_published_profile_tables_pass(shared_dir):
    """Every row of the thesis's Figures 4.16 and 4.25 as printed passes the new checks."""
    ref = shared_dir / "reference" / "profiles"
    assert len(read_maxprotru(ref / "maxprotru.txt")) == 15
    assert all(v > 0 for v in read_lipthick(ref / "lipthick.txt").values())


def test_written_profile_tables_match_preprocess(subject_dir, tmp_path):
    profiles = preprocess(Corpus(subject_dir))
    write_maxprotru(tmp_path / "m.txt", profiles)
    write_lipthick(tmp_path / "l.txt", profiles)
    row = read_maxprotru(tmp_path / "m.txt")["JW90"]
    np.testing.assert_allclose(row, profiles["JW90"].maxprotru, atol=5e-7)
    assert read_lipthick(tmp_path / "l.txt")["JW90"] == pytest.approx(profiles["JW90"].lipthick,
                                                                      abs=5e-7)
