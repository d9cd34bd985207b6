"""The face's closed-lip span, from published vermilion heights and real jaw-pellet spacings,
tested (not tuned) against the thesis's statements about which lips touch at the first row."""
from __future__ import annotations

import numpy as np
import pytest

from cassi.data.corpus.profile import read_lipthick
from cassi.data.face import numbering as N
from cassi.data.face.build import CLOSED_LIP_SPAN
from cassi.data.face.model import build_face, jaw_length_units
from cassi.data.synth.subjects import SUBJECTS, VERMILION_HEIGHTS_MM
from cassi.harness.rubric.registry import get_check

#: The real jaw-pellet spacings (MNI-MNM) the project holds: JW11 (median of the real frames)
#: and JW45 (thesis Figure 3.9); the other subjects' are the generator's choice.
REAL_JAW = ("JW11", "JW45")


@pytest.fixture(scope="module")
def neutral():
    return build_face().vertices


def z(v, n):
    return float(v[n - 1, 2])


def lips_heights(v):
    """(upper lip 67-61, lower lip 58-49, resting gap 61-58), Parke units."""
    return z(v, N.UL) - z(v, 61), z(v, 58) - z(v, N.LL), z(v, 61) - z(v, 58)


def test_closed_lip_span_from_its_sources(neutral):
    # both real speakers are men: the men's vermilion heights
    assert {SUBJECTS[s].sex for s in REAL_JAW} == {"M"}
    vermilion = sum(VERMILION_HEIGHTS_MM["M"])                       # 17.05 mm
    jaw = float(np.mean([SUBJECTS[s].jaw_length_mm for s in REAL_JAW]))  # 38.39 mm
    p = jaw_length_units(neutral)
    up, low, gap = lips_heights(neutral)
    assert up + low == pytest.approx(CLOSED_LIP_SPAN)
    assert CLOSED_LIP_SPAN == pytest.approx(vermilion / jaw * p, abs=0.05)
    # the design's resting gap (lips lightly apart) and equal shares are kept
    assert gap == pytest.approx(5.0) and up == pytest.approx(low)


def test_which_first_rows_read_as_touching_against_the_thesis(neutral, fixtures_dir):
    """Thesis 4.2.3 assumes every subject's lips are "lightly placed together in the first line of
    valid data" (lipthick.txt is that UL-LL distance over the jaw length), and says that with
    CASSI 1.0 "a few subjects had upper and lower lips that never touched or lips that largely
    overlapped". CASSI 1.0 puts the face's lips on the pellets, so at the first row their edges
    are (lipthick - span / p) d apart. Read by the rubric's first-frame checks (apart beyond
    lips_apart_at_start's 1.5 mm, pressed beyond lips_pressed's 2 mm), the span touches for JW25
    and JW27 only: 13 of the 15 speakers' first rows are apart, against the thesis's assumption
    that all 15 touch. The span was set from its sources before this was computed."""
    lipthick = read_lipthick(fixtures_dir / "profiles" / "lipthick.txt")
    assert len(lipthick) == 15
    share = CLOSED_LIP_SPAN / jaw_length_units(neutral)
    apart_mm = get_check("lips_apart_at_start").thresholds[0]
    pressed_mm = get_check("lips_pressed").thresholds[0]
    gap = {s: (lt - share) * SUBJECTS[s].jaw_length_mm for s, lt in lipthick.items()}
    touching = {s for s, g in gap.items() if -pressed_mm <= g <= apart_mm}
    pressed = {s for s, g in gap.items() if g < -pressed_mm}
    assert touching == {"JW25", "JW27"}
    assert not pressed
    assert len(gap) - len(touching) == 13
