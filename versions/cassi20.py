"""CASSI 2.0 (June 1999; thesis 4.2): CASSI 1.0 with the lip movement algorithm of 4.2.4.

Everything but the lips is CASSI 1.0's (jaw rotation, nose clearance, tongue): the version only
swaps 1.0's lip stage for :class:`~cassi.versions.lips.LipMovementStage` (lip rounding by
ellipses, the parabolic track, the subject's lip thickness), through 1.0's ``lip_stage`` hook.
"""
from __future__ import annotations

from cassi.versions.cassi10 import Cassi10
from cassi.versions.lips import EqualThicknessPolicy, LipMovementStage, ThicknessPolicy
from cassi.versions.lips_ellipse import OuterAbcParams
from cassi.versions.protocol import Stage

__all__ = ["Cassi20"]


class Cassi20(Cassi10):
    """CASSI 2.0: lips round forward, stretch back, ride the parabolic track, equal thickness.

    Parameters
    ----------
    params : OuterAbcParams, optional
        OUTER_ABC_CALC's tuning (rho, "near c_rest", "small c'"); the defaults are
        :mod:`cassi.versions.lips_constants`'.
    """

    name = "cassi-2.0"

    def __init__(self, *, params: OuterAbcParams | None = None):
        super().__init__()
        self.params = params or OuterAbcParams()

    def thickness_policy(self) -> ThicknessPolicy:
        """How currthick splits between the lips; 2.1 overrides this and nothing else."""
        return EqualThicknessPolicy()

    def lip_stage(self) -> Stage:
        return LipMovementStage(policy=self.thickness_policy(), params=self.params)
