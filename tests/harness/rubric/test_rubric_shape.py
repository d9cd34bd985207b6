"""Table G, the shape between the pellets: a face whose lips follow the recording passes; a face
frozen at rest is charged the most for contact and rounding; an "oracle" with every pellet site
exactly on its pellet but lips twice as wide passes Table F and is caught by Table G."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from cassi.data.face import numbering as N
from cassi.data.face.model import build_face
from cassi.harness import rubric as R
from cassi.harness.rubric.leaveout import WITHHELD, WithheldSite
from cassi.versions.mapping import XrmbToParke

from test_rubric_fidelity import F, recording  # the speech-like pellets of Table F's tests

#: A real jaw length (the synthetic subjects' MNI-MNM is 34-38 mm), so the face's mouth has an
#: adult's width in the subject's millimetres.
JAW_MM = 37.0
SHAPE = [c.name for c in R.checks_for(kind="fidelity", table="G")]
PELLET_CHECKS = [c.name for c in R.checks_for(kind="fidelity", table="F")]
UPPER = list(N.UPPER_LIP)                                   # 61-69
LOWER = list(N.LOWER_LIP)                                   # 49-60
CORNERS = [N.CORNER, N.INNER_CORNER]                        # 70, 287


@pytest.fixture(scope="module")
def face():
    return build_face()


def lips_that_follow(face, rec, *, rounding=1.0, width=1.0):
    """Every pellet site on its pellet but LL's (the lower lip raised so that its inner edge
    meets the upper's at the recording's narrowest aperture), the whole upper lip moving with UL
    and the lower with LL, the corners drawn in by ``rounding`` mm
    of mouth width per mm of protrusion, and every lip vertex's y scaled by ``width``."""
    m = XrmbToParke.from_face(face.vertices, JAW_MM)
    pos = np.repeat(np.asarray(face.vertices, float)[None], F, 0)
    move = m.to_parke3(rec.xy_mm) - m.to_parke3(rec.xy_mm[:1])    # (F, 8, 3), Parke units
    for rows, k in ((UPPER, 0), (LOWER, 1)):
        for r in rows:
            pos[:, r - 1, [0, 2]] += move[:, k][:, [0, 2]]
    for r in CORNERS:
        pos[:, r - 1, [0, 2]] += 0.5 * (move[:, 0] + move[:, 1])[:, [0, 2]]
    sites = {6: [N.MANI], 7: list(N.MANM_PAIR)}
    for k, rows in sites.items():
        for r in rows:
            pos[:, r - 1, [0, 2]] += move[:, k][:, [0, 2]]
    # the tongue's sites on their pellets (a leave-one-out prediction on the spot)
    for k, r in enumerate(N.TONGUE_PELLETS, start=2):
        pos[:, r - 1, [0, 2]] = m.to_parke3(rec.xy_mm[:, k])[:, [0, 2]]
    # the inner edges meet (gap 0) at the recording's narrowest lip aperture
    narrowest = int(np.argmin(np.linalg.norm(rec.xy_mm[:, 0] - rec.xy_mm[:, 1], axis=1)))
    gap = pos[narrowest, N.UPPER_INNER[0] - 1, 2] - pos[narrowest, N.LOWER_INNER[0] - 1, 2]
    for r in LOWER:
        pos[:, r - 1, 2] += gap
    prot = 0.5 * (move[:, 0, 0] + move[:, 1, 0])                  # units forward
    for r in CORNERS:
        y = pos[:, r - 1, 1]
        pos[:, r - 1, 1] = np.sign(y) * np.maximum(np.abs(y) - 0.5 * rounding * prot, 0.0)
    for r in UPPER + LOWER + CORNERS:
        pos[:, r - 1, 1] *= width
    return pos


def sites_of(face, positions):
    """The planted face as its own leave-one-out prediction: its T2 and T3 sites (290, 291)."""
    m = XrmbToParke.from_face(face.vertices, JAW_MM)
    return {p: WithheldSite(p, np.arange(F),
                            m.to_xrmb(positions[:, N.TONGUE_PELLETS[k] - 1][:, [0, 2]]))
            for k, p in ((1, "T2"), (2, "T3"))}


def judge(face, positions, rec, *, task=118):
    anim = SimpleNamespace(positions=positions, frames=np.arange(F), diagnostics=None,
                           version="planted")
    out = R.run_geometry_checks(anim, face, SimpleNamespace(jaw_length_mm=JAW_MM, subject="SYN"),
                                task=task, recording=rec, checks=SHAPE + PELLET_CHECKS,
                                withheld=sites_of(face, positions))
    return out[out["frame"] == -1].set_index("check")


def test_table_g_is_its_own_table_of_fidelity_checks():
    assert set(SHAPE) == {"shape_lip_contact", "shape_mouth_width", "shape_rounding",
                          "shape_tongue_t2", "shape_tongue_t3"}
    assert WITHHELD == ("T2", "T3")
    assert all(R.get_check(c).table == "G" for c in SHAPE)
    assert "not in the thesis" in R.table_title("G")
    assert R.get_check("shape_rounding").tasks == (118,)


