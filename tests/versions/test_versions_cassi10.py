"""CASSI 1.0 (thesis 4.1), the XRMB -> Parke mapping and the Parke baseline (3.1.3).

Unit tests run on the stand-in face of ``_versions_toy`` (vertices placed by hand so results can be
derived); ``test_real_face_*`` run on the face model when ``cassi.data.face.model`` is installed.
"""
from __future__ import annotations

import importlib
import math

import numpy as np

from cassi.data.face import numbering as N
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _versions_toy import JW45_ROW, ToyFace, toy_profile, toy_recording, toy_vertices
from cassi.common.errors import CassiInputError
from cassi.versions import constants as K
from cassi.versions.cassi10 import Cassi10, TongueReading, check_parameters, tongue_followers
from cassi.versions.mapping import XrmbToParke, model_jaw_length
from cassi.versions.parke1974 import Parke1974
from cassi.versions.protocol import Animation, held_pellets

UL, LL, T1, T2, T3, T4, MNI, MNM = range(8)


@pytest.fixture(scope="module")
def face():
    return ToyFace(toy_vertices())


@pytest.fixture(scope="module")
def rec():
    return toy_recording()


@pytest.fixture(scope="module")
def anim10(face, rec) -> Animation:
    return Cassi10().animate(toy_profile(), face, rec)


# --- mapping (4.1.1) ------------------------------------------------------------------------
def test_mapping_hand_case():
    # 258 at (x, z) = (10, -20); 281 at (-28, -12) and 286 at (-32, -8): MANm site (-30, -10).
    # p = |(10 + 30, -20 + 10)| = sqrt(40^2 + 10^2) = 41.2310563; d = 50 mm -> p/d = 0.8246211.
    # 226 at (3, 7): XRMB (1, 2) mm -> (3 + 0.8246211, 7 + 2 * 0.8246211) = (3.8246211, 8.6492423).
    v = np.zeros((300, 3))
    v[257] = (10, 0, -20)
    v[280] = (-28, 5, -12)
    v[285] = (-32, 9, -8)
    v[225] = (3, 0, 7)
    assert model_jaw_length(v) == pytest.approx(math.sqrt(1700))
    m = XrmbToParke.from_face(v, 50.0)
    assert m.scale == pytest.approx(0.8246211251)
    np.testing.assert_allclose(m.to_parke(np.array([1.0, 2.0])), [3.8246211251, 8.6492422502])
    np.testing.assert_allclose(m.to_parke(np.zeros(2)), [3.0, 7.0])       # origin -> vertex 226
    np.testing.assert_allclose(m.to_xrmb(m.to_parke(JW45_ROW)), JW45_ROW)
    p3 = m.to_parke3(JW45_ROW)
    assert p3.shape == (8, 3) and np.all(p3[:, 1] == 0.0)                # midsagittal plane


@settings(max_examples=50, deadline=None)
@given(d=st.floats(min_value=20, max_value=60))
def test_mapping_gives_equal_jaw_lengths(d):
    # "This scaling creates equal jaw lengths, p, between the facial model and the XRMB data."
    v = toy_vertices()
    m = XrmbToParke.from_face(v, d)
    mni, mnm = np.array([0.3, -7.0]), np.array([0.3 - d * 0.99, -7.0 - d * math.sqrt(1 - .99 ** 2)])
    assert np.hypot(*(m.to_parke(mni) - m.to_parke(mnm))) == pytest.approx(model_jaw_length(v))


def test_a_subject_face_knows_its_scale():
    """subject_face keeps the jaw length d on the face, and the face's units per mm is the
    mapping's p / d, with or without a palate; the neutral face keeps the model's nominal scale."""
    from cassi.data.face import numbering as N
    from cassi.data.face.model import build_face
    from cassi.versions.mapping import subject_face
    assert build_face().units_per_mm == N.UNITS_PER_MM
    pal = np.array([[-5.0, 8.5], [-20.0, 14.0], [-35.0, 16.0], [-53.0, 21.0]])
    for palate in (None, pal):
        face = subject_face(palate_mm=palate, jaw_length_mm=73.0)
        assert face.jaw_length_mm == 73.0
        assert face.units_per_mm == pytest.approx(XrmbToParke.from_face(face.vertices, 73.0).scale)
        assert face.units_per_mm != pytest.approx(N.UNITS_PER_MM, rel=1e-3)


