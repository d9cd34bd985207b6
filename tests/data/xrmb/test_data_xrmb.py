"""XRMB file formats: task files, PAL/PHA.DAT, Mis.dat, head measures (thesis 3.2.5)."""
from __future__ import annotations

import numpy as np
import pytest
from data_helpers import FIXTURES, JW45_EXCERPT, recording

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.headmeasures import HeadMeasures
from cassi.data.xrmb.files import (BAD_VALUE, NOMINAL_PERIOD_US, PELLETS, TaskRecording, format_txy, parse_mis,
                             parse_outline, parse_task_name, parse_txy, read_head_measures,
                             read_mis, read_pal, read_pha, read_txy, write_head_measures,
                             write_mis, write_pal, write_txy, recording_period_us, rows_spanning)

JW99 = FIXTURES / "xrmb" / "JW99"
ROW = "6866\t" + "\t".join(["100"] * 16)


# ----------------------------------------------------------------------------- task files
def test_jw45_excerpt_first_valid_row_is_27464_us():
    """Thesis Figure 3.9 / shared reference README: first row with all eight pellets valid."""
    rec = read_txy(JW45_EXCERPT)
    assert (rec.subject, rec.task, rec.rep) == ("JW45", 13, 1)
    assert rec.n_frames == 16
    assert rec.first_valid_index == 4
    assert rec.first_valid_time_us == 27464
    assert rec.warnings == ()
    # Row 20598 us: UL bad (1000000) but LL tracked; the value must become a mask, not 1000 mm.
    assert not rec.valid[3, 0] and rec.valid[3, 1]
    assert np.isnan(rec.xy_mm[3, 0]).all()
    np.testing.assert_allclose(rec.pellet("UL")[4], [15.757, 11.596])
    np.testing.assert_allclose(rec.pellet("MNM")[15], [-34.845, -9.997])
    assert rec.xy_mm.shape == (16, 8, 2) and rec.time_us.dtype == np.int64
    assert np.nanmax(np.abs(rec.xy_mm)) < 100


def test_write_txy_reproduces_the_excerpt_bytes(tmp_path):
    rec = read_txy(JW45_EXCERPT)
    write_txy(tmp_path / "tp013.txy", rec)
    assert (tmp_path / "tp013.txy").read_bytes() == JW45_EXCERPT.read_bytes()


@pytest.mark.parametrize("name", ["tp005.txy", "tp006.txy"])
def test_crlf_spaces_and_no_final_newline_read_like_the_original(name):
    ref = read_txy(JW45_EXCERPT)
    rec = read_txy(JW99 / name)
    assert rec.subject == "JW99" and rec.task == int(name[2:5])
    np.testing.assert_array_equal(rec.time_us, ref.time_us)
    np.testing.assert_array_equal(rec.valid, ref.valid)
    np.testing.assert_array_equal(np.nan_to_num(rec.xy_mm), np.nan_to_num(ref.xy_mm))
    assert rec.warnings == ()


def test_pellet_lost_partway_is_a_recorded_warning():
    rec = read_txy(JW99 / "TP007_2.TXY")
    assert (rec.task, rec.rep) == (7, 2)
    assert rec.first_valid_time_us == 27464
    assert not rec.valid[9:, 1].any()
    assert any("pellet LL invalid from time 61794 us to the end" in w and ":10:" in w
               for w in rec.warnings)


@pytest.mark.parametrize("name, expected", [
    ("tp001.txy", (None, 1, 1)), ("TP118.TXY", (None, 118, 1)), ("tp015_2.txy", (None, 15, 2)),
    ("JW45_013.TXY", ("JW45", 13, 1)), ("jw502_007_3.txy", ("JW502", 7, 3)),
])
def test_task_names(name, expected):
    assert parse_task_name(name) == expected


@pytest.mark.parametrize("name", ["tp.txy", "tp001.xyd", "../tp001.txy", "tp000.txy", "x.txt"])
def test_bad_task_names(name):
    with pytest.raises(CassiInputError):
        parse_task_name(name)


