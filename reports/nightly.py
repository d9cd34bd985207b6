"""``cassi nightly``: run the default evaluation, report it, compare with the previous night,
apply the gates and keep a history.

Layout of the nightly directory::

    DIR/runs/<YYYY-MM-DD>[-N]/      each night's run (cassi run output)
    DIR/reports/<same name>/        its report (index.html, tables, images)
    DIR/golden/                     golden renders (only `cassi golden` writes them)
    DIR/history.csv                 night, version, negatives, gate (one row per version a night)
    DIR/latest.txt                  the name of the newest night
"""
from __future__ import annotations

import datetime as dt
import json
import os
import sys
import time
from pathlib import Path

import pandas as pd

from cassi.common.atomic import atomic_write_text
from cassi.harness.config import RunConfig
from cassi.harness.tableset import SET_FILE as TABLE_SET
from cassi.reports.gates import (GOLDEN_MARK, GateResult, MismatchedBaseline, gate, job_gates,
                                 write_gate_report)
from cassi.reports.report import write_report
from cassi.reports.runio import load_run
from cassi.harness.rubric import version_totals

HISTORY_COLUMNS = ["night", "version", "negatives", "gate"]

from cassi.reports.nightly_plan import (NIGHTLY_ANIMATE_STRIDE, NIGHTLY_EXTREMES,  # noqa: E402,F401
                                         NIGHTLY_STRIDE)


#: Written into a night's run directory once the whole night (run, gates, history, report) is
#: done; a night of today's date without it was interrupted and is resumed.
NIGHT_DONE = "night.json"


def night_name(runs_dir: Path, today: dt.date | None = None) -> str:
    """Today's ISO date; an unfinished night of that date is resumed (same name, its finished
    jobs reused), a finished one is followed by -2, -3 ..."""
    base = (today or dt.datetime.now(dt.timezone.utc).date()).isoformat()
    name, n = base, 1
    while (runs_dir / name).exists():
        if not (runs_dir / name / NIGHT_DONE).is_file():
            return name
        n += 1
        name = f"{base}-{n}"
    return name


def previous_night(runs_dir: Path, current: str) -> Path | None:
    """The newest night before ``current`` with a complete table set."""
    nights = sorted((p for p in runs_dir.iterdir() if p.is_dir() and p.name != current
                     and (p / TABLE_SET).is_file()), key=lambda p: p.name)
    earlier = [p for p in nights if p.name < current]
    return earlier[-1] if earlier else None


def read_history(path: Path) -> pd.DataFrame:
    if not path.is_file():
        return pd.DataFrame(columns=HISTORY_COLUMNS)
    return pd.read_csv(path, dtype={"night": str, "version": str})


def nightly(out_dir: str | os.PathLike, *, corpus: str | os.PathLike | None = None,
            config: RunConfig | None = None, today: dt.date | None = None,
            progress: bool = True, common_only: bool = False) -> tuple[bool, Path]:
    """One night. Returns (gates passed, report index path).

    A previous night or golden set of another scope fails tonight's gate with the reason
    (unless ``common_only``), and a failed job fails it too; the report is written anyway.
    """
    from cassi.harness.farm import run as run_farm  # noqa: PLC0415 - heavy import, only here

    timer = StageTimer(progress)
    root = Path(out_dir)
    runs_dir, reports_dir = root / "runs", root / "reports"
    runs_dir.mkdir(parents=True, exist_ok=True)
    name = night_name(runs_dir, today)
    run_dir = runs_dir / name
    cfg = (config or RunConfig()).replace(out=run_dir, corpus=Path(corpus) if corpus else None)
    with timer("run"):
        result = run_farm(cfg, progress=progress)
    timer.worker_seconds(result)
    timer.say(f"variant: {_variant_of(run_dir)}")

    timer.start("gates")
    prev = previous_night(runs_dir, name)
    golden = root / "golden"
    baselines = [p for p in (prev, golden if (golden / GOLDEN_MARK).is_file() else None)
                 if p is not None]
    gate_results = job_gates(load_run(run_dir))
    for baseline in baselines:
        try:
            gate_results += gate(run_dir, baseline, common_only=common_only, jobs=False)[1]
        except MismatchedBaseline as err:
            gate_results.append(GateResult("baseline", "all", "all", str(baseline), "fail",
                                           err.reason))
    passed = not any(r.status == "fail" for r in gate_results)
    write_gate_report(run_dir, passed, gate_results,
                      baseline=", ".join(map(str, baselines)) or "none (first night, no golden "
                                                                 "images)")
    passed = passed and result.ok

    history_path = root / "history.csv"
    history = read_history(history_path)
    # the total over every table cell, as the report's tables count it (Table C's rules included)
    tonight = version_totals(load_run(run_dir).results)
    tonight.insert(0, "night", name)
    tonight["gate"] = "pass" if passed else "fail"
    history = pd.concat([history[history["night"] != name], tonight], ignore_index=True)
    atomic_write_text(history_path, history[HISTORY_COLUMNS].to_csv(index=False, lineterminator="\n"))

    timer.stop()
    with timer("report (tables, pages, videos)"):
        index = write_report(run_dir, reports_dir / name, compare=prev, history=history)
    atomic_write_text(root / "latest.txt", name + "\n")
    atomic_write_text(run_dir / NIGHT_DONE, json.dumps(
        {"night": name, "passed": passed,
         "finished": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")}) + "\n")
    timer.say(timer.summary())
    return passed, index


def _variant_of(run_dir: Path) -> str:
    """The Mitsuba variant the night rendered with (run.json, as the farm resolved it)."""
    meta = load_run(run_dir).meta
    if not meta.get("views_resolved"):
        return "none (no renders)"
    return str(meta.get("variant_resolved") or "unknown (not recorded)")


class StageTimer:
    """Wall time of each stage of a night, printed as it goes (stderr) and summed at the end."""

    def __init__(self, verbose: bool = True):
        self.verbose = verbose
        self.seconds: dict[str, float] = {}
        self.notes: list[str] = []
        self._current: tuple[str, float] | None = None

    def start(self, name: str) -> None:
        self.stop()
        self._current = (name, time.perf_counter())

    def stop(self) -> None:
        if self._current is not None:
            name, t0 = self._current
            self.seconds[name] = time.perf_counter() - t0
            self._current = None
            self.say(f"{name}: {self.seconds[name]:.1f} s")

    def __call__(self, name: str):
        timer = self

        class _Stage:
            def __enter__(self):
                timer.start(name)

            def __exit__(self, *exc):
                timer.stop()
        return _Stage()

    def worker_seconds(self, result) -> None:
        """The farm's worker time per stage (geometry, render, image), from its job records."""
        per = {}
        for rec in result.records.values():
            per[rec.stage] = per.get(rec.stage, 0.0) + rec.seconds
        self.notes.append("worker time " + ", ".join(f"{k} {v:.1f} s" for k, v in per.items()))
        self.say(self.notes[-1])

    def summary(self) -> str:
        total = sum(self.seconds.values())
        parts = ", ".join(f"{k} {v:.1f} s" for k, v in self.seconds.items())
        return f"night: {total:.1f} s ({parts}; {'; '.join(self.notes)})"

    def say(self, line: str) -> None:
        if self.verbose:
            print(f"cassi nightly: {line}", file=sys.stderr, flush=True)
