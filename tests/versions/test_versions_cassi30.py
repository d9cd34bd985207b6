"""CASSI 3.0, the plug-in version (plugins/cassi30): registered through the entry point and
built on public names only; a thick tongue kept behind the teeth and under the palate, smoothly;
back points that follow T3-T4 along PHA.DAT; a palate fitted above the upper incisor tip; chunked
animation equal to the whole. Tasks come from the embedded synthetic corpus (they describe the
software, not real speakers). Skips where the plug-in is not installed
(``pip install --no-deps -e plugins/cassi30``).
"""
from __future__ import annotations

import ast
import dataclasses
import importlib
from importlib.metadata import entry_points
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

cassi30 = pytest.importorskip("cassi30", reason="the cassi-3.0 plug-in is not installed")

from cassi.versions.mapping import subject_face  # noqa: E402
from cassi.data.face import numbering as N  # noqa: E402
from cassi.harness.evaluation.caches import get_corpus, get_face, get_profile  # noqa: E402
from cassi.harness.rubric import geometry as G  # noqa: E402
from cassi.versions.protocol import version_face  # noqa: E402
from cassi.versions.registry import get_version  # noqa: E402
from cassi30 import constants as K  # noqa: E402
from cassi30.collision import FrontTeeth, PalateHeights, soft_below  # noqa: E402
from cassi30.face import tongue_numbers, tongue_rows  # noqa: E402
from cassi30.shape import BACK_STATION, PELLET_STATIONS, STATIONS, back_points  # noqa: E402

C = len(K.SECTION_PHI)


@pytest.fixture(scope="module")
def corpus():
    return get_corpus(None)


@pytest.fixture(scope="module")
def version():
    return get_version("cassi-3.0")


def _inputs(corpus, subject, task):
    profile = get_profile(corpus, subject)
    return profile, get_face(corpus, subject, profile), corpus.subject(subject).load(task)


@pytest.fixture(scope="module")
def protrusion(corpus, version):
    """JW11 task 118: maximum lip, then tongue protrusion (the tongue leaves the mouth)."""
    profile, face, rec = _inputs(corpus, "JW11", 118)
    return version.animate(profile, face, rec), version_face(version, face), profile


@pytest.fixture(scope="module")
def sentence(corpus, version):
    """JW11 task 19 (sentences): the tongue touches the palate."""
    profile, face, rec = _inputs(corpus, "JW11", 19)
    return version.animate(profile, face, rec), version_face(version, face), profile, rec


# --- the extension path ------------------------------------------------------------------------

def test_registered_through_the_entry_point_group(version):
    eps = {ep.name: ep.value for ep in entry_points(group="cassi.versions")}
    assert eps.get("cassi-3.0") == "cassi30:Cassi30"
    assert type(version).__name__ == "Cassi30" and version.name == "cassi-3.0"


def test_the_plug_in_imports_only_public_names_of_cassi():
    """Every ``from cassi.X import name`` of the plug-in names a module or a name listed in the
    module's ``__all__`` (what a third party may rely on); no ``_private`` name anywhere."""
    root = Path(cassi30.__file__).parent
    for path in root.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("cassi."):
                module = importlib.import_module(node.module)
                for alias in node.names:
                    name = alias.name
                    assert not name.startswith("_"), (path.name, node.module, name)
                    public = getattr(module, "__all__", None)
                    is_module = importlib.util.find_spec(f"{node.module}.{name}") is not None \
                        if hasattr(module, "__path__") else False
                    assert is_module or public is None or name in public, \
                        f"{path.name}: {node.module}.{name} is not public"


def test_other_versions_animate_the_shared_face(corpus):
    profile, face, _ = _inputs(corpus, "JW45", 106)
    for name in ("parke-1974", "cassi-1.0", "cassi-2.0", "cassi-2.1"):
        assert version_face(get_version(name), face) is face


