"""What the benchmarks measure with: memory of this process, the machine's load, a fresh
process's result, a benchmark's failure as an entry. Every figure is taken in-process or read
from a child's JSON line, never from log text."""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
import traceback

from cassi.harness.farm.workers import thread_env

#: A fresh process's limit: a geometry job on a 100,000-row task takes a few minutes on a
#: loaded machine; a child past half an hour is stuck, not slow.
CHILD_TIMEOUT_S = 1800


def rss_mb() -> float:
    """Resident set size of this process in MB (Linux /proc; 0.0 where unavailable)."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError, IndexError):
        return 0.0


def peak_rss_mb() -> float:
    """Peak resident set size of this process so far in MB (``ru_maxrss`` is in KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def loadavg() -> float | None:
    """The 1-minute load average: timings on a shared machine mean little without it."""
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None


def time_loop(fn, n: int) -> float:
    """Mean wall seconds of ``fn(k)`` for k in 0..n-1."""
    t = time.perf_counter()
    for k in range(n):
        fn(k)
    return (time.perf_counter() - t) / n


def json_child(code: str) -> dict:
    """Run ``code`` in a fresh Python on one thread: the JSON object it prints as its last
    stdout line, or ``{"error": [its last stderr line]}`` when it fails."""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env={**os.environ, **thread_env(1)}, timeout=CHILD_TIMEOUT_S)
    if proc.returncode != 0:
        return {"error": proc.stderr.strip().splitlines()[-1:]}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def guarded(fn, quick: bool) -> dict:
    """``fn(quick)``, or ``{"error", "traceback"}`` when it raises: one failing benchmark must not
    hide the others, and is never replaced by made-up numbers."""
    try:
        out = fn(quick)
    except Exception as err:  # noqa: BLE001 - reported in the benchmark's entry
        return {"error": f"{type(err).__name__}: {err}",
                "traceback": traceback.format_exc().splitlines()[-6:]}
    return out if isinstance(out, dict) else {"result": out}
