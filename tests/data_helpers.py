"""Helpers for the cassi.data tests: small recordings and corpora built with our own writers."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from cassi.data.xrmb.mis import MistrackEntry, write_mis
from cassi.data.xrmb.files import (NOMINAL_PERIOD_US, PELLETS, TaskRecording, task_file_name, write_pal,
                             write_pha, write_txy)

FIXTURES = Path(__file__).resolve().parent / "fixtures"
JW45_EXCERPT = FIXTURES / "xrmb" / "JW45" / "JW45_013.TXY"

# A plausible resting posture (mm, XRMB frame), rows in PELLETS order.
REST = np.array([[15.0, 11.0], [12.0, -10.0], [-8.0, 5.0], [-27.0, 11.0], [-43.0, 9.0],
                 [-54.0, 1.0], [-1.0, -7.5], [-35.0, -10.0]])


def recording(n=40, *, subject="JW90", task=1, rep=1, lead=3, ul_dx=None, lost=None,
              rest=REST) -> TaskRecording:
    """A recording of ``n`` rows: ``lead`` leading rows of bad values, then the rest posture with
    UL x offset by ``ul_dx[i]`` (mm) in row i; ``lost=(pellet, row)`` loses a pellet from a row."""
    xy = np.repeat(rest[None], n, axis=0).copy()
    if ul_dx is not None:
        xy[:, 0, 0] += np.asarray(ul_dx, dtype=float)
    valid = np.ones((n, len(PELLETS)), dtype=bool)
    valid[:lead] = False
    if lost is not None:
        valid[lost[1]:, PELLETS.index(lost[0])] = False
    xy[~valid] = np.nan
    t = np.arange(n, dtype=np.int64) * NOMINAL_PERIOD_US
    return TaskRecording(None, subject, task, rep, t, xy, valid)


def write_subject(root: Path, name: str, recordings: dict, *, mis=(), palate=None) -> Path:
    """Write a subject directory with task files ``{(task, rep): TaskRecording}``."""
    d = root / name
    d.mkdir(parents=True, exist_ok=True)
    for (task, rep), rec in recordings.items():
        write_txy(d / task_file_name(task, rep), rec)
    write_pal(d / "PAL.DAT", palate if palate is not None else
              np.array([[-5.0, 8.5], [-10.0, 11.5], [-20.0, 19.0], [-40.0, 23.0]]))
    write_pha(d / "PHA.DAT", np.array([[-60.0, -5.0], [-62.0, -20.0]]))
    write_mis(d / "Mis.dat", [MistrackEntry(t, p, 0, -1) for t, p in mis])
    return d


def write_metadata(root: Path, **meta) -> None:
    (root / "corpus.json").write_text(json.dumps(meta))


def long_task_copy(corpus: Path, dest: Path) -> Path:
    """A copy of ``corpus`` at ``dest`` whose JW12 task 2 is 30 times as long (about 30,000
    rows), so that its geometry job runs for several seconds (a signal can land mid-run)."""
    data = shutil.copytree(corpus, dest)
    path = data / "JW12" / "tp002.txy"
    rows = [line.split("\t") for line in path.read_text().splitlines()]
    step = int(rows[1][0]) - int(rows[0][0])
    path.write_text("".join("\t".join([str((k * len(rows) + i) * step), *r[1:]]) + "\n"
                            for k in range(30) for i, r in enumerate(rows)))
    return data