def test_a_face_hook_that_drops_vertices_is_refused(corpus):
    from cassi.common.errors import CassiInputError

    profile, face, _ = _inputs(corpus, "JW45", 106)

    class Bad:
        name = "bad"

        def animated_face(self, f):
            return dataclasses.replace(f, vertices=f.vertices[:-1], st1=f.st1[:-1],
                                       st2=f.st2[:-1])

    with pytest.raises(CassiInputError, match="keep their numbers"):
        version_face(Bad(), face)


# --- the face ----------------------------------------------------------------------------------

def test_the_face_keeps_the_shared_numbers_and_adds_a_closed_tongue(corpus, version):
    from cassi.data.face.topology import boundary_edges, render_topology

    profile, face, _ = _inputs(corpus, "JW16", 3)
    own = version_face(version, face)
    n = face.vertex_count
    assert own.vertex_count == n + STATIONS * C - len(N.TONGUE)
    assert version_face(version, own) is own                       # deriving twice: the same
    moved = set(N.TONGUE) | set(N.PALATE)
    same = [i for i in range(n) if i + 1 not in moved]
    np.testing.assert_array_equal(own.vertices[same], face.vertices[same])
    tongue = render_topology(own).parts["tongue"]
    assert len(boundary_edges(tongue.triangles)) == 0               # a closed body
    parts = G.mouth_parts(own)
    assert len(parts.tongue) == STATIONS * C
    # the rubric's centre line (T3, T4, back) is the tongue's
    np.testing.assert_array_equal(parts.tongue[3:6], np.asarray([N.T3, N.T4, N.TONGUE_BACK]) - 1)


def test_the_tongue_polygons_face_outward(corpus, version):
    """Parke's order is clockwise seen from outside: each polygon's right-hand normal points
    into the tongue (toward its station's centre line)."""
    profile, face, _ = _inputs(corpus, "JW16", 3)
    own = version_face(version, face)
    v = own.vertices
    body = []
    for poly in own.polygons_of("tongue"):
        p = v[np.asarray(poly.vertices) - 1]
        normal = np.cross(p[1] - p[0], p[2] - p[0])
        inward = v[np.asarray(N.TONGUE_CENTRE) - 1].mean(0) - p.mean(0)
        inward[1] = -p.mean(0)[1]          # toward the midsagittal plane as well
        body.append(np.dot(normal, inward) > 0)
    assert np.mean(body) > 0.9, np.mean(body)


def test_the_palate_never_reaches_below_the_incisor_tip(corpus, version):
    """Every subject of the corpus, and a planted outline that dips 3 mm below the tip."""
    from cassi.data.face.model import build_face

    faces = [get_face(corpus, s, get_profile(corpus, s)) for s in corpus.subjects[:6]]
    low = np.array([(-2.0, -3.0), (-6.0, 2.0), (-15.0, 14.0), (-30.0, 20.0), (-50.0, 19.0)])
    faces.append(subject_face(palate_mm=low))
    assert np.ptp(faces[-1].vertices[np.asarray(N.PALATE) - 1, 2]) > 0
    planted_below = faces[-1].vertices[N.UPPER_INCISOR_TIP - 1, 2] - \
        faces[-1].vertices[np.asarray(N.PALATE) - 1, 2].min()
    assert planted_below > 2.0 * N.UNITS_PER_MM                    # the fault is there
    for face in faces:
        own = version_face(version, face)
        lowest = own.vertices[np.asarray(N.PALATE) - 1, 2].min()
        tip = own.vertices[N.UPPER_INCISOR_TIP - 1, 2]
        # in the subject's millimetres (p / d, the scale the pellets are mapped by)
        assert face.units_per_mm == own.units_per_mm
        assert lowest >= tip + K.PALATE_ABOVE_INCISOR_MM * face.units_per_mm - 1e-9


# --- collisions --------------------------------------------------------------------------------

