"""The rubric's acceptance test: every geometric check fires on a planted defect, stays silent on
the clean case, and a larger planted defect never earns fewer negatives.

The mouth is the synthetic one of ``rubric_synth`` (1 unit = 1 mm): upper front teeth front
surface at x = 0 (tip z = 0), lower front teeth at x = -1 (tip z = 1), lips in front, tongue
behind, palate at z = 10. Each planter takes a magnitude (mm, degrees or a fraction, as its
check's unit says) and returns the animation with that defect planted.
"""
from __future__ import annotations

import numpy as np
import pytest

import rubric_synth as S
from cassi.harness import rubric as R
from cassi.harness.rubric.measures import GeometryContext
from cassi.harness.rubric.registry import TEETH_HOLD_FRAMES
from cassi.harness.rubric import geometry as G

M = S.build()
P = M.parts
N = M.names


class _Face:
    vertices = M.rest


def _base(task):
    if task == 118:
        return S.protrude(M, S.animate(M, open_rad=0.03))
    if task == 106:
        return S.round_opening(M, S.animate(M, open_rad=0.2))
    return S.animate(M)


BASE = {t: _base(t) for t in (5, 106, 118)}


def run(anim, task, checks=None):
    df = R.run_geometry_checks(anim, _Face, None, task=task, parts=P, mm_per_unit=1.0,
                               neutral=M.rest, subject="SYN", checks=checks)
    return df[df["frame"] == -1].set_index("check")


def lower_teeth():
    return np.unique(np.concatenate([P.lower_teeth_tris.ravel(),
                                     [P.lower_incisor_tip, P.lower_gum, P.lower_molar]]))


# --- planters: (anim, magnitude) -> anim --------------------------------------------------------

def p_front_overlap(a, d):
    a.positions[:, lower_teeth(), 2] += d
    return a


def p_back_overlap(a, d):
    a.positions[:, P.lower_molar, 2] += d
    return a


def _tilt_lower(a, deg):
    v = lower_teeth()
    pivot = a.positions[:, P.lower_molar][:, None, :]
    d = a.positions[:, v] - pivot
    t = np.radians(deg)
    x = d[..., 0] * np.cos(t) - d[..., 2] * np.sin(t)
    z = d[..., 0] * np.sin(t) + d[..., 2] * np.cos(t)
    a.positions[:, v, 0] = pivot[..., 0] + x
    a.positions[:, v, 2] = pivot[..., 2] + z
    return a


def p_slope_up(a, deg):
    return _tilt_lower(a, deg)


def p_slope_down(a, deg):
    return _tilt_lower(a, -deg)


def p_teeth_apart(a, d):
    a.positions[:, lower_teeth(), 2] -= d
    return a


def p_open_lips(a, d):
    a.positions[:, M.lower_lip, 2] -= d
    return a


def p_open_at_start(a, d):
    a.positions[:6, M.lower_lip, 2] -= d
    return a


def p_pressed(a, d):
    a.positions[:4, M.lower_lip, 2] += d
    return a


def p_lower_lip_below(a, frac):
    n = int(round(frac * a.positions.shape[0]))
    a.positions[:n, M.lower_lip, 2] -= 9.0
    return a


def p_lip_through_teeth(a, d):
    # the upper lip's inner edge pushed back through the upper front teeth's front surface (x=0)
    for k in ("61", "62"):
        a.positions[20:40, N[k], 0] = -d
    return a


def p_lower_protrudes(a, d):
    a.positions[:, P.ll_outer, 0] += d
    return a


def p_lips_cross(a, d):
    a.positions[95:106, P.ll_inner, 2] += d
    return a


def p_handled_cross(a, d):
    a = p_lips_cross(a, 1.5)
    a.diagnostics["lips_overlap"] = False
    a.diagnostics.loc[95:105, "lips_overlap"] = True
    # lips grown by d (fraction) in height while they cross
    outer = np.concatenate([P.upper_outer, P.lower_outer, [P.corner]])
    a.positions[95:106, outer, 2] *= 1 + d
    return a


