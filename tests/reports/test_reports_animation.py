"""Task videos: the farm renders every view at the video stride (the same frames for every
version), the report turns each task file into a four-view video per version and compares the
versions side by side in the front view; videos play in real time, panels are labelled, and
a task's WAV is carried in sync."""
from __future__ import annotations

import subprocess

import imageio_ffmpeg
import numpy as np
import pandas as pd
import pytest
from scipy.io import wavfile

from cassi.reports import media

ROW_S = 6866e-6


def _decode_audio(path, rate: int = 8000) -> np.ndarray:
    """The MP4's audio track as mono float samples at ``rate`` Hz (ffmpeg from imageio-ffmpeg)."""
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(path), "-vn", "-ac", "1",
           "-ar", str(rate), "-f", "s16le", "-"]
    raw = subprocess.run(cmd, check=True, capture_output=True).stdout
    return np.frombuffer(raw, np.int16).astype(float) / 32768.0


def _panel(tmp_path, name: str, shade: int):
    path = tmp_path / f"{name}.png"
    import imageio.v3 as iio

    iio.imwrite(path, np.full((64, 64, 3), shade, np.uint8))
    return str(path)


def test_tone_onset_is_in_sync_and_panels_are_labelled(tmp_path):
    """A generated tone that starts 2.0 s into the recording is heard 2.0 s - t(first frame)
    into the video; the video lasts frames / fps and plays in real time."""
    stride, first, n = 20, 50, 30   # rows 50, 70, ..., 630: 0.343 s .. 4.33 s
    rows = []
    for k in range(n):
        f = first + k * stride
        for view in ("front", "half"):
            rows.append({"subject": "JW99", "task": 7, "rep": 1, "version": "v1", "view": view,
                         "frame": f, "path": _panel(tmp_path, f"{view}_{f}", 40 + k * 6)})
    rows.append({**rows[0], "frame": first + 3, "path": rows[0]["path"]})  # an extreme: off grid
    rate = 16000
    t = np.arange(int(6.0 * rate)) / rate
    tone = np.where(t >= 2.0, 0.5 * np.sin(2 * np.pi * 440 * t), 0.0)
    wav = tmp_path / "tp007.wav"
    wavfile.write(wav, rate, (tone * 32767).astype(np.int16))

    dest = tmp_path / "video.mp4"
    out = media.task_video(pd.DataFrame(rows), dest, stride=stride, audio=wav,
                           columns=[("v1", "front"), ("v1", "half")])
    assert out["frames"] == n and out["audio"]
    assert out["fps"] == pytest.approx(1 / (stride * ROW_S), rel=1e-3)  # real time
    n_frames, secs = imageio_ffmpeg.count_frames_and_secs(str(dest))
    assert n_frames == n and secs == pytest.approx(n / out["fps"], abs=0.1)

    audio = _decode_audio(dest)
    env = np.abs(audio)
    onset = np.flatnonzero(env > 0.1)[0] / 8000
    assert onset == pytest.approx(2.0 - first * ROW_S, abs=0.03)
    assert len(audio) / 8000 == pytest.approx(n / out["fps"], abs=0.1)

    # two labelled panels side by side: a dark band with light text above each 64 px image
    reader = imageio_ffmpeg.read_frames(str(dest))
    meta = next(reader)
    w, h = meta["size"]
    first_frame = np.frombuffer(next(reader), np.uint8).reshape(h, w, 3)
    reader.close()
    band = h - 64
    assert band >= 2 * media.LABEL_PX and w >= 2 * 64
    assert (first_frame[:band].max(axis=2) > 150).sum() > 30
    assert abs(int(first_frame[band + 20, 20].mean()) - 40) <= 6  # the panel below, unchanged


def test_label_panel_draws_text_above_the_image():
    img = np.full((40, 80, 3), 200, np.uint8)
    out = media.label_panel(img, ["cassi-2.1 | half", "JW11 task 1 | t = 0.343 s"])
    band = out.shape[0] - img.shape[0]
    assert band >= 2 * media.LABEL_PX and np.array_equal(out[band:], img)
    top = out[:band]
    assert (top.max(axis=2) > 150).sum() > 30 and (top.max(axis=2) < 40).mean() > 0.5


