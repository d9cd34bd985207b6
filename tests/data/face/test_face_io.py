"""Parke's st1.pts / st2.pts / stt.top formats: the thesis's excerpts load, writers round-trip,
bad input names file and line."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.parke_io import (Polygon, PtsFile, TopFile, read_pts, read_top, write_pts,
                                 write_top)

# Thesis Figure 3.2: the first vertices of Parke's st1.pts.
FIGURE_3_2 = {1: (45, 0, -594), 2: (28, 50, -585), 5: (-90, 187, -518), 16: (326, 0, -423),
              17: (302, 60, -418)}


def test_thesis_excerpt_pts_loads(fixtures_dir):
    path = fixtures_dir / "parke" / "st1_excerpt.pts"
    with pytest.raises(CassiInputError) as err:
        read_pts(path)  # the header says 275 defined vertices; the excerpt has 17
    assert ":2:" in str(err.value) and "275" in str(err.value)
    pts = read_pts(path, strict=False)
    assert pts.description.startswith("st1.pts - first vertices set FIP 10 May 90")
    assert pts.count == 287
    assert int(pts.defined.sum()) == 17
    for n, xyz in FIGURE_3_2.items():
        np.testing.assert_array_equal(pts.vertices[n - 1], xyz)
    assert np.isnan(pts.vertices[17:]).all()


def test_thesis_excerpt_top_loads(fixtures_dir):
    path = fixtures_dir / "parke" / "stt_excerpt.top"
    with pytest.raises(CassiInputError):
        read_top(path)
    top = read_top(path, strict=False)
    assert len(top.polygons) == 20
    first = top.polygons[0]
    assert first.material == 4 and first.vertices == (222, 212, 190) and first.crease == (1, 1, 1)
    assert top.polygons[1] == Polygon(4, (223, 224, 225, 226))
    assert top.polygons[-3] == Polygon(1, (1, 6, 7, 2))
    # Parke's winding: with Figure 3.2's vertices, 1 6 7 2 runs clockwise seen from outside
    # (its right-hand normal points into the neck, toward -x).
    pts = read_pts(fixtures_dir / "parke" / "st1_excerpt.pts", strict=False).vertices
    a, b, c = (pts[v - 1] for v in (1, 6, 7))
    assert np.cross(b - a, c - a)[0] < 0


def test_real_file_quirks(tmp_path):
    p = tmp_path / "st1.pts"
    p.write_bytes(b"desc\r\n3 2\r\n\r\n1\t1.5  2 -3\r\n3 4 5 6")  # CRLF, tabs, no final newline
    pts = read_pts(p)
    np.testing.assert_array_equal(pts.vertices[0], (1.5, 2, -3))
    assert pts.defined.tolist() == [True, False, True]


@pytest.mark.parametrize("text, line, what", [
    ("d\n2 2\n1 0 0 0\n", 2, "defined"),
    ("d\n2 1\n3 0 0 0\n", 3, "outside"),
    ("d\n2 2\n1 0 0 0\n1 1 1 1\n", 4, "twice"),
    ("d\n2 1\n1 0 zero 0\n", 3, "not a number"),
    ("d\n2 1\n1 0 0\n", 3, "number x y z"),
    ("d\nmany\n", 2, "integer"),
    ("d\n2000000000 0\n", 2, "beyond any face"),          # not 45 GiB of vertices
    ("d\n2 1\n\u0661 0 0 0\n", 3, "not an integer"),          # ASCII digits, as Parke wrote
    ("d\n2 1\n1 1_000 0 0\n", 3, "not a number"),
    ("d\n2 1\n1 1e-05 -2.5E+3 .5\n", None, None),           # repr's exponents read back
])
def test_bad_pts_names_line(tmp_path, text, line, what):
    p = tmp_path / "bad.pts"
    p.write_text(text)
    if line is None:
        np.testing.assert_array_equal(read_pts(p, strict=False).vertices[0], [1e-05, -2500.0, 0.5])
        return
    with pytest.raises(CassiInputError) as err:
        read_pts(p)
    assert f"bad.pts:{line}:" in str(err.value) and what in str(err.value)


@pytest.mark.parametrize("text, line", [
    ("d\n2\n1 1 2 3\n", 2),             # count mismatch
    ("d\n1\n1 1 2\n", 3),               # too few vertices
    ("d\n1\n1 1 2 x\n", 3),             # not a number
    ("d\n1\n1 1 2 2\n", 3),             # repeated vertex
    ("d\n1\n1 1 2 3.a\n", 3),           # bad crease suffix
    ("d\n1\n1 1 2 3 4 5\n", 3),         # a pentagon: Parke's are triangles and quads
    ("d\n1\n-7 1 2 3\n", 3),            # no material -7
    ("d\n1\n1 1 2 \u0663\n", 3),         # ASCII digits only
])
def test_bad_top_names_line(tmp_path, text, line):
    p = tmp_path / "bad.top"
    p.write_text(text)
    with pytest.raises(CassiInputError) as err:
        read_top(p)
    assert f"bad.top:{line}:" in str(err.value)


coords = st.floats(min_value=-1e4, max_value=1e4, allow_nan=False, allow_infinity=False)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(coords, coords, coords), min_size=1, max_size=30),
       st.lists(st.booleans(), min_size=30, max_size=30))
def test_pts_round_trip(tmp_path_factory, xyz, keep):
    v = np.array(xyz, float)
    mask = np.array(keep[:len(v)])
    mask[0] = True
    v[~mask] = np.nan
    path = tmp_path_factory.mktemp("pts") / "st.pts"
    write_pts(path, PtsFile("round trip", v))
    back = read_pts(path)
    assert back.description == "round trip"
    np.testing.assert_array_equal(back.defined, mask)
    np.testing.assert_array_equal(back.vertices[mask], v[mask])


polygon = st.builds(
    lambda mat, vs, cr: Polygon(mat, tuple(vs), tuple(cr[:len(vs)])),
    st.integers(1, 12), st.lists(st.integers(1, 500), min_size=3, max_size=4, unique=True),
    st.lists(st.integers(0, 3), min_size=4, max_size=4))


@settings(max_examples=40, deadline=None)
@given(st.lists(polygon, min_size=0, max_size=25))
def test_top_round_trip(tmp_path_factory, polys):
    path = tmp_path_factory.mktemp("top") / "stt.top"
    write_top(path, TopFile("topology", tuple(polys)))
    back = read_top(path)
    assert back.polygons == tuple(polys)


def test_writers_reject_multiline_description(tmp_path):
    with pytest.raises(CassiInputError):
        write_pts(tmp_path / "x.pts", np.zeros((1, 3)), "two\nlines")