def p_tongue_lower(a, d):
    # tongue tip through the back surface (x=-3) of the lower front teeth by d
    lt = M.rest[P.lower_incisor_tip]
    a.positions[:, P.tongue[0]] = S.on_jaw(M, a, (lt[0] - 2.0 + d, 0.0, lt[2] - 3.0), open_rad=0.10)
    return a


def p_tongue_both(a, d):
    a = p_tongue_lower(a, d)
    t2 = P.tongue[2]
    a.positions[:, t2] = (-2.0 + d, 0.0, 3.0)  # through the upper front teeth's back (x=-2)
    return a


def p_tongue_palate(a, d):
    a.positions[:, P.tongue[3], 2] = 10.0 + d
    return a


def p_palate_low(a, d):
    front = P.palate[a.positions[0, P.palate, 0] > -5]
    a.positions[:, front, 2] = -d
    return a


def _scale_jaw(a, sx, sz):
    """The jaw scaled about the tip of the upper front teeth, which stays with the head."""
    j = P.jaw
    c = a.positions[:, P.upper_incisor_tip][:, None, :]
    a.positions[:, j, 0] = c[..., 0] + (a.positions[:, j, 0] - c[..., 0]) * sx
    a.positions[:, j, 2] = c[..., 2] + (a.positions[:, j, 2] - c[..., 2]) * sz
    return a


def p_jaw_long(a, s):
    return _scale_jaw(a, 1.0, 1 + s)


def p_jaw_large(a, s):
    return _scale_jaw(a, 1 + s, 1 + s)


def p_jaw_square(a, s):
    # move the jaw points a fraction s of the way to their bounding box's nearest corner
    j = P.jaw
    p = a.positions[:, j][:, :, [0, 2]]
    lo, hi = p.min(axis=1, keepdims=True), p.max(axis=1, keepdims=True)
    corner = np.where(p - lo < hi - p, lo, hi)
    p = p + s * (corner - p)
    a.positions[:, j, 0], a.positions[:, j, 2] = p[..., 0], p[..., 1]
    return a


def p_no_rounding(a, s):
    # s = how much of the rounding is lost (1 = corners stay where they started)
    r = S.protrude(M, S.animate(M, open_rad=0.03), round_to=0.75 + 0.25 * s)
    a.positions[:] = r.positions
    return a


def p_stick_out(a, d):
    r = S.protrude(M, S.animate(M, open_rad=0.03), forward=5.0 + d)
    a.positions[:] = r.positions
    return a


def _w(a):
    F = a.positions.shape[0]
    return np.sin(np.pi * np.arange(F) / (F - 1)) ** 2


def p_above_cave(a, d):
    a.positions[:, P.above_lip[0], 0] -= d * _w(a)
    return a


def p_into_nose(a, k):
    # the upper lip's edge moved a fraction k of the way to the nose base
    ul, sn = a.positions[:, P.ul_outer], a.positions[:, P.subnasale]
    a.positions[:, P.ul_outer] = ul + k * (sn - ul)
    return a


def p_too_big(a, s):
    outer = np.concatenate([P.upper_outer, P.lower_outer, [P.corner]])
    a.positions[:, outer, 2] *= 1 + s
    return a


def p_lower_protrudes_start(a, d):
    a.positions[:3, P.ll_outer, 0] += d
    return a


def p_upper_more(a, d):
    a.positions[:, P.ul_outer, 0] += d
    return a


def p_sharp(a, d):
    a.positions[:, P.ul_outer, 0] += d * _w(a)
    return a


def p_jitter(a, d):
    sign = (-1.0) ** np.arange(40, 80)
    a.positions[40:80, P.corner, 1] += d * sign
    return a


def p_diamond(a, s):
    # inner outline points pulled (fraction s) onto the straight lines centre -> inner corner
    pos = a.positions
    for centre, pts in ((P.ul_inner, P.upper_inner[1:]), (P.ll_inner, P.lower_inner[1:])):
        for v in pts:
            t = pos[:, v, 1] / pos[:, P.inner_corner, 1]
            line = pos[:, centre, 2] + t * (pos[:, P.inner_corner, 2] - pos[:, centre, 2])
            pos[:, v, 2] += s * (line - pos[:, v, 2])
    return a