def test_the_tongue_stays_under_the_palate_with_its_margin(sentence):
    anim, face, profile, rec = sentence
    rows = tongue_rows(face.vertex_count)
    tris = np.asarray([(q[0], q[k], q[k + 1]) for q in (p.vertices for p in
                       face.polygons_of("palate")) for k in range(1, len(q) - 1)]) - 1
    pos = anim.positions.astype(np.float64)
    scale = 1.0 / G.mm_per_unit(face.vertices, profile.jaw_length_mm)
    heights = PalateHeights(pos[0], tris, K.PALATE_GRID_MM * scale)
    dorsum = rows.reshape(STATIONS, C)[:, :K.DORSUM_COLUMNS].ravel()
    p = pos[:, dorsum]
    room = heights(p[..., 0], p[..., 1]) - p[..., 2]
    # the data puts the tongue through the palate in this task; the margin is kept anyway
    # (float32 storage rounds by ~1e-5 units)
    assert room.min() >= K.COLLISION_MARGIN_MM * scale - 1e-3
    parts = G.mouth_parts(face)
    assert G.tongue_palate_penetration(pos, parts).max() == 0.0


def test_the_tongue_stays_behind_the_teeth_or_passes_between_them(protrusion):
    anim, face, profile = protrusion
    pos = anim.positions.astype(np.float64)
    parts = G.mouth_parts(face)
    depth = G.tongue_teeth_penetration(pos, parts, rest=face.vertices)
    mm = G.mm_per_unit(face.vertices, profile.jaw_length_mm)
    assert max(depth["upper"].max(), depth["lower"].max()) * mm < 0.05
    # the protruded tongue really leaves the mouth: T1 in front of the upper incisors, on its
    # pellet
    out = anim.diagnostics["tongue_protruded"].to_numpy()
    assert (pos[out, N.T1 - 1, 0] > pos[out, N.UPPER_INCISOR_TIP - 1, 0]).sum() > 50


def test_the_look_ahead_keeps_task_118_out_of_the_teeth_and_palate(protrusion):
    """JW11 task 118 with the way out capped by the time until the jaw's gap shuts: no tongue
    point through the teeth (the rubric's measure samples the edges) or the palate in any
    frame, and in every frame where the gap is shut the tongue is not released in front."""
    anim, face, profile = protrusion
    pos = anim.positions.astype(np.float64)
    parts = G.mouth_parts(face)
    depth = G.tongue_teeth_penetration(pos, parts, rest=face.vertices)
    mm = G.mm_per_unit(face.vertices, profile.jaw_length_mm)
    assert max(depth["upper"].max(), depth["lower"].max()) * mm < 0.05
    assert G.tongue_palate_penetration(pos, parts).max() == 0.0
    gap = pos[:, N.UPPER_INCISOR_TIP - 1, 2] - pos[:, N.LOWER_INCISOR_TIP - 1, 2]
    shut = gap <= 2.0 * K.COLLISION_MARGIN_MM / mm
    assert shut.any()
    assert anim.diagnostics["tongue_release_mm"].to_numpy()[shut].max() == 0.0


def test_no_edge_cuts_the_teeth_while_t2_is_near_them(corpus, version):
    """JW16 task 118: the tongue far out while T2 is only a few mm behind where it passes the
    teeth; the station between T1 and T2 must be placed there in full, or the edge to T2
    cuts the upper incisors (1.2 mm deep, in 200 frames, when its placement ramped over 8 mm
    of T2's distance instead of 3). The rubric's measure samples the edges."""
    profile, face, rec = _inputs(corpus, "JW16", 118)
    anim = version.animate(profile, face, rec)
    own = version_face(version, face)
    depth = G.tongue_teeth_penetration(anim.positions.astype(np.float64), G.mouth_parts(own),
                                       rest=own.vertices)
    mm = G.mm_per_unit(own.vertices, profile.jaw_length_mm)
    assert max(depth["upper"].max(), depth["lower"].max()) * mm < 0.05


