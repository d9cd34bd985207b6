"""A recording at another rate (EMA's 500 Hz) goes through the whole path as XRMB's 145.6 Hz.

A synthetic XRMB task (JW11, task 106: jaw wagging, about 8 s) is resampled to 2000 us rows and
written as a .txy beside the original in a corpus of its own, with a WAV and xwaves labels.
Both run (cassi-2.1, front view, preview) and report; the 500 Hz copy must give the same
results per second of speech: the checks' values within the tolerances below, the viewer's
rate and time span, the video's length and sound (in sync with the labels), the export's times.
Results on the synthetic corpus describe the software, not real speakers.
"""
from __future__ import annotations

import json
import shutil
import subprocess

import imageio_ffmpeg
import numpy as np
import pandas as pd
import pytest
from gltf_helpers import accessor, chunks
from scipy.io import wavfile

from cassi.data.xrmb.files import TaskRecording, read_txy, write_txy
from cassi.harness.cli import main as cli_main
from cassi.harness.evaluation.caches import corpus_root
from cassi.reports.report import write_report

pytestmark = pytest.mark.render

EMA_US = 2000          # MOCHA-TIMIT's 500 Hz
AUDIO_RATE = 16000     # MOCHA's sound
TONE_AT_S = 2.0        # a tone starts here, where a label ends
#: The checks' values (mm, degrees, ratios) at 500 Hz against 145.6 Hz: linear resampling
#: moves a peak between rows by at most the motion in half an XRMB row, and the windows in ms
#: round to whole rows differently (20 ms: 3 rows against 10).
VALUE_RTOL, VALUE_ATOL = 0.10, 0.15
#: Checks whose value depends on the rate, with the reason; their negatives must still agree.
#: OUTER_ABC_CALC picks its branch from one row to the next (height increasing, decreasing or,
#: at the pellets' 1 um resolution, equal: thesis Figure 4.18), so how often cassi-2.x's lip
#: corners leave the band near rest, and their jitter, depends on how many rows there are
#: (JW11 task 106, cassi-2.1: 0.73 mm at 145.6 Hz, 0.49 mm at 500 Hz; the threshold is 1 mm).
RATE_DEPENDENT = {"corner_jump_switch"}


def resample(rec: TaskRecording, period_us: int) -> TaskRecording:
    """``rec`` at ``period_us``: pellets linearly interpolated; a row is valid where both XRMB
    rows around it are."""
    t = np.arange(int(rec.time_us[0]), int(rec.time_us[-1]) + 1, period_us, dtype=np.int64)
    xy = np.empty((len(t),) + rec.xy_mm.shape[1:])
    for p in range(rec.xy_mm.shape[1]):
        for c in range(2):
            xy[:, p, c] = np.interp(t, rec.time_us, np.nan_to_num(rec.xy_mm[:, p, c]))
    k = np.clip(np.searchsorted(rec.time_us, t), 1, len(rec.time_us) - 1)
    valid = rec.valid[k] & rec.valid[k - 1]
    xy[~valid] = np.nan
    return TaskRecording(None, rec.subject, rec.task, rec.rep, t, xy, valid)


def _corpus(root, *, period_us=None):
    src = corpus_root(None)
    (root / "JW11").mkdir(parents=True)
    shutil.copy(src / "Headmeasures.txt", root)
    for name in ("Mis.dat", "PAL.DAT", "PHA.DAT"):
        shutil.copy(src / "JW11" / name, root / "JW11")
    # every task file of the subject, so its profile (thesis 4.2.1: rest, protrusion) is the
    # subject's, as a real corpus's would be, not task 106's alone
    for path in sorted((src / "JW11").glob("tp*.txy")):
        rec = read_txy(path)
        if period_us is not None:
            rec = resample(rec, period_us)
        write_txy(root / "JW11" / path.name, rec)
    rec = read_txy(root / "JW11" / "tp106.txy")
    seconds = (rec.time_us[-1] - rec.time_us[0]) / 1e6
    t = np.arange(int(seconds * AUDIO_RATE)) / AUDIO_RATE
    tone = np.where(t >= TONE_AT_S, 0.5 * np.sin(2 * np.pi * 440 * t), 0.0)
    wavfile.write(root / "JW11" / "tp106.wav", AUDIO_RATE, (tone * 32767).astype(np.int16))
    (root / "JW11" / "tp106.lab").write_text(
        f"signal tp106\nnfields 1\n#\n {TONE_AT_S:.4f} 26 sil\n {seconds:.4f} 26 aa\n")
    return rec


