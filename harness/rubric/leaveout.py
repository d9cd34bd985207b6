"""Table G's tongue between the pellets: leave one pellet out (cassi-farm's addition).

Every CASSI version puts 289-292 on T1-T4, so Table F cannot tell their tongues apart. Here the
version is animated again with T2 (then T3) withheld (:mod:`cassi.harness.evaluation.withheld`)
and its site vertex is compared, frame by frame, with the pellet the recording has there: the
versions' tongue models ranked on real interpolation. Positions, not movements, are compared:
where the model puts the withheld site at the first frame is part of its prediction.

On the synthetic corpus the tongue between the pellets is the generator's (T2 moves with
0.4 x tip + 0.6 x body), not a speaker's: the figures describe the software.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.harness.rubric.model import Measurement
from cassi.harness.rubric.registry import MIN_FRAMES
from cassi.versions.protocol import PELLET_INDEX

__all__ = ["WITHHELD", "WithheldSite", "LeaveOutContext", "m_tongue_t2", "m_tongue_t3"]

#: The pellets withheld, one at a time: the two with a pellet on either side.
WITHHELD = ("T2", "T3")


@dataclass(frozen=True)
class WithheldSite:
    """Where a version animated without pellet ``name`` put its site.

    Attributes
    ----------
    name : str
    frames : int64 (F,)
        Recording rows of that animation (its first valid row ignores the withheld pellet).
    site_mm : float64 (F, 2)
        The site vertex in the XRMB frame, mm (the 4.1.1 mapping, as Table F's pellets).
    """

    name: str
    frames: np.ndarray
    site_mm: np.ndarray


@dataclass(frozen=True)
class LeaveOutContext:
    """The leave-one-out sites of one version and task file beside its recording."""

    sites: dict
    recording: object

    def error(self, name: str) -> tuple[np.ndarray, np.ndarray] | Measurement:
        """(rows, distance mm) over the frames where the withheld pellet was measured, or a
        Measurement saying why nothing is judged."""
        site = self.sites.get(name)
        if site is None:
            return Measurement(float("nan"), -1, f"the version cannot be animated with {name} "
                                                 f"withheld: its tongue between the pellets is "
                                                 f"not measured")
        rows = np.asarray(site.frames, np.int64)
        k = PELLET_INDEX[name]
        ok = np.asarray(self.recording.valid, bool)[rows, k]
        if ok.sum() < MIN_FRAMES:
            return Measurement(float("nan"), -1, f"{name} valid in {ok.sum()} frames: nothing to "
                                                 f"compare the prediction with")
        data = np.asarray(self.recording.xy_mm, np.float64)[rows[ok], k]
        return rows[ok], np.linalg.norm(np.asarray(site.site_mm)[ok] - data, axis=1)


def _withheld_error(ctx: LeaveOutContext, name: str) -> Measurement:
    e = ctx.error(name)
    if isinstance(e, Measurement):
        return e
    rows, d = e
    rms = float(np.sqrt(np.mean(d * d)))
    worst = int(np.argmax(d))
    # No frame to render: the run's renders show the version driven by every pellet, where
    # the site is on the pellet; the worst row is named in the text instead.
    return Measurement(rms, -1, f"{name} withheld, the version's site vertex lies {rms:.1f} mm "
                                f"RMS from the measured {name} over {d.size} frames (median "
                                f"{np.median(d):.1f} mm, worst {d[worst]:.1f} mm at row "
                                f"{int(rows[worst])})")


def m_tongue_t2(ctx: LeaveOutContext) -> Measurement:
    """RMS distance (mm) between the version's T2 site, animated with T2 withheld, and T2."""
    return _withheld_error(ctx, "T2")


def m_tongue_t3(ctx: LeaveOutContext) -> Measurement:
    """RMS distance (mm) between the version's T3 site, animated with T3 withheld, and T3."""
    return _withheld_error(ctx, "T3")
