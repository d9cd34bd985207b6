"""CASSI 2.0/2.1 lip equations against hand-computed cases (thesis 4.2-4.3).

Each case writes its derivation next to the expected number; the numbers were worked out by hand
from the equations as printed in the thesis, not by running the code.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cassi.common.errors import CassiInputError
from cassi.versions import lips_constants as K
from cassi.versions.lips_ellipse import (
    BRANCH_LABELS,
    OuterAbcParams,
    OuterAbcState,
    _step_state,
    c_prime,
    ellipse_z,
    focal_c,
    is_vertical,
    limit_abc,
    major_a,
    mid_inner_abc,
    outer_abc_sequence,
    outer_abc_step,
)
from cassi.versions.lips_thickness import (
    EQUAL_THICKNESS,
    LOW_LIPS_THICKNESS,
    blend_inner_corner_z,
    centreline_z,
    current_thickness,
    hermite_f1,
    hermite_f2,
    LowLipsReading,
    is_low_lips,
    low_lips_margin,
    rounding_t,
    thick_from_lipthick,
)
from cassi.versions.lips_track import track_x, track_y_for_x

# Explicit tuning for the hand-worked OUTER_ABC_CALC cases, so they do not depend on the chosen
# defaults in lips_constants.
P = OuterAbcParams(rho=0.3, near_c_rest=5.0, small_c_prime=25.0, c_rest=65.0)
#: The thesis's key c values and rounding onset (on the thesis's face), for the hand-worked cases;
#: the defaults are rescaled to this project's face (lips_constants.C_SCALE).
THESIS_C = {"c_rest": 65.0, "c_min": 0.0, "c_max": 85.0}
THESIS_ONSET = 50.0


# --- Equation 4.13 ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "x, expected",
    [
        # forward of rest: (x - 10)(0 - 65)/(20 - 10) + 65
        (15.0, 5 * (-6.5) + 65),   # = 32.5, half way to fully rounded
        (20.0, 0.0),               # x_max -> c_min
        (25.0, -32.5),             # beyond x_max: not clipped
        # at or behind rest: (x - 10)(85 - 65)/(0 - 10) + 65
        (10.0, 65.0),              # x_rest -> c_rest ("otherwise" branch, 0 + 65)
        (5.0, (-5) * 20 / (-10) + 65),  # = 75
        (0.0, 85.0),               # x_min -> c_max
    ],
)
def test_eq_4_13_c_prime(x, expected):
    assert c_prime(x, 10.0, 20.0, 0.0, **THESIS_C) == pytest.approx(expected)


def test_eq_4_13_vectorised_and_thesis_constants():
    x = np.array([15.0, 20.0, 0.0, 10.0])
    np.testing.assert_allclose(c_prime(x, 10.0, 20.0, 0.0, **THESIS_C), [32.5, 0.0, 85.0, 65.0])
    # the defaults: the thesis's key values rescaled to this face, the same place on Eq. 4.13
    assert K.THESIS_C_REST == 65.0
    assert (K.C_REST, K.C_MIN, K.C_MAX) == pytest.approx((83.4, 0.0, 85.0 * 83.4 / 65.0))
    np.testing.assert_allclose(c_prime(x, 10.0, 20.0, 0.0), [32.5 * K.C_SCALE, 0.0, K.C_MAX,
                                                             K.C_REST])


@pytest.mark.parametrize("rest, mx, mn", [(10, 10, 0), (10, 20, 10), (10, 5, 20)])
def test_eq_4_13_rejects_unordered_key_values(rest, mx, mn):
    with pytest.raises(CassiInputError, match="MIN UL < REST UL < MAX UL"):
        c_prime(1.0, rest, mx, mn)


# --- Equations 4.8 and 4.14 ------------------------------------------------------------------
def test_eq_4_8_and_4_14_pythagorean_triples():
    assert major_a(3.0, 4.0) == pytest.approx(5.0)           # sqrt(9 + 16)
    assert focal_c(5.0, 3.0) == pytest.approx(4.0)           # horizontal: sqrt(25 - 9)
    assert focal_c(3.0, 5.0) == pytest.approx(4.0)           # switched: sqrt(25 - 9)
    assert focal_c(4.0, 4.0) == pytest.approx(0.0)           # the switch itself: c = 0
    assert not is_vertical(5.0, 3.0) and is_vertical(3.0, 5.0) and is_vertical(4.0, 4.0)


@given(st.floats(0.1, 200), st.floats(0.1, 200))
def test_eq_4_14_inverts_4_8_for_horizontal(b, c):
    a = major_a(b, c)
    assert focal_c(a, b) == pytest.approx(c, rel=1e-6, abs=1e-6)


# --- Algorithm OUTER_ABC_CALC (Figure 4.18) -----------------------------------------------------
def _step(b, cp, prev=(50.0, 30.0, 40.0), new=False):
    return outer_abc_step(b, cp, *prev, new, P)


def test_outer_new_subject():
    # Step 3: c := c' = 40, a = sqrt(30^2 + 40^2) = 50.
    a, c, br = _step(30.0, 40.0, prev=(0.0, 0.0, 0.0), new=True)
    assert (a, c, BRANCH_LABELS[br]) == (pytest.approx(50.0), 40.0, "3")


def test_outer_3a_lips_dropping():
    # Height 30 -> 40 (increasing), c' = 63 within 5 of 65:
    # a = 50 + (30 - 40)/10 = 49; c = sqrt(49^2 - 40^2) = sqrt(801).
    a, c, br = _step(40.0, 63.0)
    assert a == pytest.approx(49.0)
    assert c == pytest.approx(math.sqrt(801.0))
    assert BRANCH_LABELS[br] == "3a"


def test_outer_3b_lips_rising():
    # Height 30 -> 20 (decreasing), c' = 67: a = 50 + (30 - 20)/10 = 51;
    # c = sqrt(51^2 - 20^2) = sqrt(2201).
    a, c, br = _step(20.0, 67.0)
    assert a == pytest.approx(51.0)
    assert c == pytest.approx(math.sqrt(2201.0))
    assert BRANCH_LABELS[br] == "3b"


def test_outer_3c_ii_horizontal():
    # c' = 20 is not near 65: c = 0.3*20 + 0.7*40 = 34; b = 35 < prev_a = 50 (horizontal):
    # a = sqrt(35^2 + 34^2) = sqrt(2381).
    a, c, br = _step(35.0, 20.0)
    assert c == pytest.approx(34.0)
    assert a == pytest.approx(math.sqrt(2381.0))
    assert BRANCH_LABELS[br] == "3c-ii"


def test_outer_3c_iii_may_be_vertical():
    # c' = 40: not near rest, not small (>= 25); b = 55 >= prev_a = 50:
    # a = 50 - (30 - 55)/10 = 52.5; c = sqrt(55^2 - 52.5^2) = sqrt(268.75) (vertical).
    a, c, br = _step(55.0, 40.0)
    assert a == pytest.approx(52.5)
    assert c == pytest.approx(math.sqrt(268.75))
    assert BRANCH_LABELS[br] == "3c-iii"
    assert is_vertical(a, 55.0)


def test_outer_3c_ii_small_c_prime_overrides_vertical():
    # Same tall height 55 but c' = 10 < 25 (round lips): c = 0.3*10 + 0.7*40 = 31;
    # a = sqrt(55^2 + 31^2) = sqrt(3986).
    a, c, br = _step(55.0, 10.0)
    assert c == pytest.approx(31.0)
    assert a == pytest.approx(math.sqrt(3986.0))
    assert BRANCH_LABELS[br] == "3c-ii"


def test_outer_unchanged_height_near_rest_goes_to_3c():
    # Neither increasing nor decreasing: 3(c). c = 0.3*65 + 0.7*40 = 47.5;
    # a = sqrt(30^2 + 47.5^2) = sqrt(3156.25).
    a, c, br = _step(30.0, 65.0)
    assert c == pytest.approx(47.5)
    assert a == pytest.approx(math.sqrt(3156.25))
    assert BRANCH_LABELS[br] == "3c-ii"


def test_outer_state_carries_previous_values():
    # Frame 0: NewSubject (a = 50, c = 40); frame 1: height 30 -> 40, c' = 63: 3a, a = 49.
    st_ = OuterAbcState()
    _step_state(st_, 30.0, 40.0, P)
    assert (st_.prev_a, st_.prev_b, st_.prev_c, st_.new_subject) == (
        pytest.approx(50.0), 30.0, 40.0, False)
    a, c, br = _step_state(st_, 40.0, 63.0, P)
    assert a == pytest.approx(49.0) and BRANCH_LABELS[br] == "3a"
    assert st_.prev_b == 40.0


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.floats(0, 120), st.floats(-40, 120)), min_size=1, max_size=60),
    st.integers(0, 60),
)
def test_outer_sequence_equals_stepwise_and_chunks(rows, cut):
    b = np.array([r[0] for r in rows])
    cp = np.array([r[1] for r in rows])
    whole = outer_abc_sequence(b, cp, params=P)
    st_ = OuterAbcState()
    steps = [_step_state(st_, float(bi), float(ci), P) for bi, ci in zip(b, cp)]
    np.testing.assert_allclose(whole.a, [s[0] for s in steps])
    np.testing.assert_allclose(whole.c, [s[1] for s in steps])
    assert whole.branch.tolist() == [s[2] for s in steps]
    assert whole.branch[0] == 0 and (whole.branch[1:] != 0).all()
    # Processing in two chunks with a carried state gives the same result.
    cut = min(cut, len(b))
    st2 = OuterAbcState()
    first = outer_abc_sequence(b[:cut], cp[:cut], params=P, state=st2)
    second = outer_abc_sequence(b[cut:], cp[cut:], params=P, state=st2)
    np.testing.assert_allclose(np.concatenate([first.a, second.a]), whole.a)


def test_outer_params_validated():
    with pytest.raises(CassiInputError):
        OuterAbcParams(rho=0.0)
    with pytest.raises(CassiInputError):
        OuterAbcParams(rho=1.5)


def test_step7_limits():
    a, c = limit_abc([10.0, 60.0, 500.0], [-1.0, 50.0, 200.0], a_min=40, a_max=110, c_limit=85)
    np.testing.assert_allclose(a, [40.0, 60.0, 110.0])
    np.testing.assert_allclose(c, [0.0, 50.0, 85.0])


# --- MID_INNER_ABC_CALC and Equation 4.16 ---------------------------------------------------------
def test_mid_inner_abc():
    # b = (10 - 4)/2 = 3, a = corner y = 5, c = sqrt(25 - 9) = 4.
    a, b, c = mid_inner_abc(np.array([10.0]), np.array([4.0]), np.array([5.0]))
    assert (a[0], b[0], c[0]) == (5.0, 3.0, pytest.approx(4.0))


def test_eq_4_16_outline():
    # a = 6, b = 2, k = 10. y = 0: 10 +/- 2. y = 3: 10 +/- sqrt(4 - 9*4/36) = 10 +/- sqrt(3).
    # y = a and beyond (vertex 70 past a): z = k.
    y = np.array([0.0, 3.0, 6.0, 9.0])
    np.testing.assert_allclose(ellipse_z(y, 6.0, 2.0, 10.0, upper=True),
                               [12.0, 10 + math.sqrt(3), 10.0, 10.0])
    np.testing.assert_allclose(ellipse_z(y, 6.0, 2.0, 10.0, upper=False),
                               [8.0, 10 - math.sqrt(3), 10.0, 10.0])


def test_eq_4_16_at_thirds():
    # a = 9, b = 3, k = 0: y = a/3 = 3 -> 3 sqrt(1 - 1/9) = sqrt(8); y = 2a/3 = 6 -> 3 sqrt(5/9)
    # = sqrt(5).
    z = ellipse_z(np.array(K.OUTLINE_FRACTIONS) * 9.0, 9.0, 3.0, 0.0, upper=True)
    np.testing.assert_allclose(z, [3.0, math.sqrt(8), math.sqrt(5)])


# --- Equation 4.19 -----------------------------------------------------------------------------
def test_eq_4_19_track():
    # x = y^2/(4p) + h with p = -37: y = 74 -> 5476 / -148 + 100 = -37 + 100 = 63.
    assert track_x(74.0, 100.0) == pytest.approx(63.0)
    assert track_x(0.0, 100.0) == pytest.approx(100.0)
    assert K.TRACK_P == -37.0
    assert track_y_for_x(63.0, 100.0) == pytest.approx(74.0)
    with pytest.raises(CassiInputError):
        track_x(1.0, 0.0, p=5.0)


# --- Section 4.2.3: thickness --------------------------------------------------------------------
def test_thick_from_lipthick():
    # 0.6 (per jaw length) * 200 (Parke jaw distance) / 2 (two lips) = 60.
    assert thick_from_lipthick(0.6, 200.0) == pytest.approx(60.0)
    with pytest.raises(CassiInputError):
        thick_from_lipthick(-0.1, 200.0)


@pytest.mark.parametrize(
    "cp, expected",
    [
        (65.0, 10.0),   # resting: currthick = Thick
        (50.0, 10.0),   # onset, t = 0
        (25.0, 12.0),   # t = (50 - 25)/50 = 0.5: 10 (1 + 0.4 * 0.5)
        (0.0, 14.0),    # fully round, t = 1: 10 * 1.4
        (-10.0, 14.0),  # t clipped at 1
    ],
)
def test_step8_currthick(cp, expected):
    assert current_thickness(10.0, cp, onset=THESIS_ONSET, gain=0.4) == pytest.approx(expected)
    # the default onset is the thesis's 50 on this face's c scale: the same lip, the same result
    assert current_thickness(10.0, cp * K.C_SCALE, gain=0.4) == pytest.approx(expected)


def test_centreline_equal_thickness():
    # 2.0: 64 = 100 - 12/2, 61 = 100 - 12; 52 = 40 + 12/3, 55 = 40 + 24/3, 58 = 40 + 12.
    up, lo = EQUAL_THICKNESS.split(12.0)
    z = centreline_z(100.0, 40.0, up, lo)
    assert {v: float(z[v]) for v in z} == pytest.approx({64: 94.0, 61: 88.0, 52: 44.0, 55: 48.0,
                                                         58: 52.0})


def test_centreline_low_lips_thickness():
    # 2.1: upper = 2/3 * 12 = 8, lower = 4/3 * 12 = 16: 64 = 96, 61 = 92, 52 = 40 + 16/3,
    # 55 = 40 + 32/3, 58 = 56. The combined thickness stays 2 * currthick = 24.
    up, lo = LOW_LIPS_THICKNESS.split(12.0)
    assert (float(up), float(lo)) == pytest.approx((8.0, 16.0))
    z = centreline_z(100.0, 40.0, up, lo)
    assert {v: float(z[v]) for v in z} == pytest.approx(
        {64: 96.0, 61: 92.0, 52: 40 + 16 / 3, 55: 40 + 32 / 3, 58: 56.0})


# --- Section 4.3: criterion and blending functions ----------------------------------------------
def test_low_lips_criterion():
    assert is_low_lips(-25.0, 0.0)        # 25 below 226 > 20
    assert not is_low_lips(-20.0, 0.0)    # exactly 20: does not exceed the threshold
    assert not is_low_lips(5.0, 0.0)      # above the teeth tip
    assert K.LOW_LIPS_THRESHOLD == 20.0


def test_low_lips_criterion_results_reading():
    """The results' reading: the inside edge lower than 20 units above 226."""
    res = LowLipsReading.RESULTS
    assert is_low_lips(5.0, 0.0, reading=res)          # 5 above: adjusted
    assert is_low_lips(-25.0, 0.0, reading=res)        # below 226 too
    assert not is_low_lips(20.0, 0.0, reading=res)     # exactly 20 above: not lower than it
    assert not is_low_lips(25.0, 0.0, reading=res)     # centred high
    # The margin is signed, Parke units: the threshold height minus the edge.
    assert low_lips_margin(5.0, 1.0, reading=res) == 16.0
    assert low_lips_margin(5.0, 1.0, reading="text") == -24.0
    with pytest.raises(ValueError):
        low_lips_margin(5.0, 1.0, reading="prose")


