"""``full_set``: a first night of the whole corpus (``--set full``), estimated from one subject.

The whole corpus is 15 subjects x 120 task files; a benchmark that ran it would take as long
as the night it measures. This one runs one subject's full set (every task file, every
version and view, the nightly's own settings, report included) as a first night in a fresh
nightly directory, reads each stage's seconds from the night's ``night.json``, and scales the
night by the usable task files: the whole corpus's over the subject's. The scaling is linear
(jobs are per task file and version); the report's fixed costs make it a slight overestimate.
It is an estimate and says so (``full_set_estimate_basis``).
"""
from __future__ import annotations

import datetime as dt
import json
import shutil
import tempfile
import time
from pathlib import Path

from cassi.common.lazy import resolve
from cassi.harness.bench.measure import loadavg, peak_rss_mb
from cassi.harness.evaluation.caches import get_corpus, get_profile
from cassi.harness.evaluation.config import NIGHT_REVIEW, NIGHTLY
from cassi.harness.evaluation.evalset import full_tasks
from cassi.harness.evaluation.inputs import check_inputs
from cassi.harness.evaluation.nightly import nightly
from cassi.harness.evaluation.nights import NIGHT_DONE

#: The issue's target for a first night of the whole corpus on 2 cores, report included.
TARGET_S = 30 * 60


def _usable(corpus, subjects=None) -> int:
    """Usable task files of ``subjects`` (all: None) in the full set, as a run would find them."""
    tasks = full_tasks(corpus, subjects)
    return sum(t.usable for t in check_inputs(corpus, tasks, get_profile=get_profile).tasks)


def bench_full_set(quick: bool = False, *, subject: str = "JW11") -> dict:
    cfg = NIGHTLY.replace(set="full", subjects=(subject,))
    if quick:  # a few task files, two versions, the front view: the benchmark's path only
        cfg = NIGHTLY.replace(subjects=(subject,), tasks=(1, 2, 3),
                              versions=("cassi-1.0", "cassi-2.1"), views=("front",))
    corpus = get_corpus(None)
    tmp = Path(tempfile.mkdtemp(prefix="cassi-bench-fullset-"))
    try:
        t0 = time.perf_counter()
        passed, _ = nightly(tmp, review=resolve(NIGHT_REVIEW), config=cfg,
                            today=dt.date(2026, 1, 1), progress=False)
        seconds = time.perf_counter() - t0
        night = json.loads((tmp / "runs" / "2026-01-01" / NIGHT_DONE).read_text())
        summary = json.loads((tmp / "runs" / "2026-01-01" / "summary.json").read_text())
        meta = json.loads((tmp / "runs" / "2026-01-01" / "run.json").read_text())
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    mine = sum(1 for _, _, _, usable, *_ in meta["tasks_resolved"] if usable)
    everyone = _usable(corpus)
    scale = everyone / max(mine, 1)
    return {"subject": subject, "quick": quick, "night_s": round(seconds, 1),
            "stage_seconds": night.get("stage_seconds", {}), "jobs": summary.get("jobs"),
            "usable_files_run": mine, "usable_files_full_set": everyone,
            "full_set_estimate_s": round(seconds * scale, 0),
            "full_set_estimate_basis": f"{subject}'s full set ({mine} usable task files) x "
                                       f"{scale:.2f} (the whole corpus's {everyone} usable files)",
            "target_s": TARGET_S, "gates_passed": passed,
            "driver_peak_rss_mb": round(peak_rss_mb()),
            "loadavg": loadavg()}

