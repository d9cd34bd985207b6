"""The generated face: numbering as the thesis names it, a closed outward-facing skin where
Parke's is closed, the render topology, the palate, and the files round-trip."""
from __future__ import annotations

import numpy as np
import pytest

from cassi.versions.mapping import subject_face
from cassi.data.face import numbering as N
from cassi.common.errors import CassiInputError
from cassi.data.face.model import FaceModel, build_face
from cassi.data.face.build import (CENTRE, EYEBALL_RADIUS, EYELID_RADIUS, PARKE_EXCERPT,
                                   arch_points)
from cassi.data.face.topology import (boundary_loops, inconsistent_edges, nonmanifold_edges,
                                 render_topology, signed_volume)


@pytest.fixture(scope="module")
def face():
    return build_face()


@pytest.fixture(scope="module")
def topo(face):
    return render_topology(face)


def v(face, n):
    return face.vertices[n - 1]


# --- numbering ---------------------------------------------------------------------------------

def test_every_vertex_defined_and_counts(face):
    assert face.vertex_count == N.EYES_FIRST - 1 + 2 * 105
    assert np.isfinite(face.vertices).all()
    assert N.PALATE_FIRST == 301 and N.PALATE_COUNT == N.PALATE_STATIONS * N.PALATE_ACROSS
    used = {n for p in face.polygons for n in p.vertices}
    # every vertex but the jaw pivot (a point, not a surface) belongs to some polygon
    assert set(range(1, face.vertex_count + 1)) - used == {N.JAW_PIVOT}


def test_parke_excerpt_vertices_kept(face):
    for n, xyz in PARKE_EXCERPT.items():
        np.testing.assert_array_equal(v(face, n), xyz)
    assert v(face, 1)[2] == -594


def test_centre_lines(face):
    for n in N.LOWER_LIP_CENTRE + N.UPPER_LIP_CENTRE + (N.TEETH_TIP, N.MANI) + \
            N.TONGUE_CENTRE + N.PALATE_CENTRE + (N.MENTON, N.POGONION, N.SUBNASALE):
        assert v(face, n)[1] == 0.0, n
    for rows in (N.UPPER_LIP_ROWS, N.LOWER_LIP_ROWS):
        for row in rows:
            ys = [v(face, n)[1] for n in row]
            assert ys[0] == 0 and ys[0] < ys[1] < ys[2], row


def test_lip_order_top_to_bottom(face):
    z = [v(face, n)[2] for n in N.LIP_CENTRE_TOP_TO_BOTTOM]
    assert z == sorted(z, reverse=True)       # 67 at the top ... 49 at the bottom
    # UL and LL pellet vertices on the outer edges, in front of the teeth
    assert v(face, N.UL)[0] > v(face, N.TEETH_TIP)[0] + 20
    assert v(face, N.LL)[0] > v(face, N.MANI)[0] + 20
    # the corner is the widest point of the lips; the corners' order outer-middle-inner
    lips = np.asarray(N.UPPER_LIP + N.LOWER_LIP) - 1
    assert v(face, N.CORNER)[1] > face.vertices[lips, 1].max()
    assert v(face, N.CORNER)[0] > v(face, N.CORNER_MIDDLE)[0] > v(face, N.INNER_CORNER)[0]
    # above the lip / below the lip follow the centre-to-corner columns
    for row in (N.ABOVE_LIP, N.BELOW_LIP):
        assert v(face, row[0])[1] == 0 and v(face, row[1])[1] < v(face, row[2])[1]
    assert all(v(face, n)[2] > v(face, N.UL)[2] for n in N.ABOVE_LIP)
    assert all(v(face, n)[2] < v(face, N.LL)[2] for n in N.BELOW_LIP)


