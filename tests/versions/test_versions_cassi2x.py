"""CASSI 2.0 and 2.1 as versions (thesis 4.2-4.3): the lip stage inside CASSI 1.0's pipeline.

Pipeline tests run on the stand-in face of ``_versions_toy``; ``test_real_face_*`` run on the
face model (``cassi.data.face.model.build_face``) and skip while it is not installed.
"""
from __future__ import annotations

import importlib
import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _versions_toy import ToyFace, toy_profile, toy_recording, toy_vertices
from data_helpers import FIXTURES
from cassi.data.corpus.profile import SubjectProfile, read_lipthick, read_maxprotru
from cassi.data.xrmb.files import read_txy
from cassi.versions import lips_constants as LK
from cassi.versions.cassi10 import Cassi10
from cassi.versions.cassi20 import Cassi20
from cassi.versions.cassi21 import Cassi21
from cassi.versions.lips import LIP_VERTICES, LipMovementStage
from cassi.versions.lips_thickness import LowLipsReading
from cassi.versions.mapping import model_jaw_length
from cassi.versions.registry import get_version

UL, LL = 0, 1
#: Vertices the lip stage may move besides the lips: 71-73, 41-43, 44 (4.2.1) and the nose tip,
#: which CASSI 1.0's clearance stage raises after the lips (4.1.1).
NEIGHBOURS = (41, 42, 43, 44, 71, 72, 73)
NOSE_TIP = tuple(range(80, 102))


