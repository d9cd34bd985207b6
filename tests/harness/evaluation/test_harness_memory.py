"""Memory of an image job does not grow with the frames it judges (issue 14: flat memory).

Each figure is a fresh process's peak RSS (``cassi.harness.bench.memory``); before the image
checks reduced each frame to a few numbers as it was read, 400 frames held about 0.5 GB more
than 40.
"""
import pytest

from cassi.harness.bench.memory import bench_image_memory

pytestmark = pytest.mark.render


def test_image_job_memory_is_flat_in_the_number_of_frames():
    few = bench_image_memory(frames=40)
    many = bench_image_memory(frames=400)
    assert "error" not in few and "error" not in many, (few, many)
    assert few["rows"] == many["rows"] > 0
    growth = many["peak_rss_mb"] - few["peak_rss_mb"]
    assert growth < 60.0, f"peak RSS grew {growth:.0f} MB from 40 to 400 frames"
