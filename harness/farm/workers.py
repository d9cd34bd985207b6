"""A worker process's thread environment: one home for how many threads native code may use.

A farm worker is one core by default: the farm scales by processes, and a renderer that spread
over every core in each of N workers would only make them fight (Dr.Jit's LLVM backend
otherwise starts a thread per core in every process).
"""
from __future__ import annotations

import os

#: Thread-pool variables of the native libraries a worker may load (BLAS, OpenMP, numexpr).
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                    "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")


def thread_env(threads: int) -> dict[str, str]:
    """Environment that limits a worker's native thread pools to ``threads``: given to a new
    process from its first instruction (pools are sized when their library is imported)."""
    n = str(max(1, int(threads)))
    return {v: n for v in THREAD_VARIABLES}


def worker_env(threads: int | None = 1) -> None:
    """Set up this worker process: ``threads`` CPU threads for its native libraries (variables
    not already set, and Dr.Jit's pool where Dr.Jit is installed). None leaves the defaults."""
    if threads is None:
        return
    for var, value in thread_env(threads).items():
        os.environ.setdefault(var, value)
    try:
        import drjit  # noqa: PLC0415 - the renderer's JIT: optional for the farm, heavy to import

        drjit.set_thread_count(int(threads))
    except (ImportError, AttributeError, RuntimeError):
        pass
