"""`--executor ray --address` at a port where something other than a Ray cluster answers (the
dashboard's HTTP port 8265 is the easy mistake) exits 2 at once, naming the address and what
answered, instead of Ray retrying for good; SIGTERM ends a Ray run at every stage (connecting
included, where Ray blocks in native code), with nothing half written."""
from __future__ import annotations

import http.server
import os
import secrets
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from data_helpers import long_task_copy
from cassi.data.synth.corpus import make_corpus

pytest.importorskip("ray")

#: An HTTP/2 SETTINGS frame, empty: what a gRPC server says first.
SETTINGS = bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("corpus") / "c", subjects=["JW12"])


def _cassi_run(corpus, out, *args, env=None) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "cassi.harness.cli", "run", "--executor",
                             "ray", *args, "--corpus", str(corpus), "--subjects", "JW12",
                             "--tasks", "2", "--versions", "cassi-1.0", "--views", "geometry",
                             "--out", str(out), "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


class _SilentGrpc:
    """A server that answers a gRPC client's first bytes with a SETTINGS frame, then never
    another word: the probe takes it for a gRPC server, Ray waits on it."""

    def __init__(self):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.accepted = threading.Event()
        self.conns: list[socket.socket] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)
            try:
                conn.recv(64)
                conn.sendall(SETTINGS)
            except OSError:
                pass
            self.accepted.set()

    def close(self):
        self.sock.close()
        for c in self.conns:
            c.close()


def test_an_http_port_is_not_a_ray_cluster(corpus, tmp_path):
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.BaseHTTPRequestHandler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    address = f"127.0.0.1:{server.server_address[1]}"
    out = tmp_path / "out"
    t0 = time.monotonic()
    proc = _cassi_run(corpus, out, "--address", address)
    try:
        _, err = proc.communicate(timeout=45)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        server.shutdown()
    assert time.monotonic() - t0 < 30
    assert proc.returncode == 2, err
    assert f"{address} is not a Ray cluster's address: an HTTP server answered (" in err
    assert "8265" in err
    assert not out.exists()


def test_sigterm_while_ray_connects_ends_the_run(corpus, tmp_path):
    server = _SilentGrpc()
    out = tmp_path / "out"
    proc = _cassi_run(corpus, out, "--address", f"127.0.0.1:{server.port}")
    try:
        assert server.accepted.wait(60), proc.communicate()
        time.sleep(3)  # past the probe: inside Ray's connection retries
        assert proc.poll() is None, proc.communicate()
        err = _terminate(proc, within_s=10)
    finally:
        _kill(proc)
        server.close()
    assert proc.returncode == 128 + signal.SIGTERM and "terminated" in err, err
    assert not out.exists()


def test_a_grpc_server_that_never_accepts_the_driver_is_refused_in_bounded_time():
    server = _SilentGrpc()
    code = ("from cassi.harness.farm.executors import RayExecutor\n"
            f"RayExecutor('127.0.0.1:{server.port}', init_timeout=3).start()\n")
    try:
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              timeout=60)
    finally:
        server.close()
    assert proc.returncode == 1
    assert (f"CassiInputError: the Ray cluster at 127.0.0.1:{server.port} answered but did not "
            f"accept this driver within 3 s") in proc.stderr


#: A cluster of this machine for a driver of its own to connect to: prints its address, stays
#: up until its standard input closes.
HEAD = """
import sys, ray
ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False, logging_level="ERROR")
print(ray.get_runtime_context().gcs_address, flush=True)
sys.stdin.read()
"""


@pytest.fixture
def head():
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0", "RAY_AUTH_MODE": "token",
           "RAY_AUTH_TOKEN": secrets.token_hex(16)}
    proc = subprocess.Popen([sys.executable, "-c", HEAD], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env)
    try:
        address = proc.stdout.readline().strip()
        assert address, "the head did not start"
        yield address, env
    finally:
        proc.stdin.close()  # the head's driver ends, and its cluster with it
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.terminate()
            proc.wait(timeout=30)


def _terminate(proc, *, within_s: float) -> str:
    """SIGTERM ``proc``; it must end within ``within_s``. Returns its stderr."""
    proc.send_signal(signal.SIGTERM)
    t0 = time.monotonic()
    _, err = proc.communicate(timeout=within_s + 10)
    assert time.monotonic() - t0 < within_s
    return err


def _kill(proc) -> None:
    if proc.poll() is None:
        proc.kill()
        proc.communicate()


@pytest.mark.ray
@pytest.mark.parametrize("cluster", ["local", "address"])
def test_sigterm_mid_run_on_a_ray_cluster(corpus, tmp_path, request, cluster):
    """Ray's init replaces the run's SIGTERM handler (a local cluster's with ``sys.exit``, and
    in native code with one that kills the driver unwinding nothing)."""
    data, out = long_task_copy(corpus, tmp_path / "c"), tmp_path / "out"
    address, env = request.getfixturevalue("head") if cluster == "address" else (None, None)
    proc = _cassi_run(data, out, *(["--address", address] if address else []), env=env)
    try:
        deadline = time.monotonic() + 90
        while not (out / "run.json").exists():
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.1)
        time.sleep(1.0)  # the job is running on the cluster
        err = _terminate(proc, within_s=20)
    finally:
        _kill(proc)
    assert proc.returncode == 128 + signal.SIGTERM and "terminated" in err, err
    left = sorted(p.name for p in out.iterdir())
    assert "tables.json" not in left and "results.parquet" not in left, left
    assert not list(out.rglob(".*.tmp*")), "a half-written file"
