"""Every value CASSI 3.0 adds, with its reason (lengths in subject mm, turned into Parke units
with the subject's p/d scale like the pellets, thesis 4.1.1).

The thesis (6.3) names the faults and leaves their fixes open; each value below is CHOSEN for the
reason given, from the anatomy and from looking at renders, never from counting how often a
rubric check fires.
"""
from __future__ import annotations

import numpy as np

# --- the tongue's shape -----------------------------------------------------------------------
#: Cross-section of the tongue: angles from the top of the centre line (0) round the left side
#: (pi/2, the lateral margin) to the bottom of the centre line (pi). A point sits at
#: ``y = half_width * sin(phi)`` and ``thickness * (cos(phi) - 1) / 2`` along the dorsum's
#: normal: an ellipse whose top is the dorsum through the pellets (XRMB pellets are glued on the
#: midline of the dorsum), whose margins are half the thickness lower (the dorsum is convex
#: across, thesis 6.3 "no curve") and whose bottom is the underside. Seven points per station
#: (left half; the right half is the mirror) show the curve in the front and half views.
SECTION_PHI = np.linspace(0.0, np.pi, 7)
#: Which of SECTION_PHI are the dorsum (top centre to the margin): the palate bounds these.
DORSUM_COLUMNS = 4

#: Thickness (dorsum to underside along the normal) at the tip, at T1, over the body (T2-T4) and
#: at the last back point. A real tongue body is ~40 mm tall, but the model has no floor of the
#: mouth and its dorsum rests only ~6 mm below the lower incisors' tips: 12 mm shows a body in
#: the half view while the underside stays inside the lower arch and above the chin's skin; the
#: tip is thin (a blade), the root thins toward the hyoid where the model ends.
THICKNESS_TIP_MM = 4.0
THICKNESS_T1_MM = 8.0
THICKNESS_BODY_MM = 12.0
THICKNESS_ROOT_END_MM = 6.0
#: Half-width at the tip station (the blade is narrow and rounded), mm.
HALF_WIDTH_TIP_MM = 5.0
#: The lateral margins stay this far inside the lower dental arch's inner side (the generated
#: face's flat tongue keeps 18 units, 4.5 mm, for the same reason: "the tongue has been designed
#: to fit inside the arch of the bottom teeth", thesis 4.1.1, Figure 4.6).
ARCH_MARGIN_MM = 4.5
#: The narrowest and widest half-width of the body (mm): the arch's width behind the molars
#: would give the root more than the pharynx holds (real tongues are ~50 mm wide).
HALF_WIDTH_MIN_MM = 3.0
HALF_WIDTH_MAX_MM = 22.0

# --- the back of the tongue (PHA.DAT) ---------------------------------------------------------
#: Back points behind T4, replacing CASSI 1.0's anchored back vertex (thesis 6.3: the anchored
#: back points made a V at the back of the tongue). Arc length between them, mm: the root runs
#: ~25 mm down from the dorsum's back to the level of the epiglottis, which PHA.DAT's outline
#: spans (XRMB traced the pharyngeal wall from about the palate's height down).
BACK_STEP_MM = 8.0
BACK_POINTS = 3
#: Turn of each back step from the T3 -> T4 direction toward the pharyngeal wall's direction
#: (fractions of the way): the first step nearly continues the dorsum (no V at T4), the last
#: runs along the wall, so the root follows PHA.DAT's outline as the tongue moves.
BACK_TURN = (0.25, 0.6, 0.9)
#: The root stays at least this far in front of the pharyngeal wall (mm): the airway behind the
#: tongue root is rarely narrower than a few millimetres outside a pharyngeal constriction.
PHARYNX_CLEARANCE_MM = 3.0