def p_hexagon(a, s):
    # CASSI 1.0's opening (synthetic JW24 task 106 row 957): the inner outline's side points
    # pulled (fraction s) to the height of its centre, flat top and bottom edges kinked
    # beside the corners
    pos = a.positions
    for centre, pts in ((P.ul_inner, P.upper_inner[1:]), (P.ll_inner, P.lower_inner[1:])):
        for v in pts:
            pos[:, v, 2] += s * (pos[:, centre, 2] - pos[:, v, 2])
    return a


def p_lower_lip_through_lower(a, d):
    lt = M.rest[P.lower_incisor_tip]
    for v in (P.ll_inner, P.lower_inner[1]):
        y = M.rest[v, 1]
        a.positions[:, v] = S.on_jaw(M, a, (lt[0] - d, y, lt[2] - 2.0), open_rad=0.2)
    return a


def p_below_cave(a, d):
    a.positions[:, P.below_lip[0], 0] -= d
    return a


def p_corner_up(a, d):
    a.positions[:, P.corner, 2] = a.positions[:, P.upper_outer[-1], 2] + d
    return a


def p_chin_cave(a, d):
    a.positions[:, P.chin, 0] -= d
    return a


def p_switch_jump(a, d):
    b = a.diagnostics["ellipse"].to_numpy()
    s = int(np.flatnonzero(b[1:] != b[:-1])[0]) + 1
    a.positions[s, P.corner, 1] += d
    return a


def test_a_branch_change_that_is_no_ellipse_switch_is_no_switch_jump():
    """corner_jump_switch reads the `ellipse` diagnostic: OUTER_ABC_CALC leaving the band near
    c_rest changes branch without switching between horizontal and vertical ellipse."""
    a = S.copy(BASE[106])
    b = a.diagnostics["outer_abc_branch"].to_numpy()
    e = a.diagnostics["ellipse"].to_numpy()
    changes = np.flatnonzero(b[1:] != b[:-1]) + 1
    not_switch = [int(f) for f in changes if e[f] == e[f - 1]]
    assert not_switch
    a.positions[not_switch[0], P.corner, 1] += 2.0
    r = run(a, 106, checks=["corner_jump_switch"]).loc["corner_jump_switch"]
    assert r["negatives"] == 0 and "0 ellipse switches" not in r["detail"]