@pytest.mark.parametrize("text, line, reason", [
    ("", None, "empty file"),
    ("\n\n  \n", 1, "empty file"),
    ("0\t1\t2\n", 1, "expected 17 columns, found 3"),
    (ROW + "\n6866 1 2\n", 2, "expected 17 columns, found 3"),
    ("0 " + " ".join(["1"] * 15) + " x1\n", 1, "column 17 (MNMy): 'x1' is not a number"),
    ("0 " + " ".join(["1"] * 15) + " 1_000\n", 1, "is not a number"),
    ("0 " + " ".join(["1"] * 15) + " " + "9" * 30 + "\n", 1, "column 17 (MNMy): '999"),
    ("0 " + " ".join(["1"] * 15) + " " + "9" * 13 + "\n", 1, "has too many digits"),
    ("0.5 " + " ".join(["1"] * 16) + "\n", 1, "column 1 (time)"),
    ("-5 " + " ".join(["1"] * 16) + "\n", 1, "must be a non-negative integer"),
    (ROW + "\n" + ROW + "\n", 2, "time not increasing: 6866 us after 6866 us"),
    (ROW + "\n" + ROW.replace("6866", "100", 1) + "\n", 2, "time not increasing"),
    ("0 " + " ".join([str(BAD_VALUE)] * 16) + "\n", 1, "no row has all eight pellets valid"),
    ("0 " + " ".join(["1"] * 16) + "\n\xe9\n", 2, "non-ASCII"),
])
def test_malformed_task_files_name_file_line_and_reason(text, line, reason):
    with pytest.raises(CassiInputError) as info:
        parse_txy(text.encode("latin-1"), path="S/tp001.txy")
    err = info.value
    assert reason in err.reason
    assert err.line == line
    assert str(err).startswith("S/tp001.txy:" + (f"{line}:" if line else ""))


def test_no_valid_row_can_be_read_for_reporting():
    text = "0 " + " ".join(["5"] * 14) + f" {BAD_VALUE} {BAD_VALUE}\n"
    rec = parse_txy(text, path="tp002.txy", require_valid=False)
    assert rec.first_valid_index is None
    assert any("never valid: MNM" in w for w in rec.warnings)


def test_half_bad_pair_masks_the_pellet_and_warns():
    vals = ["1"] * 16
    vals[2] = str(BAD_VALUE)  # LLx bad, LLy not
    rec = parse_txy("0 " + " ".join(["2"] * 16) + "\n6866 " + " ".join(vals) + "\n",
                    path="tp003.txy")
    assert not rec.valid[1, 1] and rec.valid[1].sum() == 7
    assert any("only one coordinate" in w and ":2:" in w for w in rec.warnings)


def test_irregular_period_and_header_and_inner_blank_lines_are_warnings():
    header = "Time ULx ULy LLx LLy T1x T1y T2x T2y T3x T3y T4x T4y MNIx MNIy MNMx MNMy\n"
    row = " " + " ".join(["2"] * 16) + "\n"
    body = "0" + row + "\n" + "".join(f"{t}{row}" for t in (6866, 13732, 20732))
    rec = parse_txy(header + body, path="tp004.txy")
    assert rec.n_frames == 4 and rec.period_us == 6866
    joined = "\n".join(rec.warnings)
    assert "header" in joined and "blank line" in joined and "nominal 6866" in joined


def test_a_recording_keeps_its_own_period():
    """A 500 Hz recording (EMA) reads without a warning; its period is its median interval."""
    row = " " + " ".join(["2"] * 16) + "\n"
    rec = parse_txy("".join(f"{2000 * i}{row}" for i in range(5)), path="tp004.txy")
    assert rec.period_us == 2000 and rec.warnings == ()
    late = parse_txy("".join(f"{t}{row}" for t in (0, 2000, 4000, 6500, 8500)), path="tp004.txy")
    assert late.period_us == 2000 and "nominal 2000" in "\n".join(late.warnings)
    assert recording_period_us([5]) == NOMINAL_PERIOD_US
    assert rows_spanning(62_000, 6866, odd=True) == 9 and rows_spanning(62_000, 2000, odd=True) == 31


