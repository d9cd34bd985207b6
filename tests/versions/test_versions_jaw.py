"""Jaw rotation: thesis Eqs. 3.3-3.6 and 4.1-4.7, Tables 3.2 and 4.3."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cassi.versions import constants as K
from cassi.versions.jaw import (apply_zones, fixed_pivot_motion, jaw_angle, line_angle,
                                rotate_about, rotation_point, solve_jaw_motion)


def test_eq_4_1_to_4_3_hand_case():
    # Original jaw line: MANi (0, 0), MANm (-40, 0): tan(alpha) = (0 - 0) / (0 + 40) = 0, alpha = 0.
    # Current: MANi (0, -4), MANm (-40, 0): tan(beta) = (-4 - 0) / (0 + 40) = -0.1,
    # beta = atan(-0.1) = -0.09966865249116204; theta = alpha - beta = +0.0996686... (jaw opens).
    assert line_angle(np.array([0.0, 0.0]), np.array([-40.0, 0.0])) == 0.0
    theta = jaw_angle(np.array([0.0, 0.0]), np.array([-40.0, 0.0]),
                      np.array([0.0, -4.0]), np.array([-40.0, 0.0]))
    assert theta == pytest.approx(0.09966865249116204, abs=1e-15)


def test_eq_3_3_3_4_hand_case():
    # (10, 0) about (5, 5) by 90 degrees: dx = 5, dz = -5;
    # x' = 5 cos 90 + (-5) sin 90 + 5 = 0; z' = (-5) cos 90 - 5 sin 90 + 5 = 0.
    out = rotate_about(np.array([[10.0, 0.0]]), np.array([math.pi / 2]), np.array([[5.0, 5.0]]))
    np.testing.assert_allclose(out, [[[0.0, 0.0]]], atol=1e-12)


def test_eq_4_6_4_7_hand_cases():
    # About the origin by 90 deg, Eq. 4.4-4.5 send (10, 0) to (0, -10). With cos = 0, sin = 1:
    # b = ((-10 + 10 - 0)(1) - (0 - 0 - 0)(1)) / 2 = 0; a = (-10 + 10 - 0 - 0) / 1 = 0.
    a, b = rotation_point(10.0, 0.0, 0.0, -10.0, math.pi / 2)
    assert (float(a), float(b)) == pytest.approx((0.0, 0.0), abs=1e-12)
    # About (5, 5) by 90 deg, (10, 0) goes to (0, 0) (see the Eq. 3.3 case):
    # b = ((0 + 10 - 0)(1) - (0 - 0 - 0)(1)) / 2 = 5; a = (0 + 10 - 0 - 5 (1)) / 1 = 5.
    a, b = rotation_point(10.0, 0.0, 0.0, 0.0, math.pi / 2)
    assert (float(a), float(b)) == pytest.approx((5.0, 5.0), abs=1e-12)


def test_point_of_rotation_undefined_at_zero_angle():
    a, b = rotation_point(1.0, 2.0, 1.5, 2.0, 0.0)
    assert np.isnan(a) and np.isnan(b)


def test_table_4_3_fractions_are_parke_times_1_11111():
    # Table 4.3 prints Parke's fraction x 1.11111 per zone: 1.11111, 0.999999, 0.8333325,
    # 0.555555, 0.3888885; every CASSI zone must be its Parke zone's fraction times 1.11111.
    printed = K.TABLE_4_3_PRINTED
    parke = {z.name.split()[0]: z.fraction for z in K.PARKE_ZONES}
    for zone in K.CASSI10_ZONES:
        key = zone.name.split()[0]
        assert zone.fraction == pytest.approx(printed[key], abs=5e-8)
        assert zone.fraction == pytest.approx(parke[key] * K.CASSI_FRACTION_FACTOR, abs=5e-8)


def test_cassi_zones_move_22_30_and_drop_lower_lip():
    cassi = {v for z in K.CASSI10_ZONES for v in z.vertices}
    parke = {v for z in K.PARKE_ZONES for v in z.vertices}
    assert not cassi & set(range(49, 61)), "1.0 no longer rotates the lower lip (4.1.2)"
    assert set(range(49, 61)) <= parke
    third = {v for z in K.CASSI10_ZONES if z.name.startswith("3rd") for v in z.vertices}
    assert {22, 30} <= third
    first = {v for z in K.CASSI10_ZONES if z.name.startswith("1st") for v in z.vertices}
    assert not {22, 30} & first and set(range(14, 44)) - {22, 30} == first


angles = st.floats(min_value=1e-3, max_value=0.7).flatmap(
    lambda t: st.sampled_from([t, -t]))
coords = st.floats(min_value=-200.0, max_value=200.0)


@settings(max_examples=200, deadline=None)
@given(theta=angles, a=coords, b=coords, x1=coords, y1=coords,
       length=st.floats(min_value=20.0, max_value=120.0),
       incline=st.floats(min_value=-1.0, max_value=1.0))
def test_rotated_jaw_gives_back_angle_and_point(theta, a, b, x1, y1, length, incline):
    # A jaw line of the given length and incline, rotated by theta about (a, b) with Eq. 3.3-3.4:
    # Eqs. 4.1-4.3 must return theta and Eqs. 4.6-4.7 must return (a, b).
    p1 = np.array([x1, y1])
    p2 = p1 - length * np.array([math.cos(incline), math.sin(incline)])
    q = rotate_about(np.stack([p1, p2]), np.array(theta), np.array([a, b]))
    motion = solve_jaw_motion(p1, p2, q[None, 0], q[None, 1])
    assert motion.theta[0] == pytest.approx(theta, abs=1e-9)
    scale = 1.0 + max(abs(a), abs(b), abs(x1), abs(y1))
    np.testing.assert_allclose(motion.point[0], [a, b], atol=1e-7 * scale / abs(theta))


@settings(max_examples=100, deadline=None)
@given(theta=angles, a=coords, b=coords, f=st.sampled_from([z.fraction for z in K.CASSI10_ZONES]))
def test_zones_rotate_by_their_fraction(theta, a, b, f):
    # A zone with fraction f rotated by theta about (a, b) is the same as Eq. 3.5-3.6 by f*theta.
    base = np.zeros((4, 3))
    base[:, 0] = [10.0, -5.0, 30.0, 0.0]
    base[:, 2] = [-20.0, 4.0, 1.0, 7.0]
    base[:, 1] = [1.0, 2.0, 3.0, 4.0]
    zone = K.Zone("test", f, (1, 2, 3))
    motion = fixed_pivot_motion(np.array([theta]), np.array([a, b]))
    out = apply_zones(base, motion, [zone])
    want = rotate_about(base[:3][:, [0, 2]], np.array(f * theta), np.array([a, b]))
    np.testing.assert_allclose(out[0, :3][:, [0, 2]], want, atol=1e-9)
    np.testing.assert_array_equal(out[0, :, 1], base[:, 1])     # y (lateral) never rotates
    np.testing.assert_array_equal(out[0, 3], base[3])            # vertex 4 not in the zone


def test_z_only_zone_keeps_x():
    base = np.array([[10.0, 0.0, -10.0]])
    motion = fixed_pivot_motion(np.array([0.3]), np.array([0.0, 0.0]))
    out = apply_zones(base, motion, [K.Zone("neck", 0.5, (1,), "z")])
    assert out[0, 0, 0] == 10.0
    # z' = (z - 0) cos(0.15) - (x - 0) sin(0.15)
    assert out[0, 0, 2] == pytest.approx(-10 * math.cos(0.15) - 10 * math.sin(0.15))


def test_tiny_angle_is_continuous_with_translation():
    # Same jaw line moved by a pure translation, and by a tiny rotation: zone vertices must move
    # by (almost) the fraction times the translation, never by something huge.
    p1, p2 = np.array([0.0, 0.0]), np.array([-40.0, 0.0])
    shift = np.array([0.5, -0.25])
    for eps in (0.0, 1e-12, 1e-8, 1e-6):
        q1 = rotate_about(p1[None], np.array(eps), p1 + [20.0, 0.0])[0] + shift
        q2 = rotate_about(p2[None], np.array(eps), p1 + [20.0, 0.0])[0] + shift
        motion = solve_jaw_motion(p1, p2, q1[None], q2[None])
        base = np.array([[5.0, 0.0, -3.0]])
        out = apply_zones(base, motion, [K.Zone("z", 0.9, (1,))])
        moved = out[0, 0, [0, 2]] - base[0, [0, 2]]
        np.testing.assert_allclose(moved, 0.9 * (q1 - p1), atol=1e-4)


def test_vectorised_over_frames_matches_per_frame():
    rng = np.random.default_rng(3)
    F = 50
    p1, p2 = np.array([0.0, 0.0]), np.array([-45.0, -5.0])
    th = rng.uniform(-0.3, 0.3, F)
    ctr = rng.uniform(-80, 20, (F, 2))
    q = np.stack([rotate_about(np.stack([p1, p2]), th[i], ctr[i]) for i in range(F)])
    motion = solve_jaw_motion(p1, p2, q[:, 0], q[:, 1])
    np.testing.assert_allclose(motion.theta, th, atol=1e-9)
    base = rng.normal(size=(10, 3)) * 30
    zones = [K.Zone("a", 0.75, (1, 2, 3)), K.Zone("b", 1.0, (5, 9), "z")]
    out = apply_zones(base, motion, zones)
    for i in (0, 17, 49):
        one = fixed_pivot_motion(th[i:i + 1], motion.point[i])
        np.testing.assert_allclose(out[i], apply_zones(base, one, zones)[0], atol=1e-8)


def test_anchor_point_follows_exactly():
    # Jaw line lengths differ (40 -> 42): no rotation carries one onto the other, so only the
    # anchor point can land exactly; anchor 1 (MANi, the default) or anchor 2 (MANm).
    p1, p2 = np.array([0.0, 0.0]), np.array([-40.0, 0.0])
    q1, q2 = np.array([[1.0, -5.0]]), np.array([[-40.0, 2.0]])
    for anchor, src, dst in ((1, p1, q1[0]), (2, p2, q2[0])):
        motion = solve_jaw_motion(p1, p2, q1, q2, anchor=anchor)
        out = apply_zones(np.array([[src[0], 0.0, src[1]]]), motion, [K.Zone("z", 1.0, (1,))])
        np.testing.assert_allclose(out[0, 0, [0, 2]], dst, atol=1e-9)
    with pytest.raises(ValueError):
        solve_jaw_motion(p1, p2, q1, q2, anchor=3)