#: check -> (task, planter, magnitudes mild..severe, negatives expected at each magnitude)
CASES = {
    "teeth_front_overlap": (5, p_front_overlap, [1.0, 3.5, 6.0], [0, 1, 1]),
    "teeth_back_overlap": (5, p_back_overlap, [0.5, 2.5], [0, 1]),
    "teeth_slope_up": (5, p_slope_up, [3.0, 8.0, 30.0], [0, 1, 3]),
    "teeth_slope_down": (5, p_slope_down, [3.0, 8.0], [0, 1]),
    "teeth_too_far_apart": (5, p_teeth_apart, [2.0, 7.0], [0, 1]),
    "lips_never_touch": (5, p_open_lips, [0.5, 2.5, 6.0], [0, 1, 2]),
    "lips_apart_at_start": (5, p_open_at_start, [0.5, 2.5, 6.0], [0, 1, 2]),
    "lips_pressed": (5, p_pressed, [1.0, 3.0], [0, 1]),
    "lower_lip_below_teeth": (5, p_lower_lip_below, [0.05, 0.3, 0.7], [0, 1, 2]),
    "lips_through_teeth": (5, p_lip_through_teeth, [0.2, 1.5], [0, 1]),
    "lower_lip_protrudes": (5, p_lower_protrudes, [1.0, 2.5, 5.0], [0, 1, 2]),
    "lips_overlap": (5, p_lips_cross, [0.4, 1.5], [0, 1]),
    "lips_too_large_moving": (5, p_handled_cross, [0.2, 0.8], [0, 1]),
    "tongue_through_teeth": (5, p_tongue_lower, [0.2, 2.0], [0, 1]),
    "palate_below_incisor": (5, p_palate_low, [-1.0, 1.0, 3.0], [0, 1, 2]),
    "jaw_long": (5, p_jaw_long, [0.05, 0.3], [0, 1]),
    "jaw_large": (5, p_jaw_large, [0.05, 0.2], [0, 1]),
    "jaw_square": (5, p_jaw_square, [0.02, 0.9], [0, 1]),
    "no_lip_rounding": (118, p_no_rounding, [0.5, 1.0], [0, 3]),
    "lips_stick_out": (118, p_stick_out, [2.0, 8.0], [0, 1]),
    "above_lip_cave_in": (118, p_above_cave, [0.5, 4.5], [0, 1]),
    "lips_into_nose": (118, p_into_nose, [0.3, 0.6, 0.9], [0, 1, 2]),
    "lips_too_big": (118, p_too_big, [0.5, 1.5], [0, 1]),
    "lower_lip_protrudes_start": (118, p_lower_protrudes_start, [1.0, 3.0], [0, 1]),
    "upper_protrudes_more": (118, p_upper_more, [2.0, 6.0], [0, 1]),
    "upper_lip_sharp": (118, p_sharp, [0.3, 4.0], [0, 1]),
    "lip_jitter": (118, p_jitter, [0.05, 1.0], [0, 1]),
    "lip_shape_triangular": (106, p_diamond, [0.2, 1.0], [0, 1]),
    "lip_outline_angular": (106, p_hexagon, [0.2, 1.0], [0, 1]),
    "lower_lip_through_teeth": (106, p_lower_lip_through_lower, [-1.0, 2.0], [0, 1]),
    "below_lip_cave_in": (106, p_below_cave, [1.5, 4.0], [0, 1]),
    "corners_misplaced": (106, p_corner_up, [0.5, 2.5], [0, 1]),
    "chin_cave_in": (106, p_chin_cave, [2.0, 5.0], [0, 1]),   # its chin bulges 3.2 mm
    "corner_jump_switch": (106, p_switch_jump, [0.3, 2.0], [0, 1]),
}


def test_every_geometry_check_has_a_planted_defect():
    counted = {c.name for c in R.checks_for(kind="geometry") if c.counted}
    assert counted - set(CASES) == set(), "a counted geometric check without a planted defect"


@pytest.mark.parametrize("task", [5, 106, 118])
def test_clean_case_is_silent(task):
    res = run(S.copy(BASE[task]), task)
    assert set(res.index) == {c.name for c in R.checks_for(kind="geometry", task=task)}
    fired = res[res["negatives"] > 0]
    assert fired.empty, fired[["value", "detail"]].to_string()
    for name, r in res.iterrows():
        assert not R.CHECKS[name].fires(r["value"]), (name, r["value"])


@pytest.mark.parametrize("name", sorted(CASES))
def test_planted_defect_fires_and_grades(name):
    task, plant, mags, expected = CASES[name]
    got = []
    for mag in mags:
        r = run(plant(S.copy(BASE[task]), mag), task, checks=[name]).loc[name]
        got.append(int(r["negatives"]))
    assert got == expected, f"{name}: negatives {got} for magnitudes {mags}"
    # severity: a larger planted defect never earns fewer negatives
    assert got == sorted(got)


@pytest.mark.parametrize("name", sorted(CASES))
def test_severity_is_monotonic_on_a_fine_sweep(name):
    task, plant, mags, _ = CASES[name]
    sweep = np.linspace(min(mags), max(mags), 6)
    negs = [int(run(plant(S.copy(BASE[task]), m), task, checks=[name]).loc[name, "negatives"])
            for m in sweep]
    assert negs == sorted(negs), f"{name}: {list(zip(sweep.round(2), negs))}"


