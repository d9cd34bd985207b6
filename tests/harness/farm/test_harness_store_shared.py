"""A store shared between runs (`cassi run --cache`, a nightly directory's store): reuse by
digest, per-version code digests, the packages in the digest, garbage collection, media."""
from __future__ import annotations

import dataclasses
import datetime as dt
import json
import os
from pathlib import Path

import pandas as pd
import pytest

from cassi.common.errors import CassiInputError
from cassi.data.synth.corpus import make_corpus
from cassi.harness.evaluation import provenance
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.nightly import nightly
from cassi.harness.evaluation.nights import gc
from cassi.harness.evaluation.run import run
from cassi.harness.farm.jobs import Job, StageContext
from cassi.harness.farm.store import collect_garbage, store_lock
from cassi.reports import media
from cassi.reports.nightly import review_night

VERSIONS = ("cassi-1.0", "cassi-2.1")


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW45"])


def _cfg(corpus, out, cache, **kw):
    base = dict(out=out, corpus=corpus, cache=cache, subjects=("JW45",), tasks=(2,),
                versions=VERSIONS, views=("geometry",), workers=1)
    return RunConfig(**{**base, **kw})


def _states(result) -> dict[str, str]:
    return {k: r.state.value for k, r in result.records.items()}


def test_a_second_run_reuses_every_job_from_the_store(corpus, tmp_path):
    first = run(_cfg(corpus, tmp_path / "a", tmp_path / "store"), progress=False)
    assert set(_states(first).values()) == {"done"} and first.summary.reused == 0
    second = run(_cfg(corpus, tmp_path / "b", tmp_path / "store"), progress=False)
    assert set(_states(second).values()) == {"cached"}
    assert second.summary.reused == len(second.records)
    assert "reused from the shared store" in second.summary.text()
    for name in ("results.csv", "ratings.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    # the run directory is whole by itself: its blobs are links to the store's, not copies
    blobs = sorted((tmp_path / "b" / "objects").glob("*/*"))
    assert blobs and all(b.stat().st_nlink == 3 for b in blobs)  # store, a, b


def test_one_versions_code_changes_only_its_jobs(tmp_path):
    """A job's digest takes the shared code and its own version's code only: another digest
    for cassi-2.1 changes 2.1's jobs and leaves 1.0's (the store then reuses 1.0's). Workers
    check that they run the code the driver planned with, so the change is made in the plan,
    as a real edit of versions/cassi21.py would change it."""
    ctx = StageContext(out_dir=tmp_path, provenance="shared",
                       version_provenance=(("cassi-1.0", "d10"), ("cassi-2.1", "d21")))
    edited = dataclasses.replace(ctx, version_provenance=(("cassi-1.0", "d10"),
                                                          ("cassi-2.1", "d21-edited")))
    jobs = {v: Job("geometry", "JW45", 2, 1, v, "geometry") for v in VERSIONS}
    assert jobs["cassi-1.0"].digest(ctx.salt("cassi-1.0")) == \
        jobs["cassi-1.0"].digest(edited.salt("cassi-1.0"))
    assert jobs["cassi-2.1"].digest(ctx.salt("cassi-2.1")) != \
        jobs["cassi-2.1"].digest(edited.salt("cassi-2.1"))
    assert ctx.salt("cassi-1.0") != ctx.salt("cassi-2.1")


def test_the_versions_code_digests_follow_their_imports():
    closures = provenance._closures()
    assert "cassi.versions.cassi21" in closures["cassi-2.1"]
    assert "cassi.versions.cassi21" not in closures["cassi-1.0"]
    assert "cassi.versions.lips" not in closures["cassi-1.0"]      # 2.x's lips only
    assert "cassi.versions.protocol" in closures["cassi-1.0"]     # shared: in every version's
    assert "cassi.versions.cassi10" in closures["cassi-2.0"]      # 2.0 builds on 1.0
    if "cassi-3.0" in closures:                                   # the plug-in imports 2.1
        assert "cassi.versions.cassi21" in closures["cassi-3.0"]
    assert provenance.version_digest("cassi-1.0") != provenance.version_digest("cassi-2.1")


def test_the_packages_that_shape_results_are_in_every_digest(corpus, tmp_path, monkeypatch):
    run(_cfg(corpus, tmp_path / "a", tmp_path / "store"), progress=False)
    pkgs = provenance.package_versions()
    assert {"numpy", "mitsuba", "drjit"} <= set(pkgs)
    monkeypatch.setattr(provenance, "package_versions", lambda: {**pkgs, "mitsuba": "9.9.9"})
    again = run(_cfg(corpus, tmp_path / "b", tmp_path / "store"), progress=False)
    assert set(_states(again).values()) == {"done"}  # upgrading Mitsuba recomputes


def test_reports_and_benchmarks_are_not_in_the_job_digest(tmp_path, monkeypatch):
    """They never run inside a job: editing them must not recompute a night."""
    files = provenance.shared_code_files()
    reports = provenance._package_dirs("cassi.reports")[0].resolve()
    bench = provenance._package_dirs("cassi.harness.bench")[0].resolve()
    stages = provenance._package_dirs("cassi.harness.evaluation")[0].resolve() / "stages.py"
    assert stages in {f.resolve() for f in files}                 # the harness's code is in
    assert not any(f.resolve().is_relative_to(reports) or f.resolve().is_relative_to(bench)
                   for f in files)


def test_gc_keeps_the_newest_nights_and_what_they_link(corpus, tmp_path):
    root = tmp_path / "nightly"
    for day in (1, 2, 3):
        store = root / "store"
        out = root / "runs" / f"2026-11-0{day}"
        cfg = _cfg(corpus, out, store, versions=VERSIONS[:1] if day == 1 else VERSIONS[1:])
        run(cfg, progress=False)
    only_first = {p.name for p in (root / "runs" / "2026-11-01" / "objects").glob("*/*")}
    kept_blobs = {p.name for d in ("2026-11-02", "2026-11-03")
                  for p in (root / "runs" / d / "objects").glob("*/*")}
    assert only_first - kept_blobs
    out = gc(root, keep=2)
    assert out["nights_removed"] == ["2026-11-01"] and not (root / "runs" / "2026-11-01").exists()
    left = {p.name for p in (root / "store" / "objects").glob("*/*")}
    assert left == kept_blobs                    # every blob a kept night links, nothing else
    assert out["blobs_removed"] == len(only_first - kept_blobs)
    # the kept nights' jobs still verify: a rerun into the newest reuses all of them
    again = run(_cfg(corpus, root / "runs" / "2026-11-03", root / "store",
                     versions=VERSIONS[1:]), progress=False)
    assert set(_states(again).values()) == {"cached"}
    with pytest.raises(CassiInputError, match="at least 1"):
        gc(root, keep=0)


def test_gc_refuses_while_a_run_holds_the_store(tmp_path):
    store = tmp_path / "store"
    (store / "objects").mkdir(parents=True)
    (store / "manifests").mkdir()
    with store_lock(store, exclusive=False):
        with pytest.raises(CassiInputError, match="a run is using this store"):
            with store_lock(store, exclusive=True):
                pass
    assert collect_garbage(store).blobs == 0


@pytest.mark.render
def test_a_second_night_reuses_its_jobs_and_its_videos(corpus, tmp_path, monkeypatch, capsys):
    cfg = RunConfig(subjects=("JW45",), tasks=(13,), versions=VERSIONS, views=("front",),
                    stride=0, extremes=1, animate_stride=40, workers=1)
    ok1, _ = nightly(tmp_path, review=review_night, corpus=corpus, config=cfg,
                     today=dt.date(2026, 11, 20), progress=True)
    videos1 = sorted((tmp_path / "reports" / "2026-11-20").rglob("*.mp4"))
    assert ok1 and videos1
    calls = []
    monkeypatch.setattr(media, "write_animation", lambda *a, **k: calls.append(a))
    ok2, _ = nightly(tmp_path, review=review_night, corpus=corpus, config=cfg,
                     today=dt.date(2026, 11, 21), progress=True)
    assert ok2 and not calls                       # every video linked from the store
    err = capsys.readouterr().err
    summary = json.loads((tmp_path / "runs" / "2026-11-21" / "summary.json").read_text())
    assert summary["reused"] == summary["jobs"] > 0
    assert f"jobs reused from earlier nights (same inputs and code): {summary['jobs']} of" in err
    videos2 = sorted((tmp_path / "reports" / "2026-11-21").rglob("*.mp4"))
    assert [v.name for v in videos2] == [v.name for v in videos1]
    assert all(a.stat().st_ino == b.stat().st_ino for a, b in zip(videos1, videos2))
    gates = json.loads((tmp_path / "runs" / "2026-11-21" / "gate.json").read_text())
    assert gates["passed"] and all(g["status"] == "pass" for g in gates["gates"])
    assert pd.read_csv(tmp_path / "history.csv")["night"].nunique() == 2


def test_cassi_gc_command(corpus, tmp_path, capsys):
    from cassi.harness.cli import main as cli_main

    store = tmp_path / "store"
    run(_cfg(corpus, tmp_path / "a", store), progress=False)
    assert cli_main(["gc", str(store)]) == 0          # an ad-hoc store: run a links everything
    assert "removed 0 object(s)" in capsys.readouterr().out
    assert cli_main(["gc", str(tmp_path / "a")]) == 2  # neither a nightly directory nor a store
    assert "neither a nightly directory" in capsys.readouterr().err
