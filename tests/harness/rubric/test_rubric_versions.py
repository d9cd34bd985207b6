"""The rubric on real animations of every version (the embedded synthetic corpus, subject JW11).

Per version: every applicable check yields one whole-task row with a finite value; a face held
still at its first frame is silent for the motion checks (jitter, jumps); and defects planted
on top of the version's own animation fire (lips opened, palate lowered below the incisor tip,
lower lip dropped below the lower teeth, tongue pushed 2 mm through the incisors, a one-frame
jump at an ellipse switch). Results on the synthetic corpus describe the software only.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cassi.versions.mapping import subject_face
from cassi.harness import rubric as R
from cassi.harness.rubric import CHECKS
from cassi.harness.rubric import geometry as G

VERSIONS = ("parke-1974", "cassi-1.0", "cassi-2.0", "cassi-2.1")


def _subject(name):
    from cassi.data.corpus.disk import Corpus
    from cassi.data.corpus.profile import preprocess
    from cassi.data.synth.corpus import default_corpus

    corpus = Corpus(default_corpus())
    prof = preprocess(corpus, [name])[name]
    face = subject_face(palate_mm=prof.palate_mm, head_measures=prof.head_measures)
    return corpus, prof, face


@pytest.fixture(scope="module")
def subject():
    return _subject("JW11")


@pytest.fixture(scope="module")
def switching_subject():
    """JW16: its jaw wagging (task 106) with the upper lip held at rest (:func:`_upper_lip_held`)
    opens the 2.x mouths taller than wide in about a quarter of the frames."""
    return _subject("JW16")


def _upper_lip_held(rec, wander_mm=0.0):
    """``rec`` with the upper lip pellet's x held at its first valid row's (plus a fore-aft
    wander of ``wander_mm``): c' stays near c_rest while the jaw wags, so OUTER_ABC_CALC's
    branches 3(a)/3(b) take the mouth taller than wide (the generated upper lip is drawn back by
    the opening jaw, motion.UL_BACK_MM_PER_DEG, which keeps 2.x's task 106 horizontal)."""
    xy = np.array(rec.xy_mm, np.float64)
    first = int(np.flatnonzero(np.asarray(rec.valid).all(axis=1))[0])
    t = np.arange(xy.shape[0]) * 0.006866
    xy[:, 0, 0] = xy[first, 0, 0] + wander_mm * np.sin(2 * np.pi * 0.37 * t)
    return dataclasses.replace(rec, xy_mm=xy)


def _animate(subject, version, task, held=False):
    from cassi.versions.registry import get_version

    corpus, prof, face = subject
    rec = corpus.subject(prof.subject).load(task, 1)
    return get_version(version).animate(prof, face, _upper_lip_held(rec) if held else rec)


def _with(anim, positions):
    return dataclasses.replace(anim, positions=positions.astype(np.float32))


def _run(subject, anim, task, checks=None):
    _, prof, face = subject
    df = R.run_geometry_checks(anim, face, prof, task=task, subject=prof.subject, checks=checks)
    return df[(df["frame"] == -1) & (df["view"] == "geometry")].set_index("check")


@pytest.mark.parametrize("version", VERSIONS)
def test_every_check_measures_every_version(subject, version):
    for task in (5, 106, 118):
        anim = _animate(subject, version, task)
        res = _run(subject, anim, task)
        assert set(res.index) == {c.name for c in R.checks_for(kind="geometry", task=task)}
        assert (res["version"] == version).all()
        measurable = res.drop(index=[c for c in ("lips_too_large_moving",) if c in res.index])
        assert np.isfinite(measurable["value"]).all(), measurable[~np.isfinite(measurable["value"])]
        assert res["negatives"].between(0, 3).all()


@pytest.mark.parametrize("version", VERSIONS)
def test_a_still_face_does_not_jitter(subject, version):
    anim = _animate(subject, version, 106)
    still = np.repeat(anim.positions[:1], anim.n_frames, axis=0)
    res = _run(subject, _with(anim, still), 106, checks=["corner_jump_switch", "lip_jitter"])
    assert res.loc["corner_jump_switch", "negatives"] == 0
    anim = _animate(subject, version, 118)
    still = np.repeat(anim.positions[:1], anim.n_frames, axis=0)
    res = _run(subject, _with(anim, still), 118, checks=["lip_jitter"])
    assert res.loc["lip_jitter", "negatives"] == 0


@pytest.mark.parametrize("version", VERSIONS)
def test_planted_defects_fire_on_every_version(subject, version):
    _, prof, face = subject
    parts = G.mouth_parts(face)
    mm = G.mm_per_unit(face.vertices, prof.jaw_length_mm)
    anim = _animate(subject, version, 5)
    pos = anim.positions.astype(np.float64)
    F = pos.shape[0]

    # lips opened so they are at least 10 mm apart in every frame: never touching, two negatives
    p = pos.copy()
    lower = [v - 1 for v in range(49, 61)]
    gap = p[:, parts.ul_inner, 2] - p[:, parts.ll_inner, 2]
    p[:, lower, 2] -= 10.0 / mm - gap.min()
    assert _run(subject, _with(anim, p), 5, ["lips_never_touch"]).loc[
        "lips_never_touch", "negatives"] == 2

    # palate lowered 3 mm below the incisor tip: very noticeable, two negatives
    p = pos.copy()
    p[:, parts.palate, 2] = np.minimum(p[:, parts.palate, 2],
                                       p[:1, parts.upper_incisor_tip, 2] - 3.0 / mm)
    assert _run(subject, _with(anim, p), 5, ["palate_below_incisor"]).loc[
        "palate_below_incisor", "negatives"] == 2

    # the lower lip dropped 5 mm below the lower gum line in 60 % of the frames: usual state
    p = pos.copy()
    n = int(0.6 * F)
    drop = p[:n, parts.ll_inner, 2] - (p[:n, parts.lower_gum, 2] - 5.0 / mm)
    p[:n, lower, 2] -= drop[:, None]
    assert _run(subject, _with(anim, p), 5, ["lower_lip_below_teeth"]).loc[
        "lower_lip_below_teeth", "negatives"] == 2

    # the tongue tip 2 mm through the back of the upper incisors (at the tooth's middle height)
    p = pos.copy()
    tris = G.front_triangles(face.vertices, parts.upper_teeth_tris)
    tip = parts.tongue[0]
    probe = p[:, tris].mean(axis=(1, 2))                         # (F, 3) inside the front teeth
    probe[:, 1] = 0.0
    lo, _ = G.surface_hits(probe[:, None, :], p[:, tris], axis=0)
    p[:, tip] = probe
    p[:, tip, 0] = lo[:, 0] + 2.0 / mm
    r = _run(subject, _with(anim, p), 5, ["tongue_through_teeth"]).loc["tongue_through_teeth"]
    upper = float(r["detail"].split("upper ")[1].split(" mm")[0])
    assert r["negatives"] >= 1 and upper >= 1.95, r["detail"]


@pytest.mark.parametrize("version", ("cassi-2.0", "cassi-2.1"))
def test_one_frame_jump_at_the_ellipse_switch_fires(switching_subject, version):
    subject = switching_subject
    anim = _animate(subject, version, 106, held=True)
    before = _run(subject, anim, 106, ["corner_jump_switch"]).loc["corner_jump_switch"]
    b = anim.diagnostics["ellipse"].to_numpy()       # horizontal <-> vertical
    switches = np.flatnonzero(b[1:] != b[:-1]) + 1
    assert switches.size, "the version reports no ellipse switch on this task"
    _, prof, face = subject
    parts = G.mouth_parts(face)
    mm = G.mm_per_unit(face.vertices, prof.jaw_length_mm)
    p = anim.positions.astype(np.float64)
    s = int(switches[len(switches) // 2])
    p[s:, parts.corner, 1] += 3.0 / mm        # the corner steps 3 mm out at the switch and stays
    r = _run(subject, _with(anim, p), 106, ["corner_jump_switch"]).loc["corner_jump_switch"]
    # the jaw's own step in that frame is subtracted: the switch falls while the jaw opens
    assert r["negatives"] == 1 and r["value"] >= max(2.0, before["value"]), r["detail"]


@pytest.mark.parametrize("version", VERSIONS)
def test_the_2_1_criterion_margin_is_a_whole_task_row(subject, version):
    """cassi-2.1's low-lips decision (thesis 4.3.1) is one row per task file, view criterion,
    never charged: the margin in mm (the diagnostic in units times mm per unit), signed as
    the decision (> 0: adjusted); the other versions make no such decision."""
    _, prof, face = subject
    anim = _animate(subject, version, 5)
    df = R.run_geometry_checks(anim, face, prof, task=5, subject="JW11")
    crit = df[df["view"] == "criterion"]
    if version != "cassi-2.1":
        assert crit.empty
        return
    assert len(crit) == 1
    row = crit.iloc[0]
    assert row["check"] == "low_lips_margin" and row["frame"] == -1 and row["negatives"] == 0
    assert row["table"] is None or row["table"] != row["table"]
    mm = G.mm_per_unit(face.vertices, prof.jaw_length_mm)
    margin = anim.diagnostics["low_lips_margin"].iloc[0]
    assert row["value"] == pytest.approx(margin * mm)
    adjusted = anim.diagnostics["thickness_rule"].iloc[0] == "low-lips"
    assert (row["value"] > 0) == adjusted
    assert ("adjusted" if adjusted else "as 2.0") in row["detail"]
    assert "reading results" in row["detail"]
    # a run that asks for named checks gets only those
    assert R.run_geometry_checks(anim, face, prof, task=5, subject="JW11",
                                 checks=["teeth_front_overlap"])["view"].eq("geometry").all()


def test_2_0_s_jitter_on_the_jaw_wagging_is_charged_and_2_1_s_is_not(subject):
    """Thesis 5.4: the judges charged 2.0 with "a jitter in the transition from horizontal to
    vertical ellipse" and not 2.1. On JW11's own task 106 (embedded corpus, nothing planted): as
    the jaw opens, the upper lip drawn back by it leaves the band near c_rest on the way to the
    switch; OUTER_ABC_CALC leaves 3(a) for 3(c), where 2.0 (rho 1) snaps the width to Eq. 4.8's
    in one row and 2.1 (rho 0.1) eases it. Results on the synthetic corpus describe the software."""
    threshold = CHECKS["corner_jump_switch"].thresholds[0]
    _, prof, face = subject
    parts = G.mouth_parts(face)
    mm = G.mm_per_unit(face.vertices, prof.jaw_length_mm)
    r, step, branch = {}, {}, {}
    for v in ("cassi-2.0", "cassi-2.1"):
        anim = _animate(subject, v, 106)
        r[v] = _run(subject, anim, 106, ["corner_jump_switch"]).loc["corner_jump_switch"]
        step[v] = G.corner_step_excess(anim.positions.astype(np.float64), parts) * mm
        branch[v] = anim.diagnostics["outer_abc_branch"].to_numpy()
    assert r["cassi-2.0"]["negatives"] == 1 and r["cassi-2.0"]["value"] > threshold, r["cassi-2.0"]
    assert r["cassi-2.1"]["negatives"] == 0 and r["cassi-2.1"]["value"] < threshold, r["cassi-2.1"]
    # the pop: 2.0's corner steps several mm in the row where 3(a)/3(b) gives way to 3(c); 2.1's
    # moves a fraction of that there and as much in the rows after (eased over ~10 rows)
    f = int(np.argmax(step["cassi-2.0"]))
    assert step["cassi-2.0"][f] > 5.0 and step["cassi-2.1"][f] < 0.2 * step["cassi-2.0"][f]
    b20 = branch["cassi-2.0"]
    assert b20[f - 1] in ("3a", "3b") and b20[f] == "3c-ii", b20[f - 2:f + 2]


def test_2_0_s_switch_jitter_is_charged_and_2_1_s_is_not(subject):
    """The same at the switch itself (planted): JW11's task 106 with the upper lip held at rest
    but wandering 0.5 mm fore and aft (:func:`_upper_lip_held`), so the mouth turns taller than
    wide in 3(a) and c' leaves the band around the switches."""
    corpus, prof, face = subject
    rec = _upper_lip_held(corpus.subject("JW11").load(106, 1), wander_mm=0.5)
    from cassi.versions.registry import get_version

    r = {v: _run(subject, get_version(v).animate(prof, face, rec), 106,
                 ["corner_jump_switch"]).loc["corner_jump_switch"]
         for v in ("cassi-2.0", "cassi-2.1")}
    threshold = CHECKS["corner_jump_switch"].thresholds[0]
    assert r["cassi-2.0"]["negatives"] == 1 and r["cassi-2.0"]["value"] > threshold, r["cassi-2.0"]
    assert "ellipse switch" in r["cassi-2.0"]["detail"]
    assert r["cassi-2.1"]["negatives"] == 0, r["cassi-2.1"]
