"""Image and metric gates, golden updates and the `cassi gate` / `cassi golden` commands."""
from __future__ import annotations

import json

import numpy as np
import pytest

from other_machine import as_another_cpu
from reports_fixtures import image, results_rows, write_run
from cassi.data.face.model import build_face, render_topology
from cassi.data.face.params import jaw_rotation
from cassi.harness.cli import main
from cassi.renderer.render import FaceRenderer
from cassi.reports.gates import (MismatchedBaseline, gate, image_metrics, metric_gates,
                                 update_golden)

KEY = ("JW11", 19, "cassi-2.0", "front", 0)


def test_image_metrics_identical_one_level_and_shifted():
    a = image(1)
    same = image_metrics(a, a)
    assert same["changed_px"] == 0 and same["max_levels"] == 0 and same["flip_mouth"] == 0.0
    # one 8-bit level everywhere (llvm against scalar_rgb) is no change
    off = image_metrics(np.clip(a.astype(int) + 1, 0, 255).astype(np.uint8), a)
    assert off["changed_px"] == 0 and off["comparison"].passed
    shifted = image_metrics(np.roll(a, 2, axis=1), a, (8, 40, 10, 50))
    assert shifted["changed_px"] > 50 and shifted["flip_mouth"] > 3 * off["flip_mouth"]
    assert not shifted["comparison"].passed
    assert shifted["flip_map"].shape == (32, 40)  # the mouth box only


def test_failed_image_gate_writes_what_changed(tmp_path):
    run1 = write_run(tmp_path / "run1", results_rows({}), images={KEY: image(1)})
    golden = tmp_path / "golden"
    update_golden(run1, golden)
    moved = write_run(tmp_path / "run2", results_rows({}), images={KEY: np.roll(image(1), 2, axis=0)})
    ok, results = gate(moved, golden)
    fail = [r for r in results if r.gate == "image"][0]
    assert not ok and fail.status == "fail" and "FLIP" in fail.reason
    names = sorted(p.name for p in (moved / "gate-images").rglob("*.png"))
    assert names == [f"JW11_019_1_00000.{n}.png" for n in
                     ("difference", "flip_mouth", "reference", "rendered")]


def test_metric_gate_fails_only_when_negatives_grow():
    base = results_rows({("cassi-2.0", "JW11", "lip_gap_start"): 1})
    same = metric_gates(base, base)
    assert same and all(g.status == "pass" for g in same)
    worse = results_rows({("cassi-2.0", "JW11", "lip_gap_start"): 2})
    fails = [g for g in metric_gates(worse, base) if g.status == "fail"]
    assert len(fails) == 1 and fails[0].version == "cassi-2.0" and "lip_gap_start" in fails[0].item
    better = results_rows({})
    assert all(g.status == "pass" for g in metric_gates(better, base))


def test_golden_roundtrip_pass_fail_and_skip(tmp_path):
    res = results_rows({})
    run1 = write_run(tmp_path / "run1", res, images={KEY: image(1)})
    golden = tmp_path / "golden"
    assert update_golden(run1, golden) == 1
    ok, results = gate(run1, golden)
    assert ok and [r.status for r in results if r.gate == "image"] == ["pass"]

    moved = write_run(tmp_path / "run2", res, images={KEY: np.roll(image(1), 8, axis=0),
                                                      ("JW12", 19, "cassi-2.0", "side", 0): image(3)})
    # a render the golden lacks is refused, or (--common-only) a skipped gate, never a pass
    with pytest.raises(MismatchedBaseline, match=r"renders differ \(only in the run: "
                                                 r"JW12/019-1/cassi-2.0/side \(frame 0\)\)"):
        gate(moved, golden)
    ok, results = gate(moved, golden, common_only=True)
    statuses = sorted(r.status for r in results if r.gate == "image")
    assert not ok and statuses == ["fail", "skip"]
    report = json.loads((moved / "gate.json").read_text())
    assert report["passed"] is False and report["counts"]["skip"] == 1
    assert "no golden image" in (moved / "gate.md").read_text()


def test_gate_and_golden_commands_exit_codes(tmp_path, capsys):
    base = write_run(tmp_path / "base", results_rows({}), images={KEY: image(1)})
    worse = write_run(tmp_path / "worse", results_rows({("cassi-2.1", "JW12", "lip_gap_start"): 1}),
                      images={KEY: image(1)})
    assert main(["gate", str(base), "--baseline", str(base)]) == 0
    assert main(["gate", str(worse), "--baseline", str(base)]) == 1
    assert "lip_gap_start" in capsys.readouterr().out
    assert main(["gate", str(worse), "--baseline", str(tmp_path / "nothing")]) == 2
    assert main(["golden", str(base), "--golden", str(tmp_path / "g")]) == 0
    assert (tmp_path / "g" / "cassi-2.0" / "front" / "JW11_019_1_00000.png").is_file()


@pytest.mark.render
def test_night_from_another_code_path_passes_and_a_real_change_fails(tmp_path):
    """A baseline night rendered with llvm, gated against a night of the same frames rendered
    with scalar_rgb (its half view's eye highlight changed as another CPU changes it): passes,
    against the previous night as a run and as a golden directory. The jaw lowered by 4 Parke
    units (0.5 degrees) in the same other-path night fails."""
    face = build_face()
    pos = np.asarray(face.vertices)
    keys = {"front": ("JW11", 19, "cassi-2.0", "front", 0),
            "half": ("JW11", 19, "cassi-2.0", "half", 0)}

    def night(variant, positions, highlight=False):
        out = {}
        for view, key in keys.items():
            topo = render_topology(face, half=(view == "half"))
            srgb = FaceRenderer(topo, view, "preview", variant).render(positions).srgb8()
            out[key] = as_another_cpu(srgb) if highlight and view == "half" else srgb
        return out

    res = results_rows({})
    base = write_run(tmp_path / "llvm", res, images=night("llvm", pos))
    golden = tmp_path / "golden"
    update_golden(base, golden)
    other = write_run(tmp_path / "scalar", res, images=night("scalar", pos, highlight=True))
    for baseline in (base, golden):
        ok, results = gate(other, baseline)
        image_results = [r for r in results if r.gate == "image"]
        assert ok and [r.status for r in image_results] == ["pass", "pass"], results
    half = next(r for r in image_results if r.item.startswith("half"))
    assert half.value > 0.001  # the highlight's pixels were counted, and allowed

    lowered = write_run(tmp_path / "lowered", res,
                        images=night("scalar", jaw_rotation(pos, 0.5), highlight=True))
    ok, results = gate(lowered, golden)
    assert not ok
    assert [r.status for r in results if r.gate == "image"] == ["fail", "fail"], results