def test_mapping_rejects_bad_jaw_length():
    with pytest.raises(CassiInputError):
        XrmbToParke.from_face(toy_vertices(), 0.0)


# --- first valid row, held pellets --------------------------------------------------------
def test_frames_start_at_first_valid_row(anim10, rec):
    assert anim10.frames[0] == rec.first_valid_index == 3
    assert anim10.n_frames == rec.xy_mm.shape[0] - 3
    assert anim10.positions.dtype == np.float32
    assert list(anim10.diagnostics["frame"]) == list(anim10.frames)
    np.testing.assert_array_equal(anim10.time_us, rec.time_us[3:])


def test_no_valid_row_is_input_error(face):
    rec = toy_recording(n=10, invalid_head=10)
    with pytest.raises(CassiInputError, match="no row"):
        Cassi10().animate(toy_profile(), face, rec)


def test_held_pellets_hold_last_valid_value():
    xy = np.arange(5 * 8 * 2, dtype=float).reshape(5, 8, 2)
    valid = np.ones((5, 8), bool)
    valid[2:4, 1] = False
    xy[2:4, 1] = np.nan
    out, held = held_pellets(xy, valid, 0)
    np.testing.assert_array_equal(out[2, 1], xy[1, 1])
    np.testing.assert_array_equal(out[3, 1], xy[1, 1])
    np.testing.assert_array_equal(out[4, 1], xy[4, 1])
    assert held[:, 1].tolist() == [False, False, True, True, False] and held.sum() == 2


def test_missing_pellet_mid_task_is_held_and_flagged(face):
    rec = toy_recording()
    rec.xy_mm[50:60, UL] = np.nan
    rec.valid[50:60, UL] = False
    anim = Cassi10().animate(toy_profile(), face, rec)
    diag = anim.diagnostics.set_index("frame")
    assert diag.loc[50:59, "held_UL"].all() and not diag.loc[60, "held_UL"]
    i49, i55 = np.searchsorted(anim.frames, [49, 55])
    np.testing.assert_array_equal(anim.vertex(K.V_UL)[i55], anim.vertex(K.V_UL)[i49])
    assert np.isfinite(anim.positions).all()


# --- initialisation and animation of 1.0 ---------------------------------------------------
def test_lips_sit_on_their_pellets_every_frame(anim10, face, rec):
    m = XrmbToParke.from_face(face.vertices, toy_profile().jaw_length_mm)
    want_ul = m.to_parke(rec.xy_mm[3:, UL])
    want_ll = m.to_parke(rec.xy_mm[3:, LL])
    np.testing.assert_allclose(anim10.vertex(K.V_UL)[:, [0, 2]], want_ul, atol=1e-3)
    np.testing.assert_allclose(anim10.vertex(K.V_LL)[:, [0, 2]], want_ll, atol=1e-3)


def test_other_lip_vertices_follow_their_pellet(anim10):
    # Every upper-lip vertex keeps its offset from 67 and every lower-lip vertex from 49.
    for group, anchor in ((K.UPPER_LIP_VERTICES, K.V_UL), (K.LOWER_LIP_VERTICES, K.V_LL)):
        rel = anim10.positions[:, np.asarray(group) - 1] - anim10.vertex(anchor)[:, None, :]
        np.testing.assert_allclose(rel, np.broadcast_to(rel[0], rel.shape), atol=1e-3)