def test_eq_4_20_4_21_hermite():
    t = np.array([0.0, 0.25, 0.5, 1.0])
    # F1(0.25) = 2/64 - 3/16 + 1 = 0.84375; F2(0.25) = -2/64 + 3/16 = 0.15625.
    np.testing.assert_allclose(hermite_f1(t), [1.0, 0.84375, 0.5, 0.0])
    np.testing.assert_allclose(hermite_f2(t), [0.0, 0.15625, 0.5, 1.0])


@given(st.floats(0, 1))
def test_hermite_sum_is_one_and_monotone(t):
    assert hermite_f1(t) + hermite_f2(t) == pytest.approx(1.0)
    assert hermite_f1(min(t + 0.01, 1.0)) <= hermite_f1(t) + 1e-12


def test_blend_inner_corner():
    # c' = 37.5 -> t = (50 - 37.5)/50 = 0.25: 0.84375 * 10 + 0.15625 * 20 = 11.5625.
    on = THESIS_ONSET
    assert blend_inner_corner_z(10.0, 20.0, 37.5, onset=on) == pytest.approx(11.5625)
    assert blend_inner_corner_z(10.0, 20.0, 50.0, onset=on) == pytest.approx(10.0)  # not rounding
    assert blend_inner_corner_z(10.0, 20.0, 70.0, onset=on) == pytest.approx(10.0)
    assert blend_inner_corner_z(10.0, 20.0, 0.0, onset=on) == pytest.approx(20.0)   # fully round
    np.testing.assert_allclose(rounding_t([60.0, 50.0, 25.0, 0.0, -5.0], onset=on),
                               [0, 0, 0.5, 1, 1])
    assert blend_inner_corner_z(10.0, 20.0, 37.5 * K.C_SCALE) == pytest.approx(11.5625)
