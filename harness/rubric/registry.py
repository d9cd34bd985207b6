"""The check registry: every criterion of the rubric, declared once with its thresholds and reasons.

The thesis's authors watched each animation and wrote down faults ("negatives"), one to three
per fault, and turned the count into a rating (thesis chapter 5, Table 5.2; restated in
``shared/spec/rubric.md``). Every criterion of rubric.md's Tables A-E, and cassi-farm's Table F
(fidelity to the recording), is a :class:`~cassi.harness.rubric.model.Check` declared here with
what it measures, its unit, view and frames, its thresholds and the negatives each earns, the
reason for each threshold, and the negative's text as the thesis writes it. ALL THRESHOLDS AND
WINDOWS LIVE IN THIS FILE, each with its reason; so do the rules that aggregate checks into the
thesis's tables (:mod:`.tables` applies them). Tables, reports and gates read the registry;
nothing else decides what a negative is.

No threshold here was tuned by counting how often a check fires on the synthetic corpus: each
comes from the thesis or from looking at renders, as its reason says.

Tables (``Check.table``): ``A`` teeth/lips/tongue per subject (thesis Table 5.3), ``B`` face
shape at initialization (5.4), ``C`` lip placement across versions (5.5, summary 5.6), ``D``
maximum lip protrusion, task 118 (5.8), ``E`` jaw wagging, task 106 (5.9), ``F`` fidelity to
the recording at the pellet sites and ``G`` the lips and tongue between the pellets (neither is the
thesis's; G is charged apart from F because a face on the pellets can still be the wrong shape).
"""
from __future__ import annotations

import dataclasses
import difflib

import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.files import (JAW_WAGGING_TASK, MAX_PROTRUSION_TASK, NOMINAL_PERIOD_US,
                                   ORAL_MOTOR_TASKS, rows_spanning)

from cassi.harness.rubric.model import Check

__all__ = ["CHECKS", "get_check", "checks_for", "registry_table", "MIN_FRAMES", "MIN_FAULT_MS", "SPEECH_TABLES",
           "TABLE_C_FROM_A", "MARKED_SHARE", "AGGREGATION_RULES", "CENTERED_SHARE"]

# ----------------------------------------------------------------------------------------------
# Windows: which frames and pixels a measure looks at
# ----------------------------------------------------------------------------------------------

# The windows below are stated in time (the thesis fixes none of them per frame): a recording
# at another rate (EMA at 500 Hz) is judged over the same milliseconds, in its own rows
# (GeometryContext reads its period); the *_FRAMES names are their row counts at XRMB's 6866 us.

#: A fault "during the task" must last MIN_FAULT_MS (3 x 6.866 ms ~ 20 ms) before it counts:
#: a single-frame graze is invisible at 146 frames per second, which is why sustained measures
#: take the MIN_FRAMES-th worst frame. One-frame jumps have their own check (corner_jump_switch).
MIN_FAULT_MS = 20.0
MIN_FRAMES = rows_spanning(MIN_FAULT_MS * 1000, NOMINAL_PERIOD_US)
#: "During the task, especially at its end" (Table 5.3, teeth): the end is the last END_SHARE of
#: the frames (at least MIN_FRAMES), where the jaw returns to rest and the half view holds still.
END_SHARE = 0.05
#: ... and during the task a teeth fault counts when held TEETH_HOLD_FRAMES frames (~100 ms): the
#: teeth are judged from the half view, where a posture held a tenth of a second is seen while a
#: passing phase of the jaw is not (a held consonant closure lasts 50-150 ms).
TEETH_HOLD_MS = 100.0
TEETH_HOLD_FRAMES = rows_spanning(TEETH_HOLD_MS * 1000, NOMINAL_PERIOD_US)
#: A jaw open for speech slants the lower teeth down and parts them: that is the movement, not a
#: fault. Slope and "too far apart" are therefore judged during the task only in the frames where
#: the jaw (vertex 258) is within JAW_NEAR_CLOSED_MM of its most closed position in the task,
#: i.e. where the teeth should sit as at rest; overlap (the jaw closing through the teeth) is a
#: fault in any frame. 2 mm: a jaw lowered less than that barely parts the incisors.
JAW_NEAR_CLOSED_MM = 2.0
#: The lower lip "goes below the bottom of the lower front teeth" when its edge (58) is this far
#: below the lower gum line (258): half a millimetre is beyond the round-off of the two outlines.
LIPS_BELOW_TEETH_MM = 0.5
#: The lips are "open wide" (Table E's shape, image extent) at this share of the task's widest
#: opening, and at least WIDE_OPEN_MM apart: the shape of a slit is not the shape of the mouth.
WIDE_OPEN_SHARE = 0.7
WIDE_OPEN_MM = 3.0
#: An outline reads as angular (Table E's "diamond-shaped") when it turns at a kink sharper than
#: this, degrees, away from the mouth's corners: a regular hexagon's 120 plus 5 for the shading's
#: round-off (lip_outline_angular's reason names the renders).
LIP_OUTLINE_KINK_DEG = 125.0
#: "Often" over a task for protrusion and crossing lips: the value a tenth of the frames reach
#: (90th percentile), so a few frames at a turning point do not decide and a habit does.
OFTEN_PERCENTILE = 90
#: Lip jitter: shake is the distance from a Savitzky-Golay fit over JITTER_WINDOW frames of degree
#: JITTER_ORDER over JITTER_WINDOW_MS (9 frames = 62 ms, shorter than a syllable, so speech
#: movements are smooth in it); the window is odd (centred on its frame).
JITTER_WINDOW_MS = 62.0
JITTER_WINDOW = rows_spanning(JITTER_WINDOW_MS * 1000, NOMINAL_PERIOD_US, odd=True)
JITTER_ORDER = 2

#: Lips are "open" for the image measures when the mouth opening covers at least this many pixels
#: in the front view (a sliver between touching lips is not an opening to judge centering in).
OPEN_MIN_PIXELS = 30
#: ... and is at least this many pixels tall somewhere. Added after the renders: Parke's neutral
#: lips part by 1.35 mm, a 1-pixel slit of ~40 pixels at the preview front view that passed the
#: area rule and had its glint of upper teeth judged as "centered high" (synthetic JW11 task 118).
OPEN_MIN_HEIGHT = 3
#: Centering (upper vs lower teeth inside the opening) is judged on frames open at least this
#: share of the task's widest opening. Added after the renders: Parke's face on synthetic JW11
#: task 118 showed the lower teeth more than the upper when open (share 0.32) but the median over
#: every open frame was 0.85 "centered high", carried by 3-pixel slits showing an upper edge only.
CENTERING_OPEN_SHARE = 0.5
#: Lip centring, "well centered" = "similar portions" of the upper and lower teeth inside the lip
#: opening (thesis 5.3.1, Figure 5.9, where a subject "centered slightly low" was charged): a file
#: is centred high (low) when the upper (lower) teeth's share of the teeth pixels inside the
#: opening, median over the open frames, is above CENTERED_SHARE. From front renders, the rule
#: declared first ("slightly low" begins where a viewer sees clearly more lower than upper teeth;
#: the mean of the crossings, one value both ways unless they differ by more than a step): one open
#: frame with the lip parts moved up and down in 0.5-1 mm steps, each render judged before its
#: share was read. Synthetic JW11 task 19, CASSI 2.1, frame 1055 (8 mm inner gap, final preset):
#: an upper share of 0.59 reads as similar portions, 0.66 and more as clearly more upper; a lower
#: share of 0.62 as barely more lower, 0.63 and more as clearly more lower. Synthetic JW18 task 4,
#: CASSI 2.0, frame 619 (7 mm, teeth in shadow): a lower share of 0.70 reads as similar portions
#: (the shadowed lower teeth count as pixels but barely show), 0.80 as clearly more lower.
#: Crossings 0.62 up, 0.63 and 0.75 down (0.69): 0.65 both ways. The 4:1 split (0.80) it replaces
#: caught only gross miscentring, which these renders show as one set of teeth alone.
CENTERED_SHARE = 0.65
#: A frame judges centering only when this many teeth pixels show inside the opening (a third of
#: the smallest opening: fewer is a glint, not "portions of the teeth").
TEETH_MIN_PIXELS = OPEN_MIN_PIXELS // 3
#: The lower teeth are "seen" in a frame when this many of their pixels show in the opening.
LOWER_TEETH_MIN_PIXELS = 5
#: The tongue "shows" when a connected patch of at least this many pixels of it lies inside the
#: lip opening. Tuned on renders: at the preview front view (1.3 mm per pixel) the tongue shows
#: through the 1-pixel gaps between the teeth as vertical slivers of 1-4 pixels, which the eye
#: does not read as the tongue; 6 px (~10 mm^2) is a visible patch.
TONGUE_MIN_PIXELS = 6

