"""A night whose every job is in the store: it hashes no blob the store stamped, reads the
combined results from the store's memo, starts no worker; and every shortcut still notices
a blob written into since (the stamps), and a different set of jobs (the memo)."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from cassi.data.synth.corpus import make_corpus
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.run import run
from cassi.harness.farm import executors, results, runner, store
from cassi.harness.farm.store import Stamps, collect_garbage


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW45"])


def _cfg(corpus, out, cache, **kw):
    base = dict(out=out, corpus=corpus, cache=cache, subjects=("JW45",), tasks=(2, 13),
                versions=("cassi-1.0", "cassi-2.1"), views=("geometry",), workers=1)
    return RunConfig(**{**base, **kw})


@pytest.fixture
def new_process(monkeypatch):
    """What a later process knows: nothing hashed yet; returns the list of files it hashes."""
    hashed, real = [], store.sha256_file
    monkeypatch.setattr(store, "_HASHED", {})
    monkeypatch.setattr(store, "sha256_file", lambda p: hashed.append(str(p)) or real(p))
    return hashed


def test_a_reused_night_hashes_no_stamped_blob_and_starts_no_worker(corpus, tmp_path,
                                                                     new_process, monkeypatch):
    first = run(_cfg(corpus, tmp_path / "a", tmp_path / "store"), progress=False)
    assert (tmp_path / "store" / Stamps.NAME).is_file()
    new_process.clear()
    store._HASHED.clear()

    def no_worker(*_):
        raise AssertionError("a worker was started for a night with nothing to do")

    monkeypatch.setattr(executors.LocalExecutor, "_spawn", no_worker)
    second = run(_cfg(corpus, tmp_path / "b", tmp_path / "store"), progress=False)
    assert {r.state.value for r in second.records.values()} == {"cached"}
    assert new_process == []
    assert first.results.equals(second.results)
    for name in ("results.parquet", "ratings.parquet", "renders.parquet"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    # a job manifest reused under its own key is the store's file, linked
    jobs = sorted((tmp_path / "b" / "jobs").rglob("*.json"))
    assert jobs and all(p.stat().st_nlink >= 2 for p in jobs)


def test_a_blob_written_into_after_it_was_stamped_is_hashed_and_its_job_runs_again(
        corpus, tmp_path, new_process):
    run(_cfg(corpus, tmp_path / "a", tmp_path / "store"), progress=False)
    stamped = json.loads((tmp_path / "store" / Stamps.NAME).read_text())["blobs"]
    rows = next(rel for rel in sorted(stamped) if rel.endswith(".parquet"))
    blob = tmp_path / "store" / rows
    os.chmod(blob, 0o644)
    data = bytearray(blob.read_bytes())
    data[-1] ^= 0xFF  # same size: only the stat times give it away
    with open(blob, "r+b") as fh:
        fh.write(bytes(data))
    store._HASHED.clear()
    new_process.clear()
    second = run(_cfg(corpus, tmp_path / "b", tmp_path / "store"), progress=False)
    assert str(blob) in new_process  # hashed, not trusted
    states = {r.state.value for r in second.records.values()}
    assert "done" in states  # the job whose rows were damaged ran again
    assert (tmp_path / "a" / "results.parquet").read_bytes() == \
        (tmp_path / "b" / "results.parquet").read_bytes()


def test_the_combined_results_come_from_the_memo_only_for_the_same_jobs(corpus, tmp_path,
                                                                         monkeypatch):
    run(_cfg(corpus, tmp_path / "a", tmp_path / "store"), progress=False)
    combined = []
    real = results.combine
    monkeypatch.setattr(results, "combine", lambda frames: combined.append(1) or real(frames))
    run(_cfg(corpus, tmp_path / "b", tmp_path / "store"), progress=False)
    assert combined == []  # the same jobs' rows: the memo
    one = run(_cfg(corpus, tmp_path / "c", tmp_path / "store", versions=("cassi-1.0",)),
              progress=False)
    assert combined == [1]  # other jobs: combined again
    alone = run(_cfg(corpus, tmp_path / "d", None, versions=("cassi-1.0",)), progress=False)
    assert (tmp_path / "c" / "results.parquet").read_bytes() == \
        (tmp_path / "d" / "results.parquet").read_bytes()
    assert set(one.results["version"]) == {"cassi-1.0"}
    assert runner.COMBINED_MEMO in {p.name for p in (tmp_path / "store" / "memo").iterdir()}


def test_garbage_collection_forgets_the_stamps_and_memos_of_removed_blobs(corpus, tmp_path):
    import shutil
    run(_cfg(corpus, tmp_path / "a", tmp_path / "store"), progress=False)
    assert list((tmp_path / "store" / "memo").rglob("*.json"))
    shutil.rmtree(tmp_path / "a")
    collect_garbage(tmp_path / "store")
    assert not (tmp_path / "store" / Stamps.NAME).exists()
    assert not list((tmp_path / "store" / "memo").rglob("*.json"))