def test_tongue_through_both_front_teeth_grades_two_then_three():
    a = p_tongue_both(S.copy(BASE[5]), 1.0)
    r = run(a, 5, checks=["tongue_through_teeth"]).loc["tongue_through_teeth"]
    assert r["negatives"] == 2, r["detail"]
    a = p_tongue_both(S.copy(BASE[5]), 3.0)
    r = run(a, 5, checks=["tongue_through_teeth"]).loc["tongue_through_teeth"]
    assert r["negatives"] == 3, r["detail"]
    assert r["value"] == pytest.approx(3.0, abs=0.1)


def test_crossing_the_version_handles_is_not_the_table_a_overlap():
    a = p_handled_cross(S.copy(BASE[5]), 0.0)
    assert run(a, 5, checks=["lips_overlap"]).loc["lips_overlap", "negatives"] == 0
    a.diagnostics["lips_overlap"] = False
    assert run(a, 5, checks=["lips_overlap"]).loc["lips_overlap", "negatives"] == 1


def test_lip_contact_is_judged_at_the_first_and_the_last_frame():
    """Thesis 5.3.1: the front view at the starting and ending frame shows whether the lips
    lightly touch, are too far apart or too close together: a fault at the end counts as one at
    the start; lips parted in between are not a contact fault; and the whole file's smallest gap
    is cassi-farm's own measure, in Table G."""
    checks = ["lips_apart_at_start", "lips_pressed", "lips_never_touch"]
    last = BASE[5].positions.shape[0] - 1

    def lower_lip_moved(frames, dz):
        a = S.copy(BASE[5])
        a.positions[frames, M.lower_lip, 2] += dz
        return run(a, 5, checks=checks)

    r = lower_lip_moved(slice(-6, None), -2.5)                      # apart at the end only
    assert r.loc["lips_apart_at_start", "negatives"] == 1
    assert f"worst frame {last}" in r.loc["lips_apart_at_start", "detail"]
    assert r.loc["lips_never_touch", "negatives"] == 0              # they touch at the start
    assert lower_lip_moved(slice(-6, None), -6.0).loc["lips_apart_at_start", "negatives"] == 2
    r = lower_lip_moved(slice(-4, None), 3.0)                       # pressed at the end only
    assert r.loc["lips_pressed", "negatives"] == 1
    assert f"worst frame {last}" in r.loc["lips_pressed", "detail"]
    r = lower_lip_moved(slice(6, -6), -6.0)                         # apart between the two
    assert (r.loc[checks, "negatives"] == 0).all(), r.loc[checks, ["value", "detail"]]
    r = lower_lip_moved(slice(None), -2.5)                          # apart in every frame
    assert r.loc["lips_apart_at_start", "negatives"] == 1
    assert r.loc["lips_never_touch", "negatives"] == 1
    assert (r.loc["lips_apart_at_start", "table"], r.loc["lips_never_touch", "table"]) == ("A", "G")


def test_jaw_turned_down_at_initialization_reads_long_not_square():
    # CASSI 1.0 turns Parke's jaw onto the head measures about a point far behind (4.1.3): the
    # jaw keeps its shape (not squarer) but reaches further below the teeth (longer, larger)
    a = S.copy(BASE[5])
    j = P.jaw
    t = np.full(len(a.positions), np.radians(6.0))
    a.positions[:, j] = S._rotate(a.positions[:, j], M.pivot, t)
    res = run(a, 5, checks=["jaw_long", "jaw_square", "jaw_large"])["value"]
    assert res["jaw_square"] == pytest.approx(1.0, abs=0.02), res
    assert res["jaw_long"] > 1.05 and res["jaw_large"] > 1.05, res


def test_tongue_two_mm_through_incisors_measures_two_mm():
    a = p_tongue_lower(S.copy(BASE[5]), 2.0)
    up = G.tongue_teeth_penetration(a.positions, P, rest=M.rest)
    assert up["lower"].max() == pytest.approx(2.0, abs=0.05)
    assert up["upper"].max() == 0.0


