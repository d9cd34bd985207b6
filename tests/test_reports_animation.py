"""Task 118 animated for every version side by side: the farm renders the front view at the
animation stride (the same frames for every version) and the report turns them into an MP4."""
from __future__ import annotations

import imageio_ffmpeg
import pandas as pd
import pytest

from cassi.harness.config import RunConfig
from cassi.harness.farm import run
from cassi.reports.report import write_report

pytestmark = pytest.mark.render


def test_animation_frames_are_shared_by_versions_and_become_a_video(tmp_path):
    cfg = RunConfig(out=tmp_path / "run", subjects=("JW45",), tasks=(118,),
                    versions=("cassi-1.0", "cassi-2.0"), views=("front", "half"), stride=0,
                    extremes=1, animate_stride=300, workers=1)
    assert run(cfg, progress=False).ok
    renders = pd.read_parquet(tmp_path / "run" / "renders.parquet")
    front = renders[renders["view"] == "front"].groupby("version")["frame"].apply(set)
    half = renders[renders["view"] == "half"].groupby("version")["frame"].apply(set)
    shared = front["cassi-1.0"] & front["cassi-2.0"]
    assert len(shared) >= 4  # first frame + every 300th of ~1,470 rows
    assert all(len(front[v]) > len(half[v]) for v in front.index)  # only the front view animates
    index = write_report(tmp_path / "run", tmp_path / "report")
    videos = list((tmp_path / "report" / "animations").glob("JW45_118_1_front.mp4"))
    assert len(videos) == 1 and "animations/JW45_118_1_front.mp4" in index.read_text()
    n_frames, _ = imageio_ffmpeg.count_frames_and_secs(str(videos[0]))
    assert n_frames == len(shared)  # one video frame per frame every version rendered
