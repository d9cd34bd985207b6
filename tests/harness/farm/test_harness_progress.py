"""Progress in a log (cron, CI): plain lines per stage at most every few seconds, never
carriage-return updates; bars only on a terminal."""
from __future__ import annotations

import io

from cassi.harness.farm.jobs import State
from cassi.harness.farm.progress import Progress


def test_log_gets_a_line_per_stage_at_most_every_interval():
    out = io.StringIO()
    p = Progress(("geometry", "render"), terminal=False, interval=3600.0, stream=out)
    p.planned("geometry", 2)
    p.planned("render", 4)
    p._last -= 3601.0  # the interval has passed
    p.finished("geometry", State.DONE)
    for _ in range(3):
        p.finished("render", State.FAILED)  # within the interval: no new lines
    p.close()
    text = out.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert len(lines) == 4  # one line per stage after the interval, one per stage at the end
    assert "geometry: 1/2 jobs (50%)" in lines[0] and "render: 0/4 jobs" in lines[1]
    assert "render: 3/4 jobs (75%)" in lines[3] and "3 failed" in lines[3]


def test_disabled_is_silent():
    out = io.StringIO()
    p = Progress(("geometry",), enabled=False, terminal=False, interval=0.0, stream=out)
    p.planned("geometry")
    p.finished("geometry", State.DONE)
    p.close()
    assert out.getvalue() == ""