def protrusion_recording(profile, n=600, wag_deg=2.0):
    """The toy jaw-wagging task with the upper lip taken to the subject's MAX UL (rounded), then
    back through rest to MIN UL (stretched); the lower lip follows 0.8 of the upper's x."""
    rec = toy_recording(n, wag_deg=wag_deg)
    xy = rec.xy_mm.copy()
    d = profile.jaw_length_mm
    start = rec.first_valid_index
    x0 = xy[start, UL, 0]
    target = np.concatenate([
        np.linspace(x0, profile.max_ul * d, n // 4), np.full(n // 4, profile.max_ul * d),
        np.linspace(profile.max_ul * d, profile.min_ul * d, n // 4),
        np.full(n - 3 * (n // 4), profile.min_ul * d),
    ])
    dx = target - x0
    xy[:, UL, 0] = x0 + dx
    xy[:, LL, 0] += 0.8 * dx
    xy[~rec.valid] = np.nan
    return dataclasses.replace(rec, xy_mm=xy)


#: The stand-in face is built at ~10 units per mm; CASSI 2.0's key c values (65, 0, 85) and the
#: limits of step 7 are in Parke's units, ~4 per mm (cassi.data.face.numbering.MM_PER_UNIT), so the
#: stand-in is scaled to that before the lips run on it.
TOY_TO_PARKE = 0.4


@pytest.fixture(scope="module")
def face():
    return ToyFace(toy_vertices() * TOY_TO_PARKE)


@pytest.fixture(scope="module")
def profile():
    return toy_profile()


@pytest.fixture(scope="module")
def rec(profile):
    return protrusion_recording(profile)


@pytest.fixture(scope="module")
def anims(face, profile, rec):
    return {v.name: v.animate(profile, face, rec) for v in (Cassi10(), Cassi20(), Cassi21())}


def test_registry_names_the_lip_versions():
    assert isinstance(get_version("cassi-2.0"), Cassi20)
    assert isinstance(get_version("cassi-2.1"), Cassi21)
    # 2.0 is 1.0 with another lip stage; 2.1 is 2.0 with another thickness policy.
    assert issubclass(Cassi20, Cassi10) and issubclass(Cassi21, Cassi20)
    names = [type(s).__name__ for s in Cassi20().stages()]
    assert names == [type(s).__name__ for s in Cassi10().stages()][:1] + ["LipMovementStage"] + \
        [type(s).__name__ for s in Cassi10().stages()][2:]
    assert isinstance(Cassi21().lip_stage(), LipMovementStage)


def test_lips_on_their_pellets_and_diagnostics(anims, rec):
    anim = anims["cassi-2.0"]
    assert anim.version == "cassi-2.0"
    assert anim.positions.shape[0] == len(rec.time_us) - rec.first_valid_index
    d = anim.diagnostics
    for col in ("a", "b", "c", "c_prime", "currthick", "outer_abc_branch", "ellipse",
                "jaw_angle_rad", "param_63", "thickness_rule"):
        assert col in d.columns, col
    assert d["outer_abc_branch"].iloc[0] == "3"
    # 67 and 49 stay on the mapped pellets (steps 1-4), exactly as in 1.0.
    ref = anims["cassi-1.0"]
    np.testing.assert_allclose(anim.vertex(67)[:, [0, 2]], ref.vertex(67)[:, [0, 2]], atol=1e-3)
    np.testing.assert_allclose(anim.vertex(49)[:, [0, 2]], ref.vertex(49)[:, [0, 2]], atol=1e-3)


def test_everything_but_the_lips_is_cassi_1_0(anims):
    moved = set(LIP_VERTICES) | set(NEIGHBOURS) | set(NOSE_TIP)
    a20, a10 = anims["cassi-2.0"].positions, anims["cassi-1.0"].positions
    keep = np.array([v - 1 for v in range(1, a20.shape[1] + 1) if v not in moved])
    np.testing.assert_array_equal(a20[:, keep], a10[:, keep])
    # ... and the lips really are different (the ellipses reshape them).
    lips = np.asarray(LIP_VERTICES) - 1
    assert np.abs(a20[:, lips] - a10[:, lips]).max() > 1.0


def test_1_0_never_rounds_2_0_rounds_forward_and_stretches_back(anims, rec):
    n = anims["cassi-2.0"].n_frames
    q = (len(rec.time_us)) // 4
    rest, rounded, stretched = 0, 2 * q - 10 - rec.first_valid_index, n - 1
    y10 = anims["cassi-1.0"].vertex(70)[:, 1]
    assert np.ptp(y10) == 0.0                         # 1.0: corners never move sideways
    y20 = anims["cassi-2.0"].vertex(70)[:, 1]
    cp = anims["cassi-2.0"].diagnostics["c_prime"].to_numpy()
    assert cp[rounded] < 5 and cp[stretched] > 80
    assert y20[rounded] < 0.8 * y20[rest]
    assert y20[stretched] > y20[rest]


def test_frame_0_is_the_initialised_face(face, profile, rec):
    version = Cassi20()
    ctx = version.context(profile, face, rec)
    for stage in version.stages():
        stage.initialise(ctx)
    anim = version.animate(profile, face, rec)
    np.testing.assert_allclose(anim.positions[0], ctx.start, atol=1e-3)


def test_neighbours_follow_their_lip_vertices(anims, face, profile, rec):
    a20 = anims["cassi-2.0"]
    # 71 moves by ABOVE_LIP_PORTION of 67's movement since the first frame.
    m71 = a20.vertex(71) - a20.vertex(71)[0]
    m67 = a20.vertex(67) - a20.vertex(67)[0]
    np.testing.assert_allclose(m71, LK.ABOVE_LIP_PORTION * m67, atol=1e-3)
    # 41's y moves by BELOW_LIP_Y_PORTION of 49's (the jaw rotation leaves y alone).
    m41 = a20.vertex(41)[:, 1] - a20.vertex(41)[0, 1]
    m49 = a20.vertex(49)[:, 1] - a20.vertex(49)[0, 1]
    np.testing.assert_allclose(m41, LK.BELOW_LIP_Y_PORTION * m49, atol=1e-3)
    # 41's x and z: half the jaw rotation (the jaw stage alone, run on 2.0's starting face),
    # half 49's movement.
    version = Cassi20()
    ctx = version.context(profile, face, rec)
    stages = version.stages()
    for stage in stages:
        stage.initialise(ctx)
    alone = np.empty((ctx.n_frames,) + ctx.start.shape, dtype=np.float32)
    alone[...] = ctx.start
    stages[0].animate(ctx, alone)
    jaw = alone[:, 40][:, [0, 2]] - ctx.start[40, [0, 2]]
    lip = a20.vertex(49)[:, [0, 2]] - a20.vertex(49)[0, [0, 2]]
    # The blend, then the side-view bound of 4.2.1's 41-43 (lips_constants.BELOW_LIP_CHAIN),
    # which is the only change to it.
    from cassi.versions.lips import LIP_VERTICES, bound_below_lip
    blend = np.array(a20.positions, dtype=np.float64)
    blend[:, 40, [0, 2]] = a20.vertex(41)[0, [0, 2]] + 0.5 * jaw + 0.5 * lip
    bounded = blend.copy()
    bound_below_lip(bounded, blend[:, np.asarray(LIP_VERTICES) - 1], np.asarray(face.vertices))
    np.testing.assert_allclose(a20.vertex(41)[:, [0, 2]], bounded[:, 40, [0, 2]], atol=1e-3)


def _concavity(p, a, m, b):
    d = p[:, b, [0, 2]] - p[:, a, [0, 2]]
    n = np.stack([d[:, 1], -d[:, 0]], axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n *= np.where(n[:, :1] < 0, -1.0, 1.0)
    return -np.sum((p[:, m, [0, 2]] - p[:, a, [0, 2]]) * n, axis=1)


def test_below_lip_bound_keeps_41_to_43_from_folding():
    # Regression for 41-43 pulled by half the lower lip's movement into a fold of the chin
    # (task 106): on the face model, 41-43 pushed 8 mm forward, 8 mm back, or left alone.
    face_mod = importlib.import_module("cassi.data.face.model")
    from cassi.versions.lips import LIP_VERTICES, bound_below_lip
    rest = np.asarray(face_mod.build_face().vertices, dtype=np.float64)
    out = np.repeat(rest[None], 3, axis=0)
    for v, lip, jaw, _ in LK.BELOW_LIP_CHAIN:
        # 8 mm (32 units) along the forward normal of the lip-jaw chord, the bound's direction
        d = rest[jaw - 1, [0, 2]] - rest[lip - 1, [0, 2]]
        n = np.array([d[1], -d[0]]) / np.hypot(*d)
        n *= np.sign(n[0])
        out[0, v - 1, [0, 2]] += 32.0 * n    # forward: the chin would cave in behind v's chord
        out[1, v - 1, [0, 2]] -= 32.0 * n    # back: a hollow under the lip
    lips = out[:, np.asarray(LIP_VERTICES) - 1].copy()
    bounded = out.copy()
    bound_below_lip(bounded, lips, rest)
    for v, lip, jaw, jaw2 in LK.BELOW_LIP_CHAIN:
        v, lip, jaw, jaw2 = v - 1, lip - 1, jaw - 1, jaw2 - 1
        under0 = _concavity(rest[None], lip, v, jaw)[0]
        chin0 = _concavity(rest[None], v, jaw, jaw2)[0]
        assert np.all(_concavity(bounded, lip, v, jaw) <= under0 + 1e-4)
        assert np.all(_concavity(bounded, v, jaw, jaw2) <= chin0 + 1e-4)
        # the unbounded moves did fold it (so this test can fail)
        assert _concavity(out, v, jaw, jaw2)[0] > chin0 + 1.0
        assert _concavity(out, lip, v, jaw)[1] > under0 + 1.0
    np.testing.assert_allclose(bounded[2], rest, atol=1e-9)        # rest is left alone
    again = bounded.copy()
    bound_below_lip(again, lips, rest)
    np.testing.assert_allclose(again, bounded, atol=1e-9)          # a projection


def _ul_raised(rec, dy_mm):
    xy = rec.xy_mm.copy()
    xy[:, UL, 1] += dy_mm
    return dataclasses.replace(rec, xy_mm=xy)


def test_2_1_identical_to_2_0_for_well_centred_subjects(face, profile, rec, anims):
    # The toy's inside edge starts ~4 units above 226: not 20 below (the text's reading).
    a21 = Cassi21(reading="text").animate(profile, face, rec)
    assert a21.diagnostics["thickness_rule"].iloc[0] == "equal"
    # the thickness is 2.0's; the tuning of OUTER_ABC_CALC is each version's own (TUNINGS)
    np.testing.assert_array_equal(a21.positions,
                                  Cassi20(tuning="2.1").animate(profile, face, rec).positions)
    # ... but lower than 20 above: the default (results) reading adjusts it.
    assert anims["cassi-2.1"].diagnostics["thickness_rule"].iloc[0] == "low-lips"


def test_2_1_leaves_lips_centred_high_alone(face, profile, rec):
    """The results' reading spares lips whose inside edge starts more than 20 units above 226
    (JW16, JW18: "centered high", unchanged by 2.1): the upper lip raised 8 mm puts it ~36 above."""
    high = _ul_raised(rec, 8.0)
    a21 = Cassi21().animate(profile, face, high)
    d = a21.diagnostics
    assert d["low_lips_inside_edge"].iloc[0] > LK.LOW_LIPS_THRESHOLD
    assert d["low_lips_margin"].iloc[0] < 0 and d["thickness_rule"].iloc[0] == "equal"
    np.testing.assert_array_equal(a21.positions,
                                  Cassi20(tuning="2.1").animate(profile, face, high).positions)


def test_2_1_reading_is_a_parameter():
    assert Cassi21().reading is LowLipsReading.RESULTS
    assert Cassi21(reading="text").reading is LowLipsReading.TEXT
    assert Cassi21(reading="text").thickness_policy().reading is LowLipsReading.TEXT
    with pytest.raises(ValueError):
        Cassi21(reading="prose")


def test_2_1_thins_the_upper_lip_of_low_lip_subjects(face, rec):
    # A thick-lipped subject: 61 (67 - Thick) starts far below 226 -> low lips.
    thick = dataclasses.replace(toy_profile(), lipthick=3.0)
    a20 = Cassi20().animate(thick, face, rec)
    a21 = Cassi21().animate(thick, face, rec)
    assert a21.diagnostics["thickness_rule"].iloc[0] == "low-lips"
    # 2/3 and 4/3 of currthick, both scaled alike where the pellets press the lips together
    # (lips_constants.LIP_COMPRESS_MIN), so the upper lip is half the lower.
    up, lo = (a21.diagnostics[k].to_numpy() for k in ("currthick_upper", "currthick_lower"))
    np.testing.assert_allclose(up, 0.5 * lo, rtol=1e-9)
    ct = a21.diagnostics["currthick"].to_numpy()
    assert np.all(up <= 2 / 3 * ct + 1e-9) and np.all(up >= LK.LIP_COMPRESS_MIN * 2 / 3 * ct - 1e-9)
    np.testing.assert_allclose(a21.vertex(67)[:, 2] - a21.vertex(61)[:, 2], up, rtol=1e-4)
    np.testing.assert_allclose(a21.vertex(58)[:, 2] - a21.vertex(49)[:, 2], lo, rtol=1e-4)
    np.testing.assert_allclose(a20.vertex(67)[:, 2] - a20.vertex(61)[:, 2],
                               a20.diagnostics["currthick_upper"], rtol=1e-4)
    # Only lip vertices (and what follows them) differ.
    diff = np.abs(a21.positions - a20.positions).max(axis=(0, 2))
    changed = {i + 1 for i in np.nonzero(diff > 1e-4)[0]}
    assert changed and changed <= set(LIP_VERTICES) | set(NEIGHBOURS) | set(NOSE_TIP)


# --- on the face model ------------------------------------------------------------------------
@pytest.fixture(scope="module")
def real_face():
    from cassi.data.face.model import build_face

    return build_face()


def test_real_face_lips_stay_in_front_of_the_upper_teeth(real_face, profile):
    """Section 4.2.2: the parabolic track keeps the lips from folding through the teeth. Where
    the data put a lip's centre line in front of the upper front teeth, no vertex of that lip's
    outline goes behind the teeth's labial surface, while the lips round and stretch. (Where the
    pellet itself is at or behind the incisors, as the stretched end of this task puts it, the
    thesis promises nothing.)"""
    from cassi.data.face import numbering as N

    rec = protrusion_recording(profile)
    anim = Cassi20().animate(profile, real_face, rec)
    teeth = np.asarray(N.UPPER_TEETH) - 1
    outlines = {67: (67, 68, 69, 70), 64: (64, 65, 66, 300)}
    checked = 0
    for f in range(anim.n_frames):
        tx, ty = anim.positions[f, teeth, 0], anim.positions[f, teeth, 1]
        order = np.argsort(ty)
        surface = lambda y: np.interp(y, ty[order], tx[order])  # noqa: E731
        for centre, outline in outlines.items():
            if anim.positions[f, centre - 1, 0] <= surface(0.0):
                continue
            for v in outline:
                x, y, _ = anim.positions[f, v - 1]
                if y <= ty.max():
                    checked += 1
                    assert x >= surface(y) - 1e-3, (f, v)
    assert checked > 2 * anim.n_frames


def test_real_face_runs_all_lip_versions(real_face, profile):
    rec = toy_recording(300)
    for v in (Cassi20(), Cassi21()):
        anim = v.animate(profile, real_face, rec)
        assert np.isfinite(anim.positions).all()


def test_real_face_no_jump_at_the_ellipse_switch(real_face, profile):
    """Thesis 4.2.5 / Table 5.9: on a wide jaw-wagging task (task 106) the lips switch between
    horizontal and vertical ellipses without a frame jump larger than the data's own (the
    largest per-row step of the lip pellets' vertices 67 and 49). The shared tuning (rho 0.1, a
    band of 5 c' units, under which the toy's wag switches 8 times)."""
    anim = Cassi20(tuning="shared").animate(profile, real_face, toy_recording(1200, wag_deg=20.0))
    kind = anim.diagnostics["ellipse"].to_numpy()
    switches = np.nonzero(kind[1:] != kind[:-1])[0]
    assert len(switches) >= 4
    lips = np.asarray(LIP_VERTICES) - 1
    step = np.linalg.norm(np.diff(anim.positions[:, lips], axis=0), axis=-1).max(axis=1)
    data = max(np.linalg.norm(np.diff(anim.vertex(v), axis=0), axis=1).max() for v in (67, 49))
    assert step[switches].max() <= data
    assert step.max() <= 1.05 * data


def test_real_face_2_0_jumps_where_c_prime_leaves_the_band_and_2_1_does_not(real_face, profile):
    """Thesis 5.4: 2.0, untuned (rho 1), snaps the width from Eq. 4.14's c to c' in one row
    where c' leaves the band near c_rest (the toy's upper lip moves 15 c' units and more);
    2.1 (rho 0.1) spreads the same change over rows (on this toy 14.7 and 2.2 times the pellets'
    largest step per row)."""
    rec = toy_recording(1200, wag_deg=20.0)
    lips = np.asarray(LIP_VERTICES) - 1
    ratio = {}
    for version in (Cassi20(), Cassi21()):
        anim = version.animate(profile, real_face, rec)
        step = np.linalg.norm(np.diff(anim.positions[:, lips], axis=0), axis=-1).max(axis=1)
        data = max(np.linalg.norm(np.diff(anim.vertex(v), axis=0), axis=1).max() for v in (67, 49))
        ratio[version.name] = step.max() / data
    assert ratio["cassi-2.0"] > 4.0 * ratio["cassi-2.1"], ratio


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lipthick=st.floats(0.2, 2.5), ul_dy=st.floats(-6.0, 12.0),
       reading=st.sampled_from(list(LowLipsReading)))
def test_2_1_differs_from_2_0_exactly_for_low_lip_subjects(face, lipthick, ul_dy, reading):
    """Thesis 4.3.1: 2.1 changes a subject only when, with 2.0's equal thicknesses, the upper
    lip's inside edge (z67 - currthick) starts beyond the threshold (more than 20 units below
    vertex 226 by the text, lower than 20 above it by the results); then only the lips (and
    what follows them) change."""
    prof = dataclasses.replace(toy_profile(), lipthick=lipthick)
    rec = _ul_raised(toy_recording(60), ul_dy)   # the upper lip starts higher or lower
    a20 = Cassi20(tuning="2.1").animate(prof, face, rec)    # 2.1's tuning: only thickness differs
    a21 = Cassi21(reading=reading).animate(prof, face, rec)
    z226 = face.vertices[225, 2]
    edge = a20.vertex(67)[0, 2] - a20.diagnostics["currthick"].iloc[0]
    if reading is LowLipsReading.TEXT:
        low = z226 - edge > LK.LOW_LIPS_THRESHOLD
    else:
        low = edge - z226 < LK.LOW_LIPS_THRESHOLD
    np.testing.assert_allclose(a21.diagnostics["low_lips_inside_edge"].iloc[0], edge - z226,
                               atol=1e-3)
    assert a21.diagnostics["thickness_rule"].iloc[0] == ("low-lips" if low else "equal")
    if not low:
        np.testing.assert_array_equal(a21.positions, a20.positions)
    else:
        diff = np.abs(a21.positions - a20.positions).max(axis=(0, 2))
        changed = {i + 1 for i in np.nonzero(diff > 1e-4)[0]}
        assert 61 in changed
        assert changed <= set(LIP_VERTICES) | set(NEIGHBOURS) | set(NOSE_TIP)


#: thesis Figure 3.9 via tests/fixtures/SOURCES.md: the first 16 rows of JW45 task 13.
JW45_TASK_13 = FIXTURES / "xrmb" / "JW45" / "JW45_013.TXY"


def _jw45():
    """JW45 task 13 (the fixture) with JW45's rows of maxprotru.txt and lipthick.txt (thesis
    Figures 4.16, 4.25); the jaw length is this file's MNI-MNM at its first valid row."""
    rec = read_txy(JW45_TASK_13, subject="JW45", task=13)
    row = rec.xy_mm[rec.first_valid_index]
    mp = read_maxprotru(FIXTURES / "profiles" / "maxprotru.txt")["JW45"]
    lt = read_lipthick(FIXTURES / "profiles" / "lipthick.txt")["JW45"]
    prof = SubjectProfile("JW45", float(np.hypot(*(row[6] - row[7]))), mp.rest_ul, mp.rest_ll,
                          mp.max_ul, mp.max_ll, mp.min_ul, mp.min_ll, lt)
    return prof, rec


def test_real_face_jw45_task_13_fires_under_the_results_reading(real_face):
    """JW45's first valid row (thesis Figure 3.9) puts the inside edge 1.0 mm above 226; the
    thesis reports 2.1 changed JW45: the results' reading adjusts it, the text's does not."""
    prof, rec = _jw45()
    res = Cassi21(reading="results").animate(prof, real_face, rec).diagnostics
    text = Cassi21(reading="text").animate(prof, real_face, rec).diagnostics
    units_per_mm = model_jaw_length(real_face.vertices) / prof.jaw_length_mm
    edge_mm = res["low_lips_inside_edge"].iloc[0] / units_per_mm
    assert edge_mm == pytest.approx(1.0, abs=0.1)
    assert res["thickness_rule"].iloc[0] == "low-lips" and res["low_lips_margin"].iloc[0] > 0
    assert text["thickness_rule"].iloc[0] == "equal" and text["low_lips_margin"].iloc[0] < 0
    # one decision per task: the same values in every frame
    assert res["low_lips_margin"].nunique() == 1 and (res["low_lips_reading"] == "results").all()


def test_the_corner_reading_is_a_documented_option_of_2_0_and_2_1():
    from cassi.versions.lips import CornerReading
    assert Cassi20().corner is CornerReading.RESULTS
    assert Cassi20(corner="text").corner is CornerReading.TEXT
    assert Cassi21(corner="text").lip_stage().corner is CornerReading.TEXT
    assert Cassi21(reading="text").lip_stage().corner is CornerReading.RESULTS
    with pytest.raises(ValueError):
        Cassi20(corner="diamond")