def test_teeth(face):
    tip = v(face, N.TEETH_TIP)
    upper = face.vertices[np.asarray(N.UPPER_TEETH) - 1]
    # 226: the bottom of the top front teeth: front-most and lowest of the front teeth
    assert tip[0] == upper[:, 0].max()
    assert tip[2] <= upper[upper[:, 0] > tip[0] - 30, 2].min() + 1e-9
    # MANi 258 on the lower incisor's outer surface at the gum line, below 226
    mani = v(face, N.MANI)
    assert mani[2] < tip[2] and abs(mani[0] - tip[0]) < 20
    lower_tip = v(face, N.LOWER_INCISOR_TIP)
    assert lower_tip[2] > mani[2] and lower_tip[2] > tip[2]      # overbite
    # MANm site: about 35 mm behind MANi (XRMB jaw lengths are ~30-40 mm)
    assert 30 < face.jaw_length * N.MM_PER_UNIT < 40
    mm = 0.5 * (v(face, 281) + v(face, 286))
    assert mm[0] < mani[0] - 100 and mm[1] > 50
    teeth = [p for p in face.polygons if face.material_name(p.material) == "teeth"]
    assert len(teeth) == 16 and all(len(p.vertices) == 4 for p in teeth)
    assert sorted(n for p in teeth for n in p.vertices) == list(N.TEETH)


def test_tongue_flat_inside_lower_arch(face):
    t = face.vertices[np.asarray(N.TONGUE) - 1]
    assert np.ptp(t[:, 2]) == 0.0                     # flat: no width in z (4.1.1)
    xs = [v(face, n)[0] for n in N.TONGUE_CENTRE]
    assert xs == sorted(xs, reverse=True)            # tip, T1..T4, back: front to back
    # T1 about 10 mm behind the tip (thesis 3.2.3)
    assert abs((xs[0] - xs[1]) * N.MM_PER_UNIT - 10) < 1
    pts, _ = arch_points("lower")
    order = np.argsort(pts[:, 0])
    for n in N.TONGUE_EDGE:
        x, y, _ = v(face, n)
        if x >= pts[:, 0].min():
            assert y < np.interp(x, pts[order, 0], pts[order, 1]), n
    tongue = face.polygons_of("tongue")
    assert sorted({n for p in tongue for n in p.vertices}) == list(N.TONGUE)


def test_jaw_zones_as_data():
    parke = {z: f for z, f, _, _ in N.PARKE_JAW_ZONES}
    assert parke == {"1st": 1.0, "2nd": 0.9, "3rd": 0.75, "4th": 0.5, "5th": 0.35}
    cassi = dict((z, f) for z, f, _, _ in N.CASSI10_JAW_ZONES)
    for z in parke:
        assert cassi[z] == pytest.approx(parke[z] * 1.11111, abs=1e-6)
    first = next(vs for z, _, vs, _ in N.CASSI10_JAW_ZONES if z == "1st")
    assert 22 not in first and 30 not in first and len(first) == 28
    assert all(ax == "z" for z, _, vs, ax in N.PARKE_JAW_ZONES if 6 in vs or 11 in vs)


def test_jaw_and_cheek_regions(face):
    jaw = face.vertices[np.asarray(N.JAW) - 1]
    assert (jaw[:, 2] < v(face, N.LL)[2] + 60).all()   # the jaw is below the mouth
    # 22 and 30 at the back of the jaw: among the rearmost jaw vertices
    back = np.asarray(N.JAW)[np.argsort(jaw[:, 0])[:5]]
    assert 22 in back and 30 in back
    pivot = v(face, N.JAW_PIVOT)
    assert pivot[0] < jaw[:, 0].min() + 120 and pivot[2] > jaw[:, 2].max()
    cheek = face.vertices[np.asarray(N.LOWER_CHEEK) - 1]
    assert (cheek[:, 1] > v(face, N.CORNER)[1] * 0.9).all()
    nose = face.vertices[np.asarray(N.NOSE) - 1]
    assert v(face, N.NOSE_TIP_CENTRE)[0] == nose[:, 0].max()
    assert v(face, N.SUBNASALE)[2] > v(face, N.UL)[2]
    # gnathion between pogonion and menton on the centre line; gonion at the jaw's angle
    g = v(face, N.GNATHION)
    assert g[1] == 0 and v(face, N.MENTON)[2] < g[2] < v(face, N.POGONION)[2]
    assert N.GONION in N.JAW and v(face, N.GONION)[0] < v(face, N.MENTON)[0] - 200


