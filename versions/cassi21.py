"""CASSI 2.1 (September 1999; thesis 4.3): CASSI 2.0 with adjusted lip thickness.

Subjects whose lips start centred low (the upper lip's inside edge, placed with 2.0's equal
thicknesses, more than 20 units below vertex 226) get an upper lip of 2/3 and a lower lip of 4/3
of currthick, and the inside corner 287 is blended toward vertex 60's height as the lips round
(Hermite F1, F2, Eqs. 4.20-4.21). Every other subject is animated exactly as by CASSI 2.0.
"""
from __future__ import annotations

from cassi.versions.cassi20 import Cassi20
from cassi.versions.lips import LowLipsThicknessPolicy, ThicknessPolicy

__all__ = ["Cassi21"]


class Cassi21(Cassi20):
    """CASSI 2.1: 2.0 with the low-lips thickness rule of section 4.3."""

    name = "cassi-2.1"

    def thickness_policy(self) -> ThicknessPolicy:
        return LowLipsThicknessPolicy()