def test_lips_that_follow_the_recording_pass(face):
    rec = recording()
    r = judge(face, lips_that_follow(face, rec), rec)
    assert set(SHAPE) <= set(r.index)
    assert (r.loc[SHAPE, "negatives"] == 0).all(), r.loc[SHAPE, ["value", "detail"]]
    assert r.loc["shape_lip_contact", "value"] == pytest.approx(1.0)
    assert r.loc["shape_mouth_width", "value"] == 0.0
    assert r.loc["shape_rounding", "value"] == pytest.approx(1.0, rel=0.05)


def test_a_still_face_scores_worst_on_contact_rounding_and_the_tongue_between_pellets(face):
    """Every Table G measure of movement gives a still face its most negatives; a measure of the
    face at rest (``Check.at_rest``, declared with its reason) judges the still face as it judges
    a moving face with the same rest."""
    rec = recording()
    still = np.repeat(np.asarray(face.vertices, float)[None], F, 0)
    r, moving = judge(face, still, rec), judge(face, lips_that_follow(face, rec), rec)
    at_rest = [c for c in SHAPE if R.get_check(c).at_rest]
    assert at_rest == ["shape_mouth_width"]
    for check in SHAPE:
        if check in at_rest:
            assert r.loc[check, "value"] == moving.loc[check, "value"], check
            assert r.loc[check, "negatives"] == moving.loc[check, "negatives"], check
        else:
            c = R.get_check(check)
            assert r.loc[check, "negatives"] == max(c.negatives), (check, r.loc[check, "detail"])
    # a face that never changes its contact shares nothing with the recording's closures
    assert r.loc["shape_lip_contact", "value"] == pytest.approx(0.0)
    assert r.loc["shape_rounding", "value"] == pytest.approx(0.0)
    # Parke's tongue stays where the model has it, centimetres from the recorded T2 and T3
    assert r.loc[["shape_tongue_t2", "shape_tongue_t3"], "value"].min() > 6.0


def test_a_measure_of_the_face_at_rest_reads_the_rest_only(face):
    """What ``at_rest`` declares holds: lips twice as wide after the first frame leave every such
    measure where the rest puts it, and each says why it reads the rest."""
    rec = recording()
    still = np.repeat(np.asarray(face.vertices, float)[None], F, 0)
    wide = lips_that_follow(face, rec, width=2.0)
    wide[0] = still[0]
    r, rest = judge(face, wide, rec), judge(face, still, rec)
    at_rest = [c for c in R.CHECKS.values() if c.at_rest]
    assert at_rest and all(c.frames == "first frame" for c in at_rest)
    for c in at_rest:
        assert r.loc[c.name, "value"] == rest.loc[c.name, "value"], c.name
    assert "not a movement" in R.get_check("shape_mouth_width").at_rest


def test_an_oracle_on_the_pellets_with_lips_twice_as_wide_is_caught(face):
    rec = recording()
    r = judge(face, lips_that_follow(face, rec, width=2.0), rec)
    assert r.loc["fidelity_lips_error", "value"] == pytest.approx(0.0, abs=1e-3)
    assert (r.loc[PELLET_CHECKS, "negatives"] == 0).all()          # Table F sees nothing wrong
    assert r.loc["shape_mouth_width", "negatives"] == 2
    assert r.loc["shape_mouth_width", "value"] > 20.0
    assert "mouth width at rest" in r.loc["shape_mouth_width", "detail"]


def test_lips_that_shut_where_the_speaker_opens_are_charged(face):
    rec = recording()
    pos = lips_that_follow(face, rec)
    # the lower lip's inner edge (58, 59, 60) stays up against the upper: always touching
    for r in N.LOWER_INNER:
        pos[:, r - 1, 2] = pos[:, N.UPPER_INNER[0] - 1, 2]
    r = judge(face, pos, rec)
    assert r.loc["shape_lip_contact", "negatives"] == 2
    assert "model lips apart in 0%" in r.loc["shape_lip_contact", "detail"]


def test_a_protrusion_without_rounding_is_charged_on_task_118_only(face):
    rec = recording()
    pos = lips_that_follow(face, rec, rounding=0.3)
    r = judge(face, pos, rec)
    assert r.loc["shape_rounding", "negatives"] == 1
    assert "shape_rounding" not in judge(face, pos, rec, task=5).index


def test_a_recording_whose_lips_never_close_is_not_judged_for_contact(face):
    rec = recording()
    rec.xy_mm[:] = rec.xy_mm[:1]
    r = judge(face, np.repeat(np.asarray(face.vertices, float)[None], F, 0), rec)
    assert np.isnan(r.loc["shape_lip_contact", "value"])
    assert r.loc["shape_lip_contact", "negatives"] == 0
    assert np.isnan(r.loc["shape_rounding", "value"])
