"""A large run's video grid that nobody looks at is rendered as masks only: the region that holds
what the image measures read, the very pixels of a whole frame, and the same results."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from cassi.data.synth.corpus import make_corpus
from cassi.harness.evaluation import frames as frame_policy
from cassi.harness.evaluation.caches import (get_corpus, get_face, get_profile, get_renderer,
                                             get_version_face)
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.run import run
from cassi.harness.evaluation.stages import masks_blob, read_masks_blob
from cassi.harness.farm.jobs import Job
from cassi.harness.farm.plan import BatchPlan, TaskSpec
from cassi.harness.rubric.image import FrameMasks, FrameStats, is_read
from cassi.versions.registry import get_version


def _plan(masks_only=()):
    return BatchPlan.build([TaskSpec("JW11", 19), TaskSpec("JW11", 106)], ["cassi-2.1"],
                           ["front", "side"], chunk_size=4, render=True, images=True,
                           masks_only=masks_only)


def test_masks_only_chunks_keep_the_shown_frames_pictured_and_the_image_job_whole():
    meta = {"render_frames": [0, 5, 50], "render_frames_by_view": {"front": list(range(0, 100, 10)) + [5]}}
    manifest = {"meta": meta, "outputs": {}}
    geometry = Job("geometry", "JW11", 19, 1, "cassi-2.1")
    plain = _plan().render_jobs(geometry, manifest)
    split = _plan({("JW11", 19, 1, "front")}).render_jobs(geometry, manifest)
    assert all(j.pictures for j in plain["front"]) and [j.key for j in plain["side"]] == \
        [j.key for j in split["side"]]
    pictured = [j for j in split["front"] if j.pictures]
    masks = [j for j in split["front"] if not j.pictures]
    assert [f for j in pictured for f in j.frames] == [0, 5, 50]
    assert [f for j in masks for f in j.frames] == [10, 20, 30, 40, 60, 70, 80, 90]
    assert masks[0].key == "JW11/019-1/cassi-2.1/front/masks-000"
    assert len(pictured) == 1 and len(masks) == 1  # chunks of 4 pictures, or of 16 masks
    assert len({j.key for j in split["front"]}) == len(split["front"])
    whole = BatchPlan.image_job(split["front"], [])
    assert whole.frames == tuple(sorted([0, 5, 50, 10, 20, 30, 40, 60, 70, 80, 90]))
    assert whole.frames == BatchPlan.image_job(plain["front"], []).frames


def test_only_a_large_run_renders_masks_only_and_never_the_compared_tasks(monkeypatch):
    tasks = [TaskSpec("JW11", t) for t in (5, 19, 106, 118)] + [TaskSpec("JW12", 7, usable=False)]
    views = ("front", "side", "half", "top")
    assert frame_policy.masks_only(tasks, views) == frozenset()
    monkeypatch.setattr(frame_policy, "ALL_RENDERS_UP_TO", 3)
    assert frame_policy.masks_only(tasks, views) == {("JW11", 5, 1, "front"),
                                                      ("JW11", 19, 1, "front")}
    monkeypatch.setattr(frame_policy, "ALL_RENDERS_UP_TO", 4)  # the unusable file does not count
    assert frame_policy.masks_only(tasks, views) == frozenset()


def test_an_image_job_follows_only_the_views_an_image_check_judges():
    tasks = [TaskSpec("JW11", 19), TaskSpec("JW11", 106), TaskSpec("JW12", 7, usable=False)]
    views = ("front", "side", "half", "top")
    judged = frame_policy.judged_views(tasks, views)
    assert judged == {("JW11", 19, 1, "front"), ("JW11", 106, 1, "front")}
    plan = BatchPlan.build(tasks, ["cassi-2.1"], views, chunk_size=4, render=True, images=True,
                           judged=judged)
    render = Job("render", "JW11", 19, 1, "cassi-2.1", "front", (0,))
    assert plan.judges(render)
    assert not plan.judges(Job("render", "JW11", 19, 1, "cassi-2.1", "side", (0,)))
    assert not plan.judges(Job("render", "JW11", 19, 1, "cassi-2.1", "front", (0,), evidence=True))
    unsaid = BatchPlan.build(tasks, ["cassi-2.1"], views, chunk_size=4, render=True, images=True)
    assert unsaid.judges(Job("render", "JW11", 19, 1, "cassi-2.1", "side", (0,)))  # every view
    none = BatchPlan.build(tasks, ["cassi-2.1"], views, chunk_size=4, render=True, images=False)
    assert not none.judges(render)


@pytest.mark.render
def test_a_region_holds_the_whole_frames_pixels_and_gives_the_same_masks_blob(tmp_path):
    corpus = get_corpus(make_corpus(tmp_path / "c", subjects=["JW45"]))
    profile = get_profile(corpus, "JW45")
    rec = corpus.subject("JW45").load(2)
    for version in ("parke-1974", "cassi-2.1"):
        face = get_version_face(corpus, "JW45", profile, get_version(version))
        anim = get_version(version).animate(profile, get_face(corpus, "JW45", profile), rec)
        renderer = get_renderer(corpus, "JW45", face, "front", "preview", None)
        for k in range(0, len(anim.frames), max(1, len(anim.frames) // 12)):
            whole = renderer.render(anim.positions[k])
            mask, depth, (r, c) = renderer.render_region(anim.positions[k], is_read)
            h, w = mask.shape
            assert 0 < h < whole.mask.shape[0] and 0 < w < whole.mask.shape[1]
            assert np.array_equal(whole.mask[r:r + h, c:c + w], mask)
            assert np.array_equal(whole.depth[r:r + h, c:c + w], depth)
            blob = masks_blob(mask, depth, renderer.part_names, origin=(r, c),
                              shape=whole.mask.shape)
            assert blob == masks_blob(whole.mask, whole.depth, whole.part_names)
            assert FrameStats.of(FrameMasks.of(k, read_masks_blob(blob))) == \
                FrameStats.of(FrameMasks.of(k, whole))


def test_a_region_that_cuts_what_the_measures_read_is_refused():
    names = ("background", "skin", "lips")
    mask = np.zeros((8, 8), np.int32)
    mask[0:3, 2:5] = 2  # lips on the region's top edge, which is not the frame's
    with pytest.raises(ValueError, match="cuts the parts the image measures read"):
        masks_blob(mask, np.zeros((8, 8), np.float32), names, origin=(10, 10), shape=(64, 64))
    masks_blob(mask, np.zeros((8, 8), np.float32), names, origin=(0, 10), shape=(64, 64))


@pytest.mark.render
def test_a_large_runs_masks_only_grid_gives_the_same_results(tmp_path, monkeypatch):
    corpus = make_corpus(tmp_path / "c", subjects=["JW45"])

    def night(name):
        out = tmp_path / name
        run(RunConfig(out=out, corpus=corpus, subjects=("JW45",), tasks=(2, 5),
                      versions=("cassi-1.0", "cassi-2.1"), views=("front", "side"), stride=0,
                      extremes=1, animate_stride=24, workers=1), progress=False)
        return out

    plain = night("plain")
    monkeypatch.setattr(frame_policy, "ALL_RENDERS_UP_TO", 1)
    large = night("large")
    assert (plain / "results.parquet").read_bytes() == (large / "results.parquet").read_bytes()
    renders = {n: pd.read_parquet(d / "renders.parquet") for n, d in (("plain", plain), ("large", large))}
    front = {n: r[r["view"] == "front"] for n, r in renders.items()}
    # the pictures left: each file's first and check frames; the judged grid only as masks
    assert len(front["large"]) < len(front["plain"]) / 3
    shown = set(map(tuple, front["large"][["task", "version", "frame"]].values.tolist()))
    assert shown < set(map(tuple, front["plain"][["task", "version", "frame"]].values.tolist()))
    side = {n: r[r["view"] == "side"].reset_index(drop=True) for n, r in renders.items()}
    assert side["large"].drop(columns="path").equals(side["plain"].drop(columns="path"))
    masks_jobs = [p.name for p in (large / "jobs").rglob("*.json") if "masks-" in p.name]
    assert masks_jobs and not [p for p in (plain / "jobs").rglob("*.json") if "masks-" in p.name]
    # the side view's renders are followed by no image job: no image check judges it
    checks = [p.parent.name for p in (plain / "jobs").rglob("checks.json")]
    assert len(checks) == 4 and set(checks) == {"front"}