def test_write_read_roundtrip_keeps_mask_and_rounds_to_micrometres(tmp_path):
    rec = recording(12, lead=2, lost=("T4", 9), ul_dx=np.linspace(0, 3.21234, 12))
    write_txy(tmp_path / "tp010.txy", rec)
    back = read_txy(tmp_path / "tp010.txy", subject="JW90")
    np.testing.assert_array_equal(back.valid, rec.valid)
    np.testing.assert_allclose(back.xy_mm[rec.valid], rec.xy_mm[rec.valid], atol=5e-4)
    assert "1000000" in (tmp_path / "tp010.txy").read_text()


def test_writer_refuses_inconsistent_records():
    rec = recording(4)
    bad = TaskRecording(None, "S", 1, 1, rec.time_us[::-1].copy(), rec.xy_mm, rec.valid)
    with pytest.raises(CassiInputError, match="increasing"):
        format_txy(bad)
    far = rec.xy_mm.copy()
    far[3, 0, 0] = 1000.0  # 1 m: would be written as the bad value
    with pytest.raises(CassiInputError, match="collide"):
        format_txy(TaskRecording(None, "S", 1, 1, rec.time_us, far, np.ones((4, 8), bool)))


# ----------------------------------------------------------------------------- outlines
def test_jw12_palate_reads_and_writes_back_identically(tmp_path):
    """Thesis Figure 3.11: 12 points, front (-5, 8.5) mm to back (-53.1, 21.333) mm."""
    src = FIXTURES / "xrmb" / "JW12" / "PAL.DAT"
    pal = read_pal(src)
    assert pal.shape == (12, 2)
    np.testing.assert_allclose(pal[0], [-5.0, 8.5])
    np.testing.assert_allclose(pal[-1], [-53.1, 21.333])
    write_pal(tmp_path / "PAL.DAT", pal)
    assert (tmp_path / "PAL.DAT").read_bytes() == src.read_bytes()


def test_lowercase_crlf_palate_and_pharynx():
    np.testing.assert_array_equal(read_pal(JW99 / "pal.dat"), read_pal(FIXTURES / "xrmb" / "JW12"
                                                                        / "PAL.DAT"))
    assert read_pha(JW99 / "PHA.DAT").shape == (3, 2)


@pytest.mark.parametrize("text, line, reason", [
    ("", None, "empty file"), ("1 2 3\n", 1, "expected 2 columns"), ("1 2\nx 2\n", 2, "not a number"),
    ("1000000 5\n", 1, "bad value"),
])
def test_malformed_outlines(text, line, reason):
    with pytest.raises(CassiInputError) as info:
        parse_outline(text, path="PAL.DAT")
    assert reason in info.value.reason and info.value.line == line


def test_a_palate_too_short_for_a_face_is_refused_where_it_is_read(tmp_path):
    # two points 0.1 mm apart parse as an outline, but no face can take them: the error names
    # the file at once (corpus check), not a later face build without it
    (tmp_path / "PAL.DAT").write_text("1000 2000\n1100 2000\n")
    with pytest.raises(CassiInputError, match="shorter than the 5 mm") as info:
        read_pal(tmp_path / "PAL.DAT")
    assert info.value.path == str(tmp_path / "PAL.DAT")
    assert read_pal(FIXTURES / "xrmb" / "JW12" / "PAL.DAT").shape[0] > 2


