"""``cassi nightly``'s orchestration: one night's run in a dated directory (:mod:`.nights`:
the directory's layout and its nights), then its review.

The harness runs the evaluation; what reads the night's results (gates, history, report) is
the ``review`` the caller passes (:func:`cassi.reports.nightly.review_night`, named by the
command as :data:`~cassi.harness.evaluation.config.NIGHT_REVIEW`), so that reports never start
a run and the harness never imports reports.
"""
from __future__ import annotations

import datetime as dt
import json
import os
from pathlib import Path
from typing import Callable

from cassi.common.atomic import atomic_write_text
from cassi.harness.evaluation.config import NIGHTLY, RunConfig
from cassi.harness.evaluation.nights import (LATEST, NIGHT_DONE, SENSITIVITY_MEMO, STORE_DIR,
                                             Night, StageTimer, night_name, previous_night)
from cassi.harness.evaluation.run import run as run_farm
from cassi.harness.evaluation.sensitivity import sensitivity


def nightly(out_dir: str | os.PathLike, *, review: Callable[[Night], tuple[bool, Path]],
            corpus: str | os.PathLike | None = None, config: RunConfig | None = None,
            today: dt.date | None = None, progress: bool = True) -> tuple[bool, Path]:
    """One night: run the evaluation into ``DIR/runs/<night>``, then ``review(night)`` (gates,
    history, report), then mark the night done. Returns what the review returns (gates
    passed, report index); a night whose run failed a job never passes.
    """
    timer = StageTimer(progress)
    root = Path(out_dir)
    runs_dir, reports_dir = root / "runs", root / "reports"
    runs_dir.mkdir(parents=True, exist_ok=True)
    name = night_name(runs_dir, today)
    run_dir = runs_dir / name
    cfg = config or NIGHTLY
    cfg = cfg.replace(out=run_dir, corpus=Path(corpus) if corpus else cfg.corpus,
                      cache=root / STORE_DIR)
    with timer("run"):
        result = run_farm(cfg, progress=progress)
    timer.say(f"jobs reused from earlier nights (same inputs and code): "
              f"{result.summary.reused} of {len(result.records)}")
    timer.worker_seconds(result)
    timer.say(f"variant: {_variant_of(run_dir)}")
    if result.ok:
        # each finding's robustness to the rubric's own thresholds (seconds: no re-render);
        # the versions' constants cost a geometry stage each: `cassi sensitivity RUN`
        with timer("robustness (thresholds)"):
            sensitivity(run_dir, only="thresholds", log=timer.say,
                        memo=root / STORE_DIR / SENSITIVITY_MEMO)
    passed, index = review(Night(root, name, run_dir, reports_dir / name, result,
                                 previous_night(runs_dir, name), timer))
    passed = passed and result.ok
    atomic_write_text(root / LATEST, name + "\n")
    atomic_write_text(run_dir / NIGHT_DONE, json.dumps(
        {"night": name, "passed": passed,
         "finished": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
         "stage_seconds": {k: round(v, 2) for k, v in timer.seconds.items()}}) + "\n")
    timer.say(timer.summary())
    return passed, index


def _variant_of(run_dir: Path) -> str:
    """The Mitsuba variant the night rendered with (run.json, as the farm resolved it)."""
    meta = json.loads((run_dir / "run.json").read_text())
    if not meta.get("views_resolved"):
        return "none (no renders)"
    return str(meta.get("variant_resolved") or "unknown (not recorded)")