def test_cassi10_never_rounds(anim10):
    # No lip rounding in 1.0: no lip vertex ever moves sideways (Parke y) and the mouth keeps its
    # width, however far the upper lip protrudes.
    lips = np.asarray(K.UPPER_LIP_VERTICES + K.LOWER_LIP_VERTICES + K.LIP_CORNER_VERTICES) - 1
    y = anim10.positions[:, lips, 1]
    np.testing.assert_array_equal(y, np.broadcast_to(y[0], y.shape))
    assert np.ptp(anim10.diagnostics["param_63"]) > 1.0       # the lip did protrude


def test_lower_lip_not_rotated_with_jaw(face):
    # Jaw wags, the LL pellet stands still: the lower lip must stay put (4.1.2) while the teeth
    # rotate with the jaw.
    rec = toy_recording()
    rec.xy_mm[3:, LL] = rec.xy_mm[3, LL]
    anim = Cassi10().animate(toy_profile(), face, rec)
    lower = np.asarray(K.LOWER_LIP_VERTICES) - 1
    np.testing.assert_allclose(anim.positions[:, lower], np.broadcast_to(
        anim.positions[0, lower], anim.positions[:, lower].shape), atol=1e-4)
    assert np.ptp(anim.vertex(K.V_MANI)[:, 2]) > 50
    # ... whereas Parke rotates lip vertex 49 with the jaw.
    parke = Parke1974().animate(toy_profile(), face, rec)
    assert np.ptp(parke.vertex(49)[:, 2]) > 50


def test_mni_site_on_mni_pellet(anim10, face, rec):
    # The teeth rotation puts vertex 258 on the mapped MANi pellet at initialisation and every
    # frame (Eqs. 4.6-4.7 solve the point of rotation from MANi; the teeth's fraction 0.999999
    # leaves < 1e-6 * theta * radius, below 1e-3 units here).
    m = XrmbToParke.from_face(face.vertices, toy_profile().jaw_length_mm)
    want = m.to_parke(rec.xy_mm[3:, MNI])
    np.testing.assert_allclose(anim10.vertex(K.V_MANI)[:, [0, 2]], want, atol=2e-3)
    # MANm's site follows its pellet as well as the jaw lengths agree (here d = the row's length).
    manm = 0.5 * (anim10.vertex(281) + anim10.vertex(286))[:, [0, 2]]
    np.testing.assert_allclose(manm, m.to_parke(rec.xy_mm[3:, MNM]), atol=0.5)


def test_jaw_diagnostics_recover_the_wagging_pivot(anim10, face):
    # toy_recording rotates the jaw pellets about (-80, 10) mm: Eqs. 4.6-4.7 must find that point.
    m = XrmbToParke.from_face(face.vertices, toy_profile().jaw_length_mm)
    pivot = m.to_parke(np.array([-80.0, 10.0]))
    d = anim10.diagnostics
    moving = d["jaw_angle_rad"].abs() > 1e-3
    np.testing.assert_allclose(d.loc[moving, ["jaw_point_x", "jaw_point_z"]].to_numpy(),
                               np.broadcast_to(pivot, (int(moving.sum()), 2)), atol=1e-3)
    # The angle is relative to the first valid row (3), where the wag is already
    # 12 * (1 - cos(2 pi 3 / 120)) / 2 = 0.0738 degrees: the peak reads 12 - 0.0738.
    first = 12.0 * 0.5 * (1 - math.cos(2 * math.pi * 3 / 120.0))
    assert d["jaw_angle_deg"].max() == pytest.approx(12.0 - first, abs=1e-6)
    assert math.isnan(d["jaw_point_x"].iloc[0])               # theta = 0: no point of rotation