def test_jaw_angle_and_occlusal_plane_anatomical(face):
    """The neutral jaw is a real jaw's shape, so CASSI 1.0's initialisation turns the chin and
    the teeth only a few degrees onto a subject's head measures and jaw pellets: the gonion
    ~80-90 mm behind the upper incisor tip and above the gnathion (mandibular plane rising
    15-25 degrees backward), the gnathion low on the chin, and the MANm site 2-3 mm below MANi
    (the XRMB pellets' MNM below MNI) with the upper teeth over the lower ones front and back."""
    tip = v(face, N.TEETH_TIP)
    go, gn = v(face, N.GONION), v(face, N.GNATHION)
    assert 320 <= tip[0] - go[0] <= 360
    plane = np.degrees(np.arctan2(go[2] - gn[2], gn[0] - go[0]))
    assert 15 <= plane <= 25, plane
    assert 36 <= (tip[2] - gn[2]) * N.MM_PER_UNIT <= 45
    # the jaw angle's neighbours on the jaw line sit back there too (the ramus pair 22 / 30)
    assert abs(v(face, 30)[0] - go[0]) < 20 and v(face, 30)[2] > go[2]
    mani = v(face, N.MANI)
    manm = 0.5 * (v(face, N.MANM_PAIR[0]) + v(face, N.MANM_PAIR[1]))
    assert 2.0 <= (mani[2] - manm[2]) * N.MM_PER_UNIT <= 3.0
    slope = np.degrees(np.arctan2(mani[2] - manm[2], mani[0] - manm[0]))
    assert 2 <= slope <= 6, slope
    for k in (0, N.TEETH_PER_SET - 1):   # front and back: the upper tips below the lower tips
        up = face.vertices[np.asarray(N.upper_tooth(k)[2:]) - 1, 2]
        lo = face.vertices[np.asarray(N.lower_tooth(k)[:2]) - 1, 2]
        assert 0 < lo.min() - up.max() <= 12, k


# --- the mesh ----------------------------------------------------------------------------------

def _shell(topo, face):
    verts, tri, part = topo.mesh(face.vertices)
    names = list(topo.parts)
    shell = np.isin(part, [names.index(p) for p in ("skin", "lips", "eyelash", "eyebrow")
                           if p in names])
    return verts, tri[shell]


def test_skin_closed_except_neck_mouth_eyes(face, topo):
    verts, tri = _shell(topo, face)
    assert len(nonmanifold_edges(tri)) == 0
    assert len(inconsistent_edges(tri)) == 0
    loops = boundary_loops(tri)
    centres = sorted((verts[loop].mean(axis=0).tolist() for loop in loops), key=lambda c: c[2])
    assert len(loops) == 4, [len(loop) for loop in loops]
    neck, mouth, eye1, eye2 = centres
    assert neck[2] < -450                                 # the base of the neck
    assert abs(mouth[2] - v(face, N.TEETH_TIP)[2]) < 20 and abs(mouth[1]) < 1e-6
    assert {np.sign(eye1[1]), np.sign(eye2[1])} == {-1.0, 1.0}
    # the mouth opening is bounded by the inner lip outline and inner corners
    mouth_loop = next(lp for lp in loops if abs(verts[lp].mean(axis=0)[2] - mouth[2]) < 1e-9)
    assert len(mouth_loop) == 2 * 2 * len(N.UPPER_INNER) - 2 + 2


def test_skin_normals_face_outward(face, topo):
    verts, tri = _shell(topo, face)
    assert signed_volume(verts, tri) > 0
    # the skin is star-shaped about CENTRE: every skin triangle faces away from it, except the
    # eyelids' inner lip (which touches the eyeball and faces it)
    verts, tri, part = topo.mesh(face.vertices)
    skin = tri[part == list(topo.parts).index("skin")]
    p = verts[skin]
    d_eye = np.min([np.linalg.norm(p - c * np.array([1, s, 1]), axis=2)
                    for c in face.eye_centres[:1] for s in (1, -1)], axis=0)
    lid_lip = (d_eye < 0.5 * (EYEBALL_RADIUS + EYELID_RADIUS)).any(axis=1)
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    c = p.mean(axis=1) - CENTRE
    out = np.einsum("ij,ij->i", n, c) > 0
    assert out[~lid_lip].all(), np.round(p[~lid_lip & ~out].mean(axis=1))
    assert lid_lip.sum() < 40