def test_textgrid_tiers_whose_entries_are_not_intervals(tmp_path):
    from cassi.data.xrmb.alignment import parse_alignment
    tier = '{{"name":"phone","class":"IntervalTier","xmin":0,"xmax":1,"entries":{}}}'
    word = '{"name":"word","class":"IntervalTier","xmin":0,"xmax":1,"entries":[]}'
    bad_span = '{"xmin":0,"xmax":1e400,"tiers":[' + tier.format("[]") + "," + word + "]}"
    with pytest.raises(CassiInputError, match="not a finite span"):
        parse_alignment(bad_span, path="tp003.TextGrid")
    for entries, reason in (("5", "entries are not a list"), ("[5]", "not an interval tier")):
        text = '{"xmin":0,"xmax":1,"tiers":[' + tier.format(entries) + "," + word + "]}"
        with pytest.raises(CassiInputError, match=reason) as info:
            parse_alignment(text, path="tp003.TextGrid")
        assert info.value.path == "tp003.TextGrid"


@pytest.mark.parametrize("form", ["long_textgrid", "short_textgrid"])
def test_textgrid_interval_errors_name_their_line(tmp_path, form):
    """A bad interval is refused with the line it starts on, in Praat's long and short text
    forms (praatio's parser gives no lines): the long form's ``intervals [k]:`` line, the short
    form's xmin line."""
    from praatio import textgrid
    from cassi.data.xrmb.alignment import parse_alignment
    tg = textgrid.Textgrid()
    for name, ivs in (("phone", [(0.0, 0.2, "sp"), (0.2, 0.3, "S"), (0.3, 0.5, "AH"), (0.5, 1.0, "sp")]),
                      ("word", [(0.0, 0.2, "sp"), (0.2, 0.5, "SA"), (0.5, 1.0, "sp")])):
        tg.addTier(textgrid.IntervalTier(name, ivs, 0.0, 1.0))
    tg.save(str(tmp_path / "tp105.TextGrid"), format=form, includeBlankSpaces=True)
    good = (tmp_path / "tp105.TextGrid").read_text()
    assert len(parse_alignment(good).phones) == 4
    lines = good.splitlines()
    for tier, k, start in (("phone", 3, "0.3"), ("word", 2, "0.2")):
        # interval k (1-based) of the tier ends before it starts: its xmax line becomes 0.1
        first = next(i for i, ln in enumerate(lines) if ln.strip() in (f'name = "{tier}"', f'"{tier}"'))
        if form == "long_textgrid":
            head = next(i for i in range(first, len(lines)) if lines[i].strip() == f"intervals [{k}]:")
            j, new = head + 2, "xmax = 0.1"
        else:  # name, xmin, xmax, size, then xmin / xmax / text per interval
            j, new = first + 4 + 3 * (k - 1) + 1, "0.1"
        assert lines[j - 1].strip().endswith(start)
        bad = lines[:j] + [lines[j].replace(lines[j].strip(), new)] + lines[j + 1:]
        with pytest.raises(CassiInputError, match=f"tier '{tier}', interval {k}: bad interval") as info:
            parse_alignment("\n".join(bad) + "\n", path="tp105.TextGrid")
        hit = bad[info.value.line - 1].strip()
        assert hit == (f"intervals [{k}]:" if form == "long_textgrid" else start), (info.value, hit)


