"""Label files beside TextGrids: xwaves/ESPS .lab, HTK .lab/.rec and master label files, the
lookup by stem a corpus and the EMA adapter share, and labels that outrun their recording."""
from __future__ import annotations

import shutil

import numpy as np
import pytest
from data_helpers import FIXTURES, recording, write_subject

from cassi.common.errors import CassiInputError
from cassi.data.corpus.beside import alignment_for_stem, alignment_path_for_stem, audio_for_stem
from cassi.data.corpus.disk import Corpus
from cassi.data.xrmb.labels import (check_within, parse_htk_lab, parse_mlf, parse_xwaves_lab,
                                    read_labels)

# As MOCHA-TIMIT writes them (made up here: times end each label, colour 26 or 121)
XWAVES = """signal fsew0_001
type 0
color 121
comment created by hand
font -misc-*-bold-*-*-*-15-*-*-*-*-*-*-*
separator ;
nfields 1
#
    0.2100  26 breath
    0.3700  26 dh
    0.4400  26 @
"""
HTK = "0 2100000 sil\n2100000 3700000 dh -12.5\n3700000 4400000 @\n"
MLF = ('#!MLF!#\n"*/fsew0_001.lab"\n' + HTK + '.\n"*/fsew0_002.lab"\n0 1000000 sil\n.\n')


def _phones(al):
    return [(round(a, 4), round(b, 4), t) for a, b, t in
            zip(al.phones["start_s"], al.phones["end_s"], al.phones["label"])]


def test_xwaves_and_htk_read_to_the_same_phones():
    want = [(0.0, 0.21, "breath"), (0.21, 0.37, "dh"), (0.37, 0.44, "@")]
    x = parse_xwaves_lab(XWAVES, path="fsew0_001.lab")
    assert _phones(x) == want and x.xmax_s == pytest.approx(0.44) and not len(x.words)
    h = parse_htk_lab(HTK, path="fsew0_001.lab")
    assert [p[:2] for p in _phones(h)] == [p[:2] for p in want]
    assert h.phones["label"].tolist() == ["sil", "dh", "@"]
    m = parse_mlf(MLF, path="all.mlf")
    assert sorted(m) == ["fsew0_001", "fsew0_002"] and _phones(m["fsew0_001"]) == _phones(h)


@pytest.mark.parametrize("text, line, reason", [
    (XWAVES.replace("0.3700", "0.3x00"), 10, "is not a number"),
    (XWAVES.replace("0.4400", "0.1000"), 11, "before the label before it ends"),
    (XWAVES.replace("    0.2100  26 breath", "0.21"), 9, "expected 'time colour label'"),
    (XWAVES.replace("#\n", ""), None, "no header end"),
    (XWAVES.split("#\n")[0] + "#\n", None, "no label after the header"),
])
def test_xwaves_bad_lines_name_the_line(text, line, reason):
    with pytest.raises(CassiInputError) as e:
        parse_xwaves_lab(text, path="fsew0_001.lab")
    assert reason in str(e.value)
    assert (f"fsew0_001.lab:{line}:" in str(e.value)) if line else "fsew0_001.lab" in str(e.value)


@pytest.mark.parametrize("text, line, reason", [
    (HTK.replace("3700000 4400000", "3700000 4.4e6"), 3, "not a whole number of 100 ns"),
    (HTK.replace("3700000 4400000", "4400000 3700000"), 3, "before it starts"),
    (HTK.replace("3700000 4400000", "3000000 4400000"), 3, "before the one before ends"),
    (HTK.replace("2100000 3700000 dh -12.5", "2100000 3700000"), 2, "expected 'start end label"),
    ("", None, "no label"),
])
def test_htk_bad_lines_name_the_line(text, line, reason):
    with pytest.raises(CassiInputError) as e:
        parse_htk_lab(text, path="fsew0_001.lab")
    assert reason in str(e.value)
    if line:
        assert f"fsew0_001.lab:{line}:" in str(e.value)


@pytest.mark.parametrize("text, line, reason", [
    (MLF.replace("#!MLF!#", "MLF"), 1, "not an HTK master label file"),
    (MLF.replace('"*/fsew0_002.lab"', "fsew0_002.lab"), 7, "expected a quoted file name"),
    (MLF.rstrip(".\n") + "\n", 8, "do not end with a line '.'"),
    (MLF.replace("fsew0_002", "fsew0_001"), 7, "labelled twice"),
])
def test_mlf_bad_entries_name_the_line(text, line, reason):
    with pytest.raises(CassiInputError) as e:
        parse_mlf(text, path="all.mlf")
    assert reason in str(e.value) and f"all.mlf:{line}:" in str(e.value)


def test_lookup_by_stem_finds_each_format_and_the_sound(tmp_path):
    d = tmp_path / "fsew0"
    d.mkdir()
    assert alignment_for_stem(d, "fsew0_001") is None and audio_for_stem(d, "fsew0_001") is None
    (d / "all.mlf").write_text(MLF)
    assert alignment_path_for_stem(d, "fsew0_002") == d / "all.mlf"
    assert alignment_for_stem(d, "fsew0_002").phones["label"].tolist() == ["sil"]
    (d / "FSEW0_001.LAB").write_text(XWAVES)      # any case; its own file before the MLF
    assert alignment_for_stem(d, "fsew0_001").phones["label"].tolist()[0] == "breath"
    (d / "fsew0_003.rec").write_text(HTK)
    assert alignment_for_stem(d, "fsew0_003").phones["label"].tolist()[0] == "sil"
    (d / "fsew0_001.wav").write_bytes(b"RIFF")
    assert audio_for_stem(d, "fsew0_001") == d / "fsew0_001.wav"
    with pytest.raises(CassiInputError, match="no labels for 'fsew0_009'"):
        read_labels(d / "all.mlf", stem="fsew0_009")


def test_a_subject_reads_lab_files_beside_its_tasks(tmp_path):
    write_subject(tmp_path, "JW90", {(1, 1): recording(80), (2, 1): recording(80, task=2)})
    (tmp_path / "JW90" / "tp001.lab").write_text(XWAVES)
    (tmp_path / "JW90" / "tp002.lab").write_text(HTK)
    s = Corpus(tmp_path).subject("JW90")
    assert s.alignment(1).phones["label"].tolist() == ["breath", "dh", "@"]
    assert s.alignment(2).phones["end_s"].iloc[-1] == pytest.approx(0.44)
    shutil.copy(FIXTURES / "textgrid" / "tp001.TextGrid", tmp_path / "JW90" / "tp001.TextGrid")
    assert len(Corpus(tmp_path).subject("JW90").alignment(1).words)   # a TextGrid comes first


def test_labels_beyond_the_recording_are_refused():
    rec = recording(80)                                    # 79 rows of 6866 us: 0.542 s
    duration = float(rec.time_us[-1] - rec.time_us[0]) / 1e6
    al = parse_xwaves_lab(XWAVES, path="tp001.lab")
    check_within(al, duration)                             # ends at 0.44 s: inside
    late = parse_htk_lab(HTK + "4400000 9000000 sil\n", path="tp001.lab")
    with pytest.raises(CassiInputError, match=r"tp001.lab.*'sil' ends at 0.900 s, after the "
                                              r"recording's end at 0.542 s"):
        check_within(late, duration)
    assert np.isclose(duration, 79 * 6866e-6)