def test_keep_out_holds_the_tongue_behind_the_teeth_or_in_their_gap():
    """One upper and one lower incisor quad (vertical, x = 10, y 0..8): upper tip at z 0, gum
    10; lower tip at z -6, gum -16. Margin 1: the gap is z in [-5, -1]."""
    v = np.zeros((8, 3))
    v[0:4] = [(10, 0, 0), (10, 8, 0), (10, 8, 10), (10, 0, 10)]           # upper tm td gd gm
    v[4:8] = [(10, 0, -6), (10, 8, -6), (10, 8, -16), (10, 0, -16)]      # lower
    teeth = FrontTeeth(np.array([[[0, 3], [1, 2]]]), np.array([[[4, 7], [5, 6]]]))
    p = np.array([[12.0, 2.0, 5.0],      # through the upper tooth
                  [20.0, 2.0, -3.0],     # in front of the gap
                  [11.0, 2.0, -9.0],     # through the lower tooth
                  [8.0, 2.0, 5.0],       # behind
                  [12.0, 20.0, 5.0]])    # beside the teeth
    pos = np.broadcast_to(v, (4, 8, 3))
    inside, turning, out, edging = teeth.keep_out(
        pos, np.stack([p, p, p, p]), 1.0, toward_gap=np.array([0.0, 0.5, 1.0, 1.0]),
        release=np.array([0.0, 0.0, 100.0, 0.5]))
    # in the mouth: everything in front of the teeth goes back, whatever its height
    np.testing.assert_allclose(inside[:3, 0], [9.0, 9.0, 9.0])
    np.testing.assert_allclose(inside[3:], p[3:])
    # turning toward the gap: half way there in z, still held behind the teeth in x
    np.testing.assert_allclose(turning[0], [9.0, 2.0, 2.0])
    np.testing.assert_allclose(turning[2], [9.0, 2.0, -7.0])
    # on its way out: what is in front of the teeth passes through the gap
    np.testing.assert_allclose(out[0], [12.0, 2.0, -1.0])
    np.testing.assert_allclose(out[1], p[1])
    np.testing.assert_allclose(out[2], [11.0, 2.0, -5.0])
    np.testing.assert_allclose(out[3:], p[3:])
    # ... only as far in front of the teeth as the release lets it
    np.testing.assert_allclose(edging[:3, 0], [9.5, 9.5, 9.5])


def test_keep_out_skips_only_points_no_wall_can_reach():
    """keep_out works only on the points in front of a lower bound of the walls
    (``_lowest_wall``); on random teeth and points the bound never exceeds a wall, and the
    result equals working on every point."""
    from cassi30.collision import _lowest_wall, _wall

    rng = np.random.default_rng(3)
    F, E = 40, 60
    pos = np.zeros((F, 12, 3))
    for q in range(3):                              # three quads, leaning, moving per frame
        y0, y1 = 8.0 * q, 8.0 * q + rng.uniform(3, 8)
        x = 30.0 - 6.0 * q + rng.normal(0, 1, (F, 1))
        tip = np.stack([x + rng.normal(0, 1, (F, 2)), np.broadcast_to([y0, y1], (F, 2)),
                        np.zeros((F, 2))], -1)
        gum = tip + np.array([1.5, 0.5, 10.0]) + rng.normal(0, 0.5, (F, 2, 3))
        pos[:, 4 * q:4 * q + 2], pos[:, 4 * q + 2:4 * q + 4] = tip, gum
    edges = np.array([[[4 * q, 4 * q + 2], [4 * q + 1, 4 * q + 3]] for q in range(3)])
    p = np.stack([rng.uniform(15, 40, (F, E)), rng.uniform(-30, 30, (F, E)),
                  rng.uniform(-5, 15, (F, E))], -1)
    y = np.abs(p[..., 1])
    fi, ei = np.nonzero(np.ones((F, E), bool))
    wall, _ = _wall(pos, edges, fi, y[fi, ei], p[fi, ei, 2], 0.8)
    bound = _lowest_wall(pos, edges, y, 0.8)[fi, ei]
    assert np.isfinite(wall).sum() > 100
    assert np.all(bound <= wall)
    assert (p[fi, ei, 0] <= bound - 0.8).sum() > 100          # some are skipped
    teeth = FrontTeeth(edges[:2], edges[2:])
    kw = dict(toward_gap=rng.uniform(0, 1, F), release=rng.uniform(0, 3, F))
    every = teeth._keep_out(pos, p[fi, ei].copy(), fi, 0.8, kw["toward_gap"][fi],
                            kw["release"][fi]).reshape(F, E, 3)
    np.testing.assert_array_equal(teeth.keep_out(pos, p.copy(), 0.8, **kw), every)


