"""Table F, fidelity to the recording: a face exactly on the pellets passes, a face frozen at
rest fails, and a face with the tongue frozen (Parke's) is charged for the tongue only."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from cassi.data.face import numbering as N
from cassi.data.face.model import build_face
from cassi.harness import rubric as R
from cassi.harness.rubric import fidelity as FI
from cassi.versions.mapping import XrmbToParke

JAW_MM = 100.0
F = 300
FIDELITY = [c.name for c in R.checks_for(kind="fidelity", table="F")]


@pytest.fixture(scope="module")
def face():
    return build_face()


def recording():
    """Pellets (F, 8, 2) mm moving like speech: the jaw and the lips open and close (8 mm), the
    lips protrude (4 mm), the tongue rises and falls (12 mm), plus 0.1 mm noise."""
    t = np.arange(F) / 145.6
    rng = np.random.default_rng(1)
    rest = np.array([[10, 5], [9, -15], [-10, -8], [-25, -3], [-40, 0], [-52, -5],
                     [2, -20], [-30, -35]], float)
    xy = np.repeat(rest[None], F, 0)
    jaw = 4 * (1 - np.cos(2 * np.pi * 3 * t))            # 0..8 mm
    lips = 4 * (1 - np.cos(2 * np.pi * 2 * t + 1.0))
    xy[:, [1, 6, 7], 1] -= jaw[:, None]                  # LL rides on the jaw, MNI, MNM
    xy[:, 1, 1] -= lips
    xy[:, [0, 1], 0] += (2 * (1 - np.cos(2 * np.pi * 1 * t)))[:, None]
    xy[:, 2:6, 1] += (6 * np.sin(2 * np.pi * 2.5 * t))[:, None]
    xy += rng.normal(0, 0.1, xy.shape)
    return SimpleNamespace(xy_mm=xy, valid=np.ones((F, 8), bool), path=None)


def on_the_pellets(face, rec, *, frozen=()):
    """A face whose pellet sites sit on the mapped pellets (those in ``frozen`` stay at rest)."""
    m = XrmbToParke.from_face(face.vertices, JAW_MM)
    pos = np.repeat(np.asarray(face.vertices, float)[None], F, 0)
    p3 = m.to_parke3(rec.xy_mm)
    sites = {"UL": [N.UL], "LL": [N.LL], "T1": [N.TONGUE_PELLETS[0]], "T2": [N.TONGUE_PELLETS[1]],
             "T3": [N.TONGUE_PELLETS[2]], "T4": [N.TONGUE_PELLETS[3]], "MNI": [N.MANI],
             "MNM": list(N.MANM_PAIR)}
    for k, (name, rows) in enumerate(sites.items()):
        if name in frozen:
            continue
        for r in rows:
            # move the site with its pellet (the MNM pair keeps its midpoint on the pellet)
            pos[:, r - 1, [0, 2]] += p3[:, k][:, [0, 2]] - p3[0, k][[0, 2]]
    return pos


def judge(face, positions, rec):
    anim = SimpleNamespace(positions=positions, frames=np.arange(F), diagnostics=None,
                           version="planted")
    out = R.run_geometry_checks(anim, face, SimpleNamespace(jaw_length_mm=JAW_MM, subject="SYN"),
                                task=5, recording=rec, checks=FIDELITY)
    return out[out["frame"] == -1].set_index("check")


def test_a_face_exactly_on_the_pellets_passes(face):
    rec = recording()
    r = judge(face, on_the_pellets(face, rec), rec)
    assert set(r.index) == set(FIDELITY)
    assert (r["negatives"] == 0).all(), r[["value", "detail"]]
    assert r.loc["fidelity_lips_error", "value"] == pytest.approx(0.0, abs=1e-3)
    assert r.loc["fidelity_lip_aperture", "value"] == pytest.approx(1.0, abs=1e-6)
    assert r.loc["fidelity_jaw_opening_range", "value"] == pytest.approx(1.0, abs=1e-6)


def test_a_face_frozen_at_rest_fails(face):
    rec = recording()
    r = judge(face, np.repeat(np.asarray(face.vertices, float)[None], F, 0), rec)
    for check in ("fidelity_lips_error", "fidelity_tongue_error", "fidelity_jaw_error",
                  "fidelity_lip_aperture", "fidelity_lip_aperture_range",
                  "fidelity_jaw_opening", "fidelity_jaw_opening_range"):
        assert r.loc[check, "negatives"] >= 1, check
    assert r.loc["fidelity_lip_aperture", "value"] == 0.0      # no movement shares nothing
    # the error is the recording's own movement: LL travels up to 16 mm
    assert r.loc["fidelity_lips_error", "negatives"] == 2
    # evidence: the worst frame, and the RMSE / 95th percentile / worst in the detail
    assert "95th percentile" in r.loc["fidelity_lips_error", "detail"]


def test_a_tongue_that_does_not_follow_is_charged_for_the_tongue_only(face):
    rec = recording()
    r = judge(face, on_the_pellets(face, rec, frozen=("T1", "T2", "T3", "T4")), rec)
    assert r.loc["fidelity_tongue_error", "negatives"] >= 1
    assert r.drop(index="fidelity_tongue_error")["negatives"].sum() == 0


def test_a_recording_that_does_not_move_is_not_measured(face):
    rec = recording()
    rec.xy_mm[:] = rec.xy_mm[:1]
    r = judge(face, np.repeat(np.asarray(face.vertices, float)[None], F, 0), rec)
    assert np.isnan(r.loc["fidelity_lip_aperture", "value"])
    assert r.loc["fidelity_lip_aperture", "negatives"] == 0


def test_virtual_pellets_invert_the_mapping(face):
    rec = recording()
    m = XrmbToParke.from_face(face.vertices, JAW_MM)
    pos = np.repeat(np.asarray(face.vertices, float)[None], 2, 0)
    xy = FI.virtual_pellets(pos, m)
    assert xy.shape == (2, 8, 2)
    # vertex 226 is the XRMB origin; the UL site maps back to 67's place
    v = np.asarray(face.vertices, float)
    assert np.allclose(m.to_parke(xy[0, 0]), v[N.UL - 1, [0, 2]])
    del rec


def test_traces_of_task_106_are_kept_without_a_table(face):
    rec = recording()
    anim = SimpleNamespace(positions=on_the_pellets(face, rec), frames=np.arange(F),
                           diagnostics=None, version="planted")
    out = R.run_geometry_checks(anim, face, SimpleNamespace(jaw_length_mm=JAW_MM, subject="SYN"),
                                task=106, recording=rec, checks=None, neutral=face.vertices)
    tr = out[out["view"] == "trace"]
    assert len(tr) and tr["table"].isna().all() and (tr["negatives"] == 0).all()
    assert set(tr["check"]) == {f"trace_{v}_{s}" for v in FI.TRACT_VARIABLES for s in ("model", "data")}
    assert isinstance(out, pd.DataFrame)
