"""The Parke baseline (Parke 1974, thesis 3.1.3): Parke's own jaw rotation driven by the pellets.

The jaw, lips, lower teeth, chin, neck and cheek rotate about the fixed vertex 107 with Table
3.2's zones and fractions (Eqs. 3.5-3.6); the angle is the change of the jaw pellet line from the
first valid row (Eqs. 4.1-4.3), clipped to parameter 4's range of 0-20 degrees. Nothing else
follows the data: the lips move only with the jaw, the tongue stays where Parke's model has it.
It shows what CASSI adds.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassi.versions import constants as K
from cassi.versions.jaw import apply_zones, fixed_pivot_motion, jaw_angle
from cassi.versions.protocol import StagedVersion, Stage, TaskContext

__all__ = ["Parke1974", "ParkeJawStage", "parke_jaw_angle"]


def parke_jaw_angle(mni: np.ndarray, mnm: np.ndarray, *, closed=None) -> tuple[np.ndarray, np.ndarray]:
    """Parameter 4 from the jaw pellets: (clipped, raw) angles in radians, (F,) each.

    ``mni``, ``mnm``: (F, 2) pellet positions (any frame where x and the vertical axis agree with
    Parke's); ``closed`` the (MNI, MNM) closed reference, by default their first row.
    """
    mni0, mnm0 = (mni[0], mnm[0]) if closed is None else closed
    raw = jaw_angle(mni0, mnm0, mni, mnm)
    lo, hi = np.radians(K.PARKE_JAW_RANGE_DEG)
    return np.clip(raw, lo, hi), raw


@dataclass
class ParkeJawStage:
    """Rotation about vertex 107 with Table 3.2's zones."""

    zones: tuple = K.PARKE_ZONES
    name: str = "parke-jaw"

    def initialise(self, ctx: TaskContext) -> None:
        # Parke's model has no initialisation from the data: the neutral face is the start.
        return None

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        theta, raw = parke_jaw_angle(ctx.pellet("MNI"), ctx.pellet("MNM"),
                                     closed=(ctx.first_pellet("MNI"), ctx.first_pellet("MNM")))
        pivot = ctx.start[K.V_PARKE_JAW_PIVOT - 1, [0, 2]]
        motion = fixed_pivot_motion(theta, pivot)
        apply_zones(ctx.start, motion, self.zones, out=positions)
        ctx.state["jaw_motion"] = motion
        ctx.diagnostics["jaw_angle_rad"] = theta
        ctx.diagnostics["jaw_angle_deg"] = np.degrees(theta)
        ctx.diagnostics["jaw_angle_unclipped_rad"] = raw
        ctx.diagnostics["jaw_point_x"] = motion.point[:, 0]
        ctx.diagnostics["jaw_point_z"] = motion.point[:, 1]
        ctx.diagnostics["param_4"] = np.degrees(theta)


class Parke1974(StagedVersion):
    """The baseline: Parke's jaw rotation only."""

    name = "parke-1974"

    def stages(self) -> list[Stage]:
        return [ParkeJawStage()]