def test_slew_follows_at_the_rate_and_carries_over_chunks():
    from cassi30.version import slew

    t = np.arange(10) * 0.01
    target = np.array([0, 0, 1, 1, 1, 1, 0, 0, 0, 0], float)
    whole = slew(target, t, 25.0, {}, "k")                  # 0.25 per 10 ms
    np.testing.assert_allclose(whole, [0, 0, .25, .5, .75, 1, .75, .5, .25, 0], atol=1e-12)
    carried: dict = {}
    parts = [slew(target[a:a + 3], t[a:a + 3], 25.0, carried, "k") for a in range(0, 10, 3)]
    np.testing.assert_array_equal(np.concatenate(parts), whole)


def test_the_tongue_heads_out_and_back_without_jumps(protrusion, corpus, version):
    """The way out between the teeth is continuous: no vertex of the tongue moves more in a
    frame than 2.5 times the fastest pellet (T1-T4) of that task (4.9 mm against 2.5 mm when
    written; an on/off switch moved the front by 11.5 mm in a frame)."""
    anim, face, profile = protrusion
    rows = tongue_rows(face.vertex_count)
    pos = anim.positions.astype(np.float64)
    step = np.linalg.norm(np.diff(pos[:, rows], axis=0), axis=-1).max(axis=1)
    ctx = version.context(profile, face, corpus.subject("JW11").load(118))
    pellet = np.linalg.norm(np.diff(ctx.pellets[:, 2:6], axis=0), axis=-1).max(axis=1)
    assert anim.diagnostics["tongue_protruded"].sum() > 50
    assert step.max() < 2.5 * pellet.max()


def _turn_figures(corpus, version, subject):
    """Task 118 of ``subject`` while the front turns toward or back from the gap (gap weight
    strictly between 0 and 1): the tongue's largest step over the task's fastest pellet step,
    and its largest shake beyond its pellets' (mm)."""
    from cassi.harness.rubric.registry import JITTER_ORDER, JITTER_WINDOW

    profile, face, rec = _inputs(corpus, subject, 118)
    anim = version.animate(profile, face, rec)
    own = version_face(version, face)
    rows = tongue_rows(own.vertex_count)
    pos = anim.positions.astype(np.float64)
    w = np.asarray(anim.diagnostics["tongue_gap_weight"])
    turning = (w > 0.0) & (w < 1.0)
    step = np.linalg.norm(np.diff(pos[:, rows], axis=0), axis=-1).max(axis=1)
    pellet = np.linalg.norm(np.diff(version.context(profile, face, rec).pellets[:, 2:6], axis=0),
                            axis=-1).max()
    mm = G.mm_per_unit(face.vertices, profile.jaw_length_mm)
    shake = G.excess_jitter(pos, rows, np.asarray(N.TONGUE_PELLETS) - 1,
                            window=JITTER_WINDOW, order=JITTER_ORDER) * mm
    return turning.sum(), step[turning[1:]].max() / pellet, shake[turning].max()