@pytest.mark.parametrize("form", ["long_textgrid", "short_textgrid"])
def test_textgrid_whose_tier_does_not_hold_its_declared_count(tmp_path, form):
    """praatio reads the intervals that are there, Praat exactly the declared number: a tier cut
    short at an interval boundary, or one with an interval pasted in, is refused at its size
    line; the file as praatio wrote it reads."""
    from praatio import textgrid
    from cassi.data.xrmb.alignment import parse_alignment
    tg = textgrid.Textgrid()
    for name, ivs in (("word", [(0.0, 0.4, "sp"), (0.4, 1.0, "SA")]),
                      ("phone", [(0.0, 0.4, "sp"), (0.4, 0.6, "S"), (0.6, 1.0, "AH")])):
        tg.addTier(textgrid.IntervalTier(name, ivs, 0.0, 1.0))
    tg.save(str(tmp_path / "tp105.TextGrid"), format=form, includeBlankSpaces=True)
    good = (tmp_path / "tp105.TextGrid").read_text()
    assert len(parse_alignment(good).phones) == 3
    lines = good.rstrip("\n").split("\n")
    cut = lines[:-4 if form == "long_textgrid" else -3]          # the phone tier's last interval gone
    with pytest.raises(CassiInputError, match="tier 'phone' declares 3 intervals but holds 2") as info:
        parse_alignment("\n".join(cut) + "\n", path="tp105.TextGrid")
    size = [i + 1 for i, ln in enumerate(lines)
            if ln.strip() in ("intervals: size = 3", "3")]
    assert info.value.line == size[-1] and info.value.path == "tp105.TextGrid"
    def declared(count: str) -> str:                # the word tier's size line says count
        if form == "long_textgrid":
            return "\n".join(lines).replace("intervals: size = 2", f"intervals: size = {count}")
        head = lines.index('"word"')
        return "\n".join(lines[:head + 3] + [count] + lines[head + 4:])
    with pytest.raises(CassiInputError, match="tier 'word' declares 1 intervals but holds 2"):
        parse_alignment(declared("1") + "\n", path="tp105.TextGrid")
    # a count Python's int() refuses (over 4300 digits) is refused at its line too, not a
    # ValueError; leading zeros name the same count
    with pytest.raises(CassiInputError, match=r"declares 99999999999999999999\.\.\. \(5000 digits\)"):
        parse_alignment(declared("9" * 5000) + "\n", path="tp105.TextGrid")
    assert len(parse_alignment(declared("002") + "\n").words) == 2


def _long_grid(tiers) -> str:
    """A long-form TextGrid of (class, name, intervals or points) tiers, one-second intervals."""
    out = ['File type = "ooTextFile"', 'Object class = "TextGrid"', "", "xmin = 0", "xmax = 3",
           "tiers? <exists>", f"size = {len(tiers)}", "item []:"]
    for j, (cls, name, n) in enumerate(tiers, 1):
        out += [f"    item [{j}]:", f'        class = "{cls}"', f'        name = "{name}"',
                "        xmin = 0", "        xmax = 3"]
        kind, body = (("intervals", lambda k: [f"xmin = {k - 1}", f"xmax = {k}", 'text = "a"'])
                      if cls == "IntervalTier" else
                      ("points", lambda k: [f"number = {k}", 'mark = "a"']))
        out.append(f"        {kind}: size = {n}")
        for k in range(1, n + 1):
            out += [f"        {kind} [{k}]:"] + ["            " + b for b in body(k)]
    return "\n".join(out) + "\n"


def test_textgrid_times_praatio_would_misread_or_that_leave_the_grid():
    """praatio reads "-0.1" as 0.1: a negative time is refused where it stands. An interval
    beyond the grid's span is refused; one that overlaps the one before by rounding (< 1 us) is
    read as starting where that one ends."""
    from cassi.data.xrmb.alignment import parse_alignment
    grid = _long_grid([("IntervalTier", "phone", 3), ("IntervalTier", "word", 2)])
    lines = grid.split("\n")
    k = lines.index("            xmin = 1")                     # phone interval 2
    neg = "\n".join(lines[:k] + ["            xmin = -0.1"] + lines[k + 1:])
    with pytest.raises(CassiInputError, match="a negative time 'xmin = -0.1'") as info:
        parse_alignment(neg, path="tp1.TextGrid")
    assert info.value.line == k + 1
    j = len(lines) - 1 - lines[::-1].index("            xmax = 2")  # word interval 2 ends at 2 ...
    far = "\n".join(lines[:j] + ["            xmax = 9"] + lines[j + 1:])   # ... now at 9 in a 3 s grid
    with pytest.raises(CassiInputError, match="outside the grid's 0.0..3.0 s") as info:
        parse_alignment(far, path="tp1.TextGrid")
    assert info.value.line == j - 1
    near = "\n".join(lines[:k] + ["            xmin = 0.9999999"] + lines[k + 1:])
    a = parse_alignment(near, path="tp1.TextGrid")
    assert a.phones["start_s"].iloc[1] == 1.0
    assert parse_alignment(grid).words["end_s"].tolist() == [1.0, 2.0]
    label = grid.replace('text = "a"', 'text = "a\n-5 dB"', 1)         # a label's line, not a time
    assert len(parse_alignment(label).phones) == 3
    k2 = lines.index("            xmax = 1")                     # phone interval 1 ends at 1 ...
    inside = lines[:k2] + ["            xmax = 1.0000008"] + lines[k2 + 1:]
    inside[k + 1] = "            xmax = 1.0000005"            # ... interval 2 ends inside it
    with pytest.raises(CassiInputError, match="ends inside the one before"):
        parse_alignment("\n".join(inside), path="tp1.TextGrid")