def test_closed_parts(face, topo):
    verts, tri, part = topo.mesh(face.vertices)
    names = list(topo.parts)
    eye = np.isin(part, [names.index(p) for p in ("eye_white", "iris", "fringe", "pupil")])
    assert len(boundary_loops(tri[eye])) == 0               # eyeballs are closed
    assert signed_volume(verts, tri[eye]) > 0
    parts = topo.expand(face.vertices)

    def normals(name):
        p = parts[name][topo.parts[name].triangles].astype(float)
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        return p.mean(axis=1), n / np.linalg.norm(n, axis=1, keepdims=True)

    # teeth face out of the dental arch (labial/buccal faces), the tongue up, the palate down
    arch_centre = np.array([v(face, N.TEETH_TIP)[0] - 150.0, 0.0])
    for name in ("teeth_upper", "teeth_lower"):
        c, n = normals(name)
        assert (np.einsum("ij,ij->i", n[:, :2], c[:, :2] - arch_centre) > 0).all(), name
    assert (normals("tongue")[1][:, 2] > 0.99).all()
    assert (normals("palate")[1][:, 2] < 0).all()


def test_expand_mirrors(face, topo):
    parts = topo.expand(face.vertices)
    assert set(parts) == set(topo.parts)
    for name, arr in parts.items():
        assert arr.dtype == np.float32 and arr.shape == (len(topo.parts[name].gather), 3)
        tri = topo.parts[name].triangles
        assert tri.min() >= 0 and tri.max() < len(arr)
    skin = parts["skin"]
    # mirrored: for every left vertex off the centre line a right copy exists
    ys = np.sort(skin[:, 1])
    np.testing.assert_allclose(ys, -ys[::-1], atol=1e-4)
    # moving a vertex moves both copies
    moved = face.vertices.copy()
    moved[N.CHEEK_BY_CORNER - 1, 0] += 10.0
    skin2 = topo.expand(moved)["skin"]
    assert int((np.abs(skin2 - skin).sum(axis=1) > 1e-3).sum()) == 2


def test_half_topology(face):
    half = render_topology(face, half=True)
    assert half.half
    parts = half.expand(face.vertices)
    assert all((arr[:, 1] >= -1e-6).all() for arr in parts.values())
    full = render_topology(face)
    assert len(half.parts["skin"].triangles) * 2 == len(full.parts["skin"].triangles)
    # one eye only
    assert len(half.parts["pupil"].triangles) * 2 == len(full.parts["pupil"].triangles)
    # open at the cut: the boundary runs along y = 0
    verts, tri, part = half.mesh(face.vertices)
    skin = tri[part == list(half.parts).index("skin")]
    loops = boundary_loops(skin)
    on_cut = np.abs(verts[np.unique(np.concatenate(loops)), 1]) < 1e-6
    assert on_cut.sum() > 20


