"""A small stand-in face, profile and recording for the versions' unit tests.

The stand-in face places the vertices the versions use where Parke's model roughly has them
(Parke units ~10 per mm, X forward, Y left, Z up; the tongue and lips on the midline, the molars
off it) so the geometry can be checked by hand; the integration tests use the real face model
(``cassi.data.face.model.build_face``) when it is installed. The recording's first rows copy the JW45
excerpt of thesis Figure 3.9 (tests/../shared/reference/xrmb/JW45/JW45_013.TXY), mm.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.data.xrmb.headmeasures import HeadMeasures
from cassi.data.corpus.profile import SubjectProfile
from cassi.data.xrmb.files import TaskRecording

N_VERTICES = 310          # 1-300 as CONTRACTS numbers them, 301-310 a stand-in palate

# JW45 task 13 at 27464 us (Figure 3.9), micrometres -> mm, PELLETS order.
JW45_ROW = np.array([[15.757, 11.596], [12.175, -9.772], [-7.786, 5.158], [-27.477, 11.512],
                     [-42.758, 9.180], [-54.294, 0.829], [-0.699, -7.452], [-34.792, -9.862]])


@dataclass
class ToyFace:
    vertices: np.ndarray


def toy_vertices(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = np.zeros((N_VERTICES, 3))
    # Everything else somewhere on a head-sized blob first.
    v[:] = rng.uniform([-700, 0, -600], [250, 400, 500], size=(N_VERTICES, 3))

    def put(n, x, y, z):
        v[n - 1] = (x, y, z)

    put(226, 0, 0, 0)                          # tip of the upper front teeth (XRMB origin)
    put(107, -700, 300, 60)                    # Parke's jaw pivot
    # Lower teeth 255-286 along an arch; 258 MANi on the midline, 281/286 on the molars.
    for k, n in enumerate(range(255, 287)):
        t = k / 31.0
        v[n - 1] = (-10 - 360 * t, 20 + 160 * t, -75 - 25 * t)
    put(258, -5, 0, -75)
    put(281, -340, 150, -95)
    put(286, -350, 170, -105)
    # Lips: lower 49-60 (49 the outer edge on the midline), upper 61-69 (67 on the midline).
    for k, n in enumerate(range(49, 61)):
        v[n - 1] = (120 - 8 * (k % 4), 40 * (k // 4), -95 + 12 * (k % 4))
    for k, n in enumerate(range(61, 70)):
        v[n - 1] = (150 - 10 * (k % 3), 60 * (k // 3), 90 + 15 * (k % 3))
    put(67, 150, 0, 100)
    put(69, 140, 0, 130)                       # the top of the upper lip, under the nose
    put(70, 60, 250, 0)
    put(287, 50, 240, 0)
    put(300, 55, 245, 0)
    # Nose outline 80-101: a wedge above the lip; 80-85 the tip and its underside (z 180-200).
    for k, n in enumerate(range(80, 102)):
        t = k / 21.0
        v[n - 1] = (120 + 100 * t, 60 * t, 250 + 150 * t)
    for k, n in enumerate(range(80, 86)):
        v[n - 1] = (160 + 15 * k, 10 * k, 180 + 4 * k)
    # Tongue 288-299: tip 288, centre 289-292, back 293, edges 294-299 beside each of them.
    put(288, -20, 0, 40)
    for n, x in zip(range(289, 293), (-80, -270, -430, -540)):
        put(n, x, 0, 50)
    put(293, -640, 0, 0)
    for n, x in zip(range(294, 300), (-20, -80, -270, -430, -540, -640)):
        put(n, x, 120, 40)
    # Jaw 14-43, chin 11-13, neck 6-10, cheek 44-48.
    for k, n in enumerate(range(14, 44)):
        t = k / 29.0
        v[n - 1] = (80 - 650 * t, 100 + 200 * t, -200 - 200 * np.sin(np.pi * t))
    for n in range(6, 14):
        v[n - 1] = (100 - 20 * (n - 6), 30 * (n - 6), -450 + 10 * n)
    for n in range(44, 49):
        v[n - 1] = (-100 - 50 * (n - 44), 300, -100)
    put(17, 90, 0, -330)                       # gnathion (point of the chin)
    put(22, -560, 300, -300)                   # gonion (angle of the jaw)
    return v


def toy_profile(jaw_length_mm: float = 34.18, head_measures: bool = True) -> SubjectProfile:
    hm = HeadMeasures(gonion_mm=np.array([-70.0, -45.0]),
                      gnathion_mm=np.array([4.0, -38.0])) if head_measures else None
    return SubjectProfile(subject="TOY", jaw_length_mm=jaw_length_mm, rest_ul=0.46, rest_ll=0.36,
                          max_ul=0.69, max_ll=0.56, min_ul=0.01, min_ll=0.008, lipthick=0.62,
                          head_measures=hm)


def toy_recording(n: int = 400, *, invalid_head: int = 3, seed: int = 1,
                  wag_deg: float = 12.0) -> TaskRecording:
    """A jaw-wagging recording: the mandible pellets rotate about a moving point, the lips and
    tongue drift; the first ``invalid_head`` rows are the bad value, as in real files."""
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    xy = np.broadcast_to(JW45_ROW, (n, 8, 2)).copy()
    theta = np.radians(wag_deg) * 0.5 * (1 - np.cos(2 * np.pi * t / 120.0))
    pivot = np.array([-80.0, 10.0])
    for p in (6, 7):
        rel = JW45_ROW[p] - pivot
        c, s = np.cos(theta), np.sin(theta)
        xy[:, p, 0] = rel[0] * c + rel[1] * s + pivot[0]
        xy[:, p, 1] = rel[1] * c - rel[0] * s + pivot[1]
    xy[:, 1, 1] += xy[:, 6, 1] - JW45_ROW[6, 1]            # the lower lip rides on the jaw
    xy[:, 0, 0] += 2.0 * np.sin(2 * np.pi * t / 200.0)       # the upper lip protrudes a little
    xy[:, 2:6] += rng.normal(0, 0.2, size=(n, 4, 2))
    valid = np.ones((n, 8), dtype=bool)
    valid[:invalid_head] = False
    xy[~valid] = np.nan
    return TaskRecording(path=None, subject="TOY", task=106, rep=1,
                         time_us=(t * 6866).astype(np.int64), xy_mm=xy, valid=valid)
