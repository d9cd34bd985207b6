"""How many CPU cores this process may use: the one count every pool and default reads."""
from __future__ import annotations

import os


def usable_cores() -> int:
    """CPU cores this process may run on: its affinity (a container's or ``taskset``'s share),
    not the machine's count, so no pool starts more workers than it may use."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return os.cpu_count() or 1
