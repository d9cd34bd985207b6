"""`cassi run` end to end on the embedded default corpus with the real stages (versions, rubric,
renderer): bad input fails before any work, reruns reuse outputs, the run is saved resolved."""
from __future__ import annotations

import argparse
import json

import pandas as pd
import pytest

from cassi.common.errors import CassiInputError
from cassi.harness.evaluation import caches as P
from cassi.harness.evaluation import frames as F
from cassi.harness.evaluation import stages as S
from cassi.common.lazy import resolve
from cassi.harness.commands import register
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.run import run
from cassi.harness.farm.jobs import Job, StageContext
from cassi.harness.farm.store import OutputStore


def _cli(argv) -> int:
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="command"))
    args = p.parse_args(argv)
    return resolve(args.func)(args)


@pytest.mark.parametrize("change, match", [
    ({"subjects": ("JW99",)}, r"unknown subject JW99.*valid subjects: JW11, JW12"),
    ({"versions": ("cassi-9.9",)}, r"valid versions: .*cassi-1.0"),
    ({"views": ("back",)}, r"valid views: front, side, half, top, geometry"),
    ({"subjects": ("JW12",), "tasks": (999,)}, r"unknown task 999"),
])
def test_bad_names_fail_before_any_work(tmp_path, change, match):
    out = tmp_path / "out"
    with pytest.raises(CassiInputError, match=match):
        run(RunConfig(out=out, **change), progress=False)
    assert not out.exists()