@pytest.mark.parametrize("half", [False, True])
def test_teeth_split_into_upper_and_lower(face, half):
    """The face's one teeth material renders as two parts: every teeth triangle lies in exactly
    one of ``teeth_upper`` (Parke's 223-254, with the incisor tip 226) and ``teeth_lower``
    (255-286, with MANi 258 and the MANm pair 281/286), and only the lower part follows the jaw."""
    from cassi.data.face.topology import PARTS
    t = render_topology(face, half=half)
    assert "teeth" not in t.parts
    assert {"teeth_upper", "teeth_lower"} <= set(t.parts)
    assert list(t.parts) == [p for p in PARTS if p in t.parts]

    def face_triangles(name):
        """The part's triangles as sets of (face vertex number, side)."""
        part = t.parts[name]
        key = [(int(g) + 1, float(s)) for g, s in zip(part.gather, part.sign)]
        return [frozenset(key[i] for i in tri) for tri in part.triangles.tolist()]

    upper, lower = face_triangles("teeth_upper"), face_triangles("teeth_lower")
    up_vs = {n for tri in upper for n, _ in tri}
    lo_vs = {n for tri in lower for n, _ in tri}
    assert up_vs == set(N.UPPER_TEETH) and lo_vs == set(N.LOWER_TEETH)
    assert N.UPPER_INCISOR_TIP in up_vs and N.UPPER_INCISOR_TIP not in lo_vs
    assert {N.MANI, *N.MANM_PAIR} <= lo_vs and not {N.MANI, *N.MANM_PAIR} & up_vs
    # every teeth triangle in exactly one part: the two parts together are the triangulated
    # teeth polygons (each side once), with no triangle in both
    assert not set(upper) & set(lower)
    teeth_polys = [p for p in face.polygons if face.material_name(p.material) == "teeth"]
    sides = (1.0,) if half else (1.0, -1.0)
    assert len(upper) + len(lower) == 2 * len(teeth_polys) * len(sides)
    assert len(set(upper) | set(lower)) == len(upper) + len(lower)
    for p in teeth_polys:
        mine, other = (upper, lower) if max(p.vertices) <= N.UPPER_TEETH_LAST else (lower, upper)
        inside = lambda tris: sum({n for n, _ in tri} <= set(p.vertices) for tri in tris)  # noqa: E731
        assert (inside(mine), inside(other)) == (2 * len(sides), 0), p.vertices
    # the jaw moves only the lower part
    moved = face.vertices.copy()
    moved[np.asarray(N.LOWER_TEETH) - 1, 2] -= 20.0
    a, b = t.expand(face.vertices), t.expand(moved)
    np.testing.assert_array_equal(a["teeth_upper"], b["teeth_upper"])
    assert (b["teeth_lower"][:, 2] < a["teeth_lower"][:, 2]).all()
    if half:
        assert all((arr[:, 1] >= -1e-6).all() for arr in b.values())


# --- palate ------------------------------------------------------------------------------------

def test_palate_fixed_count_and_shape(face):
    pal1 = face.vertices[np.asarray(N.PALATE) - 1]
    short = np.array([(-4.0, 8.0), (-20.0, 20.0), (-45.0, 22.0)])
    long = np.column_stack([np.linspace(-3, -55, 40), 10 + 12 * np.sin(np.linspace(0, 2.5, 40))])
    for outline in (short, long):
        f = subject_face(palate_mm=outline)
        assert f.vertex_count == face.vertex_count
        pal = f.vertices[np.asarray(N.PALATE) - 1].reshape(N.PALATE_STATIONS, N.PALATE_ACROSS, 3)
        width = pal[:, -1, 1]
        assert width[-1] > width[0] * 1.5                    # narrow in front, wider behind
        assert (pal[:, 1:, 2] <= pal[:, :-1, 2] + 1e-9).all()  # slopes down to the edges
        assert (np.diff(pal[:, 0, 0]) < 0).all()             # stations front to back
        # the centre line follows PAL.DAT mapped to 226 at 4 units/mm
        front = f.vertex(N.TEETH_TIP)[[0, 2]] + outline[0] * N.UNITS_PER_MM
        np.testing.assert_allclose(pal[0, 0, [0, 2]], front, atol=1e-6)
    assert not np.allclose(pal1.reshape(pal.shape), pal)


def test_palate_scale_from_jaw_length():
    outline = np.array([(-5.0, 8.0), (-40.0, 20.0)])
    f = subject_face(palate_mm=outline, jaw_length_mm=70.0)
    pal = f.vertex(N.PALATE_FIRST)
    scale = f.jaw_length / 70.0                              # p / d
    np.testing.assert_allclose(pal[[0, 2]], f.vertex(N.TEETH_TIP)[[0, 2]] + outline[0] * scale)


def test_palate_given_back_to_front():
    outline = np.array([(-5.0, 8.0), (-25.0, 21.0), (-50.0, 20.0)])
    a = subject_face(palate_mm=outline).vertices[np.asarray(N.PALATE) - 1]
    b = subject_face(palate_mm=outline[::-1]).vertices[np.asarray(N.PALATE) - 1]
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("bad", [np.zeros((1, 2)), np.full((3, 2), np.nan), np.zeros((3, 3)),
                                 np.zeros((4, 2))])
