"""Leave-one-out animations: the version driven with one tongue pellet withheld.

At its pellet sites every CASSI version reproduces the recording (Table F); between the pellets
each has its own tongue. Withholding T2 (then T3) and animating from the rest shows where the
version's tongue puts that site; Table G's ``shape_tongue_t2`` / ``shape_tongue_t3`` compare it
with the pellet the recording has there (:mod:`cassi.harness.rubric.leaveout`).
"""
from __future__ import annotations

import numpy as np

from cassi.data.face import numbering as N
from cassi.harness.rubric.frames import CHUNK_FRAMES
from cassi.harness.rubric.leaveout import WITHHELD, WithheldSite
from cassi.versions.mapping import XrmbToParke
from cassi.versions.protocol import PELLET_INDEX, accepts_withheld, version_face

__all__ = ["withheld_sites"]


def withheld_sites(version, profile, face, rec) -> dict[str, WithheldSite]:
    """For each pellet of :data:`~cassi.harness.rubric.leaveout.WITHHELD`: the version animated
    without it, and its site vertex (289-292) per frame in the XRMB frame.

    Parameters
    ----------
    version, profile, rec
        As for the version's ``animate``.
    face : FaceModel
        The subject's shared face (the version derives its own, :func:`version_face`).

    Returns
    -------
    dict
        Pellet name -> :class:`WithheldSite`; empty for a version that cannot animate with a
        pellet withheld (:func:`~cassi.versions.protocol.accepts_withheld`), whose rows then
        say so.
    """
    if not accepts_withheld(version):
        return {}
    mapping = XrmbToParke.from_face(version_face(version, face).vertices, profile.jaw_length_mm)
    out = {}
    for name in WITHHELD:
        row = N.TONGUE_PELLETS[PELLET_INDEX[name] - PELLET_INDEX["T1"]] - 1
        frames, sites = [], []
        for anim in version.animate_chunks(profile, face, rec, frames=CHUNK_FRAMES,
                                           withheld=(name,)):
            frames.append(np.asarray(anim.frames, np.int64))
            sites.append(mapping.to_xrmb(np.asarray(anim.positions[:, row][:, [0, 2]], np.float64)))
        out[name] = WithheldSite(name, np.concatenate(frames), np.concatenate(sites))
    return out
