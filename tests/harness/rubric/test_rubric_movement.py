"""Movement judged in Tables C and E: a planted still face earns "the lips do not open" in C and
"the jaw does not open" in E and is not EXCELLENT there; a face that follows the recording earns
neither; lips held apart, which never close, are charged once in C (lips_apart_at_start), not
twice."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from cassi.data.face import numbering as N
from cassi.data.face.model import build_face
from cassi.harness import rubric as R
from cassi.versions.mapping import XrmbToParke

from test_rubric_fidelity import F, recording
from test_rubric_shape import JAW_MM, LOWER, lips_that_follow

MOVEMENT = ["lips_do_not_close", "lips_do_not_open", "jaw_does_not_open"]
RANGES = ["fidelity_lip_aperture_range", "fidelity_jaw_opening_range"]


@pytest.fixture(scope="module")
def face():
    return build_face()


def judge(face, positions, rec, *, tasks=(5, 106),
          checks=MOVEMENT + RANGES + ["lips_apart_at_start", "lips_never_touch"]):
    """The checks on the same animation as a speech file (task 5: Tables A-C) and as the jaw
    wagging task (106: Table E); Tables F and G judge both."""
    anim = SimpleNamespace(positions=positions, frames=np.arange(F), diagnostics=None,
                           version="planted")
    return pd.concat([R.run_geometry_checks(anim, face, SimpleNamespace(jaw_length_mm=JAW_MM,
                                                                        subject="SYN"),
                                            task=task, recording=rec, checks=checks)
                      for task in tasks], ignore_index=True)


def whole(out, task=None):
    """Whole-task rows by check: of ``task``, or the speech file's and 106's E rows."""
    rows = out[out["frame"] == -1]
    rows = rows[(rows["task"] == task) if task is not None else
                ((rows["task"] == 5) | (rows["table"] == "E"))]
    return rows.set_index("check")


def still(face, *, drop_mm=0.0):
    pos = np.repeat(np.asarray(face.vertices, float)[None], F, 0)
    if drop_mm:  # the lower lip held down: lips apart in every frame
        units = drop_mm * float(XrmbToParke.from_face(face.vertices, JAW_MM).scale)
        for r in LOWER:
            pos[:, r - 1, 2] -= units
    return pos


def cell(out, table, component):
    cr = R.component_ratings(out).set_index(["table", "component"])
    return cr.loc[(table, component)]


def test_registered_in_c_and_e_with_table_f_s_ranges():
    c, o, j = (R.get_check(n) for n in MOVEMENT)
    assert (c.table, c.component, o.table, o.component) == ("C", "lips", "C", "lips")
    assert (j.table, j.component, j.tasks) == ("E", "jaw", (106,))
    assert c.charged_with == "lips_apart_at_start"   # within C: Table A's row judged again there
    assert o.thresholds == j.thresholds == (0.5, 0.1) and c.thresholds == (0.75, 0.25)


def test_a_still_face_is_not_excellent_in_c_or_e(face):
    rec = recording()
    out = judge(face, still(face), rec)
    r = whole(out)
    assert r.loc["lips_do_not_open", "value"] == 0.0 and r.loc["lips_do_not_open", "negatives"] == 2
    assert r.loc["jaw_does_not_open", "value"] == 0.0 and r.loc["jaw_does_not_open", "negatives"] == 2
    # Parke's rest lips touch (1.35 mm), so they are closed where the speaker closes them
    assert r.loc["lips_do_not_close", "negatives"] == 0
    c, e = cell(out, "C", "lips"), cell(out, "E", "jaw")
    assert c["rating"] != "EXCELLENT" and "the lips do not open" in c["text"]
    assert e["rating"] != "EXCELLENT" and "the jaw does not open" in e["text"]
    # Table F charges the same ranges in its own table
    assert cell(out, "F", "lips")["negatives"] >= 1 and cell(out, "F", "jaw")["negatives"] >= 1


def test_jaw_does_not_open_is_judged_on_task_106_only(face):
    rec = recording()
    r = whole(judge(face, still(face), rec, tasks=(5,)), task=5)
    assert "jaw_does_not_open" not in r.index and "lips_do_not_open" in r.index
    # and C's lip checks are not judged on task 106 (the thesis's C is the Table 5.1 files)
    r = whole(judge(face, still(face), rec, tasks=(106,)), task=106)
    assert "jaw_does_not_open" in r.index
    assert not {"lips_do_not_open", "lips_do_not_close", "lips_apart_at_start",
                "lips_never_touch"} & set(r.index)


def test_a_face_that_follows_the_recording_earns_neither(face):
    rec = recording()
    out = judge(face, lips_that_follow(face, rec), rec)
    r = whole(out)
    assert (r.loc[MOVEMENT + RANGES, "negatives"] == 0).all(), r.loc[MOVEMENT, ["value", "detail"]]
    assert r.loc["lips_do_not_close", "value"] == pytest.approx(1.0)
    assert r.loc["lips_do_not_open", "value"] == pytest.approx(1.0, rel=0.1)
    assert cell(out, "E", "jaw")["rating"] == "EXCELLENT"


def test_lips_that_miss_half_the_closures_earn_one_negative(face):
    rec = recording()
    pos = lips_that_follow(face, rec)
    a = np.linalg.norm(rec.xy_mm[:, 0] - rec.xy_mm[:, 1], axis=1)
    closed = np.flatnonzero(a <= a.min() + R.registry.CLOSURE_BAND_MM)
    missed = closed[len(closed) // 2:]     # the lower lip 3 mm down there (not at the first frame)
    units = 3.0 * float(XrmbToParke.from_face(face.vertices, JAW_MM).scale)
    for r in LOWER:
        pos[missed, r - 1, 2] -= units
    # the recording ends open (mid-syllable); the face ends with its lips touching, as at rest,
    # where the judges looked at the ending frame (an open frame: lips_do_not_close unchanged)
    assert len(rec.xy_mm) - 1 not in closed
    end = pos[-1, N.UPPER_INNER[0] - 1, 2] - pos[-1, N.LOWER_INNER[0] - 1, 2]
    for r in LOWER:
        pos[-1, r - 1, 2] += end
    out = judge(face, pos, rec, tasks=(5,))
    r = whole(out, task=5)
    assert r.loc["lips_do_not_close", "value"] == pytest.approx(0.5, abs=0.02)
    assert r.loc["lips_do_not_close", "negatives"] == 1
    assert r.loc["lips_apart_at_start", "negatives"] == 0      # they touch at both ends ...
    assert r.loc["lips_never_touch", "negatives"] == 0         # ... and in the file
    v = R.verdicts(out).set_index(["table", "check"])
    assert v.loc[("C", "lips_do_not_close"), "negatives"] == 1  # C's own charge


def test_lips_held_apart_are_charged_once_in_c(face):
    rec = recording()
    out = judge(face, still(face, drop_mm=5.0), rec, tasks=(5,))
    r = whole(out, task=5)
    assert r.loc["lips_apart_at_start", "negatives"] == 2       # 4 mm or more: "large separation"
    assert r.loc["lips_never_touch", "negatives"] == 2          # Table G's, over the whole file
    assert r.loc["lips_do_not_close", "negatives"] == 2         # its own verdict ...
    v = R.verdicts(out).set_index(["table", "check"])
    # ... not charged again in C, where Table A's lips_apart_at_start charges the same fault
    assert v.loc[("C", "lips_do_not_close"), "negatives"] == 0
    assert v.loc[("C", "lips_do_not_close"), "raw_negatives"] == 2
    assert "lips_apart_at_start" in v.loc[("C", "lips_do_not_close"), "note"]
    c = cell(out, "C", "lips")
    assert c["negatives"] == 2 + 2                               # apart + do not open
    assert "do not close where" not in c["text"]


def test_a_charge_in_another_table_does_not_cancel_c_s():
    # one fault, one charge per table: lips_apart_at_start fired in another table only (a planted
    # row outside A and C) leaves C's lips_do_not_close charged
    base = dict(subject="JW11", task=106, rep=1, version="v", view="geometry", frame=-1,
                value=0.0, unit="", threshold=0.0, detail="")
    res = pd.DataFrame([dict(base, check="lips_do_not_close", table="C", component="lips",
                             negatives=1),
                        dict(base, check="lips_apart_at_start", table="G", component="lips",
                             negatives=1)])
    v = R.verdicts(res).set_index(["table", "check"])
    assert v.loc[("C", "lips_do_not_close"), "negatives"] == 1
