"""A real browser opens the report: headless Chromium (Debian's, installed by .ci/run) takes a
screenshot, which must show the rating tables (their coloured cells) and the images."""
from __future__ import annotations

import subprocess

import imageio.v3 as iio
import numpy as np
import pytest

from browsers import chromium
from reports_fixtures import image, results_rows, write_run
from cassi.reports.report import write_report

pytestmark = pytest.mark.browser


def test_chromium_screenshot_shows_tables_and_images(tmp_path):
    browser = chromium()
    res = results_rows({("cassi-1.0", "JW11", "lip_gap_start"): 3,
                        ("cassi-2.0", "JW12", "tongue_through_teeth"): 6})
    run = write_run(tmp_path / "run", res, images={("JW11", 19, "cassi-1.0", "front", 0): image(1)})
    index = write_report(run, tmp_path / "report")
    shot = tmp_path / "shot.png"
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'profile'}", "--hide-scrollbars",
           "--window-size=1280,2400", f"--screenshot={shot}", index.as_uri()]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert shot.is_file(), proc.stderr[-2000:]
    img = np.asarray(iio.imread(shot))[..., :3].astype(int)
    # Rating cells are tinted by rating: EXCELLENT green (#d9f0d3) and UNACCEPTABLE red (#f6b3a8)
    # must both be on screen, so the tables rendered with their styles.
    def present(rgb):
        return int((np.abs(img - np.array(rgb)).sum(axis=-1) <= 6).sum())
    assert present((0xd9, 0xf0, 0xd3)) > 500
    assert present((0xf6, 0xb3, 0xa8)) > 100
    # The synthetic banner (#fff3cd) is shown at the top.
    assert present((0xff, 0xf3, 0xcd)) > 1000
