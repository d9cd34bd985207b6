"""Blobs are written without fsync (harness.store.OutputStore.put): what makes that safe is that
a blob a power loss left empty or short is never trusted. These tests plant such a blob."""
from __future__ import annotations

import os

import pytest

from cassi.harness.farm.store import OutputStore


def test_blob_writes_skip_fsync_manifests_keep_it(tmp_path, monkeypatch):
    calls = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (calls.append(fd), real(fd)))
    store = OutputStore(tmp_path)
    store.prepare()
    ref = store.put(b"frame bytes", ".png")
    assert calls == []
    store.write_manifest("a/job", "d1", {"render": ref})
    assert len(calls) == 1


@pytest.mark.parametrize("left", [b"", b"frame"])
def test_a_blob_left_short_is_not_trusted_and_is_rewritten(tmp_path, left):
    store = OutputStore(tmp_path)
    store.prepare()
    ref = store.put(b"frame bytes", ".png")
    store.write_manifest("a/job", "d1", {"render": ref})
    store.path(ref).chmod(0o644)   # read-only as written: here the damage is the test's
    store.path(ref).write_bytes(left)  # what a power loss before the data reached disk leaves

    fresh = OutputStore(tmp_path)  # the process that resumes the run
    assert fresh.verified("a/job", "d1") is None  # the job runs again
    with pytest.raises(OSError, match="corrupt blob"):
        fresh.get(ref)
    assert fresh.put(b"frame bytes", ".png") == ref
    assert fresh.get(ref) == b"frame bytes"
    assert fresh.verified("a/job", "d1") is not None
