"""A nightly directory: its layout, its nights in order, what a night's review is given, and
``cassi gc``. Reading and keeping nights; running one is :mod:`.nightly`.

Layout of the nightly directory::

    DIR/runs/<YYYY-MM-DD>[-N]/      each night's run (cassi run output)
    DIR/reports/<same name>/        its report (index.html, tables, images)
    DIR/golden/                     golden renders (only `cassi golden` writes them)
    DIR/store/                      the store every night shares: a job with the same inputs
                                    and code as an earlier night's is reused, not run
                                    (`cassi gc DIR` removes what no kept night links)
    DIR/history.csv                 night, version, negatives, gate (one row per version a night)
    DIR/latest.txt                  the name of the newest night
"""
from __future__ import annotations

import datetime as dt
import json
import os
import re
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from cassi.common.errors import CassiInputError
from cassi.common.lazy import resolve
from cassi.harness.evaluation.config import KEEP_NIGHTS, MEDIA_GC
from cassi.harness.farm.store import MEDIA_DIR, collect_garbage, remove_stale_records, store_lock
from cassi.harness.farm.tableset import SET_FILE as TABLE_SET
from cassi.harness.farm.tableset import SUMMARY_FILE, TableSetError, verify_table_set

if TYPE_CHECKING:  # the farm's result, only named here: reading nights starts no run
    from cassi.harness.farm.runner import RunResult

#: The store all nights of a nightly directory share (:class:`cassi.harness.farm.store.OutputStore`).
STORE_DIR = "store"
#: Robustness analyses in the store, by what they depend on (the results table's bytes, the code
#: and rubric): a night with the results of an earlier one takes its analysis from there.
SENSITIVITY_MEMO = "derived/sensitivity"
#: Written into a night's run directory once the whole night (run, gates, history, report) is
#: done; a night of today's date without it was interrupted and is resumed.
NIGHT_DONE = "night.json"
#: The file naming the newest night (its review's report is the one to read).
LATEST = "latest.txt"
#: A night's name: its ISO date, then -2, -3 ... for the day's later nights.
_NIGHT_NAME = re.compile(r"(\d{4}-\d{2}-\d{2})(?:-([2-9]|[1-9]\d+))?")


def night_key(name: str) -> tuple[dt.date, int] | None:
    """``(date, sequence)`` of a night's name (``2026-12-07`` is the day's 1st, ``-10`` its
    10th), None for a name no night has. Nights are ordered by this key: as strings ``-10``
    sorts before ``-2``."""
    m = _NIGHT_NAME.fullmatch(name)
    if m is None:
        return None
    try:
        return dt.date.fromisoformat(m[1]), int(m[2] or 1)
    except ValueError:  # 2026-13-40
        return None


def nights(runs_dir: Path) -> list[str]:
    """The nights of ``runs_dir``, oldest first (other directories are not nights)."""
    return sorted((p.name for p in runs_dir.iterdir() if p.is_dir() and night_key(p.name)),
                  key=night_key)


def latest_night(root: Path) -> str | None:
    """The night ``DIR/latest.txt`` names, or None."""
    try:
        name = (root / LATEST).read_text(encoding="utf-8").strip()
    except (OSError, UnicodeDecodeError):
        return None
    return name if night_key(name) else None


def night_name(runs_dir: Path, today: dt.date | None = None) -> str:
    """Today's ISO date, or -2, -3 ... after the day's newest night; a name is never reused (not
    after ``cassi gc`` either: the newest night and the one ``latest.txt`` names are always
    kept). An unfinished newest night of today is resumed (same name, its finished jobs
    reused)."""
    today = today or dt.datetime.now(dt.timezone.utc).date()
    names = nights(runs_dir)
    used = names + [n for n in [latest_night(runs_dir.parent)] if n]
    newest = max(used, key=night_key, default=None)
    if newest is None:
        return today.isoformat()
    day, seq = night_key(newest)
    if day > today:  # tonight would sort before it: gated against older nights, gc'd first
        raise CassiInputError(f"the newest night, {newest}, is dated after today "
                              f"({today.isoformat()}): is the clock right?",
                              path=runs_dir / newest)
    if day < today:
        return today.isoformat()
    if newest in names and not (runs_dir / newest / NIGHT_DONE).is_file():
        return newest
    return f"{today.isoformat()}-{seq + 1}"


def previous_night(runs_dir: Path, current: str) -> Path | None:
    """The newest night before ``current`` whose run is complete: a table set that verifies and
    no failed job (a failed night is no baseline: its missing results would pass or blame
    tonight)."""
    before = [runs_dir / n for n in nights(runs_dir) if night_key(n) < night_key(current)]
    return next((p for p in reversed(before) if (p / TABLE_SET).is_file() and _complete(p)),
                None)


def _complete(run_dir: Path) -> bool:
    try:
        verify_table_set(run_dir)
        summary = json.loads((run_dir / SUMMARY_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError, TableSetError):
        return False
    return isinstance(summary, dict) and not summary.get("failed")


def gc(out_dir: str | os.PathLike, *, keep: int = KEEP_NIGHTS) -> dict:
    """Keep the newest ``keep`` nights of a nightly directory (their runs and reports) and the
    one ``latest.txt`` names, remove the other nights (directories of ``runs/`` whose names are
    no night's are left alone), then every blob of the shared store that no kept night links
    (:func:`cassi.harness.farm.store.collect_garbage`). The golden directory holds copies and
    is never touched. Returns what was removed."""
    root = Path(out_dir)
    runs_dir = root / "runs"
    if not runs_dir.is_dir():
        raise CassiInputError("not a nightly directory (no runs/)", path=root)
    if keep < 1:
        raise CassiInputError(f"--keep must be at least 1, got {keep}")
    names = nights(runs_dir)
    # The night latest.txt names stays too (its report is the one people open).
    kept = set(names[-keep:]) | {latest_night(root)}
    old = [n for n in names if n not in kept]
    with store_lock(root / STORE_DIR, exclusive=True):  # no night may write it meanwhile
        for name in old:
            for d in (runs_dir / name, root / "reports" / name):
                if d.is_dir():
                    shutil.rmtree(d)
        freed = collect_garbage(root / STORE_DIR)  # the lock made the directory: never missing
        pages = resolve(MEDIA_GC)(root / STORE_DIR / MEDIA_DIR)
        _forget_analyses_of_removed_runs(root / STORE_DIR / SENSITIVITY_MEMO)
    return {"nights_removed": old, "nights_kept": [n for n in names if n in kept],
            "blobs_removed": freed.blobs,
            "manifests_removed": freed.manifests, "bytes_freed": freed.bytes + pages}


def _forget_analyses_of_removed_runs(memo: Path) -> None:
    """Remove the kept robustness analyses whose night is gone (a later night with the same
    results table computes its own again, in seconds)."""
    remove_stale_records(memo.glob("*.json"), lambda doc: [doc["run"]], present=os.path.isdir)


@dataclass
class Night:
    """One night, as its review sees it: where it is, what the farm did and the night before."""

    root: Path
    name: str
    run_dir: Path
    report_dir: Path
    result: "RunResult"
    previous: Path | None
    timer: "StageTimer"


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