def test_textgrid_error_lines_in_awkward_layouts():
    """The line finder reads the tier the parser keeps: an interval tier (not a point tier of
    the same name), the last of names equal but for case, quoted names; CRLF, blank lines and
    multi-line labels do not shift it; a text it cannot place gives no line, never an error."""
    from cassi.data.xrmb.alignment import _interval_line

    def line_of(text, wanted, nth):
        return [i + 1 for i, ln in enumerate(text.split("\n")) if ln.strip() == wanted][nth]

    grid = _long_grid([("TextTier", "phone", 2), ("IntervalTier", "phone", 3), ("IntervalTier", "word", 2)])
    assert _interval_line(grid, "phone", 0) == line_of(grid, "intervals [1]:", 0)
    assert _interval_line(grid, "word", 1) == line_of(grid, "intervals [2]:", 1)
    assert _interval_line(grid.replace("\n", "\r\n"), "word", 1) == line_of(grid, "intervals [2]:", 1)
    assert _interval_line(grid, "word", 5) is None
    blank = grid.replace("        intervals [1]:", "\n        intervals [1]:", 1)
    assert _interval_line(blank, "phone", 0) == line_of(blank, "intervals [1]:", 0)
    cases = _long_grid([("IntervalTier", "Phone", 3), ("IntervalTier", "phone", 3), ("IntervalTier", "word", 2)])
    assert _interval_line(cases, "phone", 0) == line_of(cases, "intervals [1]:", 1)
    quoted = _long_grid([("IntervalTier", 'say ""hi""', 3), ("IntervalTier", "word", 2)])
    assert _interval_line(quoted, 'say "hi"', 0) == line_of(quoted, "intervals [1]:", 0)
    short = ('File type = "ooTextFile"\nObject class = "TextGrid"\n\n0\n3\n<exists>\n2\n'
             '"IntervalTier"\n"say ""hi"""\n0\n3\n2\n0\n1\n"a\nb"\n1\n3\n"c"\n'
             '"IntervalTier"\n"word"\n0\n3\n1\n0\n3\n"w"\n')
    assert _interval_line(short, 'say "hi"', 1) == 17          # after a two-line label
    assert _interval_line(short, "word", 0) == 25
    assert _interval_line(short.replace("\n", "\r\n"), "word", 0) == 25
    for text in ("", '{"tiers": []}', grid):
        assert _interval_line(text, "none", 0) is None


# ----------------------------------------------------------------------------- Mis.dat
def test_jw12_mis_dat(tmp_path):
    """Thesis Figure 3.10: 49 entries; codes with a space; -1 = to the end; raster-hop notes."""
    src = FIXTURES / "xrmb" / "JW12" / "Mis.dat"
    entries = read_mis(src)
    assert len(entries) == 49
    e = entries[3]
    assert (e.task, e.pellet, e.onset_ms, e.offset_ms, e.note, e.line) == (11, "TD", 2330, -1,
                                                                         "k;j", 4)
    assert e.to_end and e.xrmb_pellet == "T4" and e.offset_us == -1
    man = [x for x in entries if x.pellet == "MAN M"]
    assert len(man) == 6 and man[0].xrmb_pellet == "MNM" and man[0].onset_us == 845000
    assert [x.xrmb_pellet for x in entries if x.pellet == "MAX G"] == [None, None]
    assert sorted({x.task for x in entries})[:3] == [10, 11, 12]
    write_mis(tmp_path / "Mis.dat", entries)
    assert (tmp_path / "Mis.dat").read_bytes() == src.read_bytes()