# --- collisions (thesis 6.3: "no collision handling") ----------------------------------------
#: The tongue's surface is kept this far behind the teeth's surface and below the palate's.
#: 1 mm: the pellets (2-3 mm across) ride on the dorsum, so the tongue's own surface is about a
#: pellet radius below a pellet that touches the palate; a vertex closer than ~1 mm also shows
#: as the two surfaces fighting in the renders, and the straight edges between vertices bulge a
#: little through a curved palate.
COLLISION_MARGIN_MM = 1.0
#: Width of the soft projection under the palate and in front of the pharynx (mm): a point is moved by ``w * log(1 + exp(d / w))`` toward the
#: bound, a smooth function of where the data puts it, so a pellet sliding along the palate moves
#: the tongue smoothly (no new jitter) and a point farther than ~1 mm from the bound moves by
#: less than 0.0005 mm (the pellet sites stay on the pellets whenever the data allows).
SOFTNESS_MM = 0.15
#: Stations held behind (or between) the front teeth: tip, T1, between T1 and T2, T2. Behind T2
#: the tongue is ~25 mm behind the incisors at rest; only the front of the arch can be passed.
TEETH_STATIONS = 4
#: When the tongue is protruded (T1 out between the open teeth: the XRMB protocol's tongue
#: protrusion, task 118) and T2 is still behind the teeth, the station between T1 and T2 is put
#: where the tongue passes the teeth: this far behind the upper incisors' surface, at the gap's
#: height (half of it: 3 mm, half a real incisor crown's labio-lingual thickness of ~6-7 mm;
#: Parke's teeth are only their labial faces), when T2 is behind that place.
PROTRUSION_ZONE_MM = 6.0
#: The tongue heads for the gap over the last 8 mm of T1's approach to the upper incisors' front
#: (its front moves to the gap's height over that distance, continuously; an on/off switch made
#: it jump by up to 11 mm in one frame). 8 mm: the tip leads T1 by that much
#: (cassi.versions.constants.TONGUE_TIP_AHEAD_MM), so from there on the tongue's front is at the
#: teeth; and the front moves down to the gap about as fast as T1 moves forward.
PROTRUSION_RAMP_MM = 8.0
#: How far along its way out the tongue is (TURN_MM, then how far it may be in front of the
#: teeth) changes no faster than this (subject mm/s), so a gap that opens in one frame under a
#: T1 already past the teeth (the data and the teeth disagree) does not fling the tongue out,
#: nor pull it in at once: 400 mm/s, above the peak tongue-tip speeds of speech (150-250 mm/s;
#: McClean 2000, JSLHR 43:205; Westbury, Lindstrom & McClean 2002, JSLHR 45:651; the same
#: figures calibrate the synthetic corpus, cassi.data.synth.motion), so a real tongue's own
#: motion is never slowed; only the jumps that come from the teeth are.
TONGUE_SPEED_MM_S = 400.0
#: The first part of the tongue's way out (subject mm, at TONGUE_SPEED_MM_S) turns its front
#: toward the gap; only then may it pass the teeth (and on the way back it is behind them before
#: its front leaves the gap's height). Its length is how far the front point that moves most goes
#: during the turn, so that no point moves faster than the tongue: the station between T1 and T2
#: moves ~12 mm to where the tongue passes the teeth, and the blade's underside at T1, 8 mm below
#: the dorsum (THICKNESS_T1_MM), swings a quarter turn with it, 8 * pi / 2 = 12.6 mm more: 24 mm
#: (60 ms, 9 XRMB frames). 12 mm (the station alone) moved a point of the blade up to 5.3 mm in
#: a frame (770 mm/s, JW18 task 118, whose fastest pellet moves 450 mm/s; 590 mm/s now) and shook
#: the tongue by up to 1.8 mm as it turned back from the gap (plugins/cassi30/tools/shake.py:
#: 19 frames above 1 mm on the default set, 2 now).
TURN_MM = 24.0
#: Time constant (s) of the two lags that round the way out's corners (version.settle): the
#: rate limit alone starts and stops the turn within a frame, and the front of the tongue,
#: swung by the turn, shook by up to 1.25 mm where it turned back (JW18 task 4).
SETTLE_S = 0.015
#: The gap between the incisor tips (less the margins) must be open by this much before the
#: tongue heads out in full; a narrower gap lets it go part of the way (continuously), a shut
#: one not at all. 1 mm, the collision margin.
GAP_OPEN_MM = 1.0
#: A teeth quad is the arch's front (a wall the tongue could pass forward through) when its
#: outward normal is at least this much forward (|n_x|, 60 degrees off straight ahead); the rest
#: run along the cheek. The same value CASSI 1.0 uses for its arch (versions.constants
#: TONGUE_ARCH_FRONT_NX).
FRONT_TEETH_MIN_NX = 0.5
#: Palate heights are looked up on a grid this fine (mm) made once per task from the palate's
#: triangles; bilinear lookup stays within ~0.05 mm of the surface, well inside the margin.
PALATE_GRID_MM = 1.0

# --- the palate -------------------------------------------------------------------------------
#: The palatal outline never comes lower than this above the upper incisor tip (226) (thesis
#: 6.3: it extended below the tip for some subjects). The rubric counts any reach below the tip
#: (0.25 mm rules out round-off); 0.5 mm keeps the fitted outline clear of that at every scale.
PALATE_ABOVE_INCISOR_MM = 0.5