def test_video_frames_keep_only_the_common_grid():
    df = pd.DataFrame({"version": ["a"] * 4 + ["b"] * 3, "view": ["front"] * 7,
                       "frame": [10, 15, 20, 30, 10, 20, 30]})
    assert media.video_frames(df, stride=10) == [10, 20, 30]


@pytest.mark.render
def test_every_task_file_becomes_a_video_and_versions_compare(tmp_path, monkeypatch):
    """cassi-2.0 is the video version: all views on the grid and a two-view video; cassi-1.0
    gets the grid in the view the image checks judge (front) in every task file, so those
    checks judge both versions on the same frames, and both appear side by side."""
    from cassi.harness.evaluation.config import RunConfig
    from cassi.harness.evaluation.run import run
    from cassi.harness.evaluation.frames import image_views
    from cassi.reports.report import write_report

    cfg = RunConfig(out=tmp_path / "run", subjects=("JW45",), tasks=(5, 118),
                    versions=("cassi-1.0", "cassi-2.0"), views=("front", "half"), stride=0,
                    extremes=1, animate_stride=300, video_versions=("cassi-2.0",), workers=1)
    assert run(cfg, progress=False).ok
    renders = pd.read_parquet(tmp_path / "run" / "renders.parquet")
    for task in (5, 118):
        assert image_views(task) == {"front"}
        frames = renders[renders["task"] == task].groupby(["version", "view"])["frame"].apply(set)
        shared = (frames[("cassi-1.0", "front")] & frames[("cassi-2.0", "front")]
                  & frames[("cassi-2.0", "half")])
        assert len(shared) >= 4  # first frame + every 300th of 1,100-1,470 rows
        assert len(frames[("cassi-1.0", "half")]) <= 2  # first frame + one extreme: no video
    index = write_report(tmp_path / "run", tmp_path / "report").read_text()
    assert (tmp_path / "report" / "animations" / "JW45_005_1_front.mp4").is_file()
    renders = renders[renders["task"] == 118]
    grid = media.video_frames(renders[renders["version"] == "cassi-2.0"], stride=300)
    video = tmp_path / "report" / "videos" / "JW45_118_1_cassi-2.0.mp4"
    assert video.is_file() and "videos/JW45_118_1_cassi-2.0.mp4" in index
    assert not (tmp_path / "report" / "videos" / "JW45_118_1_cassi-1.0.mp4").exists()
    n_frames, _ = imageio_ffmpeg.count_frames_and_secs(str(video))
    assert n_frames == len(grid)
    meta = next(imageio_ffmpeg.read_frames(str(video)))
    assert meta["size"][0] > 2 * 256  # two views side by side
    comparison = tmp_path / "report" / "animations" / "JW45_118_1_front.mp4"
    assert comparison.is_file() and "animations/JW45_118_1_front.mp4" in index
    assert "silent (no tpNNN.wav in the corpus)" in index

    # A run past the large-run limit (a full set) makes the compared tasks' videos only, and
    # its index says how to get any other.
    from cassi.harness.evaluation import frames as frame_policy
    monkeypatch.setattr(frame_policy, "ALL_RENDERS_UP_TO", 1)
    index = write_report(tmp_path / "run", tmp_path / "large").read_text()
    assert (tmp_path / "large" / "animations" / "JW45_118_1_front.mp4").is_file()
    assert not (tmp_path / "large" / "animations" / "JW45_005_1_front.mp4").exists()
    assert not list((tmp_path / "large").rglob("JW45_005_*.mp4"))
    assert ("2 task files (more than 1): it makes videos only for the tasks whose versions the "
            "thesis compares side by side (106 and 118), here task 118.") in index
    assert "<code>cassi animate --subject S --task T" in index
