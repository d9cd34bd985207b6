"""``incremental_night``: a second night with nothing changed, over the first, side by side.

Both nights run in one benchmark run, in one fresh nightly directory, with the nightly's own
render settings (:mod:`cassi.harness.evaluation.config`): the first computes every job, the
second finds them all in the directory's shared store and still checks, gates and reports.
"""
from __future__ import annotations

import datetime as dt
import json
import shutil
import tempfile
import time
from pathlib import Path

from cassi.common.lazy import resolve
from cassi.harness.bench.measure import loadavg
from cassi.harness.evaluation.config import NIGHT_REVIEW, NIGHTLY, RunConfig
from cassi.harness.evaluation.nightly import nightly

#: Goal of the issue on incremental nights: a night with nothing changed costs a tenth.
GOAL_FRACTION = 0.1


def _config(quick: bool) -> RunConfig:
    """Quick: one subject, one task file, two versions, the front view. Else two subjects'
    evaluation sets in every registered version and view, as a night renders them."""
    if quick:
        return NIGHTLY.replace(subjects=("JW45",), tasks=(13,),
                               versions=("cassi-1.0", "cassi-2.1"), views=("front",))
    return NIGHTLY.replace(subjects=("JW11", "JW45"))


def bench_incremental_night(quick: bool = False) -> dict:
    cfg = _config(quick)
    review = resolve(NIGHT_REVIEW)
    tmp = Path(tempfile.mkdtemp(prefix="cassi-bench-night-"))
    try:
        seconds, passed = [], []
        for day in (1, 2):
            t0 = time.perf_counter()
            ok, _ = nightly(tmp, review=review, config=cfg, today=dt.date(2026, 1, day),
                            progress=False)
            seconds.append(time.perf_counter() - t0)
            passed.append(ok)
        summary = json.loads((tmp / "runs" / "2026-01-02" / "summary.json").read_text())
        return {"first_night_s": round(seconds[0], 2), "second_night_s": round(seconds[1], 2),
                "incremental_night_fraction": round(seconds[1] / seconds[0], 4),
                "goal_fraction": GOAL_FRACTION, "jobs": summary["jobs"],
                "reused": summary["reused"], "gates_passed": passed,
                "subjects": list(cfg.subjects or ()), "loadavg": loadavg()}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
