"""Property tests of every cassi.data parser: arbitrary bytes give a parse or a CassiInputError,
never another exception or a hang; well-formed data survives write -> read."""
from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from data_helpers import FIXTURES

from cassi.data.xrmb.alignment import parse_alignment
from cassi.common.errors import CassiInputError
from cassi.data.xrmb.headmeasures import HeadMeasures, format_head_measures, parse_head_measures
from cassi.data.xrmb.mis import MistrackEntry, format_mis, parse_mis
from cassi.data.corpus.profile import (MaxProtru, format_lipthick, format_maxprotru, parse_lipthick,
                                parse_maxprotru)
from cassi.data.xrmb.files import PELLETS, TaskRecording, format_outline, format_txy, parse_outline, parse_txy

FAST = settings(max_examples=int(os.environ.get("CASSI_FUZZ_EXAMPLES", 150)), deadline=2000, suppress_health_check=[HealthCheck.too_slow])

# Bytes biased toward the formats' own alphabet, so the fuzzing reaches deep into the parsers.
_ALPHABET = b"0123456789 \t\r\n-+.1000000 eE_xTBMANLUjk;#\"=[]<>ooTextFile item intervals"
near_text = st.lists(st.sampled_from(list(_ALPHABET)), max_size=400).map(bytes)
any_bytes = st.one_of(st.binary(max_size=400), near_text)


def _parse_txy(data):
    return parse_txy(data, path="tp001.txy")


PARSERS = {
    "txy": _parse_txy,
    "txy_unchecked": lambda d: parse_txy(d, path="tp001.txy", require_valid=False),
    "outline": lambda d: parse_outline(d, path="PAL.DAT"),
    "mis": lambda d: parse_mis(d, path="Mis.dat"),
    "head_measures": lambda d: parse_head_measures(d, path="Headmeasures.txt"),
    "maxprotru": lambda d: parse_maxprotru(d, path="maxprotru.txt"),
    "lipthick": lambda d: parse_lipthick(d, path="lipthick.txt"),
    "textgrid": lambda d: parse_alignment(d, path="tp001.TextGrid"),
}


@pytest.mark.parametrize("name", sorted(PARSERS))
@FAST
@given(data=any_bytes)
def test_arbitrary_bytes_parse_or_raise_input_error(name, data):
    try:
        PARSERS[name](data)
    except CassiInputError as err:
        assert err.path is not None  # the message names the file


# Mutations of real files reach the parsers' deeper branches (a valid prefix, then damage).
SAMPLES = {
    "txy": FIXTURES / "xrmb" / "JW45" / "JW45_013.TXY",
    "txy_unchecked": FIXTURES / "xrmb" / "JW99" / "TP007_2.TXY",
    "outline": FIXTURES / "xrmb" / "JW12" / "PAL.DAT",
    "mis": FIXTURES / "xrmb" / "JW12" / "Mis.dat",
    "head_measures": FIXTURES / "xrmb" / "JW99" / "Headmeasures.txt",
    "maxprotru": FIXTURES / "profiles" / "maxprotru.txt",
    "lipthick": FIXTURES / "profiles" / "lipthick.txt",
    "textgrid": FIXTURES / "textgrid" / "tp001.TextGrid",
}


@st.composite
def mutated(draw, original: bytes):
    data = bytearray(original)
    for _ in range(draw(st.integers(1, 4))):
        if not data:
            break
        i = draw(st.integers(0, len(data) - 1))
        j = draw(st.integers(i, min(len(data), i + 12)))
        data[i:j] = draw(st.one_of(st.binary(max_size=6), st.sampled_from(
            [b"", b"\n", b"\r", b"\t", b" ", b"-", b".", b"1000000", b"x", b"\"", b"-1", b"9" * 30])))
    return bytes(data)


@pytest.mark.parametrize("name", sorted(PARSERS))
@FAST
@given(data=st.data())
def test_mutated_real_files_parse_or_raise_input_error(name, data):
    blob = data.draw(mutated(SAMPLES[name].read_bytes()))
    try:
        PARSERS[name](blob)
    except CassiInputError as err:
        assert err.path is not None


def test_samples_parse_unmutated():
    for name, path in SAMPLES.items():
        PARSERS[name](path.read_bytes())


# A well-formed task-file row generator: valid rows with a few bad values sprinkled in.
@st.composite
def txy_rows(draw):
    n = draw(st.integers(1, 30))
    starts = draw(st.integers(0, 10_000))
    steps = draw(st.lists(st.integers(1, 20_000), min_size=n - 1, max_size=n - 1))
    t = np.cumsum([starts] + steps)
    um = np.array(draw(st.lists(st.integers(-99_999, 99_999), min_size=n * 16, max_size=n * 16)))
    bad = np.array(draw(st.lists(st.booleans(), min_size=n * 8, max_size=n * 8))).reshape(n, 8)
    bad[draw(st.integers(0, n - 1))] = False  # at least one valid row
    return t, um.reshape(n, 8, 2), bad


@FAST
@given(rows=txy_rows(), crlf=st.booleans(), sep=st.sampled_from(["\t", " ", "  ", " \t"]),
       final_newline=st.booleans())