def test_unwritable_or_locked_out_dir_is_a_clear_error(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    with pytest.raises(CassiInputError, match="not writable"):
        _cli(["run", "--out", str(tmp_path / "file" / "out"), "--subjects", "JW12",
              "--tasks", "2", "--versions", "cassi-1.0", "--views", "geometry"])
    store = OutputStore(tmp_path / "busy")
    store.prepare()
    with store.lock():
        with pytest.raises(CassiInputError, match="another cassi run"):
            _cli(["run", "--out", str(tmp_path / "busy"), "--subjects", "JW12", "--tasks", "2",
                  "--versions", "cassi-1.0", "--views", "geometry"])


def test_geometry_run_then_rerun(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["run", "--out", str(out), "--subjects", "JW12", "--tasks", "2", "118",
            "--versions", "cassi-1.0", "cassi-2.1", "--views", "geometry", "--no-progress"]
    assert _cli(argv) == 0
    first = (out / "results.csv").read_bytes()
    text = capsys.readouterr().out
    assert "4 done" in text
    df = pd.read_parquet(out / "results.parquet")
    assert set(df.view) == {"geometry", "criterion"} and set(df.version) == {"cassi-1.0", "cassi-2.1"}
    # 2.1's low-lips decision: one margin row per task file it animated (the stage keeps the
    # diagnostics it is read from), none for versions that make no such decision.
    crit = df[df.view == "criterion"]
    assert sorted(zip(crit.version, crit.task)) == [("cassi-2.1", 2), ("cassi-2.1", 118)]
    assert (crit.check == "low_lips_margin").all() and crit.value.notna().all()
    assert (crit.negatives == 0).all() and crit.table.isna().all()
    assert df.synthetic.all() and (df.frame == -1).any()
    assert {"D"} <= set(df[df.task == 118].table)  # task 118 adds Table D
    ratings = pd.read_parquet(out / "ratings.parquet")
    assert len(ratings) and ratings.rating.notna().all()
    meta = json.loads((out / "run.json").read_text())
    assert meta["synthetic"] is True and meta["package_version"] == "0.1.0"
    assert meta["tasks"] == [2, 118] and meta["summary"]["counts"]["done"] == 4
    assert "git_revision" in meta and "synthetic corpus" in meta["note"]
    assert _cli(argv) == 0
    assert "4 skipped as already done" in capsys.readouterr().out
    assert (out / "results.csv").read_bytes() == first


@pytest.mark.render
def test_render_stages_reuse_one_renderer_per_view(tmp_path):
    """In-process: geometry, then two render chunks of one view share one Mitsuba scene, then
    the image checks read both chunks."""
    from cassi.harness.farm.jobs import execute_job
    from cassi.harness.farm.runner import TaskSpec  # noqa: F401

    ctx = StageContext(out_dir=tmp_path, corpus=P.corpus_root(None), stride=0, chunk_size=2,
                       synthetic=True)
    OutputStore(tmp_path).prepare()
    geom = Job("geometry", "JW12", 2, 1, "cassi-2.1")
    out = execute_job(S.geometry_stage, geom, ctx, "d")
    frames = out.meta["render_frames"]
    assert frames and frames[0] == min(frames)
    before = P.cache_sizes()["renderers"]
    chunks = [tuple(frames[:1]), tuple(frames[1:2] or frames[:1])]
    keys = []
    for i, chunk in enumerate(chunks):
        job = Job("render", "JW12", 2, 1, "cassi-2.1", "front", chunk, i, parents=(geom.key,))
        assert execute_job(S.render_stage, job, ctx, f"r{i}").state.value == "done"
        keys.append(job.key)
    assert P.cache_sizes()["renderers"] == min(before + 1, P.RENDERERS_KEPT)
    renderer = next(reversed(P._renderers.values()))  # the most recently used
    assert renderer.loads == 1
    image = Job("image", "JW12", 2, 1, "cassi-2.1", "front", tuple(sorted(set(sum(chunks, ())))),
                parents=tuple(keys))
    res = execute_job(S.image_stage, image, ctx, "i")
    assert res.state.value == "done"
    rows = pd.read_parquet(OutputStore(tmp_path).path(
        OutputStore(tmp_path).read_manifest(image.key)["outputs"]["rows"]))
    assert (rows.view == "front").all() and (rows.frame == -1).any()
    # masks are kept only where image checks judge them (the front view), PNGs everywhere
    outputs = OutputStore(tmp_path).read_manifest(keys[0])["outputs"]
    assert any(n.startswith("masks-") for n in outputs)
    side = Job("render", "JW12", 2, 1, "cassi-2.1", "side", chunks[0], 0, parents=(geom.key,))
    assert execute_job(S.render_stage, side, ctx, "s").state.value == "done"
    outputs = OutputStore(tmp_path).read_manifest(side.key)["outputs"]
    assert any(n.startswith("render-") for n in outputs)
    assert not any(n.startswith("masks-") for n in outputs)


def test_a_worker_keeps_a_bounded_number_of_renderers(monkeypatch):
    """Scenes are dropped least recently used first, so a worker that meets every subject and
    view of a night does not grow by a scene (~6 MB) each time."""
    monkeypatch.setattr(P, "RENDERERS_KEPT", 2)
    monkeypatch.setattr(P, "_renderers", P.OrderedDict())
    c = P.get_corpus(None)
    profile = P.get_profile(c, "JW12")
    face = P.get_face(c, "JW12", profile)
    front = P.get_renderer(c, "JW12", face, "front", "preview", None)
    side = P.get_renderer(c, "JW12", face, "side", "preview", None)
    assert P.get_renderer(c, "JW12", face, "front", "preview", None) is front  # used again
    P.get_renderer(c, "JW12", face, "top", "preview", None)
    assert P.cache_sizes()["renderers"] == 2
    assert P.get_renderer(c, "JW12", face, "front", "preview", None) is front
    assert P.get_renderer(c, "JW12", face, "side", "preview", None) is not side  # was dropped


def test_extreme_frames_prefer_checks_that_fired():
    rows = pd.DataFrame([
        dict(frame=-1, check="a", negatives=0), dict(frame=40, check="a", negatives=0),
        dict(frame=-1, check="b", negatives=2), dict(frame=70, check="b", negatives=0),
        dict(frame=-1, check="c", negatives=1), dict(frame=10, check="c", negatives=0)])
    assert F.extreme_frames(rows, limit=2) == [10, 70]
    assert F.extreme_frames(rows) == [10, 40, 70]


def test_extreme_frames_ignore_the_fidelity_traces():
    rows = pd.DataFrame([
        dict(check="lip_gap", frame=-1, negatives=1, view="geometry"),
        dict(check="lip_gap", frame=40, negatives=0, view="geometry"),
        dict(check="lip_aperture", frame=10, negatives=0, view="trace"),
        dict(check="lip_aperture", frame=20, negatives=0, view="trace"),
    ])
    assert F.extreme_frames(rows, limit=8) == [40]