def test_tongue_through_palate_is_measured_not_counted():
    r = run(p_tongue_palate(S.copy(BASE[5]), 2.0), 5, checks=["tongue_through_palate"])
    row = r.loc["tongue_through_palate"]
    assert row["value"] == pytest.approx(2.0, abs=0.15)  # the palate shares the head's noise
    assert row["negatives"] == 0 and row["detail"].startswith("fired (not counted)")


def test_switch_jump_is_found_through_the_diagnostics():
    a = p_switch_jump(S.copy(BASE[106]), 2.0)
    r = run(a, 106, checks=["corner_jump_switch"]).loc["corner_jump_switch"]
    assert r["negatives"] == 1 and "ellipse switches" in r["detail"]
    assert r["value"] == pytest.approx(2.0, abs=0.35)  # less the jaw's own step (~0.3 mm)
    # a small pop away from any switch, within the data's noise, stays silent
    b = S.copy(BASE[106])
    b.positions[20, P.corner, 1] += 0.2
    assert run(b, 106, checks=["corner_jump_switch"]).loc["corner_jump_switch", "negatives"] == 0
    # without diagnostics no switch is known: only sustained corner jitter could count, and a
    # single pop is not sustained
    c = p_switch_jump(S.copy(BASE[106]), 2.0)
    c.diagnostics = c.diagnostics.drop(columns=["ellipse"])
    r = run(c, 106, checks=["corner_jump_switch"]).loc["corner_jump_switch"]
    assert r["negatives"] == 0 and "(0 ellipse switches" in r["detail"]


def test_jaw_jitter_alone_is_not_lip_jitter():
    # noise on every vertex alike (the data's jitter) must not count, however large
    a = S.animate(M, open_rad=0.03, noise=0.8)
    a = S.protrude(M, a)
    r = run(a, 118, checks=["lip_jitter"]).loc["lip_jitter"]
    assert r["negatives"] == 0, r["value"]


def test_rows_have_results_columns_and_evidence_frames():
    a = p_open_lips(S.copy(BASE[5]), 2.0)
    df = R.run_geometry_checks(a, _Face, None, task=5, parts=P, mm_per_unit=1.0, neutral=M.rest,
                               subject="SYN", rep=2)
    assert list(df.columns) == ["subject", "task", "rep", "version", "view", "frame", "check",
                                "table", "component", "value", "unit", "threshold", "negatives",
                                "detail"]
    assert set(df["view"]) == {"geometry"} and set(df["rep"]) == {2}
    agg = df[df["frame"] == -1]
    assert agg["check"].is_unique
    ev = df[df["frame"] >= 0]
    assert (ev["negatives"] == 0).all()
    assert set(ev["check"]) <= set(agg["check"])


def test_mm_per_unit_scales_lengths():
    a = p_open_lips(S.copy(BASE[5]), 2.0)
    df = R.run_geometry_checks(a, _Face, None, task=5, parts=P, mm_per_unit=0.5, neutral=M.rest,
                               checks=["lips_never_touch"])
    assert df.loc[df["frame"] == -1, "value"].iloc[0] == pytest.approx(1.1, abs=0.01)


