"""Leave-one-out tongue (Table G's shape_tongue_t2 / _t3): a version animated with T2 or T3
withheld predicts the site from the other pellets by its own tongue model; Parke's still tongue
needs no prediction; a version that would read an unpredicted pellet is refused. The measures
rank a prediction on the spot above a mean-offset one above a still tongue, and T3 is one fault
with T2. Tasks come from the embedded synthetic corpus (they describe the software)."""
from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from cassi.common.errors import CassiInputError
from cassi.data.face import numbering as N
from cassi.harness import rubric as R
from cassi.harness.evaluation.caches import get_corpus, get_face, get_profile
from cassi.harness.evaluation.withheld import withheld_sites
from cassi.harness.rubric.leaveout import LeaveOutContext, WithheldSite, m_tongue_t2
from cassi.harness.rubric.tables import component_ratings
from cassi.versions.protocol import PELLET_INDEX, accepts_withheld
from cassi.versions.registry import get_version

LEAVE = ["shape_tongue_t2", "shape_tongue_t3"]


@pytest.fixture(scope="module")
def inputs():
    corpus = get_corpus(None)
    profile = get_profile(corpus, "JW11")
    return profile, get_face(corpus, "JW11", profile), corpus.subject("JW11").load(5)


def test_the_first_valid_row_ignores_the_withheld_pellet(inputs):
    profile, face, rec = inputs
    valid = np.array(rec.valid)
    valid[: 10, PELLET_INDEX["T2"]] = False        # T2 lost for the first ten rows only
    rec2 = dataclasses.replace(rec, valid=valid)
    v = get_version("cassi-1.0")
    assert v.context(profile, face, rec2).rows[0] >= 10
    ctx = v.context(profile, face, rec2, withheld=("T2",))
    assert ctx.rows[0] == rec.first_valid_index < 10
    assert np.isnan(ctx.pellets[:, PELLET_INDEX["T2"]]).all() and ctx.held[:, 3].all()


def test_cassi_10_puts_the_withheld_site_at_its_neighbours_mean_offset(inputs):
    profile, face, rec = inputs
    v = get_version("cassi-1.0")
    anim = next(v.animate_chunks(profile, face, rec, frames=None, withheld=("T2",)))
    ctx = v.context(profile, face, rec, withheld=("T2",))
    n = np.asarray(face.vertices, float)[:, [0, 2]]
    t1, t2, t3 = N.TONGUE_PELLETS[:3]
    want = n[t2 - 1] + 0.5 * ((ctx.pellet("T1") - n[t1 - 1]) + (ctx.pellet("T3") - n[t3 - 1]))
    np.testing.assert_allclose(anim.positions[:, t2 - 1][:, [0, 2]], want, atol=1e-3)
    # every other pellet site is where the full animation puts it
    full = v.animate(profile, face, rec)
    np.testing.assert_allclose(anim.positions[:, t1 - 1], full.positions[:, t1 - 1], atol=1e-4)
    np.testing.assert_allclose(anim.positions[:, t3 - 1], full.positions[:, t3 - 1], atol=1e-4)


def test_cassi_30_predicts_a_straight_tongue_on_its_line():
    pytest.importorskip("cassi30", reason="the cassi-3.0 plug-in is not installed")
    from cassi30.version import ThickTongueStage
    line = np.array([[0.0, 0.0], [10.0, 2.0], [20.0, 4.0], [30.0, 6.0]])   # T1..T4, evenly spaced
    pellets = np.zeros((1, 8, 2))
    pellets[0, 2:6] = line
    for name, k in (("T2", 1), ("T3", 2)):
        ctx = SimpleNamespace(withheld=(name,),
                              pellet=lambda p: pellets[:, PELLET_INDEX[p]])
        got = ThickTongueStage().predict_withheld(ctx, name)[0]
        # on the line through the others (a uniform Catmull-Rom keeps collinear knots on their
        # line), between its neighbours, within a sixteenth of their spacing of the middle
        d = line[3] - line[0]
        assert abs(d[0] * (got - line[0])[1] - d[1] * (got - line[0])[0]) < 1e-9
        assert line[k - 1][0] < got[0] < line[k + 1][0]
        assert abs(got[0] - line[k][0]) <= (line[k + 1][0] - line[k - 1][0]) / 16 + 1e-9


