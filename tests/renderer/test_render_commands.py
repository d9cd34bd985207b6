"""`cassi render` and `cassi animate` end to end on a one-subject synthetic corpus."""
from __future__ import annotations

import importlib
import json

import numpy as np
import pytest

from cassi.harness.cli import main
from cassi.renderer.images import read_image, read_metadata

pytestmark = pytest.mark.render


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    importlib.import_module("cassi.data.face.model")
    from cassi.data.synth.corpus import make_corpus

    return make_corpus(tmp_path_factory.mktemp("corpus"), subjects=["JW45"])


def _first_task(corpus):
    from cassi.data.corpus.disk import Corpus

    return Corpus(corpus).subject("JW45").tasks()[0][0]


def test_render_neutral_png_with_mask(corpus, tmp_path, capsys):
    task = _first_task(corpus)
    out = tmp_path / "img" / "front.png"
    rc = main(["render", "--corpus", str(corpus), "--subject", "JW45", "--task", str(task),
               "--version", "neutral", "--view", "front", "--frame", "3", "--out", str(out),
               "--mask"])
    assert rc == 0
    img = read_image(out)
    assert img.shape == (256, 256, 3) and img.dtype == np.uint8
    meta = read_metadata(out)
    assert meta["variant"] and meta["version"] == "neutral" and meta["frame"] == 3
    side = json.loads((tmp_path / "img" / "front.png.json").read_text())
    assert side["subject"] == "JW45" and side["view"] == "front"
    mask = read_image(tmp_path / "img" / "front.mask.png")[..., 0]
    assert (mask > 0).mean() > 0.1
    assert str(out) in capsys.readouterr().out


def test_render_bad_input_exit_2(corpus, tmp_path, capsys):
    task = _first_task(corpus)
    base = ["render", "--corpus", str(corpus), "--subject", "JW45", "--task", str(task),
            "--view", "half", "--frame", "0"]
    assert main(base + ["--version", "no-such-version", "--out", str(tmp_path / "a.png")]) == 2
    assert "unknown version 'no-such-version'" in capsys.readouterr().err
    assert main(base + ["--version", "neutral", "--out", str(tmp_path / "a.jpg")]) == 2
    assert main(base + ["--version", "neutral", "--frame", "999999",
                        "--out", str(tmp_path / "a.png")]) == 2
    assert "not animated" in capsys.readouterr().err
    assert main(base + ["--version", "neutral", "--variant", "vulkan",
                        "--out", str(tmp_path / "a.png")]) == 2
    assert not list(tmp_path.iterdir())


def test_animate_neutral_mp4(corpus, tmp_path):
    import imageio_ffmpeg

    task = _first_task(corpus)
    out = tmp_path / "a.mp4"
    rc = main(["animate", "--corpus", str(corpus), "--subject", "JW45", "--task", str(task),
               "--version", "neutral", "--views", "front,half", "--out", str(out)])
    assert rc == 0
    reader = imageio_ffmpeg.read_frames(str(out))
    meta = next(reader)
    assert tuple(meta["size"]) == (512, 256)  # two 256-pixel views side by side
    assert sum(1 for _ in reader) == 1


def test_two_processes_write_byte_identical_previews(corpus, tmp_path):
    """The preview is one ray per pixel centre, no sampling: two `cassi render` processes of
    the same frame write the same PNG bytes (acceptance of issue 12)."""
    import subprocess
    import sys

    task = _first_task(corpus)
    outs = [tmp_path / f"p{i}.png" for i in (1, 2)]
    for out in outs:
        cmd = [sys.executable, "-m", "cassi.harness.cli", "render", "--corpus", str(corpus),
               "--subject", "JW45", "--task", str(task), "--version", "cassi-2.1",
               "--view", "half", "--frame", "40", "--out", str(out)]
        subprocess.run(cmd, check=True, capture_output=True, timeout=300)
    assert outs[0].read_bytes() == outs[1].read_bytes()
    assert read_metadata(outs[0])["version"] == "cassi-2.1"