def test_surface_hits_equals_solving_every_point_triangle_pair():
    """The bounding-box broad phase skips only pairs that cannot hit: on random moving
    triangles (a repeated one, a degenerate one, two sharing an edge points sit on) the
    crossings equal those of every pair solved, exactly."""
    rng = np.random.default_rng(5)
    F, P, T = 6, 300, 40
    tri = rng.uniform(-10, 10, (F, T, 3, 3))
    tri[:, 1] = tri[:, 0]                                       # a repeated triangle
    tri[:, 4, 2] = tri[:, 4, 1]                                 # a degenerate one
    tri[:, 2, 0], tri[:, 2, 1] = tri[:, 3, 0], tri[:, 3, 1]     # two corners shared with the next
    pts = rng.uniform(-10, 10, (F, P, 3))
    pts[:, :20, 1:] = 0.5 * (tri[:, 3, 0, 1:] + tri[:, 3, 1, 1:])[:, None]    # on the shared edge
    for axis in (0, 2):
        u, v = {0: (1, 2), 2: (0, 1)}[axis]
        a, b, c = (tri[:, None, :, k] for k in range(3))
        p = pts[:, :, None]
        (au, av), (bu, bv), (cu, cv), (pu, pv) = ((q[..., u], q[..., v]) for q in (a, b, c, p))
        den = (bu - au) * (cv - av) - (cu - au) * (bv - av)
        ok = np.abs(den) > 1e-9
        den = np.where(ok, den, 1.0)
        w1 = ((bu - pu) * (cv - pv) - (cu - pu) * (bv - pv)) / den
        w2 = ((cu - pu) * (av - pv) - (au - pu) * (cv - pv)) / den
        w3 = 1.0 - w1 - w2
        inside = ok & (w1 >= -1e-7) & (w2 >= -1e-7) & (w3 >= -1e-7)
        val = w1 * a[..., axis] + w2 * b[..., axis] + w3 * c[..., axis]
        with np.errstate(invalid="ignore"):
            want_lo = np.where(inside.any(-1), np.where(inside, val, np.inf).min(-1), np.nan)
            want_hi = np.where(inside.any(-1), np.where(inside, val, -np.inf).max(-1), np.nan)
        lo, hi = G.surface_hits(pts, tri, axis=axis, chunk=50_000)
        assert np.isfinite(lo).sum() > 100
        np.testing.assert_array_equal(lo, want_lo)
        np.testing.assert_array_equal(hi, want_hi)


def test_surface_hits_takes_each_points_crossings_in_triangle_order():
    """Crossings at 0.0 and -0.0 compare equal, so the smallest kept depends on their order:
    a point's crossings are taken in triangle order, as solving pair after pair did; a NaN
    corner or point crosses nothing."""
    flat = np.array([[0.0, -1, -1], [0.0, 3, -1], [0.0, -1, 3]])  # the plane x = 0
    for signs in ((0.0, -0.0), (-0.0, 0.0)):
        tri = np.stack([flat, flat, flat])[None].copy()         # (1, 3, 3, 3)
        tri[0, 0, :, 0], tri[0, 1, :, 0] = signs
        tri[0, 2, 0, 1] = np.nan
        pts = np.array([[[5.0, 0.0, 0.0], [5.0, np.nan, 0.0]]])
        lo, hi = G.surface_hits(pts, tri, axis=0)
        want = np.inf
        for s in signs:
            want = np.minimum(want, s * 1.0)
        assert lo[0, 0] == 0.0 and np.signbit(lo[0, 0]) == np.signbit(want)
        assert np.signbit(hi[0, 0]) == np.signbit(np.maximum(np.maximum(-np.inf, signs[0]),
                                                             signs[1]))
        assert np.isnan(lo[0, 1]) and np.isnan(hi[0, 1])


def test_surface_hits_against_a_unit_square():
    tri = np.array([[[0, 0, 0], [0, 1, 0], [0, 1, 1]], [[0, 0, 0], [0, 1, 1], [0, 0, 1]]], float)
    tri[..., 0] = [[1, 1, 2], [1, 2, 1]]  # a sloped plane x = 1 + z
    pts = np.array([[[5, 0.5, 0.5], [5, 2.0, 0.5]]], float)
    lo, hi = G.surface_hits(pts, tri[None], axis=0)
    assert lo[0, 0] == pytest.approx(1.5) and hi[0, 0] == pytest.approx(1.5)
    assert np.isnan(lo[0, 1])


def test_bad_positions_raise_input_error():
    from cassi.common.errors import CassiInputError

    a = S.copy(BASE[5])
    a.positions[3, 0, 0] = np.nan
    with pytest.raises(CassiInputError):
        run(a, 5)


