"""Parke's parameters (thesis Table 3.1) and eyes (dissertation 3.1, Appendix A)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cassi.data.face import eyes as E
from cassi.data.face import numbering as N
from cassi.common.errors import CassiInputError
from cassi.data.face.model import build_face
from cassi.data.face.params import (PARAMETERS, apply_parameters, check_parameters,
                                    jaw_rotation, look_at, start_values)


@pytest.fixture(scope="module")
def face():
    return build_face()


def v(face, n):
    return face.vertices[n - 1]


# --- the table ---------------------------------------------------------------------------------

def test_start_values_match_table_3_1():
    # (number, start) pairs as printed in the thesis's Table 3.1
    table = {1: .9, 2: .5, 3: 0, 4: 0, 5: 1, 6: 1, 7: 1, 8: 1, 9: 1, 10: 1, 11: 1, 12: 1, 13: 1,
             14: 0, 15: 0, 16: 0, 17: 0, 18: 0, 19: 1, 20: 1, 21: 0, 22: 15, 26: 0, 27: 0,
             28: 0, 29: 0, 30: -15, 31: 0, 32: 0, 35: 1, 36: 1, 37: 1, 38: 0, 39: 0, 40: 0,
             41: .4, 42: .85, 43: .4, 44: 70, 45: 80, 46: 0, 47: 0, 48: 38, 50: 1}
    assert start_values() == {k: float(x) for k, x in table.items()}
    for p in PARAMETERS.values():
        assert p.low <= p.start <= p.high, p
    # the ranges the thesis states "(a - b)"
    assert (PARAMETERS[1].low, PARAMETERS[1].high) == (0, 1)
    assert (PARAMETERS[4].low, PARAMETERS[4].high) == (0, 20)
    assert (PARAMETERS[50].low, PARAMETERS[50].high) == (0, 1)


@pytest.mark.parametrize("number, value", [(4, 20.5), (4, -1), (1, 1.2), (44, 20), (22, 31)])
def test_out_of_range_is_an_error_unless_clamped(face, number, value):
    with pytest.raises(CassiInputError) as err:
        apply_parameters(face, {number: value})
    assert str(number) in str(err.value) and PARAMETERS[number].name in str(err.value)
    clamped = apply_parameters(face, {number: value}, clamp=True)
    p = PARAMETERS[number]
    assert clamped.parameters[number] == min(max(value, p.low), p.high)


@pytest.mark.parametrize("bad", [{99: 1.0}, {"x": 1.0}, {4: "wide"}, {4: float("nan")}])
def test_bad_parameters(bad):
    with pytest.raises(CassiInputError):
        check_parameters(bad)


def test_start_values_give_the_neutral_face(face):
    again = apply_parameters(face, start_values())
    np.testing.assert_array_equal(again.vertices, face.vertices)
    assert face.parameters == start_values()


# --- parameters acting on the face ----------------------------------------------------------

def test_jaw_rotation_zones(face):
    opened = apply_parameters(face, {4: 15.0})
    d = opened.vertices - face.vertices
    pivot = v(face, N.JAW_PIVOT)
    # the chin swings down and back about 107 by 15 degrees (1st zone)
    r0 = v(face, N.MENTON)[[0, 2]] - pivot[[0, 2]]
    r1 = v(opened, N.MENTON)[[0, 2]] - pivot[[0, 2]]
    ang = np.degrees(np.arctan2(r0[1], r0[0]) - np.arctan2(r1[1], r1[0]))
    assert ang == pytest.approx(15.0, abs=1e-9)
    assert d[N.MENTON - 1, 2] < 0
    # lower teeth by 0.9 of the angle, the lower cheek by 0.35
    r0 = v(face, N.MANI)[[0, 2]] - pivot[[0, 2]]
    r1 = v(opened, N.MANI)[[0, 2]] - pivot[[0, 2]]
    assert np.degrees(np.arctan2(r0[1], r0[0]) - np.arctan2(r1[1], r1[0])) == \
        pytest.approx(13.5, abs=1e-9)
    # neck vertices 6-10: only z changes (Table 3.2's last column)
    neck = np.asarray(N.NECK) - 1
    assert np.all(d[neck, 0] == 0) and np.any(d[neck, 2] != 0)
    # upper teeth, upper lip, nose do not move
    for group in (N.UPPER_TEETH, N.UPPER_LIP, N.NOSE):
        assert np.all(d[np.asarray(group) - 1] == 0)
    # the mouth opens: lower lip centre drops away from the upper lip
    assert v(opened, N.LL)[2] < v(face, N.LL)[2] - 20


def test_jaw_rotation_cassi_zones(face):
    out = jaw_rotation(face.vertices, 10.0, zones=N.CASSI10_JAW_ZONES)
    assert np.all(out[np.asarray(N.LOWER_LIP) - 1] == face.vertices[np.asarray(N.LOWER_LIP) - 1])
    assert not np.allclose(out[21], face.vertices[21])          # 22 moves (3rd zone)


def test_eyelid_opening(face):
    closed = apply_parameters(face, {1: 0.0})
    opened = apply_parameters(face, {1: 1.0})
    lid = np.asarray(face.regions["eyelid"] + face.regions["eyelid_lip"]) - 1
    assert len(lid) == 24
    # the upper margin comes down to the lower one when closed
    gap = lambda f: f.vertices[lid, 2].max() - f.vertices[lid, 2].min()  # noqa: E731
    assert gap(closed) < gap(face) < gap(opened)
    np.testing.assert_allclose(opened.vertices[lid], face.st1[lid])
    np.testing.assert_allclose(closed.vertices[lid], face.st2[lid])
    # at every opening the lids lie on their spheres about the eyeball (interpolated in 2D,
    # projected, dissertation 3.1.2): the lid's lip just outside the eyeball
    c = face.eye_centres[0]
    lip = np.asarray(face.regions["eyelid_lip"]) - 1
    r_open = np.linalg.norm(face.st1[lip] - c, axis=1)
    for o in np.linspace(0, 1, 7):
        f = apply_parameters(face, {1: o})
        r = np.linalg.norm(f.vertices[lip] - c, axis=1)
        np.testing.assert_allclose(r, r_open)
        assert np.all(r > E.EyeParams().radius)


def test_eyelid_scales_and_radius(face):
    c = face.eye_centres[0]
    lid = np.asarray(face.regions["eyelid"]) - 1
    lip = np.asarray(face.regions["eyelid_lip"]) - 1
    wide = apply_parameters(face, {5: 1.1})
    assert np.ptp(wide.vertices[lip, 1]) == pytest.approx(np.ptp(face.vertices[lip, 1]) * 1.1)
    tall = apply_parameters(face, {6: 1.3})
    assert np.ptp(tall.vertices[lip, 2]) == pytest.approx(np.ptp(face.vertices[lip, 2]) * 1.3)
    far = apply_parameters(face, {45: 90.0})
    r0 = np.linalg.norm(face.vertices[lid] - c, axis=1)
    np.testing.assert_allclose(np.linalg.norm(far.vertices[lid] - c, axis=1), r0 * 90 / 80)


def test_brow_arch_and_mouth_expression(face):
    brow = np.asarray(face.regions["brow"]) - 1
    hi, lo = apply_parameters(face, {2: 1.0}), apply_parameters(face, {2: 0.0})
    mid = len(brow) // 2
    assert hi.vertices[brow[mid], 2] > face.vertices[brow[mid], 2] > lo.vertices[brow[mid], 2]
    frown = apply_parameters(face, {13: 0.0})
    assert v(frown, N.CORNER)[2] < v(face, N.CORNER)[2] - 5
    assert v(frown, N.UL)[2] == v(face, N.UL)[2]


@pytest.mark.parametrize("number, value, vertex, axis, sign", [
    (14, 10.0, N.UL, 0, 1), (16, 10.0, N.CORNER, 0, 1), (17, 10.0, N.CORNER, 1, 1),
    (18, -10.0, N.CORNER, 2, -1), (21, 10.0, N.LL, 2, -1), (22, 30.0, N.UL, 2, 1),
    (26, 10.0, N.NOSE_TIP_CENTRE, 0, 1), (27, -10.0, N.NOSE_TIP_CENTRE, 2, -1),
    (31, 10.0, N.POGONION, 0, 1), (32, -10.0, N.MENTON, 2, -1),
    (47, 10.0, N.TEETH_TIP, 0, 1), (48, 60.0, N.TEETH_TIP, 2, 1),
    (15, 10.0, N.INNER_CORNER, 1, 1), (12, 1.5, N.CORNER, 1, 1), (19, 1.5, 17, 1, 1),
    (20, 1.5, 47, 1, 1), (46, 0.1, 47, 1, 1), (35, 1.5, N.MENTON, 2, -1),
    (36, 1.5, N.MENTON, 2, -1), (37, 1.5, "forehead", 2, 1), (9, 1.2, "forehead", 2, 1),
    (7, 1.2, N.NOSE_TIP_CENTRE, 0, 1), (8, 1.2, N.CORNER, 1, 1),
])
def test_parameter_moves_its_region(face, number, value, vertex, axis, sign):
    if isinstance(vertex, str):
        vertex = face.regions[vertex][-1]
    moved = apply_parameters(face, {number: value})
    delta = v(moved, vertex)[axis] - v(face, vertex)[axis]
    assert sign * delta > 0.5, (number, delta)


def test_jaw_scale_tapers_to_zero_at_the_back(face):
    wide = apply_parameters(face, {19: 1.5})
    jaw = np.asarray(N.JAW) - 1
    back = jaw[np.argmin(face.vertices[jaw, 0])]
    assert wide.vertices[back, 1] == pytest.approx(face.vertices[back, 1])


# --- eyes ------------------------------------------------------------------------------------

def _gaze(face, k):
    first = face.eyes_first + k * E.VERTS_PER_EYE
    return E.gaze_direction(face.vertices[first - 1:first - 1 + E.VERTS_PER_EYE])


@settings(max_examples=25, deadline=None)
@given(st.floats(300, 3000), st.floats(-800, 800), st.floats(-600, 600))
def test_eyes_look_at_a_point(x, y, z):
    face = build_face()
    target = np.array([x, y, z])
    looking = look_at(face, target)
    for k in range(2):
        c = looking.eye_centres[k]
        want = (target - c) / np.linalg.norm(target - c)
        np.testing.assert_allclose(_gaze(looking, k), want, atol=1e-9)


def test_eyes_converge_on_a_near_point(face):
    near = look_at(face, np.array([500.0, 0.0, 20.0]))
    left, right = _gaze(near, 0), _gaze(near, 1)
    assert left[1] < 0 < right[1]                        # both turn toward the nose
    assert left[1] == pytest.approx(-right[1])


def test_orientation_angles_appendix_a():
    a, b = E.orientation_angles((0, 0, 0), (10, 10, 0))
    assert a == pytest.approx(np.pi / 4) and b == pytest.approx(0)
    a, b = E.orientation_angles((0, 0, 5), (10, 0, 0))      # target below: beta > 0
    assert a == pytest.approx(0) and b == pytest.approx(np.arctan2(5, 10))


def test_eyeball_construction():
    p = E.EyeParams()
    local = E.eyeball_local(p)
    assert local.shape == (E.VERTS_PER_EYE, 3)
    polys = E.eyeball_polygons(1)
    mats = [m for m, _ in polys]
    from cassi.data.face.build import FRINGE, IRIS, PUPIL, REFLECTION
    assert mats.count(PUPIL) == E.SIDES and mats.count(IRIS) == E.SIDES
    assert mats.count(FRINGE) == E.SIDES and mats.count(REFLECTION) == E.SPOT_SIDES
    # all ball vertices on the sphere; pupil, fringe-inner and iris rings at their fractions
    ball = local[:1 + E.SIDES * (3 + len(E.WHITE_RINGS_DEG)) + 1]
    np.testing.assert_allclose(np.linalg.norm(ball, axis=1), p.radius)
    rings = local[1:1 + 3 * E.SIDES].reshape(3, E.SIDES, 3)
    radii = np.linalg.norm(rings[:, :, 1:], axis=2).mean(axis=1) / p.radius
    np.testing.assert_allclose(radii, [p.iris_fraction * p.pupil_fraction,
                                       p.iris_fraction * p.fringe_fraction, p.iris_fraction])
    # the reflection spot: a hexagon in front of the iris, tangent to the lens sphere
    spot = local[-E.SPOT_SIDES:]
    lc = (np.sqrt(1 - p.iris_fraction ** 2) - p.iris_fraction) * p.radius
    d = np.linalg.norm(spot - [lc, 0, 0], axis=1)
    assert np.ptp(d) < 1e-9 and np.all(spot[:, 0] > p.radius * 0.9)


def test_eye_parameters_rebuild_the_eyeball(face):
    big = apply_parameters(face, {44: 80.0, 43: 0.5})
    first = face.eyes_first
    ball = big.vertices[first - 1:first - 1 + 2 + E.SIDES * 8]
    np.testing.assert_allclose(np.linalg.norm(ball - big.eye_centres[0], axis=1), 80.0)
    moved = apply_parameters(face, {28: 10.0})
    assert v(moved, first)[0] == pytest.approx(v(face, first)[0] + 10.0)


def test_parameters_on_a_parke_sized_model(face):
    """Parke's own files: 287 vertices, some undefined, no eyes, no region names."""
    from cassi.data.face.model import FaceModel
    st1 = face.st1[:287].copy()
    st1[[101, 102, 103, 104, 105]] = np.nan          # vertices 102-106 undefined
    parke = FaceModel(st1, (), st1=st1, st2=st1.copy())
    out = apply_parameters(parke, {4: 12.0, 19: 1.2, 20: 1.1, 35: 1.1, 36: 0.9, 37: 1.2,
                                   10: 1.2, 12: 1.1, 14: 5, 16: 3, 22: 20, 47: 5, 46: 0.05})
    defined = ~np.isnan(st1).any(axis=1)
    assert np.isfinite(out.vertices[defined]).all()
    assert np.isnan(out.vertices[~defined]).all()
    assert v(out, N.LL)[2] < v(parke, N.LL)[2]      # the jaw still opens


