"""A night's budget: the mask blob keeps depth only where the image measures read it (the
measures are unchanged), its format is in every job's digest, and the nightly's frame policy."""
from __future__ import annotations

import argparse

import numpy as np
import pytest

from cassi.harness.evaluation import run as run_mod
from cassi.harness.evaluation.config import NIGHTLY, NIGHTLY_VIDEO_VERSIONS, RunConfig
from cassi.harness.evaluation.frames import video_views
from cassi.harness.evaluation.stages import masks_blob, read_masks_blob
from cassi.harness.farm.jobs import Job, StageContext
from cassi.harness.rubric.image import FrameMasks, FrameStats
from cassi.harness.commands import config_from_args, register

NAMES = ("background", "skin", "lips", "teeth_upper", "tongue", "teeth_lower")


def _frame():
    mask = np.zeros((64, 64), np.uint8)
    mask[10:50, 5:60] = 1
    mask[20:40, 15:50] = 2
    mask[26:34, 20:45] = 0   # the opening (background behind it here)
    mask[26:29, 22:43] = 3
    mask[31:34, 22:43] = 5
    mask[29:31, 25:40] = 4
    rng = np.random.default_rng(0)
    depth = np.where(mask > 0, 100 + rng.random(mask.shape) * 5, np.inf).astype(np.float32)
    depth[29:31, 25:40] = 90.0  # tongue in front of the teeth
    return mask, depth


def test_mask_blob_keeps_depth_exactly_where_read_and_measures_are_unchanged():
    mask, depth = _frame()
    stored = read_masks_blob(masks_blob(mask, depth, NAMES))
    # the crop of what the measures read (lips rows 20-39, columns 15-49) and a ring of one pixel
    assert stored.origin == (19, 14) and stored.mask.shape == (22, 37)
    assert stored.shape == (64, 64)
    whole = stored.full()
    assert np.array_equal(whole.mask[19:41, 14:51], mask[19:41, 14:51])
    assert not whole.mask[:19].any() and not whole.mask[41:].any()
    read = np.isin(mask, [3, 4, 5])
    assert np.array_equal(whole.depth[read], depth[read])
    assert np.all(np.isinf(whole.depth[~read]))

    class Full:
        pass
    full = Full()
    full.mask, full.depth, full.part_names = mask.astype(np.int32), depth, NAMES
    assert FrameStats.of(FrameMasks.of(0, stored)) == FrameStats.of(FrameMasks.of(0, full))
    assert FrameStats.of(FrameMasks.of(0, stored)).tongue_in_front > 0


def test_masks_format_changes_every_job_digest(monkeypatch):
    cfg = RunConfig()
    job = Job(stage="render", subject="JW11", task=19, rep=1, version="cassi-2.1", view="front")
    before = job.digest(StageContext(out_dir=".", options=run_mod.run_options(cfg)).salt())
    monkeypatch.setattr(run_mod, "MASKS_FORMAT", run_mod.MASKS_FORMAT + 1)
    after = job.digest(StageContext(out_dir=".", options=run_mod.run_options(cfg)).salt())
    assert before != after


def test_nightly_frame_policy_front_grid_for_every_version_and_no_four_view_grid():
    assert NIGHTLY_VIDEO_VERSIONS == ()
    for version in ("cassi-1.0", "cassi-2.1"):
        assert video_views(19, version, NIGHTLY_VIDEO_VERSIONS) == ("front",)
    assert video_views(19, "cassi-2.1", ("cassi-2.1",)) == ("front", "side", "half", "top")


@pytest.mark.parametrize("command", ["run", "nightly"])
def test_video_versions_words_mean_the_same_in_run_and_nightly(command):
    def video_versions(*flag):
        args = _parser().parse_args([command, "--out", "o", *flag])
        return config_from_args(args, NIGHTLY if command == "nightly" else RunConfig()).video_versions

    assert video_versions("--video-versions", "none") == () == video_versions("--video-versions", "")
    assert video_versions("--video-versions", "all") is None
    assert video_versions("--video-versions", "cassi-2.1, cassi-3.0") == ("cassi-2.1", "cassi-3.0")
    assert video_versions() == (() if command == "nightly" else None)


def _parser():
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="command"))
    return p
