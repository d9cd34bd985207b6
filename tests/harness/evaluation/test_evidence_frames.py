"""The evidence frames: the frames the report links to, in the view each link opens in, and the
render budget that counts them (the frame policy, :mod:`cassi.harness.evaluation.frames`)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd

from cassi.harness.evaluation import frames as F
from cassi.harness.rubric import CHECKS, checks_for

FILE = {"subject": "JW11", "task": 19, "rep": 1, "version": "cassi-1.0"}


def _row(check, frame, negatives, *, table="A", view="geometry"):
    return {**FILE, "view": view, "frame": frame, "check": check, "table": table,
            "negatives": negatives}


def _rows() -> pd.DataFrame:
    return pd.DataFrame([
        _row("lips_through_teeth", -1, 2), _row("lips_through_teeth", 598, 0),      # side
        _row("teeth_back_overlap", -1, 1), _row("teeth_back_overlap", 1563, 0),     # half
        _row("tongue_through_teeth", -1, 1), _row("tongue_through_teeth", 1410, 0),  # front
        _row("lips_never_touch", -1, 0), _row("lips_never_touch", 300, 0),          # not charged
        _row("jaw_long", -1, 3),                                           # charged, no frame
        _row("trace_lip_aperture_data", 12, 0, table=None, view="trace"),  # per-frame data
    ])


def test_linked_frames_are_the_charged_checks_evidence_frames():
    key = ("JW11", 19, 1, "cassi-1.0")
    assert F.linked_frames(_rows()) == {(*key, "lips_through_teeth"): 598,
                                        (*key, "teeth_back_overlap"): 1563,
                                        (*key, "tongue_through_teeth"): 1410}
    assert F.linked_frames(pd.DataFrame()) == {}


def test_evidence_frames_are_in_the_view_each_check_is_judged_from():
    assert {c: F.linked_view(c) for c in ("lips_through_teeth", "teeth_back_overlap",
                                          "tongue_through_teeth")} == \
        {"lips_through_teeth": "side", "teeth_back_overlap": "half",
         "tongue_through_teeth": "front"}
    animated = np.arange(2, 1500)  # 1563 is past the last animated frame: not rendered
    assert F.evidence_frames(_rows(), animated) == {"front": [1410], "side": [598]}
    assert F.linked_view("no_such_check") is None


def test_render_budget_counts_the_evidence_frames():
    per_view = F.evidence_budget(19)
    non_image = [c for c in checks_for(task=19) if c.kind != "image"]
    assert sum(per_view.values()) == len(non_image) and per_view["side"] > 0
    assert all(CHECKS[c.name].view in per_view for c in non_image)
    task = SimpleNamespace(usable=True, subject="JW11", task=19, rep=1)
    views = ("front", "side", "top")
    n = F.render_budget({("JW11", 19, 1): 1000}, [task], ["cassi-1.0", "cassi-2.1"], views,
                        stride=0, extremes=0, animate_stride=0)
    # per version and view: the first frame, and at most one evidence frame per check
    assert n == 2 * sum(1 + per_view.get(v, 0) for v in views)
