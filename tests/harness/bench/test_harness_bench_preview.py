"""The farm preview benchmark runs end to end and reports what `cassi bench` promises
(figures are read from `cassi bench`, never asserted here)."""
from __future__ import annotations

import pytest

pytestmark = [pytest.mark.render, pytest.mark.slow]


def test_farm_preview_benchmark_reports_every_view_beside_a_bare_render():
    from cassi.harness.bench import headline
    from cassi.harness.bench.farm import bench_farm_preview

    out = bench_farm_preview(True)
    assert "error" not in out, out
    views = ("front", "side", "half", "top")
    assert set(out["by_view"]) == set(views) == set(out["bare_mi_render_frames_per_s"])
    frames = {v["frames"] for v in out["by_view"].values()}
    # every view renders the same grid; a check's evidence frames (the frames the report links)
    # come on top in the view it is judged from only
    assert min(frames) >= 20 and max(frames) <= 1.1 * min(frames), frames
    assert out["farm_preview_frames_per_s"] > 0 and out["farm_efficiency_vs_bare"] > 0
    assert 0 < out["farm_preview_cpu_frames_per_s"] and out["farm_cpu_efficiency_vs_bare"] > 0
    assert headline({"farm_preview": out}) == {
        "farm_preview_frames_per_s": out["farm_preview_frames_per_s"],
        "farm_preview_cpu_frames_per_s": out["farm_preview_cpu_frames_per_s"]}


@pytest.mark.parametrize("only", ["nope", "render,nope"])
def test_bench_only_names_unknown_benchmarks(only, tmp_path, capsys):
    from cassi.harness.cli import main

    code = main(["bench", "--only", only, "--out", str(tmp_path / "b.json")])
    assert code == 2
    err = capsys.readouterr().err
    assert "no benchmark nope" in err and "farm_preview" in err
    assert not (tmp_path / "b.json").exists()