def test_zone_fractions_applied(anim10):
    # With the point of rotation (a, b) and theta of frame k, a 5th-zone vertex of the initialised
    # face must sit where Eq. 3.5-3.6 put it for 0.3888885 theta.
    d = anim10.diagnostics
    k = int(np.argmax(d["jaw_angle_rad"].to_numpy()))
    th, a, b = d.loc[k, "jaw_angle_rad"], d.loc[k, "jaw_point_x"], d.loc[k, "jaw_point_z"]
    x0, _, z0 = anim10.vertex(46)[0].astype(float)
    t = 0.3888885 * th
    want = ((x0 - a) * math.cos(t) + (z0 - b) * math.sin(t) + a,
            (z0 - b) * math.cos(t) - (x0 - a) * math.sin(t) + b)
    np.testing.assert_allclose(anim10.vertex(46)[k, [0, 2]], want, atol=1e-3)
    # The neck (z only) keeps x.
    np.testing.assert_array_equal(anim10.vertex(8)[:, 0], anim10.vertex(8)[0, 0])


def test_head_measures_adjust_the_chin(face, rec):
    with_hm = Cassi10().animate(toy_profile(head_measures=True), face, rec)
    without = Cassi10().animate(toy_profile(head_measures=False), face, rec)
    jaw = np.asarray(K.CASSI10_ZONES[0].vertices) - 1
    # Without head measures the jaw starts as Parke's; with them it is rotated onto them.
    np.testing.assert_allclose(without.positions[0, jaw], face.vertices[jaw], atol=1e-4)
    assert np.abs(with_hm.positions[0, jaw] - face.vertices[jaw]).max() > 1.0
    # The teeth are placed by the pellets either way.
    np.testing.assert_allclose(with_hm.vertex(258)[0], without.vertex(258)[0], atol=1e-5)


def test_tongue_on_pellets_tip_with_t1_back_anchored(anim10, face, rec):
    m = XrmbToParke.from_face(face.vertices, toy_profile().jaw_length_mm)
    for n, p in zip(K.V_TONGUE_PELLETS, (T1, T2, T3, T4)):
        np.testing.assert_allclose(anim10.vertex(n)[:, [0, 2]], m.to_parke(rec.xy_mm[3:, p]),
                                   atol=1e-3)
        assert np.all(anim10.vertex(n)[:, 1] == 0)
    follow = tongue_followers(face.vertices)
    assert follow[288] == 289 and follow[293] is None        # tip from T1, back anchored
    # The text's tongue (the default): the tip is "adjusted accordingly", carried with T1 at the
    # neutral model's offset, and so is the edge beside it; nothing holds them behind the teeth.
    assert Cassi10.tongue is TongueReading.TEXT
    for n in (288, 294):
        offset = face.vertices[n - 1, [0, 2]] - face.vertices[288, [0, 2]]
        np.testing.assert_allclose(anim10.vertex(n)[:, [0, 2]] - anim10.vertex(289)[:, [0, 2]],
                                   np.broadcast_to(offset, (anim10.n_frames, 2)), atol=1e-3)
    np.testing.assert_array_equal(anim10.vertex(293), np.broadcast_to(face.vertices[292],
                                                                      (anim10.n_frames, 3)))
    assert follow[294] == 289 and follow[299] is None         # edges: beside tip -> T1, back
    assert [follow[n] for n in (295, 296, 297, 298)] == [289, 290, 291, 292]


