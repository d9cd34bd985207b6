"""CASSI 2.0 (June 1999; thesis 4.2): CASSI 1.0 with the lip movement algorithm of 4.2.4.

Everything but the lips is CASSI 1.0's (jaw rotation, nose clearance, tongue): the version only
swaps 1.0's lip stage for :class:`~cassi.versions.lips.LipMovementStage` (lip rounding by
ellipses, the parabolic track, the subject's lip thickness), through 1.0's ``lip_stage`` hook.

Where section 4.2.1's words and the judges' findings part, the words are an option: ``corner``
(:class:`~cassi.versions.lips.CornerReading`) places the lip corner 70 on a vertical ellipse
(mouth open taller than wide) beyond the outline as the text says ("text"), or at it
("results", the default: the text's corner sharpens toward the diamond that thesis Table 5.9
charges to CASSI 1.0, not to 2.0; on task 106 no Table E verdict differs between the two; the
measurements are beside ``lips_constants.CORNER_READING``).
"""
from __future__ import annotations

from cassi.versions.cassi10 import Cassi10
from cassi.versions import lips_constants as K
from cassi.versions.lips import (CornerReading, EqualThicknessPolicy, LipMovementStage,
                                 ThicknessPolicy)
from cassi.versions.lips_ellipse import OuterAbcParams, tuning as lip_tuning
from cassi.versions.protocol import Stage

__all__ = ["Cassi20"]


class Cassi20(Cassi10):
    """CASSI 2.0: lips round forward, stretch back, ride the parabolic track, equal thickness.

    Parameters
    ----------
    params : OuterAbcParams, optional
        OUTER_ABC_CALC's tuning (rho, "near c_rest", "small c'"); overrides ``tuning``.
    tuning : str, optional
        A named tuning of :data:`~cassi.versions.lips_ellipse.TUNINGS` (default
        :attr:`tuning`: this version's own; "shared" is the one both versions had before).
    corner : CornerReading or str, optional
        Where the lip corner sits on a vertical ellipse (default :attr:`corner`).
    tongue : TongueReading or str, optional
        As for :class:`~cassi.versions.cassi10.Cassi10` (1.0's tongue, unchanged in 2.0).
    """

    name = "cassi-2.0"
    #: OUTER_ABC_CALC's tuning: 2.0's own (rho 1, no smoothing; lips_constants.RHO_20).
    tuning: str = "2.0"
    #: The lip corner's reading on a vertical ellipse; RESULTS by default (module docstring).
    corner: CornerReading = CornerReading(K.CORNER_READING)

    def __init__(self, *, params: OuterAbcParams | None = None, tuning: str | None = None,
                 corner: CornerReading | str | None = None, tongue: str | None = None):
        super().__init__(tongue=tongue)
        if tuning is not None:
            self.tuning = tuning
        self.params = params or lip_tuning(self.tuning)
        if corner is not None:
            self.corner = CornerReading(corner)

    def thickness_policy(self) -> ThicknessPolicy:
        """How currthick splits between the lips; 2.1 overrides this and nothing else."""
        return EqualThicknessPolicy()

    def lip_stage(self) -> Stage:
        return LipMovementStage(policy=self.thickness_policy(), params=self.params,
                                corner=self.corner)
