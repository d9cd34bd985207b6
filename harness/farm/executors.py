"""Executors that run the same jobs: a local pool of reused processes, or a Ray cluster.

Both take work items ``(key, fn, args)`` with ``fn`` a picklable module-level function, and hand
back :class:`Finished` records as items complete. Worker processes live for the whole run, so
per-process caches (a renderer keeps its Mitsuba scene per subject and view) are built once
per process, not once per job.

A worker that dies in the middle of an item (a segfault in native code, ``os._exit``, the OOM
killer) costs only that item: it is retried on a fresh worker up to ``retries`` times, then
reported failed. Python exceptions are not retried (they are the stage's own answer) - the
stage wrappers in :mod:`.jobs` already turn them into FAILED outcomes.
"""
from __future__ import annotations

import collections
import logging
import multiprocessing as mp
import os
import re
import signal
import socket
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing.connection import wait as mp_wait
from typing import Any, Callable

from cassi.harness.farm.workers import thread_env
from cassi.common.errors import CassiInputError


@dataclass
class Finished:
    key: str
    ok: bool
    value: Any = None      # fn's return value when ok
    error: str = ""        # why not, when not ok
    attempts: int = 1


@dataclass
class _Item:
    key: str
    fn: Callable
    args: tuple
    attempts: int = 0


def _worker_main(conn, initializer, initargs) -> None:
    """A worker process: run items sent over ``conn`` until told to stop or the pipe closes."""
    init_error = ""
    if initializer is not None:
        try:
            initializer(*initargs)
        except Exception as err:  # noqa: BLE001 - every item then fails with this reason
            init_error = f"worker set-up failed: {type(err).__name__}: {err}"
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg is None:
            return
        key, fn, args = msg
        if init_error:
            try:
                conn.send((key, False, None, init_error))
                continue
            except (BrokenPipeError, OSError):
                return
        try:
            value = fn(*args)
            reply = (key, True, value, "")
        except BaseException as err:  # noqa: BLE001 - report, keep the worker
            import traceback  # noqa: PLC0415
            reply = (key, False, None, f"{type(err).__name__}: {err}\n{traceback.format_exc()}")
        try:
            conn.send(reply)
        except (BrokenPipeError, OSError):
            return  # the run went away (killed): nothing to report to