#: The front teeth, where a line along x (the depth of the side view) meets the teeth sensibly:
#: the tongue's and the lips' pass-through tests use the triangles of a set whose centroid lies in
#: its front FRONT_TEETH_SHARE of the set's x range (the incisors and canines: on the model's sets
#: their centroids lie 0.02-0.26 of that range behind the front, the first premolars from 0.33-0.39
#: on) and whose unit normal is at least FRONT_TEETH_MIN_NX along x (60 degrees off straight
#: ahead; the side teeth run along x, so a line along x would graze them). The same |n_x| as
#: CASSI 1.0's arch front (versions.constants TONGUE_ARCH_FRONT_NX), but the rubric's own.
FRONT_TEETH_SHARE = 0.35
FRONT_TEETH_MIN_NX = 0.5
#: Tongue in front of the teeth (front view, from the depth pass): the front teeth's depth is this
#: percentile of the teeth pixels' depth (the nearest teeth, robust to a stray pixel at a gap),
#: and a tongue pixel is in front of them when nearer by more than TEETH_DEPTH_MARGIN_SHARE of the
#: teeth pixels' depth spread, so a tongue seen between or behind the teeth never counts.
TEETH_FRONT_DEPTH_PERCENTILE = 10
TEETH_DEPTH_MARGIN_SHARE = 0.1
#: Touching teeth are split at the incisal line, the row where the depth steps from the upper
#: incisors to the lower ones behind them; a column shows that step when its largest
#: row-to-row depth change is more than this many times its median change (a clear edge, not the
#: curvature of one tooth's face); else the split falls back to the narrowest row.
INCISAL_STEP_FACTOR = 3.0
#: A tract variable's range in the recording and in the model: 5th to 95th percentile, so a
#: mistracked frame or two (XRMB pellets are lost and found again) does not make the range.
RANGE_PERCENTILES = (5, 95)

#: Table F: a tract variable that moves less than this in the recording (5th to 95th percentile)
#: gives nothing to follow; its correlation would be the correlation of noise (XRMB pellets are
#: accurate to ~0.5 mm), so it is not measured for that file.
FIDELITY_MIN_RANGE_MM = 2.0
#: Table F keeps the tract variables of these tasks as traces (results rows of view ``trace``,
#: no table, never negatives) for the report's "model vs data" plot: task 106, jaw wagging,
#: moves the jaw and lips through their whole range. A frame every TRACE_STEP_MS (every 10th
#: XRMB row, 14.6 Hz, three samples per syllable at 5 syllables a second) keeps the results
#: table small; a recording at another rate keeps a frame every as many of its own rows.
TRACE_TASKS = (JAW_WAGGING_TASK,)
TRACE_STEP_MS = 10 * NOMINAL_PERIOD_US / 1000
TRACE_STEP = rows_spanning(TRACE_STEP_MS * 1000, NOMINAL_PERIOD_US)

#: Table G: the model's lips "touch" when their inner edges (61 over 58) are at most this far
#: apart: lips_apart_at_start's threshold (Parke's neutral 1.35 mm reads as lips lightly touching
#: on the front render).
LIPS_TOUCH_MM = 1.5
#: Table G, lip contact: the recording's lips touch where the UL-LL pellet distance is within
#: CLOSURE_BAND_MM of its narrowest in the file, and are apart where it is OPEN_BAND_MM or more
#: beyond it. The pellets sit on the vermilion borders, so the distance at contact is the two
#: lips' thickness, which differs per speaker and is pressed thinner in a closure: Westbury &
#: Hashi (1997, "Lip-pellet positions during vowels and labial consonants", J. Phonetics 25,
#: 405-419) estimate the midline lip separation from the inter-pellet distance in just this way,
#: as the distance beyond the closed-lip distance "as long as lip-body deformation is taken into
#: account". Their per-speaker figures were not found here, so the bands are this rubric's own:
#: 1.5 mm is LIPS_TOUCH_MM (what reads as touching on the render) and 4 mm lips_apart_at_start's
#: "large separation"; frames between the two bands are not judged. The narrowest frame of a
#: file without a bilabial closure is taken as closed: a limit of a per-file rule.
CLOSURE_BAND_MM = LIPS_TOUCH_MM
OPEN_BAND_MM = 4.0
#: Table G, mouth width at rest: adult mouth width (cheilion-cheilion) 55.9 +- 3.3 mm (men) and
#: 52.0 +- 4.0 mm (women) (Maxillofacial Plastic and Reconstructive Surgery 2019, 41:20,
#: doi 10.1186/s40902-019-0191-7, Table 9: anthropometric norms, horizontal measurements). The
#: band is the women's mean - 2 SD to the men's mean + 2 SD.
MOUTH_WIDTH_RANGE_MM = (52.0 - 2 * 4.0, 55.9 + 2 * 3.3)

#: A tongue site this far from where the speaker's tongue is (mm): places of articulation along
#: the palate lie 5-10 mm apart (dental, alveolar, palatal), so a 3 mm miss blurs them in the
#: half view and 6 mm crosses one (two negatives). Table F's tongue error and Table G's
#: leave-one-out sites (``shape_tongue_t2``/``_t3``) are charged by the same bands. What a
#: tongue model can do between its pellets: a learned mapping predicts the midsagittal contour
#: from 3-4 pellets within 0.2-0.3 mm per point and "drastically improves over spline
#: interpolation" (Qin, Carreira-Perpinan, Richmond, Wrench & Renals, "Predicting tongue shapes
#: from a few landmark locations", Interspeech 2008, 2306-2309, doi 10.21437/Interspeech.2008-589):
#: a 3 mm miss between the pellets is a model's fault, not the data's limit.
TONGUE_MISS_MM = (3.0, 6.0)

#: Movement judged in Tables C and E (from Table F's ranges): the model's share of the
#: recording's opening (model range / recording range). Below HALF_REACH the lips or jaw read as
#: "do not open" (the under-articulated side of fidelity_*_range's band); below STILL_REACH a
#: 10-15 mm opening shows as about 1 mm, under a pixel at the preview front view (1.3 mm): the
#: face is seen standing still (two negatives).
HALF_REACH = 0.5
STILL_REACH = 0.1

# ----------------------------------------------------------------------------------------------
# The aggregation rules (applied by cassi.harness.rubric.tables, tested branch by branch)
# ----------------------------------------------------------------------------------------------

#: Table C is "the lip criteria of Table A, judged for each version on the same files" plus
#: Table C's own checks (rubric.md): the Table A rows of these components are judged again in C.
TABLE_C_FROM_A = ("lips",)
#: "A marked improvement over the previous version earns fewer negatives; a version that looks
#: worse earns an extra one" (rubric.md Table C). Both are measured per check on the task files
#: the two versions share, where the ratings would otherwise be the same:
#: - looks worse: some check fires in MORE of the shared files than for the previous version;
#: - marked improvement: no check fires in more files, and some check that fired for the previous
#:   version now fires in at most MARKED_SHARE of those files (the fault is gone from at least
#:   half the files that showed it).
#: Worse earns one extra negative, a marked improvement one fewer (never below zero); a version
#: both better on one check and worse on another keeps its count. When the ratings differ, the
#: counts already tell the versions apart and neither rule applies.
MARKED_SHARE = 0.5
#: The rules in words, for the report.
AGGREGATION_RULES = (
    "A check counts once per subject and version: the most negatives any of the subject's task "
    "files earned (the thesis judged each subject from its files together).",
    "One fault, one charge: a check declared as charged with another earns nothing where that "
    "one fires for the same subject, version and table (lips that do not close where the speaker "
    "closes them are not charged again in C when they are apart at the first or last frame).",
    "Table C = the lip checks of Table A judged per version + Table C's own checks.",
    "Table C, compared with the previous version on the same task files, where the ratings would "
    "be the same: a version that looks worse (a check fires in more of the shared files) earns one "
    "extra negative; a marked improvement (no check worse, and a check that fired is gone from at "
    f"least {1 - MARKED_SHARE:.0%} of the files that showed it) earns one fewer.",
    "Table F (fidelity to the recording) is cassi-farm's addition, not the thesis's: the model's "
    "pellet sites mapped back into the XRMB frame are compared with the measured pellets.",
)