def _run(tmp_path, name, *, period_us=None, animate_stride):
    corpus = tmp_path / name
    rec = _corpus(corpus, period_us=period_us)
    run = tmp_path / f"{name}-run"
    assert cli_main(["run", "--corpus", str(corpus), "--subjects", "JW11", "--tasks", "106",
                     "--versions", "cassi-2.1", "--views", "front", "--stride", "0",
                     "--extremes", "1", "--animate-stride", str(animate_stride),
                     "--no-progress", "--out", str(run)]) == 0
    write_report(run, tmp_path / f"{name}-report")
    return corpus, rec, run, tmp_path / f"{name}-report"


def _viewer(report):
    text = (report / "viewer" / "JW11" / "106_1.js").read_text()
    return json.loads(text[len("window.CASSI_VIEWER = "):-2])


def _onset_s(video) -> float:
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(video), "-vn", "-ac", "1",
           "-ar", "8000", "-f", "s16le", "-"]
    audio = np.frombuffer(subprocess.run(cmd, check=True, capture_output=True).stdout, np.int16)
    return np.flatnonzero(np.abs(audio) > 0.1 * 32768)[0] / 8000


def _export_times(corpus, out, stride) -> np.ndarray:
    assert cli_main(["export", "--corpus", str(corpus), "--subject", "JW11", "--task", "106",
                     "--version", "cassi-2.1", "--format", "gltf", "--stride", str(stride),
                     "--out", str(out)]) == 0
    gltf, binary = chunks(out.read_bytes())
    return accessor(gltf, binary, gltf["animations"][0]["samplers"][0]["input"])[:, 0]


def test_a_500_hz_recording_gives_the_results_of_its_145_hz_original(tmp_path):
    xc, xrec, xrun, xrep = _run(tmp_path, "xrmb", animate_stride=24)          # 164.8 ms
    ec, erec, erun, erep = _run(tmp_path, "ema", period_us=EMA_US, animate_stride=82)  # 164 ms
    assert erec.period_us == EMA_US and xrec.period_us == 6866
    # the checks: the same rows, values within the tolerance
    x = pd.read_parquet(xrun / "results.parquet")
    e = pd.read_parquet(erun / "results.parquet")
    # the whole-file rows (frame -1), which carry the verdicts; a check's evidence-frame value
    # is its worst single row, which rows of another length sample differently
    x, e = (d[(d["view"] == "geometry") & (d["frame"] == -1)] for d in (x, e))
    both = x.groupby("check")["value"].max().to_frame("x").join(
        e.groupby("check")["value"].max().to_frame("e"), how="inner").dropna()
    assert len(both) >= 15 and set(x["check"]) == set(e["check"])
    off = both[~np.isclose(both["e"], both["x"], rtol=VALUE_RTOL, atol=VALUE_ATOL)]
    off = off.drop(index=list(RATE_DEPENDENT & set(off.index)))
    assert off.empty, off
    negatives = [d.groupby("check")["negatives"].sum() for d in (x, e)]
    assert negatives[0].equals(negatives[1])
    # the viewer: the recording's own rate, the same span of time, labels and the sound
    xv, ev = _viewer(xrep), _viewer(erep)
    assert ev["rate_hz"] == pytest.approx(500.0) and xv["rate_hz"] == pytest.approx(145.6, abs=0.1)
    assert ev["stride"] == 14 and xv["stride"] == 4          # about 28 ms either way
    assert ev["audio"] and ev["waveform"]["seconds"] == pytest.approx(
        (erec.time_us[-1] - erec.time_us[0]) / 1e6, abs=1 / AUDIO_RATE)
    assert ev["labels"]["phones"][0][1] == pytest.approx(TONE_AT_S)
    # the video: real time at either rate, the sound in sync with the label's time
    for report, rec, stride in ((xrep, xrec, 24), (erep, erec, 82)):
        (video,) = (report / "videos").glob("*.mp4")
        n, secs = imageio_ffmpeg.count_frames_and_secs(str(video))
        fps = 1e6 / (rec.period_us * stride)
        assert secs == pytest.approx(n / fps, abs=0.1)
        assert n / fps == pytest.approx((rec.time_us[-1] - rec.time_us[0]) / 1e6, abs=0.2)
        assert _onset_s(video) == pytest.approx(TONE_AT_S - rec.time_us[0] / 1e6, abs=0.03)
    # the export: keyed at the recording's times, every 28 ms at either rate
    xt = _export_times(xc, tmp_path / "x.glb", 4)
    et = _export_times(ec, tmp_path / "e.glb", 14)
    assert np.allclose(np.diff(xt), 4 * 6866e-6, atol=1e-5)
    assert np.allclose(np.diff(et), 14 * EMA_US * 1e-6, atol=1e-5)
    assert et[-1] == pytest.approx(xt[-1], abs=0.03)