class LocalExecutor:
    """``workers`` reused worker processes on this machine.

    Parameters
    ----------
    workers : int
        Number of processes (>= 1).
    retries : int
        How often an item whose worker died is retried on a fresh worker.
    start_method : str
        ``"spawn"`` by default: native libraries (Mitsuba, Dr.Jit, Ray) do not survive ``fork``
        of a process that already started their threads.
    """

    name = "local"

    def __init__(self, workers: int = 1, *, retries: int = 1, start_method: str = "spawn",
                 initializer: Callable | None = None, initargs: tuple = (),
                 env: dict[str, str] | None = None):
        if int(workers) < 1:
            raise CassiInputError(f"--workers must be at least 1, not {workers}")
        self.workers = int(workers)
        self.retries = int(retries)
        self._ctx = mp.get_context(start_method)
        self._init = (initializer, initargs)
        self._env = dict(env or {})
        self._procs: list[tuple[Any, Any]] = []     # (process, conn)
        self._busy: dict[int, _Item] = {}            # worker index -> item
        self._queue: collections.deque[_Item] = collections.deque()
        self.crashes = 0

    def __enter__(self):
        # workers start with the first job (start): a night whose every job is reused from
        # the store spawns none
        return self

    def __exit__(self, exc_type, *exc):
        # Leaving on an error or a signal: stop the workers now, not after their current job.
        self.close(abort=exc_type is not None)

    def _spawn(self) -> tuple[Any, Any]:
        parent, child = self._ctx.Pipe(duplex=True)
        proc = self._ctx.Process(target=_worker_main, args=(child, *self._init), daemon=True,
                                 name="cassi-worker")
        # Environment for the worker from its first instruction (thread pools of native
        # libraries are sized when they are imported, before any initializer could run).
        saved = {k: os.environ.get(k) for k in self._env}
        os.environ.update(self._env)
        try:
            proc.start()
        finally:
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        child.close()
        return proc, parent

    def start(self) -> None:
        if not self._procs:
            self._procs = [self._spawn() for _ in range(self.workers)]

    def submit(self, key: str, fn: Callable, *args) -> None:
        self.start()
        self._queue.append(_Item(key, fn, args))
        self._dispatch()

    def pending(self) -> int:
        return len(self._queue) + len(self._busy)

    def _dispatch(self) -> None:
        for i in range(len(self._procs)):
            if not self._queue:
                return
            if i in self._busy:
                continue
            item = self._queue.popleft()
            item.attempts += 1
            try:
                self._procs[i][1].send((item.key, item.fn, item.args))
            except (BrokenPipeError, OSError):
                item.attempts -= 1
                self._queue.appendleft(item)
                self._replace(i)
                continue
            self._busy[i] = item

    def _replace(self, i: int) -> None:
        proc, conn = self._procs[i]
        conn.close()
        proc.join(timeout=5)
        self._procs[i] = self._spawn()

    def wait(self, timeout: float | None = None) -> list[Finished]:
        """Block until at least one item finishes (or ``timeout``); return what finished."""
        self._dispatch()
        if not self._busy:
            return []
        handles = {}
        for i in self._busy:
            proc, conn = self._procs[i]
            handles[conn] = i
            handles[proc.sentinel] = i
        ready = mp_wait(list(handles), timeout)
        done: list[Finished] = []
        for i in sorted({handles[h] for h in ready}):
            if i not in self._busy:
                continue
            proc, conn = self._procs[i]
            item = self._busy[i]
            reply = None
            try:
                if conn.poll():
                    reply = conn.recv()
            except (EOFError, OSError):
                reply = None
            if reply is not None:
                del self._busy[i]
                key, ok, value, error = reply
                done.append(Finished(key, ok, value, error, item.attempts))
                continue
            if proc.is_alive():
                continue
            # The worker died holding this item: replace it, retry or give up on the item.
            proc.join(timeout=5)
            code = proc.exitcode
            del self._busy[i]
            self.crashes += 1
            self._replace(i)
            if item.attempts <= self.retries:
                self._queue.appendleft(item)
            else:
                done.append(Finished(item.key, False, None,
                                     f"worker process died (exit code {code}) "
                                     f"{item.attempts} time(s)", item.attempts))
        self._dispatch()
        return done

    def close(self, *, abort: bool = False) -> None:
        """Stop the workers: idle ones are told to exit; with ``abort`` (or when they do not
        exit) they are terminated, busy ones included, then killed."""
        for proc, conn in self._procs:
            if abort:
                proc.terminate()
                continue
            try:
                conn.send(None)
            except (BrokenPipeError, OSError):
                pass
        for proc, conn in self._procs:
            proc.join(timeout=2 if abort else 10)
            if proc.is_alive():
                proc.terminate()
                proc.join(timeout=5)
            if proc.is_alive():
                proc.kill()
                proc.join(timeout=5)
            conn.close()
        self._procs = []
        self._busy.clear()


def _ray_call(init, initargs, fn, args):
    if init is not None:  # Ray reuses its workers too; the set-up is idempotent and cheap
        init(*initargs)
    return fn(*args)


