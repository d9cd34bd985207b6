"""A Ray cluster of two nodes on this machine where the worker node cannot see the driver's
output directory (it runs in its own mount namespace, with a tmpfs over the directory that
holds ``--out``). The head node has no CPUs, so every job runs on the worker node: the run
can only finish if the outputs travel back through Ray and the inputs are shipped with the
jobs. A corpus the worker cannot see fails its jobs with a message that says so."""
from __future__ import annotations

import json
import os
import secrets
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from cassi.data.synth.corpus import make_corpus

pytestmark = [pytest.mark.ray, pytest.mark.slow]

RAY = Path(sys.executable).with_name("ray")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _can_unshare() -> bool:
    if not shutil.which("unshare"):
        return False
    probe = subprocess.run(["unshare", "--mount", "--propagation", "private", "true"],
                           capture_output=True)
    return probe.returncode == 0


WAIT_FOR_WORKER = """
import sys, time, ray
ray.init(address=sys.argv[1], logging_level="WARNING", log_to_driver=False)
deadline = time.time() + 90
while ray.cluster_resources().get("CPU", 0) < 1:
    if time.time() > deadline:
        sys.exit("the worker node did not join")
    time.sleep(0.5)
"""


@pytest.fixture
def two_nodes(tmp_path):
    """(address, hidden, env): a head node with 0 CPUs and a 1-CPU worker node that sees an
    empty tmpfs at ``hidden``; ``env`` holds the cluster's token for drivers, which run in
    their own processes (Ray reads the token when it is imported)."""
    if not _can_unshare():
        pytest.skip("needs `unshare --mount` (root or user namespaces) to hide a directory "
                    "from the worker node")
    hidden = tmp_path / "hidden"
    hidden.mkdir()
    address = f"127.0.0.1:{_free_port()}"
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0", "RAY_AUTH_MODE": "token",
           "RAY_AUTH_TOKEN": secrets.token_hex(16)}
    subprocess.run([str(RAY), "start", "--head", f"--port={address.split(':')[1]}",
                    "--num-cpus=0", "--node-ip-address=127.0.0.1", "--include-dashboard=false",
                    "--disable-usage-stats"], check=True, capture_output=True, env=env,
                   timeout=120)
    worker = subprocess.Popen(
        ["unshare", "--mount", "--propagation", "private", "sh", "-c",
         f"mount -t tmpfs tmpfs '{hidden}' && exec '{RAY}' start --address={address} "
         f"--num-cpus=1 --node-ip-address=127.0.0.1 --block --disable-usage-stats"],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        subprocess.run([sys.executable, "-c", WAIT_FOR_WORKER, address], check=True, env=env,
                       capture_output=True, timeout=150)
        assert worker.poll() is None, "the worker node exited"
        yield address, hidden, env
    finally:
        subprocess.run([str(RAY), "stop", "--force"], capture_output=True, env=env, timeout=120)
        worker.wait(timeout=60)


def _cassi_run(env, *args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cassi.harness.cli", "run", "--executor", "ray",
                           "--no-progress", *map(str, args)], env=env, capture_output=True,
                          text=True, timeout=600)


def test_outputs_travel_back_from_a_node_that_cannot_see_them(two_nodes, tmp_path):
    address, hidden, env = two_nodes
    corpus = make_corpus(tmp_path / "corpus", subjects=["JW45"])
    out = hidden / "out"  # invisible to the worker node
    proc = _cassi_run(env, "--address", address, "--corpus", corpus, "--subjects", "JW45",
                      "--tasks", "2", "--versions", "cassi-2.1", "--views", "front",
                      "--stride", "0", "--extremes", "1", "--out", out)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    # geometry, render, image, and the evidence renders of the frames the report links
    assert summary["counts"]["done"] >= 3 and summary["counts"]["failed"] == 0, summary["counts"]
    renders = pd.read_parquet(out / "renders.parquet")
    assert len(renders) and all((out / p).is_file() for p in renders["path"])
    # geometry and image checks, and cassi-2.1's lip criterion margin (view "criterion")
    assert set(pd.read_parquet(out / "results.parquet")["view"]) == {"geometry", "front", "criterion"}


def test_a_worker_that_cannot_see_the_corpus_says_so(two_nodes, tmp_path):
    address, hidden, env = two_nodes
    corpus = make_corpus(hidden / "corpus", subjects=["JW45"])  # the driver sees it, not the node
    out = tmp_path / "out"
    proc = _cassi_run(env, "--address", address, "--corpus", corpus, "--subjects", "JW45",
                      "--tasks", "2", "--versions", "cassi-1.0", "--views", "geometry",
                      "--out", out)
    assert proc.returncode == 1
    failed = json.loads((out / "summary.json").read_text())["failed"]
    (reason,) = failed.values()
    assert "not visible" in reason and "same path" in reason
