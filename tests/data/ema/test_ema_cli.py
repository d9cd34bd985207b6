"""``cassi corpus check`` and ``cassi corpus convert`` on a small EMA corpus (real CLI)."""
from __future__ import annotations

import json

import numpy as np

from ema_writers import write_ema_speaker
from cassi.data.commands import main
from cassi.data.corpus.disk import Corpus
from cassi.harness.evaluation.caches import corpus_root


def _mocha_corpus(root):
    write_ema_speaker(root, "msak0")
    (root / "ema.yaml").write_text("preset: mocha-timit\n")
    return root


def test_check_and_convert(tmp_path, capsys):
    root = _mocha_corpus(tmp_path / "ema")
    assert main(["check", str(root), "--json"]) == 0
    records = json.loads(capsys.readouterr().out)
    assert [(r["subject"], r["task"], r["frames"], r["error_free"]) for r in records] == [
        ("msak0", 1001, 200, True), ("msak0", 1002, 200, True)]
    out = tmp_path / "xrmb"
    assert main(["convert", str(root), "--out", str(out)]) == 0
    assert sorted(p.name for p in (out / "msak0").iterdir()) == [
        "PAL.DAT", "ema_map.json", "tp1001.txy", "tp1002.txy"]
    resolved = json.loads((out / "msak0" / "ema_map.json").read_text())
    assert resolved["preset"] == "mocha-timit" and resolved["derived_pellets"] == ["T4", "MNM"]
    assert resolved["tasks"] == {"tp1001.txy": "msak0_001.ema", "tp1002.txy": "msak0_002.ema"}
    back = Corpus(out).subject("msak0").load(1001)
    ema = Corpus(root).subject("msak0").load(1001)
    assert np.abs(back.xy_mm - ema.xy_mm).max() <= 0.0005  # whole micrometres
    assert main(["convert", str(root), "--out", str(out)]) == 2  # never over a corpus
    assert "not an empty directory" in capsys.readouterr().err


def test_check_one_recording(tmp_path, capsys):
    root = _mocha_corpus(tmp_path / "ema")
    assert main(["check", str(root / "msak0" / "msak0_002.ema"), "--json"]) == 0
    (record,) = json.loads(capsys.readouterr().out)
    assert (record["subject"], record["task"], record["frames"]) == ("msak0", 1002, 200)
    data = (root / "msak0" / "msak0_002.ema").read_bytes()
    (root / "msak0" / "msak0_002.ema").write_bytes(data[:-6])
    assert main(["check", str(root / "msak0" / "msak0_002.ema")]) == 2
    assert "msak0_002.ema: truncated" in capsys.readouterr().err


def test_check_refuses_a_bad_map(tmp_path, capsys):
    root = _mocha_corpus(tmp_path / "ema")
    (root / "ema.yaml").write_text("preset: mocha-timit\nreferences: {}\n")
    assert main(["check", str(root)]) == 2
    assert "ema.yaml:2: no reference coils" in capsys.readouterr().err


def test_stats_put_an_ema_speaker_beside_an_xrmb_one(tmp_path, capsys):
    """`cassi corpus stats EMA --compare XRMB`: the same figures, side by side, each speaker at
    its own rate (500 Hz against 145.6 Hz)."""
    speaker = write_ema_speaker(tmp_path / "ema", "ncsv0", tasks=(9,), fmt="csv")
    xrmb = corpus_root(None) / "JW11"
    assert main(["stats", str(speaker), "--compare", str(xrmb)]) == 0
    out = capsys.readouterr().out
    assert f"# A: {speaker}" in out and f"# B: {xrmb}" in out
    jaw = next(line for line in out.splitlines() if line.startswith("jaw_distance_median"))
    assert jaw.split("\t")[1].startswith("42.6 | ")   # MNM derived by JW11's rigid jaw
