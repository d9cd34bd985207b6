"""Issue 42's "done when": an EMA corpus in every format (MOCHA-TIMIT's EST tracks, binary and
ASCII, under ``preset: mocha-timit``; TSV and CSV exports with their own coil maps; a 3-D
Carstens .pos with four reference coils and the occlusal plane) runs through
``cassi nightly --config`` with 2 workers, and the viewer of an utterance has its sound and its
xwaves labels. The recordings are JW11's synthetic tasks: they describe the software, not real
speakers."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from scipy.io import wavfile

from ema_writers import write_ema_speaker
from cassi.harness.cli import main as cli_main

pytestmark = pytest.mark.render

AUDIO_RATE = 16000  # MOCHA's sound
LABEL_END_S = 0.25  # the first label's end (xwaves: each time is a label's end)


def _corpus(root):
    est = write_ema_speaker(root, "fsew0", tasks=(5,))
    (root / "ema.yaml").write_text("preset: mocha-timit\n")
    write_ema_speaker(root, "nwave0", tasks=(7,), fmt="tsv")
    for name, fmt in (("fascii0", "est-ascii"), ("ncsv0", "csv"), ("ag501", "pos")):
        write_ema_speaker(root, name, tasks=(9,), fmt=fmt)
    seconds = 199 / 500  # 200 rows at 500 Hz
    tone = 0.3 * np.sin(2 * np.pi * 440 * np.arange(int(seconds * AUDIO_RATE)) / AUDIO_RATE)
    wavfile.write(est / "fsew0_001.wav", AUDIO_RATE, (tone * 32767).astype(np.int16))
    (est / "fsew0_001.lab").write_text(
        f"signal fsew0_001\nnfields 1\n#\n {LABEL_END_S:.4f} 26 sil\n {seconds:.4f} 26 aa\n")


def test_an_ema_corpus_in_every_format_runs_nightly(tmp_path, capsys):
    corpus = tmp_path / "ema"
    _corpus(corpus)
    config = tmp_path / "night.yaml"
    config.write_text(f"corpus: {corpus}\nversions: [cassi-2.1]\nviews: [front]\n"
                      "workers: 2\nextremes: 1\nanimate_stride: 50\n")
    night = tmp_path / "nightly"
    code = cli_main(["nightly", "--out", str(night), "--config", str(config), "--quiet"])
    assert code == 0, capsys.readouterr().err  # the first night records a baseline
    (run,) = (night / "runs").iterdir()
    results = pd.read_parquet(run / "results.parquet")
    # both formats judged, on the geometry and on the front view's renders
    views = results.groupby("subject")["view"].unique().map(frozenset)
    assert all({"geometry", "front"} <= v for v in views)
    assert sorted(results["subject"].unique()) == ["ag501", "fascii0", "fsew0", "ncsv0", "nwave0"]
    meta = json.loads((run / "run.json").read_text())
    # the Carstens speaker measured every pellet: nothing derived, nothing flagged
    assert sorted(meta["derived_pellets"]) == ["fascii0", "fsew0", "ncsv0", "nwave0"]
    (report,) = (night / "reports").iterdir()
    assert "EMA speakers were not measured" in (report / "index.html").read_text()
    text = (report / "viewer" / "fsew0" / "1001_1.js").read_text()
    viewer = json.loads(text[len("window.CASSI_VIEWER = "):-2])
    assert viewer["rate_hz"] == pytest.approx(500.0)
    assert viewer["audio"] and (report / "viewer" / "fsew0" / viewer["audio"]).is_file()
    assert viewer["waveform"]["seconds"] == pytest.approx(199 / 500, abs=1 / AUDIO_RATE)
    assert viewer["labels"]["phones"][0][1] == pytest.approx(LABEL_END_S)
    text = (report / "viewer" / "nwave0" / "1001_1.js").read_text()  # the TSV speaker's
    assert json.loads(text[len("window.CASSI_VIEWER = "):-2])["audio"] is None