def test_clamped_tongue_tip_ahead_of_t1_along_its_line(face, rec):
    # The clamped reading: the tip lies in front of T1 on the line T2 -> T1 (4.1.1 "T1 ... behind
    # the tip"), at most TONGUE_TIP_AHEAD_MM and at least TONGUE_TIP_MIN_AHEAD_MM (subject mm).
    anim = Cassi10(tongue="clamped").animate(toy_profile(), face, rec)
    m = XrmbToParke.from_face(face.vertices, toy_profile().jaw_length_mm)
    t1, t2, tip = (anim.vertex(n)[:, [0, 2]].astype(float) for n in (289, 290, 288))
    u = (t1 - t2) / np.linalg.norm(t1 - t2, axis=1)[:, None]
    ahead = np.einsum("ij,ij->i", tip - t1, u)
    np.testing.assert_allclose(tip, t1 + ahead[:, None] * u, atol=1e-3)
    assert ahead.max() <= K.TONGUE_TIP_AHEAD_MM * m.scale + 1e-3
    assert ahead.min() >= K.TONGUE_TIP_MIN_AHEAD_MM * m.scale - 1e-3
    np.testing.assert_allclose(anim.diagnostics["tongue_tip_ahead_mm"], ahead / m.scale, atol=1e-3)
    # The edge beside the tip keeps its neutral offset from the tip (unless the arch holds it).
    side = face.vertices[293, [0, 2]] - face.vertices[287, [0, 2]]
    np.testing.assert_allclose(anim.vertex(294)[:, 2] - anim.vertex(288)[:, 2],
                               np.full(anim.n_frames, side[1]), atol=1e-3)
    with pytest.raises(ValueError):
        Cassi10(tongue="held")
    from cassi.versions.cassi20 import Cassi20
    from cassi.versions.cassi21 import Cassi21
    for cls in (Cassi20, Cassi21):       # 1.0's tongue in 2.0 and 2.1, the reading passed on
        assert cls().stages()[-1].reading is TongueReading.TEXT
        assert cls(tongue="clamped").stages()[-1].reading is TongueReading.CLAMPED


def test_tongue_tip_behind_the_incisors_when_clamped_through_them_as_the_text_has_it():
    # On the face model, with T1 placed 4 mm behind the lower incisor (a tongue at rest): clamped,
    # the tip sits in front of T1 but behind the incisors' lingual surface by the clearance, and
    # the edge vertices inside the arch of the bottom teeth; the text's tongue carries the tip
    # 10 mm ahead of T1 (the neutral model's offset) and through the incisors, the fault the
    # thesis's judges charged (Table 5.3) and its 6.2 left to collision detection.
    from cassi.versions.cassi10 import arch_wall_x, incisor_wall_x
    face_mod = importlib.import_module("cassi.data.face.model")
    face = face_mod.build_face()
    v = np.asarray(face.vertices, dtype=np.float64)
    prof = toy_profile()
    m = XrmbToParke.from_face(v, prof.jaw_length_mm)
    rec = toy_recording()
    xy = rec.xy_mm
    # Jaw pellets onto the model's own MANi / MANm sites (no jaw rotation), T1 4 mm behind the
    # lower incisor at mid-height, T2-T4 behind it along the tongue.
    xy[:, MNI] = m.to_xrmb(v[257, [0, 2]])
    xy[:, MNM] = m.to_xrmb(v[[280, 285]][:, [0, 2]].mean(0))
    inc = m.to_xrmb(v[254, [0, 2]] * 0.5 + v[257, [0, 2]] * 0.5)
    for k, p in enumerate((T1, T2, T3, T4)):
        xy[:, p] = inc + np.array([-4.0 - 14.0 * k, 1.0])
    xy[:, T1, 0] += np.linspace(-1.0, 1.0, len(xy))      # a little motion
    anim = Cassi10(tongue="clamped").animate(prof, face, rec)
    pos = anim.positions.astype(np.float64)
    np.testing.assert_allclose(pos[:, 288, [0, 2]], m.to_parke(xy[3:, T1]), atol=1e-3)
    tip = pos[:, 287]
    wall = incisor_wall_x(pos, tip[:, 2])
    assert np.all(tip[:, 0] > pos[:, 288, 0])                                   # in front of T1
    assert np.all(tip[:, 0] <= wall - K.TONGUE_TIP_TEETH_CLEARANCE_MM * m.scale + 1e-3)
    edges = np.asarray(N.TONGUE_EDGE[:-1]) - 1
    arch = arch_wall_x(pos, v[edges, 1])
    assert np.all(pos[:, edges, 0] <= arch - K.TONGUE_TIP_TEETH_CLEARANCE_MM * m.scale + 1e-3)
    # The old rigid offset (40 units = 10 mm at Parke's scale) would have been through the teeth.
    old_tip = pos[:, 288, 0] + (v[287, 0] - v[288, 0])
    assert np.any(old_tip > wall)
    text = Cassi10().animate(prof, face, rec).positions.astype(np.float64)
    np.testing.assert_allclose(text[:, 288], pos[:, 288], atol=1e-3)        # T1 on its pellet
    assert np.all(text[:, 287, 0] > incisor_wall_x(text, text[:, 287, 2]))   # through the teeth