class RayExecutor:
    """Run items as Ray tasks (at-least-once: a task whose worker dies is retried by Ray).

    Parameters
    ----------
    address : str or None
        A running cluster (``ray://...`` or ``host:port`` or ``auto``); None starts a small local
        cluster (``num_cpus``) for this run and stops it at the end.
    retries : int
        Ray's ``max_retries`` for tasks whose worker died.
    connect_timeout : float
        Seconds to wait for the cluster's address to answer (:func:`probe_address`): Ray's own
        connection retries last minutes.
    init_timeout : float
        Seconds to wait for Ray to connect this driver once the address answered as a gRPC
        server.
    """

    name = "ray"

    def __init__(self, address: str | None = None, *, retries: int = 1, num_cpus: int = 2,
                 initializer: Callable | None = None, initargs: tuple = (),
                 connect_timeout: float = 10.0, init_timeout: float = 60.0):
        self.address = address
        self.connect_timeout = float(connect_timeout)
        self.init_timeout = float(init_timeout)
        self._init = (initializer, initargs)
        self.retries = int(retries)
        self.num_cpus = int(num_cpus)
        self._refs: dict[Any, _Item] = {}
        self._owns_cluster = False
        self._remote = None

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.close()

    def start(self) -> None:
        ray = require_ray()

        if not ray.is_initialized():
            if self.address:
                probe_address(self.address, self.connect_timeout)
            with _sigterm_kept():
                if self.address:
                    try:
                        _connect_ray(ray, self.address, self.init_timeout)
                    except (ConnectionError, ValueError, RuntimeError) as err:
                        raise CassiInputError(f"cannot reach the Ray cluster at "
                                              f"{self.address}: {err}") from err
                else:
                    ray.init(num_cpus=self.num_cpus, include_dashboard=False,
                             log_to_driver=False, logging_level="WARNING")
                    self._owns_cluster = True
        self._remote = ray.remote(max_retries=self.retries, retry_exceptions=False)(_ray_call)

    def submit(self, key: str, fn: Callable, *args) -> None:
        if self._remote is None:
            self.start()
        item = _Item(key, fn, args, attempts=1)
        self._refs[self._remote.remote(*self._init, fn, args)] = item

    def pending(self) -> int:
        return len(self._refs)

    def wait(self, timeout: float | None = None) -> list[Finished]:
        import ray  # noqa: PLC0415

        if not self._refs:
            return []
        ready, _ = ray.wait(list(self._refs), num_returns=1, timeout=timeout)
        if ready:  # collect whatever else is already done, too
            more, _ = ray.wait([r for r in self._refs if r not in ready],
                               num_returns=len(self._refs) - len(ready), timeout=0)
            ready = list(ready) + list(more)
        done = []
        for ref in ready:
            item = self._refs.pop(ref)
            try:
                done.append(Finished(item.key, True, ray.get(ref)))
            except ray.exceptions.RayTaskError as err:
                done.append(Finished(item.key, False, None, str(err)))
            except (ray.exceptions.WorkerCrashedError, ray.exceptions.RayError) as err:
                done.append(Finished(item.key, False, None,
                                     f"worker died {self.retries + 1} time(s): "
                                     f"{type(err).__name__}: {err}", self.retries + 1))
        return done

    def close(self) -> None:
        import ray  # noqa: PLC0415

        for ref in list(self._refs):
            try:
                ray.cancel(ref, force=True)
            except Exception:  # noqa: BLE001 - best effort at shutdown
                pass
        self._refs.clear()
        if self._owns_cluster and ray.is_initialized():
            ray.shutdown()
            self._owns_cluster = False


def _connect_ray(ray, address: str, timeout: float) -> None:
    """``ray.init(address)`` in a thread the run waits for, at most ``timeout`` seconds. Ray's
    connection retries block in native code for minutes, where Python runs no signal handler:
    waiting in the main thread instead keeps SIGTERM (and the bound) effective."""
    failed: list[BaseException] = []

    def connect():
        try:
            ray.init(address=address, include_dashboard=False, log_to_driver=False,
                     logging_level="WARNING")
        except BaseException as err:  # noqa: BLE001 - raised again in the waiting thread
            failed.append(err)

    # Ray warns that it sets no SIGTERM handler from this thread: the run keeps its own.
    log = logging.getLogger("ray._private.worker")
    quiet = lambda record: "SIGTERM handler is not set" not in record.getMessage()  # noqa: E731
    log.addFilter(quiet)
    thread = threading.Thread(target=connect, name="cassi-ray-connect", daemon=True)
    thread.start()
    try:
        thread.join(timeout)
    finally:
        log.removeFilter(quiet)
    if thread.is_alive():
        raise CassiInputError(f"the Ray cluster at {address} answered but did not accept this "
                              f"driver within {timeout:g} s; is it a Ray cluster of this Ray "
                              f"version ({ray.__version__})?")
    if failed:
        raise failed[0]