@pytest.mark.parametrize("opening", [0.0, 0.5, 0.9, 1.0])
def test_skin_clears_the_eyeball(face, opening):
    """No skin (lids included) dips into the eyeball at any eyelid opening."""
    from cassi.data.face.topology import render_topology
    f = apply_parameters(face, {1: opening})
    topo = render_topology(f, half=True)
    verts, tri, part = topo.mesh(f.vertices)
    names = list(topo.parts)
    shell = tri[np.isin(part, [names.index(n) for n in ("skin", "eyelash", "eyebrow")])]
    w = np.array([(a, b, 1 - a - b) for a in np.linspace(0, 1, 7) for b in np.linspace(0, 1, 7)
                  if a + b <= 1])
    samples = np.einsum("kj,tjd->tkd", w, verts[shell])
    d = np.linalg.norm(samples - f.eye_centres[0], axis=2)
    assert d.min() >= E.EyeParams().radius


def test_reflection_spot_follows_light_and_viewer(face):
    """Appendix A: the spot sits where the half-way direction of light and viewer meets the
    lens, so it moves toward the light."""
    first = face.eyes_first
    spot = slice(first - 1 + E.VERTS_PER_EYE - E.SPOT_SIDES, first - 1 + E.VERTS_PER_EYE)
    up = look_at(face, [6000, 0, 22], light=[1, 0, 1], viewer=[1, 0, 0])
    down = look_at(face, [6000, 0, 22], light=[1, 0, -1], viewer=[1, 0, 0])
    assert up.vertices[spot, 2].mean() > down.vertices[spot, 2].mean() + 5