def test_teeth_parted_by_the_jaw_opening_are_no_fault_but_teeth_apart_when_closed_are():
    """Teeth are judged during the task as well as at its end; a jaw opened for speech parts
    and slants them (no fault), teeth apart with the jaw closed are."""
    a = S.copy(BASE[5])
    r = run(a, 5, checks=["teeth_too_far_apart", "teeth_slope_down"])
    assert (r["negatives"] == 0).all()
    b = S.copy(BASE[5])
    # the lower teeth (not the jaw point) drop 7 mm for 20 frames while the jaw is near closed,
    # away from the end of the task
    closed = np.flatnonzero(GeometryContext(b.positions, P, mm_per_unit=1.0).jaw_near_closed)
    held = closed[(closed > 10) & (closed < b.positions.shape[0] - 20)][:20]
    assert len(held) >= TEETH_HOLD_FRAMES
    teeth = np.setdiff1d(lower_teeth(), [P.jaw_point])
    b.positions[np.ix_(held, teeth, [2])] -= 7.0
    r = run(b, 5, checks=["teeth_too_far_apart"]).loc["teeth_too_far_apart"]
    assert r["negatives"] == 1 and "during the task" in r["detail"]


def test_back_teeth_apart_count_as_teeth_too_far_apart():
    a = S.copy(BASE[5])
    a.positions[:, P.lower_molar, 2] -= 6.0    # back teeth 6 mm apart, the incisors still overlap
    r = run(a, 5, checks=["teeth_too_far_apart"]).loc["teeth_too_far_apart"]
    # judged in the frames with the jaw within JAW_NEAR_CLOSED_MM (2 mm) of closed: 6 to 8 mm
    assert r["negatives"] == 1 and 6.0 - 0.2 <= r["value"] <= 8.0


def test_tongue_back_v_is_measured_not_counted():
    clean = run(S.copy(BASE[5]), 5, checks=["tongue_back_v"]).loc["tongue_back_v"]
    assert clean["value"] > 150 and not clean["detail"].startswith("fired")
    a = S.copy(BASE[5])
    a.positions[:, P.tongue[4], 2] += 8.0       # T4 raised 8 mm, the back stays anchored
    r = run(a, 5, checks=["tongue_back_v"]).loc["tongue_back_v"]
    assert r["value"] < 120 and r["negatives"] == 0 and r["detail"].startswith("fired")


def test_too_few_vertices_raise_input_error():
    from cassi.common.errors import CassiInputError

    a = S.copy(BASE[5])
    a.positions = a.positions[:, :10]
    with pytest.raises(CassiInputError, match="vertices"):
        run(a, 5)


def test_a_flat_topped_hexagon_is_angular_though_it_fills_its_box():
    # CASSI 1.0's wide opening: area / box stays above an ellipse's, only the kinks show it
    r = run(p_hexagon(S.copy(BASE[106]), 1.0), 106,
            checks=["lip_shape_triangular", "lip_outline_angular"])
    assert r.loc["lip_shape_triangular", "negatives"] == 0
    assert r.loc["lip_shape_triangular", "value"] > np.pi / 4
    assert r.loc["lip_outline_angular", "negatives"] == 1
    assert r.loc["lip_outline_angular", "value"] < 125.0


def test_front_teeth_are_the_incisors_and_canines():
    """The registry's FRONT_TEETH_SHARE / FRONT_TEETH_MIN_NX keep, on the model's own sets,
    triangles of the incisors and canines (teeth 0-2 of each set) and nothing behind the first
    premolars: the teeth a line along x meets from the front."""
    from cassi.data.face import numbering as N
    from cassi.data.face.model import build_face
    face = build_face()
    parts = G.mouth_parts(face)
    for tris, tooth in ((parts.upper_teeth_tris, N.upper_tooth), (parts.lower_teeth_tris, N.lower_tooth)):
        kept = set(G.front_triangles(face.vertices, tris).ravel() + 1)
        owner = {n: k for k in range(N.TEETH_PER_SET) for n in tooth(k)}
        teeth = {owner[n] for n in kept if n in owner}
        assert {0, 1, 2} <= teeth and max(teeth) <= 3, teeth
