"""CASSI 3.0 as a plug-in of cassi-farm's version registry (entry point ``cassi-3.0``).

:class:`Cassi30` keeps CASSI 2.1's jaw and lip stages and replaces the tongue: thick and curved
through T1-T4, kept behind the teeth and under the palate by a soft projection, its back
following T3-T4 along the pharynx outline (PHA.DAT); its face's palate is fitted above the upper
incisor tip. Every value it adds is in :mod:`cassi30.constants` with its reason.
"""
from cassi30.version import Cassi30, ThickTongueStage

__all__ = ["Cassi30", "ThickTongueStage"]