@pytest.mark.parametrize("subject", ["JW16", "JW24"])
def test_the_front_turns_no_faster_than_the_tongue(corpus, version, subject, monkeypatch):
    """The turn toward the gap and back is as long as the farthest its front moves (TURN_MM,
    24 mm): no tongue vertex then steps more than 1.3 times the fastest pellet, and the tongue
    shakes no more than 2.1's worst beyond its pellets (1.09-1.20 and 0.67-1.01 mm with the
    way out settled; 1.34-1.38 and 0.87-0.95 mm before). The planted defect, the station's 12 mm
    alone: 1.33-1.45 and 0.97-1.25 mm settled; 1.81-1.94 and 1.35-1.80 mm before, in 4 frames
    (then the 19 shaking frames of the default set, issue 23 section 6)."""
    frames, ratio, shake = _turn_figures(corpus, version, subject)
    assert frames > 0 and ratio < 1.3 and shake < SHAKE_21_MM
    monkeypatch.setattr(K, "TURN_MM", 12.0)
    _, ratio_12, shake_12 = _turn_figures(corpus, version, subject)
    assert ratio_12 > 1.3 and shake_12 > shake


#: cassi-2.1's worst tongue shake beyond its pellets on the default set (tools/shake.py): 3.0's
#: may be no worse (issue 23 section 6).
SHAKE_21_MM = 1.11


def test_settle_rounds_a_ramps_corners_and_carries_over_chunks():
    from cassi30.version import settle, slew

    t = np.arange(60) / 145.6
    ramp = slew(np.r_[np.zeros(10), np.ones(50)], t, 10.0, {}, "k")
    out = settle(ramp, t, 0.015, {}, "k")
    assert out[0] == 0.0 and abs(out[-1] - 1.0) < 1e-3 and np.all(np.diff(out) >= 0.0)
    # the velocity changes by at most a fifth of the ramp's speed per frame, where the ramp's
    # own changes in one frame
    v_ramp, v = np.diff(ramp), np.diff(out)
    assert np.abs(np.diff(v_ramp)).max() == pytest.approx(v_ramp.max())
    assert np.abs(np.diff(v)).max() < v_ramp.max() / 5.0
    carried: dict = {}
    parts = [settle(ramp[a:a + 7], t[a:a + 7], 0.015, carried, "k") for a in range(0, 60, 7)]
    np.testing.assert_allclose(np.concatenate(parts), out, rtol=0, atol=1e-15)


def test_the_way_out_settles_where_it_reverses(corpus, version, monkeypatch):
    """JW18 task 4: T1 comes up to the incisors and turns back, so the way out climbs and falls
    at TONGUE_SPEED_MM_S; its corners rounded over SETTLE_S (4 x 15 ms, the jitter measure's
    9 frames) the tongue shakes 0.56 mm beyond its pellets at most, where the bare rate limit
    shook it by 1.25 mm (2.1's worst on the default set: 1.11 mm). On generator 6's JW18 the
    settled way out shakes 0.83 mm, the bare rate limit 0.94 mm: settling still takes the
    shake down, and below 2.1's worst, which is the promise."""
    from cassi.harness.rubric.registry import JITTER_ORDER, JITTER_WINDOW

    profile, face, rec = _inputs(corpus, "JW18", 4)
    own = version_face(version, face)
    rows = tongue_rows(own.vertex_count)
    mm = G.mm_per_unit(face.vertices, profile.jaw_length_mm)

    def worst():
        pos = version.animate(profile, face, rec).positions.astype(np.float64)
        return (G.excess_jitter(pos, rows, np.asarray(N.TONGUE_PELLETS) - 1,
                                window=JITTER_WINDOW, order=JITTER_ORDER) * mm).max()

    settled = worst()
    assert settled < SHAKE_21_MM
    monkeypatch.setattr(K, "SETTLE_S", 1e-9)
    assert worst() > settled + 0.05


