"""``cassi render`` and ``cassi animate`` through the harness's own path.

Positions come from exactly what ``cassi run`` uses: the corpus, the subject's profile and face
(:func:`cassi.harness.pipeline.get_corpus`, ``get_profile``, ``get_face``) and the version from
:mod:`cassi.versions.registry`; the renderer (:mod:`cassi.renderer.commands`) only renders them.
"""
from __future__ import annotations

import numpy as np

from cassi.renderer.commands import NEUTRAL
from cassi.renderer.commands import register as _register_render

__all__ = ["register", "task_positions"]


def task_positions(corpus_dir, subject: str, task: int, rep: int, version: str):
    """Face (the one ``version`` animates), recording rows int64 (F,) and positions float32
    (F, V, 3) Parke units of ``version`` animating one task file; ``neutral``: the subject's
    neutral face in every row."""
    from cassi.versions.registry import get_version  # noqa: PLC0415

    from .pipeline import get_corpus, get_face, get_profile, get_version_face  # noqa: PLC0415

    corpus = get_corpus(corpus_dir)
    rec = corpus.subject(subject).load(task, rep)
    ver = None if version == NEUTRAL else get_version(version)  # unknown: did-you-mean error
    profile = get_profile(corpus, subject)
    face = get_face(corpus, subject, profile)
    if ver is None:
        n = len(rec.time_us)
        verts = np.asarray(face.vertices, np.float32)
        return face, np.arange(n, dtype=np.int64), np.broadcast_to(verts, (n, *verts.shape))
    anim = ver.animate(profile, face, rec)
    face = get_version_face(corpus, subject, profile, ver)  # the face the version animated
    return face, np.asarray(anim.frames, np.int64), np.asarray(anim.positions, np.float32)


def register(sub) -> None:
    """The ``cassi.commands`` entry point of ``render`` and ``animate``."""
    _register_render(sub, positions_provider=task_positions)
