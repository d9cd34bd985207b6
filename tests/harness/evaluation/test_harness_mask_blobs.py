"""The render stage's part masks and depth are stored deflated: they were 4.4 of a night's
5.0 GB raw (329 KB a front frame), and the image checks read the same arrays back."""
from __future__ import annotations

import zipfile

import numpy as np
import pytest

from cassi.data.synth.corpus import make_corpus
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.run import run

pytestmark = pytest.mark.render


def test_mask_blobs_are_deflated_and_read_back_exactly(tmp_path):
    corpus = make_corpus(tmp_path / "c", subjects=["JW45"])
    out = tmp_path / "run"
    run(RunConfig(out=out, corpus=corpus, subjects=("JW45",), tasks=(2,), versions=("cassi-1.0",),
                  views=("front",), stride=0, extremes=1, workers=1), progress=False)
    masks = [p for p in (out / "objects").glob("*/*.npz")
             if "mask.npy" in zipfile.ZipFile(p).namelist()]
    assert masks
    for path in masks:
        with zipfile.ZipFile(path) as z:
            assert {i.compress_type for i in z.infolist()} == {zipfile.ZIP_DEFLATED}
            raw = sum(i.file_size for i in z.infolist())
        assert path.stat().st_size < raw / 3
        d = np.load(path)
        assert d["mask"].dtype == np.uint8 and d["depth"].dtype == np.float32
        assert d["mask"].shape == d["depth"].shape and d["mask"].max() > 0