# ----------------------------------------------------------------------------------------------
# The checks
# ----------------------------------------------------------------------------------------------

_ALL: list[Check] = [
    # ---------------- Table A (thesis 5.3): teeth ----------------
    Check(name="teeth_front_overlap",
          table="A",
          component="teeth",
          view="half",
          unit="mm",
          frames="during the task (held) and at its end",
          description="vertical overlap of the upper over the lower front teeth (z of the lower incisor tip "
                      "minus z of 226)",
          thresholds=(3.5,),
          negatives=(1,),
          direction="higher",
          reason="the reference is 'a very slight overlap'; an adult overbite of 2-3 mm looks normal, so "
                 "only more than 3.5 mm counts",
          text="front teeth overlap top to bottom",
          kind="geometry",
          measure="measures:m_teeth_front_overlap"),
    Check(name="teeth_back_overlap",
          table="A",
          component="teeth",
          view="half",
          unit="mm",
          frames="during the task (held) and at its end",
          description="vertical overlap of the back teeth (lower molar top minus upper molar bottom), beyond "
                      "Parke's rest face",
          thresholds=(1.5,),
          ranges=((1.0, 2.5),),
          range_reason="'visible in the half view': about a pixel of the preview views (1.3 mm at "
                       "the front view) more than Parke's, from a little under one (1.0 mm) to "
                       "two (2.5 mm)",
          negatives=(1,),
          direction="higher",
          reason="Parke's face is the reference alignment; 1.5 mm more overlap than it is visible in the "
                 "half-face view at its scale",
          text="back teeth overlap top to bottom",
          kind="geometry",
          measure="measures:m_teeth_back_overlap"),
    Check(name="teeth_slope_up",
          table="A",
          component="teeth",
          view="half",
          unit="deg",
          frames="during the task (held) and at its end",
          description="angle of the lower occlusal line (lower molar -> lower incisor tip) above the upper "
                      "one, beyond Parke's rest face",
          thresholds=(5.0, 25.0),
          ranges=((3.0, 8.0), (20.0, 30.0)),
          range_reason="mild: 8 deg was the value before the renders moved it to 5; 3 deg lifts "
                       "the front of the ~30 mm row by 1.6 mm, about a pixel of the half view, "
                       "the least slope that shows. Severe: 'very steep' has no figure in the "
                       "thesis; 20-30 deg around 25",
          negatives=(1, 3),
          direction="higher",
          reason="was 8 deg; 5 deg after the renders: CASSI 2.0 on synthetic JW11 task 19 ends at 7 deg "
                 "and the half view plainly shows the lower row rising toward the front against the "
                 "horizontal upper row (Parke's 0 deg reads level). The thesis gives a 'very steep "
                 "slope' three negatives: 25 deg",
          text="lower teeth slant upward toward the front",
          kind="geometry",
          measure="measures:m_teeth_slope_up"),
    Check(name="teeth_slope_down",
          table="A",
          component="teeth",
          view="half",
          unit="deg",
          frames="during the task (held) and at its end",
          description="angle of the lower occlusal line below the upper one, beyond rest",
          thresholds=(5.0,),
          ranges=((3.0, 8.0),),
          range_reason="as teeth_slope_up's mild threshold",
          negatives=(1,),
          direction="higher",
          reason="as teeth_slope_up (5 deg)",
          text="lower teeth slant downward toward the front",
          kind="geometry",
          measure="measures:m_teeth_slope_down"),
    Check(name="teeth_too_far_apart",
          table="A",
          component="teeth",
          view="half",
          unit="mm",
          frames="during the task (held) and at its end",
          description="vertical gap between the upper (226) and lower front teeth tips, or between the back "
                      "teeth beyond Parke's rest face, whichever is larger",
          thresholds=(5.0,),
          ranges=((3.5, 7.0),),
          range_reason="'clearly open' has no figure: about three to five pixels of the half view "
                       "(1.3 mm each); fewer reads as nearly closed",
          negatives=(1,),
          direction="higher",
          reason="at the end of a task the jaw is near rest, where the incisors nearly meet; a gap over "
                 "5 mm (about a fingertip's thickness) is clearly open",
          text="upper and lower teeth too far apart",
          kind="geometry",
          measure="measures:m_teeth_apart"),
    # ---------------- Table A: lips ----------------
    Check(name="lips_apart_at_start",
          table="A",
          component="lips",
          view="front",
          unit="mm",
          frames="first and last frame",
          description="gap between the lips' edges (61 above 58) at the first and at the last frame, the "
                      "larger of the two",
          thresholds=(LIPS_TOUCH_MM, 4.0),
          ranges=((1.4, 2.0), None),
          range_reason="mild: not below Parke's neutral 1.35 mm, which the front render shows as "
                       "lips touching; up to 2.0 mm, a seam of about a pixel plus the outline's "
                       "round-off. Severe: the cited 3 mm interlabial gap fixes it",
          negatives=(1, 2),
          direction="higher",
          reason="the judges examined the front view at the starting and ending frame to see whether "
                 "the lips lightly touched (desirable), were too far apart or too close together "
                 "(thesis 5.3.1), so a fault at either frame counts. Lips that touch have ~0 gap; "
                 "1.5 mm (LIPS_TOUCH_MM) after the renders: Parke's neutral face parts the lips by "
                 "1.35 mm and its front render reads as lips lightly touching (a dark seam with a "
                 "glint of teeth). The thesis gives a 'large separation' two negatives without a "
                 "figure: 4 mm, past the 3 mm that dentistry takes as the acceptable upper limit of "
                 "the interlabial gap at rest (Mosby's Dental Dictionary, 2nd ed. 2008, entry "
                 "'intralabial gap'), lips plainly held apart",
          text="lips too far apart at the start or end, not touching",
          kind="geometry",
          measure="measures:m_lips_apart_ends"),
    Check(name="lips_pressed",
          table="A",
          component="lips",
          view="front",
          unit="mm",
          frames="first and last frame",
          description="how far the lips' edges cross at the first and at the last frame (tightly pressed), "
                      "the larger of the two",
          thresholds=(2.0,),
          ranges=((1.0, 3.0),),
          range_reason="CASSI 2.0's 0.8 mm crossing renders as lips lightly closed, so not below "
                       "1.0 mm; up to 3.0 mm, past two pixels of the front view",
          negatives=(1,),
          direction="higher",
          reason="judged where the judges looked for lips too close together, the starting and ending "
                 "frame (thesis 5.3.1). Lightly touching lips meet at 0. Was 0.5 mm; 2 mm after the "
                 "renders: CASSI 2.0's 0.8 mm crossing at the start (synthetic JW12 task 5) renders as "
                 "lips lightly closed, not pressed",
          text="lips too close together, tightly pressed",
          kind="geometry",
          measure="measures:m_lips_pressed"),
    Check(name="lower_lip_below_teeth",
          table="A",
          component="lips",
          view="front",
          unit="fraction",
          frames="all frames",
          description="fraction of frames with the lower lip's edge (58) more than LIPS_BELOW_TEETH_MM below "
                      "the lower gum line (258)",
          thresholds=(0.10, 0.50),
          negatives=(1, 2),
          direction="higher",
          reason="'often' = at least a tenth of the task; 'the usual state' (two negatives) = half",
          text="the lower lip often goes below the bottom of the lower front teeth",
          kind="geometry",
          measure="measures:m_lower_lip_below_teeth"),
    Check(name="lips_centered_high",
          table="A",
          component="lips",
          view="front",
          unit="fraction",
          frames="frames with the lips open",
          description="share of the teeth pixels inside the lip opening that are upper teeth (median over open "
                      "frames)",
          thresholds=(CENTERED_SHARE,),
          ranges=((0.62, 0.75),),
          range_reason="the blind judgements of the planted centring series changed between shares of 0.62 and 0.75 (one face 0.62-0.66, the other with shadowed teeth 0.70-0.80): where similar portions end lies in that span",
          negatives=(1,),
          direction="higher",
          reason="well centered = similar portions of upper and lower teeth (thesis 5.3.1, Figure 5.9); "
                 "CENTERED_SHARE from front renders of a planted series (the lips moved in 0.5 mm steps "
                 "over synthetic JW11 task 19 CASSI 2.1 frame 1055 and JW18 task 4 CASSI 2.0 frame 619): "
                 "an upper share of 0.59 reads as similar portions, 0.66 as clearly more upper; a lower "
                 "share of 0.62 as barely more lower, 0.63 clearly, and 0.70 as similar where the lower "
                 "teeth lie in shadow; the crossings' mean, 0.65, both ways",
          text="centered high: much of the upper teeth and little of the lower teeth show",
          kind="image",
          measure="image:m_centered_high"),
    Check(name="lips_centered_low",
          table="A",
          component="lips",
          view="front",
          unit="fraction",
          frames="frames with the lips open",
          description="share of the teeth pixels inside the lip opening that are lower teeth (median over open "
                      "frames): the mirror of lips_centered_high",
          thresholds=(CENTERED_SHARE,),
          ranges=((0.62, 0.75),),
          range_reason="the blind judgements of the planted centring series changed between shares of 0.62 and 0.75 (one face 0.62-0.66, the other with shadowed teeth 0.70-0.80): where similar portions end lies in that span",
          negatives=(1,),
          direction="higher",
          reason="judged symmetrically with lips_centered_high (CENTERED_SHARE): the renders put the end "
                 "of 'similar portions' at about the same share either way (0.62 up, 0.63-0.75 down); "
                 "'centered slightly low' earned a negative (thesis 5.3.1)",
          text="centered low: much of the lower teeth and little of the upper teeth show",
          kind="image",
          measure="image:m_centered_low"),
    Check(name="lips_through_teeth",
          table="A",
          component="lips",
          view="side",
          unit="mm",
          frames="all frames (sustained 3)",
          description="depth of lip vertices behind the front surface of the front teeth",
          thresholds=(0.5,),
          ranges=((0.25, 1.0),),
          range_reason="beyond the teeth's shading: from palate_below_incisor's round-off (0.25 "
                       "mm) to under a pixel of the side view (1.0 mm)",
          negatives=(1,),
          direction="higher",
          reason="0.5 mm is beyond the teeth's shading: the lip visibly sinks in",
          text="lips pass through the surface of the teeth",
          kind="geometry",
          measure="measures:m_lips_through_teeth"),
    Check(name="lower_lip_protrudes",
          table="A",
          component="lips",
          view="side",
          unit="mm",
          frames="all frames (90th percentile)",
          description="x(49) - x(67): lower lip forward of the upper",
          thresholds=(1.0, 3.0),
          ranges=((0.5, 1.5), (2.0, 4.0)),
          range_reason="'shows in profile': about a pixel of the side view, 0.5-1.5 mm; 'marked' "
                       "has no figure: 2-4 mm around 3",
          negatives=(1, 2),
          direction="higher",
          reason="upper lip is normally at or ahead of the lower; 1 mm ahead shows in profile, 3 mm is "
                 "'marked' (two negatives)",
          text="lower lip protrudes farther than the upper lip",
          kind="geometry",
          measure="measures:m_lower_lip_protrudes"),
    Check(name="lips_overlap",
          table="A",
          component="lips",
          view="front",
          unit="mm",
          frames="all frames (sustained 3)",
          description="how far the lower lip's edge rises above the upper lip's edge (the lips cross)",
          thresholds=(0.5,),
          ranges=((0.25, 1.0),),
          range_reason="as lips_through_teeth: a crossing from past the round-off to under a "
                       "pixel",
          negatives=(1,),
          direction="higher",
          reason="crossing by 0.5 mm shows as one lip through the other",
          text="the lips overlap during the task",
          kind="geometry",
          measure="measures:m_lips_overlap"),
    # ---------------- Table A: tongue ----------------
    Check(name="tongue_through_teeth",
          table="A",
          component="tongue",
          view="front",
          unit="mm",
          frames="all frames (sustained 3)",
          description="depth of tongue vertices and edges forward of the back surface of the upper and of the "
                      "lower front teeth",
          thresholds=(0.5, 2.0),
          negatives=(1, 3),
          direction="higher",
          reason="0.5 mm through one set: one negative; through both: two; both by more than 2 mm ('very "
                 "noticeably'): three (graded by m_tongue_teeth)",
          text="tongue pokes through the front teeth",
          kind="geometry",
          measure="measures:m_tongue_teeth"),
    Check(name="tongue_hidden",
          table="A",
          component="tongue",
          view="front",
          unit="fraction",
          frames="frames with the lips open",
          description="fraction of open-lip front-view frames in which any tongue pixel shows",
          thresholds=(0.10,),
          negatives=(1,),
          direction="lower",
          reason="barely visible = seen in fewer than one open frame in ten",
          text="tongue barely visible from the front (hidden by the teeth)",
          kind="image",
          measure="image:m_tongue_visible"),
    Check(name="tongue_in_front_of_teeth",
          table="A",
          component="tongue",
          view="front",
          unit="px",
          frames="all rendered frames",
          description="tongue pixels nearer the camera than the front teeth (image cross-check of "
                      "tongue_through_teeth)",
          thresholds=(5.0,),
          negatives=(1,),
          direction="higher",
          reason="5 pixels rules out antialiasing at the teeth's edge; counted by the geometric check",
          text="tongue shows in front of the teeth",
          kind="image",
          measure="image:m_tongue_in_front",
          counted=False),
    Check(name="tongue_through_palate",
          table="A",
          component="tongue",
          view="half",
          unit="mm",
          frames="all frames (sustained 3)",
          description="height of tongue vertices and edges above the palatal surface",
          thresholds=(0.5,),
          negatives=(1,),
          direction="higher",
          reason="measured but, as in the thesis, not counted (most subjects pass the alveolar ridge)",
          text="tongue passes through the palatal outline",
          kind="geometry",
          measure="measures:m_tongue_palate",
          counted=False),
    Check(name="tongue_back_v",
          table="A",
          component="tongue",
          view="half",
          unit="deg",
          frames="all frames (sustained 3)",
          description="angle at T4 between T3 and the anchored back of the tongue (the V at the back)",
          thresholds=(120.0,),
          negatives=(1,),
          direction="lower",
          reason="measured but, as in the thesis, not counted; a bend sharper than 120 deg reads as a V",
          text="V shape at the back of the tongue (anchored back points)",
          kind="geometry",
          measure="measures:m_tongue_back_v",
          counted=False),
    # ---------------- Table B (thesis 5.4) ----------------
    Check(name="palate_below_incisor",
          table="B",
          component="palate",
          view="half",
          unit="mm",
          frames="initialization",
          description="how far the palatal outline reaches below the tip of the upper front teeth (226)",
          thresholds=(0.25, 2.0),
          ranges=(None, (1.5, 3.0)),
          range_reason="mild: 0.25 mm is the outline's numerical round-off, not a choice; 'very "
                       "noticeable' has no figure: one to two pixels of the half view",
          negatives=(1, 2),
          direction="higher",
          reason="any reach below the tip shows (0.25 mm rules out round-off); over 2 mm is 'very "
                 "noticeable' (two negatives)",
          text="palatal outline extends below the tip of the upper front "
               "teeth",
          kind="geometry",
          measure="measures:m_palate_below_incisor"),
    Check(name="jaw_long",
          table="B",
          component="jaw",
          view="side",
          unit="ratio",
          frames="initialization",
          description="how far the jaw (14-43) reaches below the upper incisor tip (226), "
                      "where the version put it, over Parke's neutral face",
          thresholds=(1.15,),
          ranges=((1.13, 1.165),),
          range_reason="the side renders bracket it: 1.12 read as an ordinary jaw, 1.17 as very "
                       "long",
          negatives=(1,),
          direction="higher",
          reason="CASSI 1.0 turns Parke's jaw onto the head measures (4.1.3), so the jaw is "
                 "judged where it sits under the head, as the side render shows it (it was "
                 "measured after undoing that turn, which hid it). 15 % lower than Parke's reads "
                 "as 'very long' on the side renders of the first frame (final preset): "
                 "cassi-1.0 JW15 1.21, JW16 1.18, JW45 1.17 show the jaw line a step below the "
                 "neutral face's; JW27, JW502 at 1.12 sit only slightly below it and read as "
                 "an ordinary jaw",
          text="unusual jaw: very long",
          kind="geometry",
          measure="measures:m_jaw_long"),
    Check(name="jaw_square",
          table="B",
          component="jaw",
          view="side",
          unit="ratio",
          frames="initialization",
          description="jaw squareness (side-view hull area / box) over Parke's neutral",
          thresholds=(1.10,),
          ranges=((1.05, 1.15),),
          range_reason="'visibly squarer' has no render cited: 5-15 % fuller than Parke's around "
                       "10 %",
          negatives=(1,),
          direction="higher",
          reason="a square jaw fills its box; 10 % fuller than Parke's is visibly squarer",
          text="unusual jaw: very square",
          kind="geometry",
          measure="measures:m_jaw_square"),
    Check(name="jaw_large",
          table="B",
          component="jaw",
          view="side",
          unit="ratio",
          frames="initialization",
          description="side-view area of the lower face (hull of the jaw 14-43 and the upper "
                      "incisor tip 226), where the version put it, over Parke's neutral face",
          thresholds=(1.25,),
          ranges=((1.2, 1.3),),
          range_reason="'a quarter larger' +-5 %; not below 1.2: the default corpus's largest "
                       "lower face (16 %) renders longer, not bigger",
          negatives=(1,),
          direction="higher",
          reason="a quarter larger than Parke's reads as 'too large seen from the side'; read "
                 "where the jaw sits under the head, as jaw_long (on the first frames of the "
                 "default corpus the lower face is at most 16 % larger: JW15, and the render "
                 "shows a longer, not a bigger, jaw)",
          text="unusual jaw: too large seen from the side",
          kind="geometry",
          measure="measures:m_jaw_large"),
    # ---------------- Table C (thesis 5.5) ----------------
    Check(name="lips_too_large_moving",
          table="C",
          component="lips",
          view="front",
          unit="ratio",
          frames="frames where the lips cross",
          description="front-view area inside the outer lip outline over the rest face's, in the frames where "
                      "the lips overlap (90th percentile)",
          thresholds=(1.5,),
          ranges=((1.3, 1.75),),
          range_reason="'half again' the rest face's lip area, from a third to three quarters "
                       "larger",
          negatives=(1,),
          direction="higher",
          reason="the thesis saw overlapping lips look too large; half again the rest face's lip area "
                 "reads so. Not the crossing depth: on renders a 12 mm crossing the version handles "
                 "(CASSI 2.0, synthetic JW11 task 5 frame 459) looks like closed lips, not large ones",
          text="lips appear too large when moving (overlapping)",
          kind="geometry",
          measure="measures:m_lips_too_large_moving"),
    Check(name="lower_lip_too_large",
          table="C",
          component="lips",
          view="front",
          unit="fraction",
          frames="frames with the lips open",
          description="fraction of open-lip front-view frames in which the lower teeth show",
          thresholds=(0.25,),
          negatives=(1,),
          direction="lower",
          reason="'bottom teeth rarely seen' = in fewer than a quarter of the open frames",
          text="the lower lip too large (bottom teeth rarely seen)",
          kind="image",
          measure="image:m_lower_teeth_seen"),
    Check(name="lips_do_not_close",
          table="C",
          component="lips",
          view="front",
          unit="fraction",
          frames="frames the recording shows closed (UL-LL pellet distance)",
          description="share of the recording's closed frames where the model's inner lip edges 61-58 "
                      "touch (the closing half of shape_lip_contact)",
          thresholds=(0.75, 0.25),
          negatives=(1, 2),
          direction="lower",
          reason="shape_lip_contact's band on its closing half alone: below 0.75 a quarter of the "
                 "speaker's closures (/p b m/, 7-22 frames each) are seen open on the front view; below "
                 "0.25 three in four, the lips read as never closing (two, as a large separation). "
                 "Charged with lips_apart_at_start (Table A's row judged again in C): lips held apart "
                 "at the first and last frame are the lips that do not close, charged once in C",
          text="the lips do not close where the speaker closes them",
          kind="fidelity",
          measure="shape:m_lip_closure",
          charged_with="lips_apart_at_start"),
    Check(name="lips_do_not_open",
          table="C",
          component="lips",
          view="front",
          unit="ratio",
          frames="all frames with valid pellets",
          description="the model's lip aperture range over the recording's (5th-95th percentile; the range "
                      "fidelity_lip_aperture_range compares)",
          thresholds=(HALF_REACH, STILL_REACH),
          negatives=(1, 2),
          direction="lower",
          reason="HALF_REACH: lips opening less than half as far as the speaker's read as not opening; "
                 "STILL_REACH: the opening is under a pixel, a still mouth (two negatives)",
          text="the lips do not open",
          kind="fidelity",
          measure="fidelity:m_lip_aperture_reach"),
    # ---------------- Table D (thesis 5.8), task 118 ----------------
    Check(name="no_lip_rounding",
          table="D",
          component="lips",
          view="front",
          unit="ratio",
          frames="maximum protrusion",
          description="lip-corner half-width at maximum protrusion over at the start",
          thresholds=(0.95,),
          ranges=((0.93, 0.97),),
          range_reason="5 % of a ~50 mm mouth is 2.5 mm, two pixels of the front view; 3-7 % is "
                       "one to about three pixels",
          negatives=(3,),
          direction="higher",
          reason="rounding draws the corners in; less than 5 % narrowing is no rounding (three negatives)",
          text="no lip rounding",
          kind="geometry",
          measure="measures:m_no_rounding",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="lips_stick_out",
          table="D",
          component="lips",
          view="side",
          unit="mm",
          frames="maximum protrusion",
          description="x(49) - x(chin) at maximum protrusion beyond its value at the first frame",
          thresholds=(8.0,),
          ranges=((6.5, 8.4),),
          range_reason="real maximum protrusion moves the lips 5-8 mm and 8.5 mm read as a beak "
                       "on the side render: the range stays below it",
          negatives=(1,),
          direction="higher",
          reason="real maximum protrusion moves the lips 5-8 mm. Was 10 mm; 8 mm after the renders: "
                 "CASSI 2.1 on synthetic JW11 task 118 at 8.5 mm shows a beak of lips far ahead of the "
                 "chin in the side view. "
                 "Measured from the first frame, not Parke's rest face: the initial placement is the "
                 "data's (survey: against the rest face every CASSI version fired at 12.4 mm)",
          text="lips stick out too much from the chin at maximum protrusion",
          kind="geometry",
          measure="measures:m_lips_from_chin",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="above_lip_cave_in",
          table="D",
          component="face",
          view="side",
          unit="mm",
          frames="all frames (sustained 3)",
          description="vertex 71 behind the chord nose base - 67, beyond rest",
          thresholds=(1.0,),
          ranges=((0.5, 1.5),),
          range_reason="'a visible shadow': half a pixel to about a pixel of the side view",
          negatives=(1,),
          direction="higher",
          reason="1 mm of new hollow above the lip casts a visible shadow",
          text="points above the lip cave in",
          kind="geometry",
          measure="measures:m_above_lip_cave",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="lips_into_nose",
          table="D",
          component="lips",
          view="side",
          unit="ratio",
          frames="all frames (sustained 3)",
          description="distance from the upper lip's edge (67) to the nose base over its rest value",
          thresholds=(0.5, 0.2),
          negatives=(1, 2),
          direction="lower",
          reason="half the rest distance squeezes the skin between them; a fifth is 'marked' (two)",
          text="lips run into the nose at maximum protrusion",
          kind="geometry",
          measure="measures:m_lips_into_nose",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="lips_too_big",
          table="D",
          component="lips",
          view="front",
          unit="ratio",
          frames="maximum protrusion",
          description="front-view area inside the outer lip outline at maximum protrusion over at rest",
          thresholds=(1.5,),
          ranges=((1.3, 1.75),),
          range_reason="as lips_too_large_moving",
          negatives=(1,),
          direction="higher",
          reason="rounded lips shrink; half again as large is 'too big'",
          text="lips too big at maximum protrusion",
          kind="geometry",
          measure="measures:m_lips_too_big",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="lips_centering_118",
          table="D",
          component="lips",
          view="front",
          unit="fraction",
          frames="frames with the lips open",
          description="distance of the upper-teeth share inside the lip opening from an even split",
          thresholds=(round(CENTERED_SHARE - 0.5, 2),),
          ranges=((0.12, 0.25),),
          range_reason="the same span as lips_centered_high/low's, as a distance from an even split",
          negatives=(1,),
          direction="higher",
          reason="an even split is 0; 0.15 is CENTERED_SHARE either way, where the front renders stop "
                 "showing similar portions of upper and lower teeth (lips_centered_high)",
          text="lips centered too high or too low",
          kind="image",
          measure="image:m_centering_offset",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="lower_lip_protrudes_start",
          table="D",
          component="lips",
          view="side",
          unit="mm",
          frames="first frame",
          description="x(49) - x(67) at the first frame",
          thresholds=(1.0,),
          negatives=(1,),
          direction="higher",
          reason="as lower_lip_protrudes",
          text="the lower lip protrudes in the initial position",
          kind="geometry",
          measure="measures:m_lower_lip_protrudes_start",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="upper_protrudes_more",
          table="D",
          component="lips",
          view="side",
          unit="mm",
          frames="maximum protrusion",
          description="x(67) - x(49) at maximum protrusion",
          thresholds=(4.0,),
          negatives=(1,),
          direction="higher",
          reason="the upper lip normally leads by 1-2 mm; more than 4 mm is marked",
          text="the top lip protrudes more than the bottom at maximum protrusion",
          kind="geometry",
          measure="measures:m_upper_protrudes_more",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="upper_lip_sharp",
          table="D",
          component="lips",
          view="side",
          unit="deg",
          frames="maximum protrusion",
          description="how much sharper the side-profile angle 71-67-61 at the upper lip's edge is at maximum "
                      "protrusion than on the rest face",
          thresholds=(10.0,),
          ranges=((7.5, 12.0),),
          range_reason="12.5 deg sharper read as a wedge on the side render, so the range stays "
                       "below it; 7.5 deg a quarter under the value",
          negatives=(1,),
          direction="higher",
          reason="relative to the rest face because Parke's own profile turns sharply there (108 deg on "
                 "the generated face; an absolute 110 deg limit fired on every version, survey). Was 40 deg; "
                 "10 deg after the renders: CASSI 2.1 on synthetic JW11 task 118 turns 12.5 deg sharper "
                 "and its side view shows the upper lip as a pointed wedge",
          text="the upper lip has a sharp profile",
          kind="geometry",
          measure="measures:m_upper_lip_sharp",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="lip_jitter",
          table="D",
          component="lips",
          view="front",
          unit="mm",
          frames="all frames (sustained 3)",
          description="frame-to-frame shake (distance from a 9-frame quadratic fit) of the computed lip "
                      "vertices beyond the jaw's and the lip pellets'",
          thresholds=(0.5,),
          ranges=((0.3, 1.0),),
          range_reason="shake 'is visible' at 146 frames a second from about a quarter of a pixel "
                       "(a shimmer) to under a pixel of the front view",
          negatives=(1,),
          direction="higher",
          reason="jitter the jaw shows equally comes from the data; 0.5 mm of shake beyond it is visible. "
                 "Was the second difference: that fired on fast but smooth rounding movements (CASSI 2.0, "
                 "synthetic JW16 task 118, frames 127/536/912: 71 % of files); the fit ignores them",
          text="the lips jitter more than the jaw",
          kind="geometry",
          measure="measures:m_lip_jitter",
          tasks=(MAX_PROTRUSION_TASK,)),
    # ---------------- Table E (thesis 5.9), task 106 ----------------
    Check(name="lip_shape_triangular",
          table="E",
          component="lips",
          view="front",
          unit="ratio",
          frames="wide-open frames",
          description="area / bounding box of the lip opening (inner outline) when open wide",
          thresholds=(0.62,),
          negatives=(1,),
          direction="lower",
          reason="an ellipse fills 0.79 of its box, a diamond or triangle 0.5; 0.62 is half way",
          text="lips very triangular or diamond-shaped when opened wide",
          kind="geometry",
          measure="measures:m_lip_shape",
          tasks=(JAW_WAGGING_TASK,)),
    Check(name="lip_shape_image",
          table="E",
          component="lips",
          view="front",
          unit="ratio",
          frames="wide-open frames",
          description="area / bounding box of the rendered mouth opening (regionprops extent), cross-check",
          thresholds=(0.62,),
          negatives=(1,),
          direction="lower",
          reason="as lip_shape_triangular; counted there",
          text="lips very triangular or diamond-shaped when opened wide",
          kind="image",
          measure="image:m_opening_extent",
          tasks=(JAW_WAGGING_TASK,),
          counted=False),
    Check(name="lip_outline_angular",
          table="E",
          component="lips",
          view="front",
          unit="deg",
          frames="wide-open frames",
          description="the lip opening's (inner outline's) sharpest interior angle away from its two "
                      "corners, median over the wide-open frames",
          thresholds=(LIP_OUTLINE_KINK_DEG,),
          ranges=((121.0, 132.0),),
          range_reason="between a regular hexagon's 120 deg (CASSI 1.0's kinks measured 110-117) "
                       "and the rounded arches measured at 136-156 deg",
          negatives=(1,),
          direction="lower",
          reason="added after the renders: CASSI 1.0 at the widest opening of task 106 (synthetic "
                 "JW24 row 957, JW40 row 364, front) shows a hexagon, flat top and bottom edges "
                 "meeting straight sides at kinks of 110-117 deg beside the corners, which "
                 "lip_shape_triangular's area/box (0.86, above an ellipse's 0.79) cannot see; "
                 "2.0, 2.1 and Parke's lips (136-156 deg there) read as rounded arches. A regular "
                 "hexagon turns 120 deg at each vertex; 125 leaves 5 deg for the round-off of the "
                 "shading. Charged with lip_shape_triangular: one fault, one charge",
          text="lips very triangular or diamond-shaped when opened wide",
          kind="geometry",
          measure="measures:m_lip_outline_angular",
          tasks=(JAW_WAGGING_TASK,),
          charged_with="lip_shape_triangular"),
    Check(name="lower_lip_through_teeth",
          table="E",
          component="lips",
          view="front",
          unit="mm",
          frames="all frames (sustained 3)",
          description="depth of lower-lip vertices behind the front surface of the lower front teeth",
          thresholds=(0.5,),
          negatives=(1,),
          direction="higher",
          reason="as lips_through_teeth",
          text="the lower lip passes through the bottom set of teeth",
          kind="geometry",
          measure="measures:m_lower_lip_through_lower_teeth",
          tasks=(JAW_WAGGING_TASK,)),
    Check(name="below_lip_cave_in",
          table="E",
          component="face",
          view="side",
          unit="mm",
          frames="all frames (sustained 3)",
          description="vertex 41 behind the chord 49 - chin, beyond rest",
          thresholds=(3.0,),
          ranges=((2.5, 3.2),),
          range_reason="the side renders bracket it: +2.3 mm read as Parke's sulcus, +3.3 mm as a "
                       "notch",
          negatives=(1,),
          direction="higher",
          reason="Parke's face has a mentolabial sulcus (41 ~7.5 mm behind the chord), so only a "
                 "deeper one is a fault. Was 1 mm; 3 mm after the side renders of task 106 "
                 "(final preset): 1.4-2.3 mm deeper read as Parke's sulcus with a sharper corner "
                 "(cassi-1.0 JW18 +1.5, JW21 +2.3; cassi-2.0 JW19, JW24 +1.4-2.0), 3.3 mm and "
                 "more as the lower lip overhanging a notch (cassi-1.0 JW16 +3.3, JW24 +4.6)",
          text="points under the lip cave in, making unusual shapes and shadows",
          kind="geometry",
          measure="measures:m_below_lip_cave",
          tasks=(JAW_WAGGING_TASK,)),
    Check(name="corners_misplaced",
          table="E",
          component="lips",
          view="side",
          unit="mm",
          frames="all frames (sustained 3)",
          description="distance of the corner (70) outside the band between 69 and 51",
          thresholds=(1.0,),
          ranges=((0.5, 1.5),),
          range_reason="a kink of half a pixel to about a pixel of the front view",
          negatives=(1,),
          direction="higher",
          reason="a corner 1 mm above, below or ahead of its neighbours kinks the outline",
          text="the lip corners badly placed relative to the other lip points",
          kind="geometry",
          measure="measures:m_corners_misplaced",
          tasks=(JAW_WAGGING_TASK,)),
    Check(name="chin_cave_in",
          table="E",
          component="jaw",
          view="side",
          unit="mm",
          frames="all frames (sustained 3)",
          description="chin vertex (24) behind the chord 41 - underside of the chin",
          thresholds=(1.0,),
          ranges=((0.5, 1.5),),
          range_reason="'shows in profile': half a pixel to about a pixel of the side view",
          negatives=(1,),
          direction="higher",
          reason="the chin bulges (Parke's 24 lies 7.7 mm ahead of the chord); it caves in when "
                 "it lies behind it, and 1 mm of hollow shows in profile. Was measured beyond "
                 "rest, which charged cassi-2.x's chins 1.2-1.6 mm flatter than Parke's from the "
                 "first frame on, still convex, and smooth on the side render (JW24 task 106 "
                 "frame 1119, cassi-2.0 beside cassi-1.0 and parke-1974)",
          text="the chin or lower jaw caves in",
          kind="geometry",
          measure="measures:m_chin_cave",
          tasks=(JAW_WAGGING_TASK,)),
    Check(name="corner_jump_switch",
          table="E",
          component="lips",
          view="side",
          unit="mm",
          frames="switches between horizontal and vertical ellipse; all frames",
          description="largest lip-corner step beyond the jaw's at a switch between horizontal and vertical "
                      "ellipse, or the corners' sustained jitter beyond the jaw's",
          thresholds=(1.0,),
          ranges=((0.5, 1.5),),
          range_reason="'a visible pop' in one frame: half a pixel to about a pixel of the front "
                       "view",
          negatives=(1,),
          direction="higher",
          reason="a 1 mm jump in one frame (7 ms) is a visible pop",
          text="the lip corners jitter, or a large frame jump at the ellipse switch",
          kind="geometry",
          measure="measures:m_corner_jump",
          tasks=(JAW_WAGGING_TASK,)),
    Check(name="jaw_does_not_open",
          table="E",
          component="jaw",
          view="side",
          unit="ratio",
          frames="all frames with valid pellets",
          description="the model's jaw opening range (-MNI y) over the recording's (5th-95th percentile; "
                      "the range fidelity_jaw_opening_range compares)",
          thresholds=(HALF_REACH, STILL_REACH),
          negatives=(1, 2),
          direction="lower",
          reason="task 106 wags the jaw through its range: a jaw opening less than half the recorded "
                 "range reads as not opening; STILL_REACH: under a pixel, a still jaw (two negatives)",
          text="the jaw does not open",
          kind="fidelity",
          measure="fidelity:m_jaw_opening_reach",
          tasks=(JAW_WAGGING_TASK,)),
    # ---------------- Table F: fidelity to the recording (cassi-farm's addition) ----------------
    Check(name="fidelity_lips_error",
          table="F",
          component="lips",
          view="side",
          unit="mm",
          frames="all frames with valid pellets",
          description="RMSE of the virtual UL (67) and LL (49) pellets' movement against the measured "
                      "pellets' (displacement from the first frame, XRMB frame via the 4.1.1 mapping)",
          thresholds=(2.0, 4.0),
          negatives=(1, 2),
          direction="higher",
          reason="lips that touch are within 1.5 mm (LIPS_TOUCH_MM): a lip 2 mm RMS off its pellet "
                 "opens where the speaker closed; 4 mm is a third of a speaker's lip aperture range in "
                 "speech (two negatives)",
          text="the lips do not follow the recorded lip pellets",
          kind="fidelity",
          measure="fidelity:m_lips_error"),
    Check(name="fidelity_tongue_error",
          table="F",
          component="tongue",
          view="half",
          unit="mm",
          frames="all frames with valid pellets",
          description="RMSE of the virtual T1-T4 pellets' (289-292) movement against the measured pellets'",
          thresholds=TONGUE_MISS_MM,
          negatives=(1, 2),
          direction="higher",
          reason="TONGUE_MISS_MM: places of articulation along the palate lie 5-10 mm apart "
                 "(dental, alveolar, palatal): a 3 mm RMS miss blurs them in the half view; 6 mm "
                 "crosses a place (two negatives)",
          text="the tongue does not follow the recorded tongue pellets",
          kind="fidelity",
          measure="fidelity:m_tongue_error"),
    Check(name="fidelity_jaw_error",
          table="F",
          component="jaw",
          view="side",
          unit="mm",
          frames="all frames with valid pellets",
          description="RMSE of the virtual MNI (258) and MNM (midpoint of 281 and 286) pellets' movement "
                      "against the measured pellets'",
          thresholds=(2.0, 4.0),
          negatives=(1, 2),
          direction="higher",
          reason="as the lips: the lower lip rides on the jaw, so a jaw 2 mm off moves the lips off "
                 "their closures; 4 mm is a third of the jaw's opening range in speech",
          text="the jaw does not follow the recorded jaw pellets",
          kind="fidelity",
          measure="fidelity:m_jaw_error"),
    Check(name="fidelity_lip_aperture",
          table="F",
          component="lips",
          view="front",
          unit="r",
          frames="all frames with valid pellets",
          description="correlation of the model's lip aperture (UL y - LL y) with the recording's",
          thresholds=(0.5,),
          negatives=(1,),
          direction="lower",
          reason="below 0.5 the model's opening shares less than a quarter of its variance with the "
                 "speaker's: openings and closures are seen at the wrong times. A face that does not "
                 "move at all scores 0",
          text="the lips open and close out of time with the recording",
          kind="fidelity",
          measure="fidelity:m_lip_aperture"),
    Check(name="fidelity_lip_aperture_range",
          table="F",
          component="lips",
          view="front",
          unit="ratio",
          frames="all frames with valid pellets",
          description="range agreement of the lip aperture: min(r, 1/r), r = model range / data range "
                      "(5th-95th percentile)",
          thresholds=(0.5,),
          negatives=(1,),
          direction="lower",
          reason="lips that open less than half (or more than twice) as far as the speaker's are "
                 "plainly under- or over-articulated on the front view",
          text="the lips open much less (or much more) than the speaker's",
          kind="fidelity",
          measure="fidelity:m_lip_aperture_range"),
    Check(name="fidelity_lip_protrusion",
          table="F",
          component="lips",
          view="side",
          unit="r",
          frames="all frames with valid pellets",
          description="correlation of the model's lip protrusion (mean x of UL and LL) with the recording's",
          thresholds=(0.5,),
          negatives=(1,),
          direction="lower",
          reason="as fidelity_lip_aperture: rounding seen at the wrong times",
          text="the lips protrude and retract out of time with the recording",
          kind="fidelity",
          measure="fidelity:m_lip_protrusion"),
    Check(name="fidelity_jaw_opening",
          table="F",
          component="jaw",
          view="side",
          unit="r",
          frames="all frames with valid pellets",
          description="correlation of the model's jaw opening (-MNI y) with the recording's",
          thresholds=(0.5,),
          negatives=(1,),
          direction="lower",
          reason="as fidelity_lip_aperture",
          text="the jaw opens and closes out of time with the recording",
          kind="fidelity",
          measure="fidelity:m_jaw_opening"),
    Check(name="fidelity_jaw_opening_range",
          table="F",
          component="jaw",
          view="side",
          unit="ratio",
          frames="all frames with valid pellets",
          description="range agreement of the jaw opening: min(r, 1/r), r = model range / data range",
          thresholds=(0.5,),
          negatives=(1,),
          direction="lower",
          reason="as fidelity_lip_aperture_range",
          text="the jaw opens much less (or much more) than the speaker's",
          kind="fidelity",
          measure="fidelity:m_jaw_opening_range"),
    # ---------------- Table G: the shape between the pellets (cassi-farm's addition) ----------------
    Check(name="shape_lip_contact",
          table="G",
          component="lips",
          view="front",
          unit="J",
          frames="frames the recording shows closed or open (UL-LL pellet distance)",
          description="Youden's J of lip contact: share of the recording's closed frames (UL-LL within "
                      "1.5 mm of its narrowest) where the model's inner edges 61-58 touch (<= 1.5 mm), plus "
                      "share of its open frames (>= 4 mm beyond) where they are apart, minus 1",
          thresholds=(0.5, 0.25),
          ranges=((0.4, 0.6), None),
          range_reason="mild: derived from the render (a quarter of the closures seen open); "
                       "+-0.1, about one closure in ten either way. Severe: a face that never "
                       "changes its contact scores 0, so 0.25 is near chance, not a choice of "
                       "view",
          negatives=(1, 2),
          direction="lower",
          reason="bands derived from the render, no published figure found: J below 0.5 means at least "
                 "a quarter of the closures (a /p b m/ closure lasts 50-150 ms, 7-22 frames) are seen "
                 "open or the openings shut; below 0.25 is little better than a face that never changes "
                 "its contact, which scores 0 (two negatives). Closure bands: CLOSURE_BAND_MM / OPEN_BAND_MM "
                 "(Westbury & Hashi 1997's inter-pellet separation)",
          text="the lips do not meet where the speaker's lips meet, or meet where they part",
          kind="fidelity",
          measure="shape:m_lip_contact"),
    Check(name="lips_never_touch",
          table="G",
          component="lips",
          view="front",
          unit="mm",
          frames="all frames",
          description="smallest gap between the lips' edges (61 above 58) over the whole task file",
          thresholds=(LIPS_TOUCH_MM, 4.0),
          ranges=((1.4, 2.0), None),
          range_reason="as lips_apart_at_start's",
          negatives=(1, 2),
          direction="higher",
          reason="cassi-farm's own measure, not the judges': they looked for lips too far apart at the "
                 "starting and ending frame (thesis 5.3.1; lips_apart_at_start), not over the whole "
                 "file. The bands as lips_apart_at_start's (1.5 mm reads as touching, 4 mm a large "
                 "separation). Speech files only, as Tables A-C: speech closes the lips (/p b m/), a jaw "
                 "wagged open or lips pushed forward need not. Charged with shape_lip_contact: lips that "
                 "never touch are closures seen open, one fault charged once in G",
          text="the lips never touch in the whole task",
          kind="geometry",
          measure="measures:m_lips_never_touch",
          skip_tasks=ORAL_MOTOR_TASKS,
          charged_with="shape_lip_contact"),
    Check(name="shape_mouth_width",
          table="G",
          component="lips",
          view="front",
          unit="mm",
          frames="first frame",
          description="how far the mouth width at rest (corner to corner, 2 |y(70)|, in the subject's mm "
                      "by the 4.1.1 scale) lies outside the adult range 44.0-62.5 mm",
          thresholds=(2.0, 10.0),
          ranges=((1.3, 3.0), None),
          range_reason="mild: past one pixel of the front view (1.3 mm) to about two; severe: a "
                       "fifth of a mouth, not a pixel count",
          negatives=(1, 2),
          direction="higher",
          reason="range: MOUTH_WIDTH_RANGE_MM (published adult cheilion-cheilion widths, mean +- 2 SD). "
                 "2 mm beyond it is past the pixel (1.3 mm at the preview front view) and the rounding "
                 "of the outline; 10 mm, a fifth of a mouth, is a plainly wrong face (two negatives)",
          text="the mouth is too wide or too narrow for a face",
          kind="fidelity",
          measure="shape:m_mouth_width",
          at_rest="the width of the mouth at its first frame is the face's shape, not a movement: a "
                  "face that stands still keeps the width of its rest, which is judged as any rest"),
    Check(name="shape_rounding",
          table="G",
          component="lips",
          view="front",
          unit="mm/mm",
          frames="the recording's greatest protrusion",
          description="mouth width lost since the first frame (2 |y(70)|) per mm of lip protrusion the "
                      "recording gains (mean x of UL and LL), at the recording's most protruded frame",
          thresholds=(0.5, 0.1),
          ranges=((0.35, 0.65), None),
          range_reason="mild: derived from the render, a 6 mm protrusion narrowing the mouth by 3 "
                       "mm; 2.1-3.9 mm is about one pixel a side +-a third. Severe: 0.1 is "
                       "corners that do not move",
          negatives=(1, 2),
          direction="lower",
          reason="Abry & Boe ('Laws' for lips, Speech Communication 5, 1986, 97-104) relate lip width, "
                 "height and protrusion: protruded (rounded) lips are narrower. Their slope was not found "
                 "here; the band is derived from the render: a 6 mm protrusion that narrows the mouth by "
                 "less than 3 mm (about one pixel a side at the preview front view) shows no rounding "
                 "from the front; below 0.1 the corners do not move at all (two negatives)",
          text="the lips protrude without rounding",
          kind="fidelity",
          measure="shape:m_rounding",
          tasks=(MAX_PROTRUSION_TASK,)),
    Check(name="shape_tongue_t2",
          table="G",
          component="tongue",
          view="half",
          unit="mm",
          frames="all frames with T2 valid, the version animated with T2 withheld",
          description="leave one out: RMS distance between the version's T2 site (290) and the measured "
                      "T2 when the version is driven by every pellet but T2 (XRMB frame, positions)",
          thresholds=TONGUE_MISS_MM,
          negatives=(1, 2),
          direction="higher",
          reason="TONGUE_MISS_MM, as Table F's tongue: a site 3 mm RMS from the speaker's blurs the "
                 "places of articulation in the half view, 6 mm crosses one; real tongue contours are "
                 "predicted from 3-4 pellets within 0.2-0.3 mm (Qin et al., Interspeech 2008)",
          text="the tongue between the pellets is not where the speaker's is",
          kind="fidelity",
          measure="leaveout:m_tongue_t2"),
    Check(name="shape_tongue_t3",
          table="G",
          component="tongue",
          view="half",
          unit="mm",
          frames="all frames with T3 valid, the version animated with T3 withheld",
          description="leave one out: as shape_tongue_t2 for T3 (291), driven by every pellet but T3",
          thresholds=TONGUE_MISS_MM,
          negatives=(1, 2),
          direction="higher",
          reason="as shape_tongue_t2; one fault with it (a tongue that misses between the pellets), "
                 "charged once",
          text="the tongue between the pellets is not where the speaker's is",
          kind="fidelity",
          measure="leaveout:m_tongue_t3",
          charged_with="shape_tongue_t2"),
]

