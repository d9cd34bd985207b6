"""Table G, the shape between the pellets (cassi-farm's addition, not the thesis's).

Table F compares the model's pellet sites with the recording; every CASSI version puts 67 and
49 on the lip pellets, so at those sites all of them reproduce the recording. What separates
them is the shape the pellets do not pin down. Table G measures it from the same animation and
the same recording:

- lip contact: do the lips' inner edges (61 over 58) meet where the recording's lip aperture
  (UL-LL pellet distance) says the speaker's lips touch, and part where it says they part?
- mouth width at rest, from the front (2 |y| of the corner 70), against published adult mouth
  widths;
- rounding on task 118: how much the mouth narrows for each millimetre the recording says the
  lips protrude.

The tongue between the pellets (leave one out) is Table G's too: :mod:`.leaveout`. Every
band is declared in :mod:`.registry` with its source; results on the synthetic corpus
describe the software, not real speakers.

Why a table of its own rather than rows of Table F: Table F's rating says "the model follows the
pellets"; a version on the pellets but with lips that never meet would earn that rating and a
bad one here, and the two faults are told apart only if they are charged apart.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.common.errors import CassiInputError

from cassi.harness.rubric import geometry as G
from cassi.harness.rubric.frames import Frames
from cassi.harness.rubric.model import Measurement
from cassi.harness.rubric.registry import (CLOSURE_BAND_MM, FIDELITY_MIN_RANGE_MM, LIPS_TOUCH_MM,
                                           MIN_FRAMES, MOUTH_WIDTH_RANGE_MM, OPEN_BAND_MM)

__all__ = ["ShapeContext", "m_lip_contact", "m_lip_closure", "m_mouth_width", "m_rounding"]


@dataclass
class ShapeContext:
    """Per-frame lip shape of one animation (mm) beside the recording's lip pellets.

    Attributes
    ----------
    gap : float64 (F,)
        The model's inner lip gap z(61) - z(58), mm (<= 0: touching or crossing).
    width : float64 (F,)
        The model's mouth width from the front, 2 |y(70)|, mm.
    protrusion : float64 (F,)
        The model's mean x of 67 and 49, mm.
    aperture : float64 (F,)
        The recording's UL-LL pellet distance, mm (NaN where either pellet is invalid).
    data_protrusion : float64 (F,)
        The recording's mean x of UL and LL, mm (NaN where invalid).
    """

    gap: np.ndarray
    width: np.ndarray
    protrusion: np.ndarray
    aperture: np.ndarray
    data_protrusion: np.ndarray

    @classmethod
    def of(cls, anim, recording, mapping, parts: G.MouthParts) -> "ShapeContext":
        """From an Animation, its TaskRecording, the subject's XrmbToParke (whose scale turns
        Parke units into the subject's millimetres, as for the pellets) and the mouth parts."""
        frames = np.asarray(anim.frames, np.int64)
        xy = np.asarray(recording.xy_mm, np.float64)
        if frames.size == 0 or frames.max() >= xy.shape[0] or frames.min() < 0:
            raise CassiInputError("the animation's frames are not rows of the recording",
                                  path=getattr(recording, "path", None))
        ok = np.asarray(recording.valid, bool)[frames][:, :2].all(axis=1)
        ul, ll = xy[frames, 0], xy[frames, 1]
        aperture = np.where(ok, np.linalg.norm(ul - ll, axis=1), np.nan)
        data_prot = np.where(ok, 0.5 * (ul[:, 0] + ll[:, 0]), np.nan)
        mm = 1.0 / float(mapping.scale)
        p = parts

        def lips(pos):
            pos = np.asarray(pos, np.float64)
            return np.stack([pos[:, p.ul_inner, 2] - pos[:, p.ll_inner, 2],
                             2.0 * np.abs(pos[:, p.corner, 1]),
                             0.5 * (pos[:, p.ul_outer, 0] + pos[:, p.ll_outer, 0])], axis=1)

        positions = anim.positions
        s = positions.series(lips) if isinstance(positions, Frames) else lips(positions)
        s = np.asarray(s, np.float64) * mm
        return cls(gap=s[:, 0], width=s[:, 1], protrusion=s[:, 2], aperture=aperture,
                   data_protrusion=data_prot)


def _contact(ctx: ShapeContext):
    """(closed, opened, touch, narrowest) boolean frames of the recording's closures and
    openings and of the model's contact, or a Measurement saying why nothing is judged."""
    a, gap = ctx.aperture, ctx.gap
    ok = np.isfinite(a)
    if ok.sum() < 2 * MIN_FRAMES:
        return Measurement(float("nan"), -1, "too few frames with both lip pellets valid")
    lo = float(np.nanmin(a))
    closed = ok & (a <= lo + CLOSURE_BAND_MM)
    opened = ok & (a >= lo + OPEN_BAND_MM)
    if closed.sum() < MIN_FRAMES or opened.sum() < MIN_FRAMES:
        return Measurement(float("nan"), -1,
                           f"the recording's lip aperture does not both close (within "
                           f"{CLOSURE_BAND_MM} mm of its narrowest, {closed.sum()} frames) and "
                           f"open ({OPEN_BAND_MM} mm beyond it, {opened.sum()} frames) for "
                           f"{MIN_FRAMES} frames: nothing to follow")
    return closed, opened, gap <= LIPS_TOUCH_MM, lo