def test_nose_kept_above_a_high_upper_lip(face):
    rec = toy_recording()
    rec.xy_mm[200:, UL, 1] += 8.0            # the upper lip rises 8 mm into the nose
    anim = Cassi10().animate(toy_profile(), face, rec)
    from cassi.versions.cassi10 import nose_tip_vertices
    tip = nose_tip_vertices(face.vertices) - 1
    upper = np.asarray(K.UPPER_LIP_VERTICES) - 1
    gap = anim.positions[:, tip, 2].min(axis=1) - anim.positions[:, upper, 2].max(axis=1)
    m = XrmbToParke.from_face(face.vertices, toy_profile().jaw_length_mm)
    assert gap.min() >= K.NOSE_LIP_MIN_GAP_MM * m.scale - 1e-3
    d = anim.diagnostics
    assert (d.loc[d["frame"] < 200, "nose_raise"] == 0).all()
    assert (d.loc[d["frame"] >= 200, "nose_raise"] > 0).all()


def test_parameters_table_4_1_and_4_2():
    assert sorted(K.NEW_PARAMETERS) == list(range(55, 67))
    with pytest.raises(CassiInputError, match="Table 4.2"):
        check_parameters({21: 1.0})
    with pytest.raises(CassiInputError, match="pellets"):
        check_parameters({63: 0.5})
    assert check_parameters({15: 0.3}) == {15: 0.3}


def test_table_4_1_parameters_in_diagnostics(anim10, face, rec):
    d = anim10.diagnostics
    m = XrmbToParke.from_face(face.vertices, toy_profile().jaw_length_mm)
    disp = (rec.xy_mm[3:, T3] - rec.xy_mm[3, T3]) * m.scale
    np.testing.assert_allclose(d["param_59"], disp[:, 0], atol=1e-9)
    np.testing.assert_allclose(d["param_60"], disp[:, 1], atol=1e-9)
    assert (d[[f"param_{n}" for n in range(55, 67)]].iloc[0] == 0).all()   # initial value 0.0


# --- the Parke baseline --------------------------------------------------------------------
def test_parke_rotates_about_vertex_107(face, rec):
    anim = Parke1974().animate(toy_profile(), face, rec)
    d = anim.diagnostics
    assert (d["jaw_point_x"] == face.vertices[106, 0]).all()
    k = int(np.argmax(d["jaw_angle_rad"]))
    th = d.loc[k, "jaw_angle_rad"]
    a, b = face.vertices[106, [0, 2]]
    x, z = face.vertices[257, [0, 2]]
    t = 0.9 * th                                  # lower teeth: 2nd zone, 0.9 theta (Table 3.2)
    want = ((x - a) * math.cos(t) + (z - b) * math.sin(t) + a,
            (z - b) * math.cos(t) - (x - a) * math.sin(t) + b)
    np.testing.assert_allclose(anim.vertex(258)[k, [0, 2]], want, atol=1e-3)
    # Lips and tongue follow nothing else: the tongue never moves, the upper lip never moves.
    tongue = np.asarray(K.TONGUE_VERTICES) - 1
    np.testing.assert_allclose(anim.positions[:, tongue], np.broadcast_to(
        face.vertices[tongue], (anim.n_frames, len(tongue), 3)), atol=1e-4)
    np.testing.assert_allclose(anim.vertex(67), np.broadcast_to(face.vertices[66],
                                                                (anim.n_frames, 3)), atol=1e-4)


def test_parke_angle_clipped_to_parameter_range(face):
    rec = toy_recording(wag_deg=30.0)
    d = Parke1974().animate(toy_profile(), face, rec).diagnostics
    assert d["jaw_angle_deg"].max() == pytest.approx(20.0)
    assert d["jaw_angle_unclipped_rad"].max() > math.radians(25)


