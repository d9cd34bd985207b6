"""A worker's caches: corpus, profiles, faces and renderers, kept across the jobs it runs.

Worker processes live for the whole run, so each keeps a corpus, a subject's profile and face,
and one :class:`~cassi.renderer.render.FaceRenderer` (one Mitsuba scene) per (subject, view,
preset) instead of rebuilding them per job.
"""
from __future__ import annotations

import os
import platform
import threading
from collections import OrderedDict
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.corpus.disk import Corpus
from cassi.data.corpus.profile import preprocess
from cassi.data.face.model import build_face
from cassi.data.face.topology import render_topology
from cassi.data.synth.corpus import default_corpus
from cassi.harness.farm.workers import worker_env
from cassi.renderer.render import FaceRenderer
from cassi.versions.mapping import subject_face
from cassi.versions.protocol import version_face

_lock = threading.Lock()
_corpora: dict[str, object] = {}
_profiles: dict[tuple[str, str], object] = {}
_faces: dict = {}
#: Renderers (Mitsuba scenes) a worker keeps, least recently used dropped first: each holds
#: about 6 MB, and a night's worker meets every subject, view and face (measured: 120 scenes,
#: 1.03 GB). Sixteen cover a task file's four views for a few faces at once.
RENDERERS_KEPT = 16
_renderers: OrderedDict[tuple, object] = OrderedDict()


def corpus_root(corpus: Path | str | None) -> Path:
    """``corpus``, or the embedded default (synthetic) corpus when None."""
    if corpus is not None:
        return Path(corpus)
    return Path(default_corpus())


def get_corpus(corpus: Path | str | None):
    """This process's :class:`~cassi.data.corpus.disk.Corpus` for ``corpus`` (cached).

    A cluster worker reads the corpus from the path the run declares: when it cannot see it,
    the error says so (outputs travel back to the driver, but the corpus is storage the
    cluster must share).
    """
    root = str(corpus_root(corpus))
    if not os.path.isdir(root):
        raise CassiInputError(
            f"the corpus directory is not visible in this process (host {platform.node()}, "
            f"pid {os.getpid()}): every node of a cluster must see the corpus at the same path",
            path=root)
    with _lock:
        if root not in _corpora:
            _corpora[root] = Corpus(root)
        return _corpora[root]


def get_profile(corpus, subject: str, *, problems: list[str] | None = None):
    """The subject's profile (cached); ``problems`` receives the malformed task files that
    preprocessing met (kept with the profile, so a cached one reports them too)."""
    key = (str(corpus.root), subject)
    if key not in _profiles:
        met: list[str] = []
        _profiles[key] = (preprocess(corpus, [subject], problems=met)[subject], tuple(met))
    profile, met = _profiles[key]
    if problems is not None:
        problems.extend(met)
    return profile


def get_face(corpus, subject: str, profile):
    key = (str(corpus.root), subject)
    if key not in _faces:
        # jaw_length_mm scales the palate by p/d like the pellets (thesis 4.1.1).
        _faces[key] = subject_face(palate_mm=getattr(profile, "palate_mm", None),
                                   head_measures=getattr(profile, "head_measures", None),
                                   jaw_length_mm=getattr(profile, "jaw_length_mm", None))
    return _faces[key]


def get_version_face(corpus, subject: str, profile, version):
    """The face ``version`` animates for ``subject`` (cached): the shared face, or the one the
    version derives from it (:func:`cassi.versions.protocol.version_face`)."""
    face = get_face(corpus, subject, profile)
    if getattr(version, "animated_face", None) is None:
        return face
    key = (str(corpus.root), subject, getattr(version, "name", repr(version)))
    if key not in _faces:
        _faces[key] = version_face(version, face)
    return _faces[key]


def get_neutral():
    """Vertices of the neutral face (no subject palate): the rubric's Table B reference."""
    if "neutral" not in _faces:
        _faces["neutral"] = np.asarray(build_face().vertices)
    return _faces["neutral"]


def get_renderer(corpus, subject: str, face, view: str, preset: str, variant: str | None):
    """The process's renderer for (subject, view, preset): its Mitsuba scene is loaded once."""
    # A version may animate a face of its own (more vertices, other polygons: see
    # cassi.versions.protocol.version_face): that face gets a scene of its own.
    key = (str(corpus.root), subject, view, preset, variant, face.vertex_count,
           hash(face.polygons))
    if key in _renderers:
        _renderers.move_to_end(key)
        return _renderers[key]
    topology = render_topology(face, half=(view == "half"))
    _renderers[key] = renderer = FaceRenderer(topology, view, preset, variant)
    while len(_renderers) > RENDERERS_KEPT:
        _renderers.popitem(last=False)
    return renderer


def cache_sizes() -> dict[str, int]:
    """How much each per-process cache holds (tests check renderer reuse)."""
    return {"corpora": len(_corpora), "profiles": len(_profiles), "faces": len(_faces),
            "renderers": len(_renderers)}


def warm_worker(corpus: str | None, subject: str, views=(), preset: str = "preview",
                variant: str | None = None, threads: int | None = 1) -> None:
    """:func:`worker_env`, then fill this process's caches for ``subject`` (corpus, profile,
    face, one renderer per view, its kernels compiled by one render), so that timings after it
    describe the steady state (``cassi bench``)."""
    worker_env(threads)
    c = get_corpus(corpus)
    profile = get_profile(c, subject)
    face = get_face(c, subject, profile)
    get_neutral()
    for view in views:
        get_renderer(c, subject, face, view, preset, variant).render(np.asarray(face.vertices))
