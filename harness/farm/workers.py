"""A worker process's thread environment: one home for how many threads native code may use.

A farm worker is one core by default: the farm scales by processes, and a renderer that spread
over every core in each of N workers would only make them fight (Dr.Jit's LLVM backend
otherwise starts a thread per core in every process).
"""
from __future__ import annotations

import os
from contextlib import contextmanager

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


@contextmanager
def renderer_threads(threads: int):
    """Dr.Jit's thread pool at ``threads`` inside the block (a benchmark measuring one core,
    as a farm worker has), restored after. Dr.Jit must already be initialised for the variant
    the caller chose (:func:`cassi.renderer.variant.choose_variant`)."""
    import drjit  # noqa: PLC0415 - only after the caller chose the variant (it sets libLLVM's path)

    before = drjit.thread_count()
    drjit.set_thread_count(max(1, int(threads)))
    try:
        yield
    finally:
        drjit.set_thread_count(before)
