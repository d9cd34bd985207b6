"""Progress bars per stage, a log per job and the end-of-run summary."""
from __future__ import annotations

import json
import sys
import time
from collections import Counter
from dataclasses import dataclass, field

from tqdm import tqdm

from cassi.common.atomic import atomic_write_text

from cassi.harness.farm.jobs import State
from cassi.harness.farm.store import OutputStore


@dataclass
class JobRecord:
    """The harness's view of one job over the run."""

    key: str
    stage: str
    state: State = State.PENDING
    attempts: int = 0
    seconds: float = 0.0
    reason: str = ""
    log: list[str] = field(default_factory=list)
    cpu_seconds: float = 0.0  # the worker's CPU time over the job, beside its wall ``seconds``


@dataclass
class Summary:
    """Counts by state, wall time, and the reason for every skipped or failed job."""

    records: dict[str, JobRecord]
    seconds: float = 0.0
    worker_crashes: int = 0
    #: Jobs (among the cached ones) reused from the store shared with other runs.
    reused: int = 0

    def counts(self) -> dict[str, int]:
        c = Counter(r.state.value for r in self.records.values())
        return {s.value: c.get(s.value, 0) for s in State if s not in (State.PENDING, State.RUNNING)}

    @property
    def failed(self) -> list[JobRecord]:
        return [r for r in self.records.values() if r.state is State.FAILED]

    @property
    def skipped(self) -> list[JobRecord]:
        return [r for r in self.records.values() if r.state is State.SKIPPED]

    def to_dict(self) -> dict:
        return {"counts": self.counts(), "seconds": round(self.seconds, 3),
                "jobs": len(self.records), "worker_crashes": self.worker_crashes,
                "reused": self.reused,
                "skipped": {r.key: r.reason for r in sorted(self.skipped, key=lambda r: r.key)},
                "failed": {r.key: r.reason for r in sorted(self.failed, key=lambda r: r.key)}}

    def text(self) -> str:
        c = self.counts()
        lines = [f"jobs: {len(self.records)} - {c['done']} done, {c['cached']} skipped as already "
                 f"done (outputs verified), {c['skipped']} skipped, {c['failed']} failed; "
                 f"{self.seconds:.1f} s"]
        if self.reused:
            lines.append(f"reused from the shared store (same inputs and code): {self.reused}")
        if self.worker_crashes:
            lines.append(f"worker processes that died: {self.worker_crashes}")
        reasons = Counter(r.reason for r in self.skipped)
        for reason, n in sorted(reasons.items()):
            lines.append(f"  skipped x{n}: {reason}")
        for r in sorted(self.failed, key=lambda r: r.key):
            lines.append(f"  FAILED {r.key}: {r.reason.splitlines()[0] if r.reason else '?'}")
        return "\n".join(lines)


class Progress:
    """Progress per stage: tqdm bars on a terminal; elsewhere (a cron log, CI) one plain line
    per stage at most every ``interval`` seconds, so a log gets a readable trace instead of
    thousands of carriage-return updates. Silent when disabled.

    Totals grow as jobs are planned.
    """

    def __init__(self, stages=("geometry", "render"), *, enabled: bool = True,
                 terminal: bool | None = None, interval: float = 10.0, stream=None):
        self.enabled = enabled
        self.stream = stream if stream is not None else sys.stderr
        isatty = getattr(self.stream, "isatty", lambda: False)
        self.terminal = isatty() if terminal is None else terminal
        self.interval = float(interval)
        self.stages = tuple(stages)
        self.totals = {s: 0 for s in self.stages}
        self.done = {s: 0 for s in self.stages}
        self.failed = {s: 0 for s in self.stages}
        self.t0 = self._last = time.monotonic()
        self.bars = {}
        if enabled and self.terminal:
            for i, stage in enumerate(stages):
                self.bars[stage] = tqdm(total=0, desc=f"{stage:>9}", unit="job", position=i,
                                        leave=True, dynamic_ncols=True, file=self.stream)

    def planned(self, stage: str, n: int = 1) -> None:
        self.totals[stage] = self.totals.get(stage, 0) + n
        bar = self.bars.get(stage)
        if bar is not None:
            bar.total += n
            bar.refresh()

    def finished(self, stage: str, state: State) -> None:
        self.done[stage] = self.done.get(stage, 0) + 1
        if state is State.FAILED:
            self.failed[stage] = self.failed.get(stage, 0) + 1
        bar = self.bars.get(stage)
        if bar is not None:
            bar.update(1)
            if state is State.FAILED:
                bar.set_postfix_str("failures!", refresh=False)
        elif self.enabled and not self.terminal and time.monotonic() - self._last >= self.interval:
            self.write_lines()

    def lines(self) -> list[str]:
        """One line per stage: jobs done of planned, rate and failures so far."""
        elapsed = time.monotonic() - self.t0
        out = []
        for stage in self.totals:
            done, total = self.done.get(stage, 0), self.totals[stage]
            if not total:
                continue
            rate = done / elapsed if elapsed > 0 else 0.0
            fail = f", {self.failed[stage]} failed" if self.failed.get(stage) else ""
            out.append(f"[{elapsed:7.1f} s] {stage}: {done}/{total} jobs "
                       f"({100.0 * done / total:.0f}%), {rate:.2f} jobs/s{fail}")
        return out

    def write_lines(self) -> None:
        self._last = time.monotonic()
        for line in self.lines():
            print(line, file=self.stream, flush=True)

    def close(self) -> None:
        for bar in self.bars.values():
            bar.close()
        if self.enabled and not self.terminal:
            self.write_lines()


def write_job_log(store: OutputStore, record: JobRecord) -> None:
    """``OUT/logs/<key>.log``: state, attempts, time, reason and the stage's own log lines."""
    head = {"key": record.key, "stage": record.stage, "state": record.state.value,
            "attempts": record.attempts, "seconds": round(record.seconds, 3),
            "reason": record.reason}
    atomic_write_text(store.log_path(record.key),
                      json.dumps(head, sort_keys=True) + "\n" + "\n".join(record.log) + "\n")
