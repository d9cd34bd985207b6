"""The geometry benchmark runs every version and reports frames per second."""
from __future__ import annotations

import numpy as np

from _versions_toy import ToyFace, toy_vertices
from cassi.harness.bench.geometry import bench_geometry, long_task


def test_long_task_is_deterministic_and_valid_after_head():
    a, b = long_task(300), long_task(300)
    np.testing.assert_array_equal(a.xy_mm, b.xy_mm)
    assert a.first_valid_index == 3 and a.valid[3:].all()


def test_bench_geometry_reports_frames_per_second():
    out = bench_geometry(True, face=ToyFace(toy_vertices()), frames=400,
                         versions=["parke-1974", "cassi-1.0"])
    assert not out["errors"]
    assert set(out["geometry_frames_per_s"]) == {"parke-1974", "cassi-1.0"}
    assert all(v > 0 for v in out["geometry_frames_per_s"].values())
    assert out["frames"] == 397


def test_bench_geometry_records_a_failing_version():
    out = bench_geometry(True, face=ToyFace(toy_vertices()), frames=100, versions=["no-such"])
    assert "no-such" in out["errors"] and not out["geometry_frames_per_s"]