#: The tables judged on the speech files only. The thesis evaluated lip placement and movement
#: (Table 5.5, C) "produced by the tasks given in Table 5.1" (section 6.1), two error-free files
#: per subject (5.1), like the teeth, lips and tongue of 1.0 (5.3, A) and the face shape (5.4,
#: B); tasks 118 and 106 had evaluations of their own (5.8, D; 5.9, E). So a check of A-C never
#: judges those two: a jaw wagged wide open or lips pushed fully forward are what D and E judge,
#: not lip placement in speech. Every other task (a corpus's own choice of two) is judged.
SPEECH_TABLES = ("A", "B", "C")

#: The registry: check name -> :class:`Check`, in rubric order.
CHECKS: dict[str, Check] = {}
for _c in _ALL:
    if _c.name in CHECKS:
        raise RuntimeError(f"check {_c.name} registered twice")
    if _c.table in SPEECH_TABLES and _c.tasks is None:
        _c = dataclasses.replace(_c, skip_tasks=ORAL_MOTOR_TASKS)
    CHECKS[_c.name] = _c
for _c in CHECKS.values():
    if _c.charged_with is not None and _c.charged_with not in CHECKS:
        raise RuntimeError(f"check {_c.name} is charged with unknown check {_c.charged_with}")
    _c.verify_ranges()