def test_bad_palate(bad):
    with pytest.raises(CassiInputError):
        subject_face(palate_mm=bad)


# --- files -------------------------------------------------------------------------------------

def test_face_files_round_trip(face, tmp_path):
    paths = face.write(tmp_path)
    assert paths["st1"].read_text().splitlines()[1] == f"{face.vertex_count} {face.vertex_count}"
    back = FaceModel.read(paths["st1"], paths["top"], paths["st2"])
    np.testing.assert_array_equal(back.st1, face.st1)
    np.testing.assert_array_equal(back.st2, face.st2)
    assert back.polygons == face.polygons
    np.testing.assert_allclose(back.eye_centres, face.eye_centres, atol=1e-6)
    assert back.regions == face.regions
    from cassi.data.face.params import apply_parameters
    np.testing.assert_array_equal(apply_parameters(back, {1: 0.3, 4: 10}).vertices,
                                  apply_parameters(face, {1: 0.3, 4: 10}).vertices)
    paths["meta"].write_text("{not json")
    with pytest.raises(CassiInputError):
        FaceModel.read(paths["st1"], paths["top"], paths["st2"])


def test_a_subject_face_keeps_its_scale_in_its_files(tmp_path):
    """The sidecar keeps the jaw length, so a written subject face reads back at its own scale;
    a jaw length that is not a positive number is refused naming the sidecar."""
    import json
    face = subject_face(jaw_length_mm=71.5)
    paths = face.write(tmp_path)
    back = FaceModel.read(paths["st1"], paths["top"], paths["st2"])
    assert back.jaw_length_mm == 71.5 and back.units_per_mm == pytest.approx(face.units_per_mm)
    meta = json.loads(paths["meta"].read_text())
    for bad in (-3, "70", True, float("nan")):
        paths["meta"].write_text(json.dumps({**meta, "jaw_length_mm": bad}))
        with pytest.raises(CassiInputError, match="jaw_length_mm") as info:
            FaceModel.read(paths["st1"], paths["top"], paths["st2"])
        assert info.value.path == str(paths["meta"])


def test_parke_sized_files_load(tmp_path):
    """A Parke-sized model (287 vertices, some undefined, no eyes) loads and renders."""
    verts = np.full((287, 3), np.nan)
    for n, xyz in PARKE_EXCERPT.items():
        verts[n - 1] = xyz
    from cassi.data.xrmb.parke_io import Polygon, write_pts, write_top
    write_pts(tmp_path / "st1.pts", verts, "st1.pts - first vertices set FIP 10 May 90")
    write_top(tmp_path / "stt.top", [Polygon(1, (1, 6, 7, 2)), Polygon(1, (7, 8, 2)),
                                     Polygon(1, (2, 8, 3))], "stt.top - simple face")
    f = FaceModel.read(tmp_path / "st1.pts", tmp_path / "stt.top")
    assert f.vertex_count == 287 and f.eyes_first is None
    t = render_topology(f)
    assert len(t.parts["skin"].triangles) == 2 * 4
    write_top(tmp_path / "bad.top", [Polygon(1, (1, 6, 40))])
    with pytest.raises(CassiInputError):
        FaceModel.read(tmp_path / "st1.pts", tmp_path / "bad.top")


def test_default_palate_is_the_typical_outline_at_the_models_own_scale():
    """The generator places its typical palate as the one mapping would at 4 units/mm."""
    from cassi.data.face.mouth import DEFAULT_PALATE_MM, DEFAULT_PALATE_XZ
    from cassi.versions.mapping import XrmbToParke

    v226 = build_face().vertex(N.TEETH_TIP)[[0, 2]]
    m = XrmbToParke(scale=N.UNITS_PER_MM, origin=v226)
    np.testing.assert_array_equal(m.to_parke(DEFAULT_PALATE_MM), DEFAULT_PALATE_XZ)
