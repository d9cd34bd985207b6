"""The rubric registry, the rating scale (thesis Table 5.2) and the tables built from results."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from cassi.common.errors import CassiInputError
from cassi.harness import rubric as R


def test_rating_scale_is_thesis_table_5_2():
    # thesis Table 5.2: EXCELLENT 0, VERY GOOD 1, GOOD 2, FAIR 3, POOR 4, VERY POOR 5,
    # UNACCEPTABLE >= 6
    expected = ["EXCELLENT", "VERY GOOD", "GOOD", "FAIR", "POOR", "VERY POOR", "UNACCEPTABLE",
                "UNACCEPTABLE", "UNACCEPTABLE"]
    assert [R.rate(n) for n in range(9)] == expected
    assert R.rate(np.int64(2)) == "GOOD"
    with pytest.raises(CassiInputError):
        R.rate(-1)


def test_registry_is_complete_and_consistent():
    assert len(R.CHECKS) == len(set(R.CHECKS))
    for name, c in R.CHECKS.items():
        assert c.name == name
        assert c.table in R.TABLES and c.thesis_table == R.TABLES[c.table][0]
        assert c.text and c.reason and c.description and c.unit and c.frames
        assert c.view in {"front", "side", "half", "top"}
        assert c.kind in {"geometry", "image", "fidelity"}
        assert callable(c.func)
        assert all(1 <= n <= 3 for n in c.negatives)
    # Tables D and E apply to their tasks only
    assert all(c.tasks == (118,) for c in R.checks_for(table="D"))
    assert all(c.tasks == (106,) for c in R.checks_for(table="E"))
    assert not any(c.applies_to(5) for c in R.checks_for(table="D"))
    # Tables A-C judge the speech files (thesis 6.1: "the tasks given in Table 5.1"), never the
    # oral-motor tasks that D and E judge; F and G judge every file
    for task, tables in ((106, {"E", "F", "G"}), (118, {"D", "F", "G"}),
                         (19, {"A", "B", "C", "F", "G"}), (105, {"A", "B", "C", "F", "G"})):
        assert {c.table for c in R.checks_for(task=task)} == tables, task
    assert all(not c.applies_to(t) and c.skip_tasks == (106, 118)
               for c in R.CHECKS.values() if c.table in "ABC" for t in (106, 118))
    assert all(c.applies_to(None) for c in R.CHECKS.values() if c.tasks is None)
    # Table F is labelled as cassi-farm's, not the thesis's
    assert R.TABLES["F"][0] == "" and "not in the thesis" in R.table_title("F")
    # one fault, one charge names a registered check
    assert R.CHECKS["lips_do_not_close"].charged_with == "lips_apart_at_start"
    # every table has at least one counted check
    assert {c.table for c in R.CHECKS.values() if c.counted} == set(R.TABLES)


def test_every_rubric_md_criterion_is_registered(shared_dir):
    """Each bullet of rubric.md's Tables A-E (bar Table C's version comparison, done by
    cassi.harness.rubric.tables) maps to a registered check; the mapping is by key words of the bullet."""
    text = " ".join((shared_dir / "spec" / "rubric.md").read_text().split())
    expected_words = {
        "front teeth overlap": "teeth_front_overlap", "back teeth overlap": "teeth_back_overlap",
        "slant upward": "teeth_slope_up", "slant downward": "teeth_slope_down",
        "too far apart": "teeth_too_far_apart",
        # judged where the judges looked, the starting and ending frame (thesis 5.3.1)
        "never touching": "lips_apart_at_start",
        "separated at the start": "lips_apart_at_start", "tightly pressed": "lips_pressed",
        "centered low": "lips_centered_low", "centered high": "lips_centered_high",
        "below the bottom of the lower front teeth": "lower_lip_below_teeth",
        "surface of the teeth": "lips_through_teeth", "protrudes farther": "lower_lip_protrudes",
        "overlap (cross": "lips_overlap", "pokes through": "tongue_through_teeth",
        "barely visible": "tongue_hidden", "palatal outline (most": "tongue_through_palate",
        "below the tip of the upper front teeth": "palate_below_incisor",
        "very long": "jaw_long", "very square": "jaw_square", "too large seen": "jaw_large",
        "bottom teeth rarely seen": "lower_lip_too_large", "no lip rounding": "no_lip_rounding",
        "stick out too much": "lips_stick_out", "above the lip cave in": "above_lip_cave_in",
        "into the nose": "lips_into_nose", "too big at maximum": "lips_too_big",
        "centered too high or too low": "lips_centering_118",
        "protrudes in the initial": "lower_lip_protrudes_start",
        "top lip protrudes more": "upper_protrudes_more", "sharp profile": "upper_lip_sharp",
        "jitter of the lips beyond": "lip_jitter", "triangular or diamond": "lip_shape_triangular",
        "through the bottom set": "lower_lip_through_teeth", "under the lip cave in": "below_lip_cave_in",
        "corners badly placed": "corners_misplaced", "chin or lower jaw caves": "chin_cave_in",
        "ellipse": "corner_jump_switch",
    }
    for words, check in expected_words.items():
        assert words in text, f"rubric.md no longer says {words!r}"
        assert check in R.CHECKS


def test_grading_by_thresholds_and_direction():
    c = R.CHECKS["lips_never_touch"]           # higher is worse: 1.0 -> 1, 4.0 -> 2
    assert [c.grade(v) for v in (0.0, 1.5, 1.51, 3.9, 4.01, 100.0)] == [0, 0, 1, 1, 2, 2]
    assert c.grade(float("nan")) == 0
    lo = R.CHECKS["lips_into_nose"]            # lower is worse: 0.5 -> 1, 0.2 -> 2
    assert [lo.grade(v) for v in (1.0, 0.49, 0.19, -1.0)] == [0, 1, 2, 2]
    assert R.CHECKS["teeth_slope_up"].grade(30.0) == 3


def _check(**over):
    kw = dict(name="x", table="A", component="lips", view="front", unit="mm", frames="",
              description="", thresholds=(1.0,), negatives=(1,), direction="higher", reason="r",
              text="t", kind="geometry", measure="measures:m_lips_pressed")
    kw.update(over)
    return R.Check(**kw)


def test_bad_check_definitions_are_refused():
    assert _check().func.__name__ == "m_lips_pressed"
    for bad in (dict(table="Z"), dict(thresholds=(2.0, 1.0), negatives=(1, 2)),
                dict(negatives=(0,)), dict(direction="up"), dict(kind="sound"),
                dict(measure="m_lips_pressed")):
        with pytest.raises(ValueError):
            _check(**bad)
    with pytest.raises(TypeError):  # declared with keywords only
        R.Check("x", "A", "lips", "front", "mm", "", "", (1.0,), (1,), "higher", "r", "t",
                "geometry", "measures:m_lips_pressed")


def test_unknown_check_names_suggest_close_ones():
    with pytest.raises(CassiInputError, match="lips_never_touch"):
        R.get_check("lips_never_tuch")


def test_thresholds_live_only_in_the_registry():
    """No grading literal in the measure modules: they return values, the registry decides."""
    for module in ("geometry.py", "image.py", "fidelity.py"):
        src = Path(R.__file__).with_name(module).read_text()
        assert "negatives" not in re.sub(r'""".*?"""', "", src, flags=re.S), module
    # the one measure with its own grading (tongue: one set, both sets, very noticeably both)
    # reads the registry's thresholds
    measures = Path(R.__file__).with_name("measures.py").read_text()
    assert measures.count("negatives=") == 1 and 'CHECKS["tongue_through_teeth"]' in measures
    # the image side reads its windows from the registry, not from literals of its own
    image = Path(R.__file__).with_name("image.py").read_text()
    assert ">= 5 " not in image and "0.7 *" not in image
    # ... and so do the depth and front-teeth windows (percentiles, step factors, shares)
    for module in ("image.py", "geometry.py"):
        src = re.sub(r'""".*?"""', "", Path(R.__file__).with_name(module).read_text(), flags=re.S)
        assert not re.search(r"percentile\([^()]*,\s*\d", src), module
        assert not re.search(r"\b(?!0\.5 )\d+\.\d+ \* ", src), module  # 0.5: midpoints
        assert not re.search(r"(share|nx)\w*: float = \d", src), module


def test_registry_table_lists_every_check_once():
    t = R.registry_table()
    assert t["check"].tolist() == list(R.CHECKS)
    assert (t["thesis_table"] == t["table"].map(lambda x: R.TABLES[x][0])).all()
