"""The versions on real inputs: the thesis's JW45 excerpt, the synthetic corpus, the face model.

Nothing here is mocked: recordings come from ``cassi.data.xrmb.files``/``cassi.data.synth.corpus``, profiles
from ``cassi.data.corpus.profile.preprocess``, the face from ``cassi.data.face.model.build_face`` (the tests
that need it skip while that module is not installed).
"""
from __future__ import annotations

import importlib
import numpy as np
import pytest

from cassi.versions.mapping import subject_face
from cassi.versions import constants as K
from cassi.versions.mapping import XrmbToParke
from cassi.versions.registry import get_version

BUILTIN = ["parke-1974", "cassi-1.0"]


@pytest.fixture(scope="module")
def synth(tmp_path_factory):
    from cassi.data.corpus.disk import Corpus
    from cassi.data.corpus.profile import preprocess
    from cassi.data.synth.corpus import make_corpus

    root = make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW45"], seed=0)
    corpus = Corpus(root)
    return corpus, preprocess(corpus, ["JW45"])["JW45"]


@pytest.fixture(scope="module")
def real_face(synth):
    face_mod = importlib.import_module("cassi.data.face.model")
    _, profile = synth
    return subject_face(palate_mm=profile.palate_mm, head_measures=profile.head_measures)


def test_thesis_excerpt_first_valid_row(shared_dir):
    # Thesis Figure 3.9: JW45 task 13's first row with all eight pellets valid is at 27464 us.
    from _versions_toy import ToyFace, toy_profile, toy_vertices
    from cassi.data.xrmb.files import read_txy

    rec = read_txy(shared_dir / "reference" / "xrmb" / "JW45" / "JW45_013.TXY", subject="JW45")
    anim = get_version("cassi-1.0").animate(toy_profile(), ToyFace(toy_vertices()), rec)
    assert anim.time_us[0] == 27464 and anim.n_frames == 12
    m = XrmbToParke.from_face(toy_vertices(), toy_profile().jaw_length_mm)
    np.testing.assert_allclose(anim.vertex(K.V_UL)[:, [0, 2]], m.to_parke(rec.xy_mm[4:, 0]),
                               atol=1e-3)


@pytest.mark.parametrize("task", [106, 118])
@pytest.mark.parametrize("name", BUILTIN)
def test_synthetic_task_on_real_face(synth, real_face, name, task):
    corpus, profile = synth
    rec = corpus.subject("JW45").load(task)
    anim = get_version(name).animate(profile, real_face, rec)
    assert anim.positions.shape == (rec.n_frames - rec.first_valid_index,
                                    len(real_face.vertices), 3)
    assert np.isfinite(anim.positions).all()
    assert len(anim.diagnostics) == anim.n_frames
    if name == "cassi-1.0":
        m = XrmbToParke.from_face(real_face.vertices, profile.jaw_length_mm)
        first = rec.first_valid_index
        # The MANi site sits on the MANi pellet (held where the pellet was invalid).
        from cassi.versions.protocol import held_pellets
        held, _ = held_pellets(rec.xy_mm, rec.valid, first)
        tol = 1e-3 * max(1.0, m.scale)
        np.testing.assert_allclose(anim.vertex(K.V_MANI)[:, [0, 2]], m.to_parke(held[:, 6]),
                                   atol=tol)
        np.testing.assert_allclose(anim.vertex(K.V_UL)[:, [0, 2]], m.to_parke(held[:, 0]),
                                   atol=tol)
        np.testing.assert_allclose(anim.vertex(K.V_LL)[:, [0, 2]], m.to_parke(held[:, 1]),
                                   atol=tol)


def test_bench_on_real_face(real_face):
    from cassi.harness.bench.geometry import bench_geometry

    out = bench_geometry(True, face=real_face, frames=600, versions=BUILTIN)
    assert not out["errors"] and set(out["geometry_frames_per_s"]) == set(BUILTIN)