def test_animate_is_deterministic(face, rec):
    a = Cassi10().animate(toy_profile(), face, rec)
    b = Cassi10().animate(toy_profile(), face, rec)
    np.testing.assert_array_equal(a.positions, b.positions)


def test_lip_corners_take_half_of_each_lip(anim10):
    # CORNER_WEIGHTS: corners 70, 287, 300 move by 0.5 dUL + 0.5 dLL (x and z).
    d67 = anim10.vertex(K.V_UL) - anim10.vertex(K.V_UL)[0]
    d49 = anim10.vertex(K.V_LL) - anim10.vertex(K.V_LL)[0]
    for n in K.LIP_CORNER_VERTICES:
        moved = anim10.vertex(n) - anim10.vertex(n)[0]
        np.testing.assert_allclose(moved, 0.5 * d67 + 0.5 * d49, atol=2e-3)


def test_head_measures_equal_to_the_model_change_nothing(face, rec):
    # Head measures placed exactly where the model's gnathion and gonion already are
    # (mapped back to XRMB mm) give theta = 0: the chin and jaw keep Parke's placement.
    from cassi.data.xrmb.headmeasures import HeadMeasures
    from cassi.data.corpus.profile import SubjectProfile
    from dataclasses import replace

    prof = toy_profile()
    m = XrmbToParke.from_face(face.vertices, prof.jaw_length_mm)
    hm = HeadMeasures(gnathion_mm=m.to_xrmb(face.vertices[N.GNATHION - 1, [0, 2]]),
                      gonion_mm=m.to_xrmb(face.vertices[N.GONION - 1, [0, 2]]))
    anim = Cassi10().animate(replace(prof, head_measures=hm), face, rec)
    jaw = np.asarray(K.CASSI10_ZONES[0].vertices) - 1
    np.testing.assert_allclose(anim.positions[0, jaw], face.vertices[jaw], atol=1e-3)
    assert anim.diagnostics["init_jaw_angle_deg"].abs().max() < 1e-9
    assert isinstance(prof, SubjectProfile)


def test_init_angles_reported(anim10):
    d = anim10.diagnostics
    assert d["init_jaw_angle_deg"].nunique() == 1 and np.isfinite(d["init_jaw_angle_deg"]).all()
    assert d["init_teeth_angle_deg"].nunique() == 1


@settings(max_examples=30, deadline=None)
@given(dx=st.floats(-4, 4), dy=st.floats(-6, 6), tilt=st.floats(-0.25, 0.25),
       d=st.floats(30, 40))
def test_mni_site_on_mni_pellet_any_first_row(dx, dy, tilt, d):
    # Whatever the first valid row's jaw pellets (moved, tilted, any jaw length), the
    # initialised vertex 258 sits on the mapped MANi pellet (Eqs. 4.6-4.7 anchored on MANi).
    face = ToyFace(toy_vertices())
    rec = toy_recording(n=8, invalid_head=1)
    mni = JW45_ROW[MNI] + [dx, dy]
    rec.xy_mm[1:, MNI] = mni
    rec.xy_mm[1:, MNM] = mni + d * np.array([-math.cos(tilt), -math.sin(tilt)])
    anim = Cassi10().animate(toy_profile(jaw_length_mm=d), face, rec)
    m = XrmbToParke.from_face(face.vertices, d)
    np.testing.assert_allclose(anim.vertex(K.V_MANI)[0, [0, 2]], m.to_parke(mni), atol=2e-3)


def test_bad_inputs_are_input_errors(rec):
    with pytest.raises(CassiInputError, match="vertices"):
        Cassi10().animate(toy_profile(), ToyFace(toy_vertices()[:250]), rec)
    with pytest.raises(CassiInputError, match="jaw length"):
        Cassi10().animate(toy_profile(jaw_length_mm=0.0), ToyFace(toy_vertices()), rec)