def test_the_projection_is_smooth_in_time():
    """A coordinate swept through its bound at constant speed: the soft projection's largest
    second difference stays a small fraction of what a hard clamp's kink gives, so a smooth
    pellet track gives a smooth vertex track (no new jitter)."""
    t = np.linspace(-3.0, 3.0, 601)
    v = 2.0 * t                                   # mm, crossing the bound 0 at t = 0
    soft = soft_below(v, np.zeros_like(v), K.SOFTNESS_MM)
    hard = np.minimum(v, 0.0)
    assert np.all(soft <= 0.0) and np.all(np.diff(soft) >= 0)      # bounded, order kept
    assert np.abs(np.diff(soft, 2)).max() < 0.2 * np.abs(np.diff(hard, 2)).max()
    clear = v < -1.0
    np.testing.assert_allclose(soft[clear], v[clear], atol=1e-3)   # far from it: untouched


def test_no_new_jitter_where_the_tongue_touches_the_teeth(sentence, version):
    """JW11 task 19 (sentences) brings the tongue to the teeth and the jaw shut on it several
    times. The tongue's shake beyond its pellets' (the rubric's lip-jitter measure,
    ``excess_jitter``, on the tongue) stays under 2.5 mm in every frame and above 1 mm in few
    (0.5 mm at most, 0 frames, when written; the on/off switch before gave 3.9 mm and 17)."""
    from cassi.harness.rubric.registry import JITTER_ORDER, JITTER_WINDOW

    anim, face, profile, rec = sentence
    rows = tongue_rows(face.vertex_count)
    pos = anim.positions.astype(np.float64)
    mm = G.mm_per_unit(face.vertices, profile.jaw_length_mm)
    excess = G.excess_jitter(pos, rows, np.asarray(N.TONGUE_PELLETS) - 1,
                             window=JITTER_WINDOW, order=JITTER_ORDER) * mm
    assert excess.max() < 2.5 and (excess > 1.0).sum() <= 5


def test_pellet_sites_stay_on_the_pellets_unless_the_palate_is_in_the_way(sentence, version):
    """T3 and T4 (behind the teeth: only the palate bounds them): on their pellets (within
    5e-4 mm, constants.SOFTNESS_MM's promise) wherever the pellet is clear of the palate's
    margin by 1.5 mm, and never above it."""
    anim, face, profile, rec = sentence
    ctx = version.context(profile, face, rec)      # the mapped pellets
    scale = ctx.mapping.scale
    pos = anim.positions.astype(np.float64)
    tris = np.asarray([(q[0], q[k], q[k + 1]) for q in (p.vertices for p in
                       face.polygons_of("palate")) for k in range(1, len(q) - 1)]) - 1
    heights = PalateHeights(pos[0], tris, K.PALATE_GRID_MM * scale)
    for j, number in ((2, N.T3), (3, N.T4)):
        pellet = ctx.pellets[:, 2 + j]
        bound = heights(pellet[:, 0], np.zeros(len(pellet))) - K.COLLISION_MARGIN_MM * scale
        site = pos[:, number - 1][:, [0, 2]]
        # clear by 1.5 mm: the bound also holds halfway to the neighbouring stations, where
        # the palate may dip by up to about half a millimetre
        clear = bound - pellet[:, 1] > 1.5 * scale
        assert clear.sum() > 100
        shift = np.linalg.norm(site - pellet, axis=1) / scale
        assert shift[clear].max() < 5e-4
        assert np.all(site[:, 1] <= bound + 1e-3)


# --- the back of the tongue --------------------------------------------------------------------

def test_back_points_turn_from_t3_t4_toward_the_wall_and_move_with_the_tongue():
    t3, t4 = np.array([[0.0, 0.0], [5.0, 3.0]]), np.array([[-10.0, -2.0], [-5.0, 1.0]])
    wall = np.array([0.0, -1.0])
    b = back_points(t3, t4, wall, 8.0)
    assert b.shape == (2, K.BACK_POINTS, 2)
    np.testing.assert_allclose(b[1] - b[0], np.broadcast_to(t4[1] - t4[0], b[0].shape))
    steps = np.diff(np.concatenate([t4[:1, None], b[:1]], axis=1)[0], axis=0)
    u = (t4[0] - t3[0]) / np.hypot(*(t4[0] - t3[0]))
    cos_u = steps @ u / 8.0
    cos_w = steps @ wall / 8.0
    assert np.all(np.diff(cos_u) < 0) and np.all(np.diff(cos_w) > 0)   # turning toward the wall
    np.testing.assert_allclose(np.hypot(*steps.T), 8.0)


