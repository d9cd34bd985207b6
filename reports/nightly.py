"""A night's review: gates against the previous night and the golden renders, the history, the
report. The night itself (its dated run) is :func:`cassi.harness.evaluation.nightly.nightly`;
this module only reads what that run wrote.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from cassi.common.atomic import atomic_write_text
from cassi.harness.evaluation.nights import STORE_DIR, Night
from cassi.harness.farm.store import MEDIA_DIR
from cassi.harness.rubric import version_totals
from cassi.reports.gates import (GOLDEN_MARK, GateResult, IncompleteRun, MismatchedBaseline,
                                 NothingCompared, compared, job_gates, load_baseline,
                                 write_gate_report)
from cassi.reports.report import write_report
from cassi.reports.runio import load_run

HISTORY_COLUMNS = ["night", "version", "negatives", "gate"]


def read_history(path: Path) -> pd.DataFrame:
    if not path.is_file():
        return pd.DataFrame(columns=HISTORY_COLUMNS)
    return pd.read_csv(path, dtype={"night": str, "version": str})


def review_night(night: Night, *, common_only: bool = False) -> tuple[bool, Path]:
    """Gate, record and report one night. Returns (gates passed, report index path).

    A previous night or golden set of another scope, or one that is incomplete or compares
    nothing, fails tonight's gate with the reason (unless ``common_only`` for the scope), and
    a failed job fails it too; the report is written anyway.
    """
    timer, root, run_dir = night.timer, night.root, night.run_dir
    timer.start("gates")
    golden = root / "golden"
    baselines = [p for p in (night.previous, golden if (golden / GOLDEN_MARK).is_file() else None)
                 if p is not None]
    run = load_run(run_dir)
    gate_results = job_gates(run)
    previous = None  # the previous night as the gates loaded it, for the report's comparison
    for baseline in baselines:
        try:
            base = load_baseline(baseline)
            if baseline == night.previous:
                previous = base.run
            gate_results += compared(run, base, common_only=common_only, jobs=False)[0]
        except (MismatchedBaseline, IncompleteRun, NothingCompared) as err:
            gate_results.append(GateResult("baseline", "all", "all", str(baseline), "fail",
                                           err.reason))
    passed = not any(r.status == "fail" for r in gate_results)
    first = not baselines and passed  # nothing to compare with: tonight becomes the baseline
    write_gate_report(run_dir, passed, gate_results,
                      baseline=", ".join(map(str, baselines)) or "none (first night, no golden "
                                                                 "images)",
                      baseline_recorded=first)
    if first:
        timer.say("baseline recorded: the first night, nothing to compare with; the next night "
                  "is gated against this one")
    passed = passed and night.result.ok

    history_path = root / "history.csv"
    history = read_history(history_path)
    # the total over every table cell, as the report's tables count it (Table C's rules included)
    tonight = version_totals(run.results)
    tonight.insert(0, "night", night.name)
    tonight["gate"] = "pass" if passed else "fail"
    history = pd.concat([history[history["night"] != night.name], tonight], ignore_index=True)
    atomic_write_text(history_path, history[HISTORY_COLUMNS].to_csv(index=False, lineterminator="\n"))

    timer.stop()
    with timer("report (tables, pages, videos)"):
        index = write_report(run, night.report_dir, history=history,
                             compare=previous if previous is not None else night.previous,
                             media_cache=root / STORE_DIR / MEDIA_DIR)
    return passed, index