def test_mis_dat_with_spaces_tabs_crlf():
    entries = read_mis(JW99 / "Mis.dat")
    assert [(e.task, e.pellet, e.onset_ms, e.offset_ms, e.note) for e in entries] == [
        (8, "MAN M", 120, 400, None), (8, "TB2", 0, -1, "j;k")]


def test_empty_mis_dat_means_no_mistracking():
    assert parse_mis(b"") == [] and parse_mis(b"\r\n") == []


@pytest.mark.parametrize("text, reason", [
    ("010 TB1 0\n", "found 3 field(s)"), ("x10 TB1 0 767\n", "not a positive integer"),
    ("010 ZZ 0 767\n", "unknown pellet code"), ("010 TB1 900 767\n", "offset 767 before onset"),
    ("010 TB1 0 -5\n", "before onset"), ("010 TB1 5 b\n", "expected integer ONSET"),
    ("010 TB1 a b\n", "malformed pellet code"),
    ("000 TB1 0 1\n", "at least 1"),
])
def test_malformed_mis_dat(text, reason):
    with pytest.raises(CassiInputError) as info:
        parse_mis("012 TB2 0 -1 j;k\n" + text, path="Mis.dat")
    assert reason in info.value.reason and info.value.line == 2


# ----------------------------------------------------------------------------- head measures
def test_head_measures_fixture_and_roundtrip(tmp_path):
    table = read_head_measures(JW99 / "Headmeasures.txt")
    assert list(table) == ["JW99"]
    np.testing.assert_allclose(table["JW99"].gonion_mm, [-80.5, -51.0])
    np.testing.assert_allclose(table["JW99"].gnathion_mm, [-5.2, -43.8])
    more = dict(table, JW11=HeadMeasures(np.array([-78.25, -49.0]), np.array([-4.0, -41.5])))
    write_head_measures(tmp_path / "Headmeasures.txt", more)
    assert read_head_measures(tmp_path / "Headmeasures.txt") == more
    text = (tmp_path / "Headmeasures.txt").read_text()
    assert text.splitlines()[1] == "Subject GONION_X GONION_Y GNATHION_X GNATHION_Y"
    assert text.splitlines()[2] == "JW11 -78250 -49000 -4000 -41500"


@pytest.mark.parametrize("text, line, reason", [
    ("JW1 1 2 3\n", 1, "expected 5 columns"), ("JW1 1 2 3 x\n", 1, "not a number"),
    ("JW1 -80000 -50000 -5000 -44000\njw1 -80000 -50000 -5000 -44000\n", 2, "listed twice"),
    ("../x 1 2 3 4\n", 1, "bad subject"),
    ("JW1 -80000 -50000 -5000 -44000\nSubject GONION_X GONION_Y GNATHION_X GNATHION_Y\n", 2,
     "header line after"),
    ("JW1 0 0 0 0\n", 1, "are not a jaw"),                          # no jaw at all
    ("JW1 -80000 50000 -5000 -44000\n", 1, "are not a jaw"),        # a gonion above the teeth
    ("JW1 -5000 -50000 -80000 -44000\n", 1, "the gonion behind the gnathion"),
])
def test_malformed_head_measures(tmp_path, text, line, reason):
    p = tmp_path / "Headmeasures.txt"
    p.write_text(text)
    with pytest.raises(CassiInputError) as info:
        read_head_measures(p)
    assert reason in info.value.reason and info.value.line == line


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(CassiInputError, match="file not found"):
        read_txy(tmp_path / "tp001.txy")
    (tmp_path / "tp002.txy").mkdir()
    with pytest.raises(CassiInputError, match="directory"):
        read_txy(tmp_path / "tp002.txy")


def test_pellet_order_is_the_thesis_column_order():
    assert PELLETS == ("UL", "LL", "T1", "T2", "T3", "T4", "MNI", "MNM")
