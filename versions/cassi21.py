"""CASSI 2.1 (September 1999; thesis 4.3): CASSI 2.0 with adjusted lip thickness.

Subjects whose lips start centred low get an upper lip of 2/3 and a lower lip of 4/3 of
currthick, and the inside corner 287 is blended toward vertex 60's height as the lips round
(Hermite F1, F2, Eqs. 4.20-4.21). Every other subject is animated exactly as by CASSI 2.0.

"Centred low" (4.3.1) compares the upper lip's inside edge at the first valid row, z67 - currthick
with the upper lip as thick as the lower, with a threshold 20 units from vertex 226. The text puts
the threshold below 226 (``LowLipsReading.TEXT``); the default is ``LowLipsReading.RESULTS``, the
threshold 20 units above 226, because only that reading changes the subjects the thesis reports
2.1 changed (JW11, whose inside edge stays 1.6-4.0 mm below 226 on a real recording, and JW45,
1.0 mm above it at the start of task 13) and spares lips centred high (JW16, JW18); the evidence
is beside ``lips_constants.LOW_LIPS_READING``.
"""
from __future__ import annotations

from cassi.versions import lips_constants as K
from cassi.versions.cassi20 import Cassi20
from cassi.versions.lips import CornerReading, LowLipsThicknessPolicy, ThicknessPolicy
from cassi.versions.lips_ellipse import OuterAbcParams
from cassi.versions.lips_thickness import LowLipsReading

__all__ = ["Cassi21", "LowLipsReading"]


class Cassi21(Cassi20):
    """CASSI 2.1: 2.0 with the low-lips thickness rule of section 4.3.

    Parameters
    ----------
    params : OuterAbcParams, optional
    tuning : str, optional
        As for :class:`~cassi.versions.cassi20.Cassi20` (default :attr:`tuning`).
    reading : LowLipsReading or str, optional
        Which side of vertex 226 the 20-unit threshold lies on (default :attr:`reading`).
    corner, tongue : CornerReading or str, TongueReading or str, optional
        As for :class:`~cassi.versions.cassi20.Cassi20`.
    """

    name = "cassi-2.1"
    #: OUTER_ABC_CALC's tuning: 2.1's own, which removes 2.0's switch jitter (rho 0.1).
    tuning: str = "2.1"
    #: The criterion's reading; RESULTS by default (see the module docstring).
    reading: LowLipsReading = LowLipsReading(K.LOW_LIPS_READING)

    def __init__(self, *, params: OuterAbcParams | None = None, tuning: str | None = None,
                 reading: LowLipsReading | str | None = None,
                 corner: CornerReading | str | None = None, tongue: str | None = None):
        super().__init__(params=params, tuning=tuning, corner=corner, tongue=tongue)
        if reading is not None:
            self.reading = LowLipsReading(reading)

    def thickness_policy(self) -> ThicknessPolicy:
        return LowLipsThicknessPolicy(reading=self.reading)
