"""Evidence render jobs: the frames a geometry job names for the report's links only are
rendered and listed in ``renders.parquet``, and no image job judges them, so the results are
the same with and without them."""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from cassi.harness.farm.executors import LocalExecutor
from cassi.harness.farm.jobs import Job, StageContext, StageOutput
from cassi.harness.farm.plan import BatchPlan, TaskSpec
from cassi.harness.farm.runner import Pipeline, run_batch
from cassi.harness.farm.store import OutputStore

META = {"render_frames": [0, 10], "render_frames_by_view": {"front": [0, 5, 10]},
        "evidence_frames_by_view": {"front": [5, 7], "side": [7], "top": [3]}}


def _plan() -> BatchPlan:
    return BatchPlan.build([TaskSpec("JW11", 19)], ["v1"], ["front", "side"], chunk_size=2,
                           render=True, images=True)


def test_evidence_chunks_are_rendered_apart_from_the_judged_ones():
    plan = _plan()
    geometry = plan.geometry[0]
    manifest = {"meta": META, "outputs": {}}
    judged = plan.render_jobs(geometry, manifest)
    evidence = plan.evidence_jobs(geometry, manifest)
    frames = lambda jobs: [f for j in jobs for f in j.frames]  # noqa: E731
    assert {v: frames(j) for v, j in judged.items()} == {"front": [0, 5, 10], "side": [0, 10]}
    # what a view renders for its image job anyway is not rendered twice; views the run
    # leaves out (top) are not rendered
    assert {v: frames(j) for v, j in evidence.items()} == {"front": [7], "side": [7]}
    assert all(j.evidence for js in evidence.values() for j in js)
    assert not any(j.evidence for js in judged.values() for j in js)
    keys = [j.key for js in (*judged.values(), *evidence.values()) for j in js]
    assert len(set(keys)) == len(keys) and evidence["front"][0].key.endswith("/front/evidence-000")
    assert plan.image_job(judged["front"], []).frames == (0, 5, 10)


def geom_stage(job: Job, ctx: StageContext, inputs) -> StageOutput:
    meta = dict(META) if ctx.option("evidence") else {k: v for k, v in META.items()
                                                      if k != "evidence_frames_by_view"}
    return StageOutput(rows=pd.DataFrame([dict(frame=-1, check="lip_gap", table="A",
                                               component="lips", value=1.0, negatives=0)]),
                       meta=meta)


def render_stage(job: Job, ctx: StageContext, inputs) -> StageOutput:
    return StageOutput(files={f"render-{f:06d}": (f"{job.view} {f}".encode(), ".png")
                              for f in job.frames})


def image_stage(job: Job, ctx: StageContext, inputs) -> StageOutput:
    """One row per frame judged, so a frame judged more or less shows in the results."""
    for f in job.frames:
        assert f"render-{f:06d}" in inputs
    return StageOutput(rows=pd.DataFrame([dict(frame=int(f), check="teeth_visible", table="A",
                                               component="teeth", value=float(f), negatives=0)
                                          for f in job.frames]))


def _run(out: Path, evidence: bool):
    ctx = StageContext(out_dir=out, chunk_size=2, options=(("evidence", evidence),))
    OutputStore(out).prepare()
    with LocalExecutor(1) as ex:
        res = run_batch([TaskSpec("JW11", 19)], ["v1"], ["front", "side"],
                        Pipeline(geometry=geom_stage, render=render_stage, image=image_stage),
                        ctx, ex, progress=False)
    assert res.ok
    return res, pd.read_parquet(out / "renders.parquet")


def test_evidence_frames_are_listed_and_never_judged(tmp_path):
    plain, plain_renders = _run(tmp_path / "plain", evidence=False)
    res, renders = _run(tmp_path / "evidence", evidence=True)
    pd.testing.assert_frame_equal(res.results, plain.results)
    judged = res.results[res.results["frame"] >= 0]
    assert sorted(zip(judged["view"], judged["frame"])) == \
        [("front", 0), ("front", 5), ("front", 10), ("side", 0), ("side", 10)]
    listed = set(zip(renders["view"], renders["frame"]))
    assert listed - set(zip(plain_renders["view"], plain_renders["frame"])) == \
        {("front", 7), ("side", 7)}
    assert any(k.endswith("/front/evidence-000") for k in res.records)