del _c


def get_check(name: str) -> Check:
    """The registered check ``name``; an unknown name says which names are close."""
    try:
        return CHECKS[name]
    except KeyError:
        close = difflib.get_close_matches(name, CHECKS, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise CassiInputError(f"unknown rubric check {name!r}{hint}") from None


def registry_table() -> pd.DataFrame:
    """The registry as a table (one row per check): what reports and docs print."""
    return pd.DataFrame([dict(check=c.name, table=c.table, thesis_table=c.thesis_table,
                              component=c.component, view=c.view, kind=c.kind, unit=c.unit,
                              frames=c.frames, thresholds=list(c.thresholds),
                              negatives=list(c.negatives), direction=c.direction,
                              counted=c.counted, tasks=None if c.tasks is None else list(c.tasks),
                              skip_tasks=list(c.skip_tasks),
                              charged_with=c.charged_with, at_rest=c.at_rest, text=c.text,
                              description=c.description, reason=c.reason)
                         for c in CHECKS.values()])


def checks_for(*, kind: str | None = None, table: str | None = None,
               task: int | None = None) -> list[Check]:
    """Registered checks filtered by kind, table and task (task 118 or 106 selects D or E's
    checks and not A-C's; any other task A-C's and F-G's)."""
    return [c for c in CHECKS.values()
            if (kind is None or c.kind == kind) and (table is None or c.table == table)
            and (task is None or c.applies_to(task))]