def _shown(gap, closed, opened, touch) -> int:
    """The frame shown: a closed frame left open (the widest), else an open frame shut (the
    tightest), else the first closed frame."""
    missed_closed = np.flatnonzero(closed & ~touch)
    missed_open = np.flatnonzero(opened & touch)
    if missed_closed.size:
        return int(missed_closed[np.argmax(gap[missed_closed])])
    if missed_open.size:
        return int(missed_open[np.argmin(gap[missed_open])])
    return int(np.flatnonzero(closed)[0])


def m_lip_contact(ctx: ShapeContext) -> Measurement:
    """Youden's J of the model's lip contact against the recording's: the share of the
    recording's closed frames where the model's lips touch, plus the share of its open frames
    where they are apart, minus 1. 1 = contact everywhere the speaker's lips touch and nowhere
    else; 0 = no more agreement than a face that never changes (always closed or always open);
    negative = the opposite of the recording."""
    c = _contact(ctx)
    if isinstance(c, Measurement):
        return c
    closed, opened, touch, lo = c
    hit_closed = float(np.mean(touch[closed]))
    hit_open = float(np.mean(~touch[opened]))
    j = hit_closed + hit_open - 1.0
    f = _shown(ctx.gap, closed, opened, touch)
    return Measurement(j, f, f"recording closed in {closed.sum()} frames (UL-LL within "
                             f"{CLOSURE_BAND_MM} mm of its narrowest {lo:.1f} mm): model lips touch "
                             f"(61-58 gap <= {LIPS_TOUCH_MM} mm) in {hit_closed:.0%}; open in "
                             f"{opened.sum()} frames: model lips apart in {hit_open:.0%}; J = {j:.2f}",
                       frame_value=float(ctx.gap[f]))


def m_lip_closure(ctx: ShapeContext) -> Measurement:
    """The closing half of :func:`m_lip_contact`: the share of the recording's closed frames
    where the model's lips touch."""
    c = _contact(ctx)
    if isinstance(c, Measurement):
        return c
    closed, opened, touch, lo = c
    share = float(np.mean(touch[closed]))
    f = _shown(ctx.gap, closed, opened, touch)  # m_lip_contact's frame: no new frame to render
    return Measurement(share, f, f"recording closed in {closed.sum()} frames (UL-LL within "
                                 f"{CLOSURE_BAND_MM} mm of its narrowest {lo:.1f} mm): model lips "
                                 f"touch in {share:.0%}", frame_value=float(ctx.gap[f]))


def m_mouth_width(ctx: ShapeContext) -> Measurement:
    """How far (mm) the model's mouth width at rest (the first frame, 2 |y(70)|) lies outside
    the published range of adult mouth widths; 0 inside it."""
    lo, hi = MOUTH_WIDTH_RANGE_MM
    w = float(ctx.width[0])
    out = max(0.0, lo - w, w - hi)
    return Measurement(out, 0, f"mouth width at rest {w:.1f} mm (corner to corner, 2 |y(70)|); "
                               f"adults {lo:.1f}-{hi:.1f} mm", frame_value=w)


def m_rounding(ctx: ShapeContext) -> Measurement:
    """Narrowing of the mouth (mm of width lost since the first frame) per millimetre of
    protrusion the recording gains, at the recording's frame of greatest protrusion."""
    dp = ctx.data_protrusion
    ok = np.isfinite(dp)
    if ok.sum() < MIN_FRAMES:
        return Measurement(float("nan"), -1, "too few frames with both lip pellets valid")
    idx = np.flatnonzero(ok)
    start = idx[0]
    f = int(idx[np.argmax(dp[ok])])
    gain = float(dp[f] - dp[start])
    if gain < FIDELITY_MIN_RANGE_MM:
        return Measurement(float("nan"), -1, f"the recording's lips protrude {gain:.1f} mm "
                                             f"(< {FIDELITY_MIN_RANGE_MM} mm): nothing to round")
    narrowing = float(ctx.width[start] - ctx.width[f])
    v = narrowing / gain
    return Measurement(v, f, f"at the recording's greatest protrusion (+{gain:.1f} mm) the model's "
                             f"mouth is {narrowing:.1f} mm narrower than at the start "
                             f"({ctx.width[start]:.1f} -> {ctx.width[f]:.1f} mm): {v:.2f} mm per mm",
                       frame_value=v)
