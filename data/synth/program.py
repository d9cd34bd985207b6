"""What happens when in a synthetic task: timed segments for the trajectory model.

Spoken tasks (1-105) are timed from the protocol's summary statistics
(:mod:`cassi.data.synth.tasks`): median phone durations scaled to the task's typical speech span,
with per-phone jitter and pauses between words as often and as long as in the real recordings; or,
when a Praat TextGrid of the task is given, exactly from its phone tier. Oral-motor tasks
(106-118) are programmes of held postures (:func:`motor_segments`).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.synth.motion import REST_SPEC, Anatomy, expand_phones
from cassi.data.synth.tasks import PHONE_DURATION_S, TaskSpec, word_phones

Segment = tuple[float, float, dict]

#: Jaw opening per task type, as a gain on the phones' jaw angles (oral-motor programmes set their
#: own). Calibrated to KINEMATIC_TARGETS of :mod:`cassi.data.synth.motion`: in syllable
#: repetitions the jaw (MNI) opens 15-25 mm at 150-250 mm/s; connected speech opens it less.
JAW_GAIN: dict[str, float] = {"speech": 1.4, "syllable repetition": 2.0}


def jaw_gain(task: TaskSpec) -> float:
    """The task type's jaw gain (:data:`JAW_GAIN`); 1 for oral-motor programmes."""
    if task.motor is not None:
        return 1.0
    return JAW_GAIN.get(task.category, JAW_GAIN["speech"])


def spoken_phones(task: TaskSpec, rng: np.random.Generator) -> tuple[list, float]:
    """Timed phones ``[(start_s, end_s, label)]`` and the recording length (s) of a spoken task."""
    words = [word_phones(w) for w in task.words]
    nominal = np.array([sum(PHONE_DURATION_S[p] for p in w) for w in words])
    n_pause = task.pause_fraction * max(0, len(words) - 1)
    rate = (task.speech_s - n_pause * task.pause_s) / max(1e-3, nominal.sum())
    rate = float(np.clip(rate, 0.55, 2.5)) * float(rng.uniform(0.93, 1.07))
    t = task.lead_s * float(rng.uniform(0.85, 1.15))
    out: list[tuple[float, float, str]] = [(0.0, t, "sp")]
    for k, w in enumerate(words):
        if k and rng.random() < task.pause_fraction:
            dur = task.pause_s * float(rng.lognormal(0.0, 0.25))
            out.append((t, t + dur, "sp"))
            t += dur
        for p in w:
            dur = PHONE_DURATION_S[p] * rate * float(rng.lognormal(0.0, 0.18))
            dur = max(dur, 0.03)
            out.append((t, t + dur, p))
            t += dur
    length = max(task.duration_s, t + 0.4)
    out.append((t, length, "sp"))
    return out, length


def textgrid_phones(path: Path) -> tuple[list, float]:
    """Timed phones and recording length from a Praat TextGrid's ``phone`` tier (praatio).

    Raises :class:`CassiInputError` when the file cannot be read or has no phone tier.
    """
    from praatio import textgrid
    try:
        tg = textgrid.openTextgrid(str(path), includeEmptyIntervals=False)
    except Exception as exc:  # praatio raises several types for malformed files
        raise CassiInputError(f"unreadable TextGrid: {exc}", path=path) from None
    names = [n for n in tg.tierNames if n.lower() in ("phone", "phones")]
    if not names:
        raise CassiInputError("TextGrid has no 'phone' tier", path=path)
    entries = tg.getTier(names[0]).entries
    if not entries:
        raise CassiInputError("TextGrid phone tier is empty", path=path)
    out: list[tuple[float, float, str]] = []
    t = 0.0
    for e in entries:
        s, f = float(e.start), float(e.end)
        if s > t + 1e-6:
            out.append((t, s, "sp"))
        out.append((max(s, t), f, e.label))
        t = max(t, f)
    length = max(float(tg.maxTimestamp), t)
    if length > t + 1e-6:
        out.append((t, length, "sp"))
    return out, length


def _hold(seq: list, t: float, dur: float, spec: dict) -> float:
    seq.append((t, t + dur, spec))
    return t + dur


