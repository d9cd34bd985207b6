"""``cassi render`` and ``cassi animate`` through the harness's own path.

Positions come from exactly what ``cassi run`` uses: the corpus, the subject's profile and face
(:func:`cassi.harness.evaluation.caches.get_corpus`, ``get_profile``, ``get_face``) and the version from
:mod:`cassi.versions.registry`; the renderer (:mod:`cassi.renderer.commands`) only renders them.
"""
from __future__ import annotations

from cassi.renderer.commands import register as _register_render

__all__ = ["register"]


def register(sub) -> None:
    """The ``cassi.commands`` entry point of ``render`` and ``animate``."""
    _register_render(sub, positions_provider="cassi.harness.actions:task_positions")