def test_back_points_follow_t3_t4_along_pha_without_a_v(sentence):
    anim, face, profile, rec = sentence
    pos = anim.positions.astype(np.float64)
    angle = G.profile_angle(pos, N.T3 - 1, N.T4 - 1, N.TONGUE_BACK - 1)
    assert angle.min() > 120.0                    # the rubric's V threshold, every frame
    # the back moves with T4 (not anchored) ...
    back = pos[:, N.TONGUE_BACK - 1, [0, 2]]
    t4 = pos[:, N.T4 - 1, [0, 2]]
    assert np.corrcoef(back[:, 1], t4[:, 1])[0, 1] > 0.8
    # ... and every back point stays in front of the pharyngeal wall
    from cassi.versions.mapping import XrmbToParke

    m = XrmbToParke.from_face(face.vertices, profile.jaw_length_mm)
    pha = m.to_parke(profile.pharynx_mm)
    order = np.argsort(pha[:, 1])
    rows = tongue_rows(face.vertex_count)
    centre_back = rows.reshape(STATIONS, C)[BACK_STATION:, 0]
    p = pos[:, centre_back]
    wall_x = np.interp(p[..., 2], pha[order, 1], pha[order, 0])
    assert (p[..., 0] - wall_x).min() >= (K.PHARYNX_CLEARANCE_MM - 0.1) * m.scale


def test_a_subject_without_pha_dat_is_refused(corpus, version):
    from cassi.common.errors import CassiInputError

    profile, face, rec = _inputs(corpus, "JW45", 106)
    with pytest.raises(CassiInputError, match="PHA.DAT"):
        version.animate(dataclasses.replace(profile, pharynx_mm=None), face, rec)


# --- chunks ------------------------------------------------------------------------------------

@pytest.mark.parametrize("frames", [97, 1000])
def test_chunks_equal_the_whole_task(corpus, version, frames):
    for subject, task in (("JW40", 5), ("JW45", 106)):
        profile, face, rec = _inputs(corpus, subject, task)
        whole = version.animate(profile, face, rec)
        chunks = list(version.animate_chunks(profile, face, rec, frames=frames))
        np.testing.assert_array_equal(np.concatenate([c.positions for c in chunks]),
                                      whole.positions)
        pd.testing.assert_frame_equal(
            pd.concat([c.diagnostics for c in chunks], ignore_index=True), whole.diagnostics)


def test_pellet_stations_are_the_pellet_vertices():
    numbers = tongue_numbers(570)
    assert tuple(numbers[list(PELLET_STATIONS), 0]) == N.TONGUE_PELLETS
    assert numbers[0, 0] == N.TONGUE_TIP and numbers[BACK_STATION, 0] == N.TONGUE_BACK


def test_the_rubric_on_streamed_chunks_equals_the_rubric_on_the_whole_task(corpus, version,
                                                                           tmp_path):
    """The geometry stage's path for 3.0 (positions streamed to a file, checks a chunk at a
    time, on the face the version animates) gives the same rows, exactly."""
    from cassi.harness.evaluation.caches import get_neutral
    from cassi.harness.evaluation.stages import animate_to_file
    from cassi.harness.rubric import run_geometry_checks

    profile, face, rec = _inputs(corpus, "JW40", 118)
    own = version_face(version, face)
    whole = version.animate(profile, face, rec)
    streamed = animate_to_file(version, profile, face, rec, tmp_path)
    streamed.positions.chunk = 97
    kw = dict(task=118, subject="JW40", rep=1, neutral=get_neutral(), recording=rec)
    pd.testing.assert_frame_equal(run_geometry_checks(whole, own, profile, **kw),
                                  run_geometry_checks(streamed, own, profile, **kw),
                                  check_exact=True)