def test_txy_text_variants_parse_to_the_same_values(rows, crlf, sep, final_newline):
    t, um, bad = rows
    vals = np.where(bad[:, :, None], 1000000, um).reshape(len(t), 16)
    eol = "\r\n" if crlf else "\n"
    text = eol.join(sep.join(str(v) for v in [ti, *row]) for ti, row in zip(t.tolist(),
                                                                             vals.tolist()))
    if final_newline:
        text += eol
    rec = parse_txy(text.encode(), path="tp001.txy")
    np.testing.assert_array_equal(rec.time_us, t)
    np.testing.assert_array_equal(rec.valid, ~bad)
    np.testing.assert_array_equal(rec.xy_mm[~bad], um[~bad] / 1000.0)
    # ... and the writer gives back the canonical form, which parses to the same recording.
    again = parse_txy(format_txy(rec), path="tp001.txy")
    np.testing.assert_array_equal(again.valid, rec.valid)
    np.testing.assert_array_equal(np.nan_to_num(again.xy_mm), np.nan_to_num(rec.xy_mm))
    # A header line sends the file down the line-by-line path: the same values, line numbers
    # counted from the header.
    header = sep.join(["time", *(f"{p}{c}" for p in PELLETS for c in "xy")])
    slow = parse_txy((header + eol + text).encode(), path="tp001.txy")
    np.testing.assert_array_equal(slow.time_us, rec.time_us)
    np.testing.assert_array_equal(slow.valid, rec.valid)
    np.testing.assert_array_equal(np.nan_to_num(slow.xy_mm), np.nan_to_num(rec.xy_mm))
    assert len(slow.warnings) == len(rec.warnings) + 1


codes = st.sampled_from(["TT", "TB1", "TB2", "TD", "UL", "LL", "MAN I", "MAN M", "MAX G"])


@FAST
@given(st.lists(st.tuples(st.integers(1, 118), codes, st.integers(0, 20000), st.integers(-1, 20000),
                          st.sampled_from([None, "k;j", "j;k", "i;g"])), max_size=20))
def test_mis_roundtrip(items):
    entries = [MistrackEntry(t, c, on, off if off == -1 else on + off, note)
               for t, c, on, off, note in items]
    back = parse_mis(format_mis(entries))
    assert [(e.task, e.pellet, e.onset_ms, e.offset_ms, e.note) for e in back] == [
        (e.task, e.pellet, e.onset_ms, e.offset_ms, e.note) for e in entries]


coord = st.integers(-200_000, 200_000).map(lambda v: v / 1000.0)


@FAST
@given(st.dictionaries(st.from_regex(r"JW[0-9]{1,3}", fullmatch=True),
                       st.tuples(coord, coord, coord, coord), max_size=8))
def test_head_measures_roundtrip(table):
    def jaw(v):  # below the incisors, the gonion behind the gnathion, as the reader requires
        gox, goy, dx, gny = (abs(round(c * 1000)) + 1 for c in v)      # whole micrometres
        return HeadMeasures(np.array([-gox, -goy]) / 1000.0, np.array([-gox + dx, -gny]) / 1000.0)
    hm = {k: jaw(v) for k, v in table.items()}
    assert parse_head_measures(format_head_measures(hm)) == hm


@FAST
@given(st.lists(st.tuples(coord, coord), min_size=1, max_size=30))
def test_outline_roundtrip(points):
    pts = np.array(points)
    np.testing.assert_array_equal(parse_outline(format_outline(pts)), pts)


value = st.integers(-2_000_000, 2_000_000).map(lambda v: v / 1e6)


@FAST
@given(st.dictionaries(st.from_regex(r"JW[0-9]{1,3}", fullmatch=True),
                       st.tuples(*[value] * 7), min_size=1, max_size=8))
def test_profile_tables_roundtrip(table):
    def row(v):  # MIN <= REST <= MAX per lip, as the reader requires
        ul, ll = sorted(v[0:3]), sorted(v[3:6])
        return MaxProtru(rest_ul=ul[1], rest_ll=ll[1], max_ul=ul[2], max_ll=ll[2], min_ul=ul[0],
                         min_ll=ll[0])
    mp = {k: row(v) for k, v in table.items()}
    back = parse_maxprotru(format_maxprotru(mp))
    assert back.keys() == mp.keys()
    for k in mp:
        np.testing.assert_allclose(back[k], mp[k], atol=5e-7)
    lt = {k: abs(v[6]) + 1e-6 for k, v in table.items()}        # a thickness is positive
    back_lt = parse_lipthick(format_lipthick(lt))
    assert set(back_lt) == set(lt) and all(abs(back_lt[k] - lt[k]) < 5e-7 for k in lt)


def test_recording_shapes_are_checked_by_the_writer():
    rec = TaskRecording(None, "S", 1, 1, np.arange(3), np.zeros((3, 7, 2)), np.ones((3, 7), bool))
    with pytest.raises(CassiInputError, match="shapes"):
        format_txy(rec)
    assert len(PELLETS) == 8