def motor_segments(task: TaskSpec, anat: Anatomy, rng: np.random.Generator) -> list[Segment]:
    """Spec segments of an oral-motor programme (tasks 106-118), starting and ending at rest."""
    fig = anat.fig
    seq: list[Segment] = []
    t = _hold(seq, 0.0, task.lead_s * float(rng.uniform(0.9, 1.1)), REST_SPEC)
    end = task.duration_s - 0.6
    m = task.motor
    u = lambda a, b: float(rng.uniform(a, b))  # noqa: E731
    if m == "jaw_wag":
        open_deg = u(10.0, 14.0)
        while t < end - 0.5:
            t = _hold(seq, t, u(0.2, 0.26), {"jaw": open_deg * u(0.9, 1.1)})
            t = _hold(seq, t, u(0.2, 0.26), {"jaw": 0.5})
    elif m == "lip_round_spread":
        while t < end - 1.2:
            t = _hold(seq, t, u(0.5, 0.7), {"ulp_mm": 0.85 * fig.max_protrusion_ul_mm,
                                             "llp_mm": 0.8 * fig.max_protrusion_ll_mm,
                                             "lips": "round", "jaw": 1.5})
            t = _hold(seq, t, u(0.5, 0.7), {"ulp_mm": -fig.spread_ul_mm, "llp_mm": -1.0,
                                             "lips": "open", "jaw": 1.0})
    elif m == "tongue_in_out":
        while t < end - 1.0:
            t = _hold(seq, t, u(0.4, 0.6), {"jaw": 7.0, "tip": ("abs", 4.0, -3.0),
                                             "body": ("own", 9.0, -1.0), "lips": "open"})
            t = _hold(seq, t, u(0.4, 0.6), {"jaw": 3.0, "tip": ("own", -2.0, 0.0),
                                             "body": ("own", -3.0, 0.0)})
    elif m == "tongue_tip_up_down":
        while t < end - 0.6:
            t = _hold(seq, t, u(0.25, 0.35), {"jaw": 5.0, "tip": ("alv", 4.0, 0.0)})
            t = _hold(seq, t, u(0.25, 0.35), {"jaw": 5.0, "tip": ("own", 0.0, -4.0)})
    elif m == "tongue_back_up_down":
        while t < end - 0.6:
            t = _hold(seq, t, u(0.25, 0.35), {"jaw": 5.0, "body": ("vel", 10.0, 0.0)})
            t = _hold(seq, t, u(0.25, 0.35), {"jaw": 5.0, "body": ("own", -1.0, -4.0)})
    elif m == "lip_open_close":
        while t < end - 0.5:
            t = _hold(seq, t, u(0.18, 0.25), {"jaw": 2.5, "lips": "close"})
            t = _hold(seq, t, u(0.18, 0.25), {"jaw": 5.0, "lips": "open"})
    elif m == "swallow":
        t = _hold(seq, t, 0.5, {"jaw": 0.0, "lips": "close"})
        t = _hold(seq, t, 0.25, {"jaw": -0.3, "lips": "close", "tip": ("alv", 5.0, 0.0)})
        t = _hold(seq, t, 0.25, {"jaw": -0.3, "lips": "close", "tip": ("alv", 5.0, 0.0),
                                 "body": ("alv", 22.0, 0.0)})
        t = _hold(seq, t, 0.3, {"jaw": -0.3, "lips": "close", "tip": ("alv", 5.0, 0.0),
                                "body": ("vel", 6.0, 0.0)})
        t = _hold(seq, t, 0.6, {"jaw": 0.0, "lips": "close", "tip": ("own", 0.0, -1.0),
                                "body": ("own", 0.0, -2.0)})
    elif m == "jaw_max_open":
        for _ in range(2):
            t = _hold(seq, t, 1.6, {"jaw": u(20.0, 25.0), "lips": "open"})
            t = _hold(seq, t, 1.0, REST_SPEC)
    elif m == "pataka":
        phones, tt = [], t
        while tt < end - 0.3:
            for p in ("P", "AH", "T", "AH", "K", "AH"):
                d = (0.055 if p != "AH" else 0.06) * u(0.85, 1.15)
                phones.append((tt, tt + d, p))
                tt += d
        seq.extend(expand_phones(phones))
        t = tt
    elif m == "sustained_vowels":
        for v in ("AA", "IY", "UW"):
            seq.extend(expand_phones([(t, t + 2.0, v)]))
            t = _hold(seq, t + 2.0, 0.8, REST_SPEC)
    elif m == "rest":
        while t < end - 1.0:
            t = _hold(seq, t, u(1.0, 2.0), {"jaw": u(-0.3, 0.8), "lips": "open"})
    elif m == "max_protrusion":
        # jaw closed: its opening would carry the lower lip back (about 0.35 mm per degree)
        lips = {"ulp_mm": fig.max_protrusion_ul_mm - 0.1, "llp_mm":
                fig.max_protrusion_ll_mm - 0.1, "lips": "round", "jaw": 0.0,
                "tip": ("own", 0.0, 0.0), "body": ("own", 0.0, 0.0)}
        t = _hold(seq, t, 1.8, lips)
        t = _hold(seq, t, 1.0, REST_SPEC)
        t = _hold(seq, t, 1.6, {"jaw": 9.0, "tip": ("abs", fig.ul_rest_mm[0] + 3.0, -4.0),
                                "body": ("own", 12.0, -2.0), "lips": "open",
                                # lips drawn back out of the tongue's way: the subject's minimum
                                "ulp_mm": -fig.spread_ul_mm + 0.2, "llp_mm": -1.0})
        t = _hold(seq, t, 1.0, REST_SPEC)
        t = _hold(seq, t, 1.8, lips)
    else:
        raise ValueError(f"unknown oral-motor programme {m!r}")
    length = max(task.duration_s, t + 0.8)
    _hold(seq, t, length - t, REST_SPEC)
    return seq


def n_frames(length_s: float, period_s: float) -> int:
    return int(math.floor(length_s / period_s)) + 1