def test_parke_needs_no_prediction_and_a_read_pellet_unpredicted_is_refused(inputs):
    profile, face, rec = inputs
    parke = get_version("parke-1974")
    a = next(parke.animate_chunks(profile, face, rec, frames=None, withheld=("T2",)))
    b = parke.animate(profile, face, rec)
    np.testing.assert_array_equal(a.positions, b.positions)     # its tongue never read T2
    with pytest.raises(CassiInputError, match="withheld"):
        next(get_version("cassi-1.0").animate_chunks(profile, face, rec, frames=None,
                                                     withheld=("UL",)))
    with pytest.raises(CassiInputError, match="cannot withhold"):
        get_version("cassi-1.0").context(profile, face, rec, withheld=("T9",))
    with pytest.raises(CassiInputError, match="withheld too"):
        next(get_version("cassi-1.0").animate_chunks(profile, face, rec, frames=None,
                                                     withheld=("T2", "T3")))


def test_chunks_with_a_pellet_withheld_equal_the_whole(inputs):
    profile, face, rec = inputs
    v = get_version("cassi-2.1")
    whole = next(v.animate_chunks(profile, face, rec, frames=None, withheld=("T3",)))
    parts = np.concatenate([a.positions for a in v.animate_chunks(profile, face, rec, frames=97,
                                                                  withheld=("T3",))])
    np.testing.assert_array_equal(parts, whole.positions)


def _rows(sites, rec, *, version="v"):
    ctx = LeaveOutContext(sites, rec)
    out = []
    for name in LEAVE:
        c = R.get_check(name)
        m = c.func(ctx)
        out.append(dict(subject="JW11", task=5, rep=1, version=version, view="geometry", frame=-1,
                        check=name, table="G", component="tongue", value=m.value, unit="mm",
                        threshold=c.threshold, negatives=c.grade(m.value), detail=m.detail))
    return pd.DataFrame(out)


def test_the_measures_rank_on_the_spot_above_offset_above_still(inputs):
    profile, face, rec = inputs
    frames = np.arange(rec.first_valid_index, rec.xy_mm.shape[0])
    on = {p: WithheldSite(p, frames, rec.xy_mm[frames, PELLET_INDEX[p]]) for p in ("T2", "T3")}
    off = {p: WithheldSite(p, frames, s.site_mm + [4.0, 0.0]) for p, s in on.items()}
    still = {p: WithheldSite(p, frames, np.repeat(s.site_mm[:1] + [0.0, -12.0], len(frames), 0))
             for p, s in on.items()}
    r = {k: _rows(s, rec).set_index("check") for k, s in (("on", on), ("off", off),
                                                          ("still", still))}
    assert (r["on"]["value"] < 1e-9).all() and (r["on"]["negatives"] == 0).all()
    assert r["off"]["value"].tolist() == pytest.approx([4.0, 4.0])
    assert (r["off"]["negatives"] == 1).all()
    assert (r["still"]["negatives"] == 2).all()
    assert "worst" in r["still"].loc["shape_tongue_t2", "detail"]


def test_t3_is_charged_with_t2_once(inputs):
    profile, face, rec = inputs
    frames = np.arange(rec.first_valid_index, rec.xy_mm.shape[0])
    still = {p: WithheldSite(p, frames, rec.xy_mm[frames, PELLET_INDEX[p]] + [0.0, 12.0])
             for p in ("T2", "T3")}
    rows = _rows(still, rec)
    assert (rows["negatives"] == 2).all()           # both fire ...
    g = component_ratings(rows)
    assert g["negatives"].tolist() == [2]           # ... one fault is charged


def test_a_version_without_the_withheld_keyword_is_said_not_measured(inputs):
    profile, face, rec = inputs

    class OnlyAnimate:
        name = "only-animate"

        def animate(self, profile, face, rec):  # pragma: no cover - never called
            raise AssertionError

    assert not accepts_withheld(OnlyAnimate())
    assert withheld_sites(OnlyAnimate(), profile, face, rec) == {}
    m = m_tongue_t2(LeaveOutContext({}, rec))
    assert np.isnan(m.value) and "cannot be animated with T2 withheld" in m.detail


def test_versions_on_the_synthetic_corpus(inputs):
    """The versions' tongues between the pellets, on JW11 task 5: Parke's still tongue is the
    worst by far; every CASSI site is within a centimetre (the software's behaviour on the
    generator's tongue, not a claim about speakers)."""
    profile, face, rec = inputs
    got = {}
    for name in ("parke-1974", "cassi-1.0", "cassi-2.1"):
        sites = withheld_sites(get_version(name), profile, face, rec)
        got[name] = _rows(sites, rec).set_index("check")["value"]
    assert (got["parke-1974"] > 3 * got["cassi-1.0"]).all()
    assert (got["cassi-1.0"] < 10.0).all()
    # 2.0 and 2.1 change the lips only: the same tongue as 1.0
    np.testing.assert_allclose(got["cassi-2.1"], got["cassi-1.0"], atol=1e-3)