@contextmanager
def _sigterm_kept():
    """Ray's init puts its own SIGTERM handlers in place of the run's (``sys.exit`` in Python;
    in native code one that prints a stack and kills the process, unwinding nothing): the
    run's is put back, and a SIGTERM meanwhile gets the run's answer."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGTERM)
    try:
        yield
    except SystemExit as err:
        if err.code == signal.SIGTERM and callable(previous):
            previous(signal.SIGTERM, None)
        raise
    finally:
        if previous is not None:  # None: not set from Python, nothing to put back
            signal.signal(signal.SIGTERM, previous)


#: What a gRPC client (Ray's GCS client, Ray Client) sends first: HTTP/2's connection preface
#: and an empty SETTINGS frame. A gRPC server answers with a SETTINGS frame of its own.
_H2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])


def probe_address(address: str, timeout: float) -> None:
    """Fail fast, with the reason, when nothing answers at a cluster's ``host:port`` (or
    ``ray://host:port``) or what answers is not a gRPC server (a Ray dashboard's HTTP port, on
    which Ray would retry for good); ``auto`` is left to Ray, which finds a local cluster by
    its files."""
    if address in ("auto", "local"):
        return
    host, _, port = address.split("://", 1)[-1].rpartition(":")
    if not host or not re.fullmatch(r"[0-9]{1,5}", port) or not 0 < int(port) < 65536:
        raise CassiInputError(f"--address {address!r}: expected host:port, ray://host:port "
                              f"or auto")
    try:
        sock = socket.create_connection((host.strip("[]"), int(port)), timeout=timeout)
    except OSError as err:
        raise CassiInputError(
            f"cannot reach the Ray cluster at {address}: {err.strerror or err} (waited up to "
            f"{timeout:g} s); start it with `ray start --head`, or give --address the head "
            f"node's host:port") from None
    if os.environ.get("RAY_USE_TLS", "0").lower() in ("1", "true"):
        sock.close()  # a TLS cluster answers a TLS handshake, not the plain preface
        return
    with sock:
        answer = _what_answers(sock, timeout)
    if answer:
        dashboard = " (as a Ray dashboard's port, 8265, does)" if "HTTP" in answer else ""
        raise CassiInputError(
            f"{address} is not a Ray cluster's address: {answer}{dashboard}; give --address the "
            f"address `ray start --head` prints (port 6379 by default), or ray://host:10001 "
            f"for Ray Client")


def _what_answers(sock: socket.socket, timeout: float) -> str:
    """What the server at ``sock`` answers to a gRPC client's first bytes: '' for a gRPC
    server, else what it was, in words."""
    reply, deadline = b"", time.monotonic() + timeout
    try:
        sock.sendall(_H2_PREFACE)
        while len(reply) < 9 and not reply.startswith(b"HTTP/"):
            sock.settimeout(max(0.01, deadline - time.monotonic()))
            chunk = sock.recv(256)
            if not chunk:
                break
            reply += chunk
    except TimeoutError:
        if not reply:
            return f"it accepted the connection but sent nothing back within {timeout:g} s"
    except OSError as err:
        return f"it closed the connection ({err.strerror or err})"
    if len(reply) >= 9 and reply[3] == 4 and reply[5:9] == bytes(4):  # a SETTINGS frame
        return ""
    first_line = reply.split(b"\n", 1)[0].strip()[:60].decode("ascii", "replace")
    if reply.startswith(b"HTTP/"):
        return f"an HTTP server answered ({first_line!r})"
    if reply.lstrip()[:14].lower().startswith((b"<!doctype html", b"<html")):
        return f"an HTTP server answered (a web page: {first_line!r})"  # HTTP/0.9 style
    if not reply:
        return "it closed the connection without an answer"
    return f"something other than a gRPC server answered ({reply[:24]!r})"


def require_ray():
    """The ``ray`` module, or a clear error saying how to install it (an optional extra)."""
    try:
        import ray  # noqa: PLC0415 - heavy; only when this executor is chosen
    except ImportError:
        raise CassiInputError("--executor ray needs Ray, which is an optional extra: "
                              "pip install 'cassi-farm[ray]'") from None
    return ray


def make_executor(kind: str, *, workers: int = 1, address: str | None = None,
                  retries: int = 1, initializer: Callable | None = None, initargs: tuple = (),
                  threads: int = 1):
    """``"local"`` -> :class:`LocalExecutor`, ``"ray"`` -> :class:`RayExecutor`.

    ``initializer(*initargs)`` runs in each local worker process before its first item (and
    before every Ray task: it must be idempotent).
    """
    if kind == "local":
        return LocalExecutor(workers, retries=retries, initializer=initializer, initargs=initargs,
                             env=thread_env(threads))
    if kind == "ray":
        # The brief's local cluster: 2 CPUs, or more when more workers were asked for.
        return RayExecutor(address, retries=retries, num_cpus=max(2, int(workers)),
                           initializer=initializer, initargs=initargs)
    raise CassiInputError(f"unknown executor {kind!r}; valid: local, ray")
