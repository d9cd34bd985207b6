"""Results that cannot lie (issue "Results that cannot lie"): what a worker reads is what the run
was planned with, every malformed file a run reads exits 2, worker temporary files name their
path and do not outlive a killed worker, an unreachable cluster fails before anything is
written, links out of the corpus say so, and SIGTERM stops the workers."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from data_helpers import long_task_copy
from cassi.data.synth.corpus import make_corpus
from cassi.harness.cli import main as cli_main
from cassi.harness.evaluation import run as run_mod
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.run import run
from cassi.harness.farm.store import OutputStore
from cassi.harness.evaluation.stages import TEMP_PREFIX, _host, remove_stale_temp_dirs
from cassi.harness.rubric.frames import FileFrames

GEOMETRY = dict(versions=("cassi-1.0",), views=("geometry",), workers=1)
KEY = "JW12/002-1/cassi-1.0/geometry"


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW12"])


def _set_last_field(path: Path, value: str, *, row: int = -1) -> None:
    lines = path.read_text().splitlines()
    fields = lines[row].split("\t")
    fields[1] = value
    lines[row] = "\t".join(fields)
    path.write_text("\n".join(lines) + "\n")


def _cfg(data: Path, out: Path) -> RunConfig:
    return RunConfig(out=out, corpus=data, subjects=("JW12",), tasks=(2,), **GEOMETRY)


# -- 1. inputs edited during a run -------------------------------------------------------------
def test_a_task_file_edited_after_planning_fails_its_job_and_is_not_stored(corpus, tmp_path,
                                                                          monkeypatch):
    data = shutil.copytree(corpus, tmp_path / "c")
    path = data / "JW12" / "tp002.txy"
    original = path.read_bytes()
    planned = run_mod.check_inputs

    def edit_after_planning(*args, **kwargs):
        checked = planned(*args, **kwargs)
        _set_last_field(path, "1234")  # still well formed: only the digest can tell
        return checked

    monkeypatch.setattr(run_mod, "check_inputs", edit_after_planning)
    first = run(_cfg(data, tmp_path / "out"), progress=False)
    rec = first.records[KEY]
    assert rec.state.value == "failed", rec
    assert "JW12/tp002.txy: changed since the run was planned" in rec.reason
    monkeypatch.undo()
    path.write_bytes(original)
    again = run(_cfg(data, tmp_path / "out"), progress=False)
    assert again.records[KEY].state.value == "done"  # not "cached": nothing was stored
    fresh = run(_cfg(data, tmp_path / "fresh"), progress=False)
    pd.testing.assert_frame_equal(again.results, fresh.results)


def test_a_worker_with_other_code_than_the_driver_fails_its_jobs(corpus, tmp_path, monkeypatch):
    real = run_mod.code_provenance

    def driver_code(versions):  # as if the driver ran another build than the worker
        return {**real(versions), "code_digest": "0" * 64}

    monkeypatch.setattr(run_mod, "code_provenance", driver_code)
    result = run(_cfg(corpus, tmp_path / "out"), progress=False)
    rec = result.records[KEY]
    assert rec.state.value == "failed"
    assert "runs other code than the driver" in rec.reason and "code_digest" in rec.reason
    assert OutputStore(tmp_path / "out").read_manifest(KEY) is None


# -- 2. a malformed file that only preprocessing reads ------------------------------------------
def test_a_malformed_file_read_only_for_the_profile_exits_2(corpus, tmp_path, capsys):
    data = shutil.copytree(corpus, tmp_path / "c")
    _set_last_field(data / "JW12" / "tp001.txy", "nan", row=5)
    out = tmp_path / "out"
    code = cli_main(["run", "--corpus", str(data), "--subjects", "JW12", "--tasks", "2",
                     "--versions", "cassi-1.0", "--views", "geometry", "--out", str(out),
                     "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "tp001.txy:6:" in err
    assert not out.exists()


# -- 3. worker temporary files -----------------------------------------------------------------
def test_a_full_temporary_disk_names_the_file(tmp_path):
    if not os.path.exists("/dev/full"):
        pytest.skip("needs /dev/full")
    frames = FileFrames("/dev/full", 4)
    with pytest.raises(OSError, match=r"/dev/full.*set TMPDIR") as err:
        frames.append(np.zeros((1000, 4, 3)))
    assert err.value.filename == "/dev/full"


def _dead_pid() -> int:
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


def test_temporary_directories_of_dead_workers_are_removed_on_the_next_start(corpus, tmp_path,
                                                                             monkeypatch):
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    stale = tmp / f"{TEMP_PREFIX}{_dead_pid()}-{_host()}-abc"
    live = tmp / f"{TEMP_PREFIX}{os.getpid()}-{_host()}-def"
    other_host = tmp / f"{TEMP_PREFIX}{_dead_pid()}-elsewhere.example-ghi"
    for d in (stale, live, other_host):
        d.mkdir()
        (d / "positions.f32").write_bytes(b"\0" * 1024)
    monkeypatch.setenv("TMPDIR", str(tmp))  # the spawned worker's temporary directory
    monkeypatch.setattr(tempfile, "tempdir", None)
    result = run(_cfg(corpus, tmp_path / "out"), progress=False)
    assert result.records[KEY].state.value == "done"
    left = sorted(p.name for p in tmp.iterdir())
    assert left == sorted([live.name, other_host.name])  # nothing of the worker's own stays
    assert remove_stale_temp_dirs(tmp) == []


# -- 4. an unreachable cluster -----------------------------------------------------------------
def test_an_unreachable_ray_cluster_fails_fast_and_writes_nothing(corpus, tmp_path):
    pytest.importorskip("ray")
    out = tmp_path / "out"
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "cassi.harness.cli", "run", "--executor", "ray",
                           "--address", "127.0.0.1:1", "--corpus", str(corpus), "--subjects",
                           "JW12", "--tasks", "2", "--versions", "cassi-1.0", "--views",
                           "geometry", "--out", str(out), "--no-progress"],
                          capture_output=True, text=True, timeout=90)
    assert proc.returncode == 2, proc.stderr
    assert "cannot reach the Ray cluster at 127.0.0.1:1" in proc.stderr
    assert time.monotonic() - t0 < 45
    assert not out.exists()


# -- 5. SIGTERM stops the workers --------------------------------------------------------------
def _children(pid: int) -> list[int]:
    """Worker processes (multiprocessing's spawn) whose parent is ``pid``."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            cmd = (stat.parent / "cmdline").read_bytes()
        except OSError:
            continue
        if int(fields[1]) == pid and b"spawn_main" in cmd:
            found.append(int(stat.parent.name))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_sigterm_stops_the_workers_at_once(corpus, tmp_path):
    data = long_task_copy(corpus, tmp_path / "c")
    out = tmp_path / "out"
    driver = subprocess.Popen([sys.executable, "-m", "cassi.harness.cli", "run", "--corpus",
                               str(data), "--subjects", "JW12", "--tasks", "2", "--versions",
                               "cassi-1.0", "--views", "geometry", "--out", str(out),
                               "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True)
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 60
        while not ((out / "run.json").exists() and _children(driver.pid)):
            assert driver.poll() is None and time.monotonic() < deadline, driver.communicate()
            time.sleep(0.1)
        workers = _children(driver.pid)
        time.sleep(1.0)  # the worker is inside its job now
        driver.send_signal(signal.SIGTERM)
        _, err = driver.communicate(timeout=30)
        stopped = time.monotonic()
        while any(_alive(w) for w in workers) and time.monotonic() - stopped < 3:
            time.sleep(0.05)
        assert not [w for w in workers if _alive(w)], "workers still running after SIGTERM"
        assert driver.returncode == 128 + signal.SIGTERM and "terminated" in err, err
    finally:
        if driver.poll() is None:
            driver.kill()
        for w in workers:
            if _alive(w):
                os.kill(w, signal.SIGKILL)


# -- 5. links out of the corpus ----------------------------------------------------------------
@pytest.mark.parametrize("link", ["task", "subject"])
def test_a_link_out_of_the_corpus_says_so(corpus, tmp_path, capsys, link):
    outside = shutil.copytree(corpus / "JW12", tmp_path / "outside")
    data = tmp_path / "c"
    data.mkdir()
    if link == "task":
        shutil.copytree(corpus / "JW12", data / "JW12")
        (data / "JW12" / "tp005.txy").unlink()
        os.symlink(outside / "tp005.txy", data / "JW12" / "tp005.txy")
        name, task = data / "JW12" / "tp005.txy", "5"
    else:
        os.symlink(outside, data / "JW12")
        name, task = data / "JW12", "2"
    code = cli_main(["run", "--corpus", str(data), "--subjects", "JW12", "--tasks", task,
                     "--versions", "cassi-1.0", "--views", "geometry", "--out",
                     str(tmp_path / "out"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{name}: is a symbolic link that leads outside the corpus directory" in err
