"""``cassi rate``: a blinded rating session for people, opened from disk.

``DIR/session/`` is what a rater gets: ``index.html`` (the session page, ``static/rate.js``),
``session.js`` (``window.CASSI_SESSION``: the cells in their shuffled order, the scale, each
cell's faults) and one task viewer page per animation (``cells/<code>.html``, the viewer's own
page and script, :mod:`cassi.reports.viewer`) whose data names the version by its code only.
``DIR/key.json`` (code -> subject, task file and version; the seed) stays with whoever runs
the study: ``cassi agree --key`` un-blinds an export with it.

A cell is one animation (a subject's task file under one version) and one of the rubric's
tables: the rater gives a word of the thesis's scale (:data:`~cassi.harness.rubric.model.
RATINGS`) and ticks the table's faults as the thesis writes them (the registry's texts) or
writes their own. The cells are shuffled across subjects, tasks, versions and tables with
numpy's Generator seeded by ``seed``; each animation's code is drawn from the same Generator.
Without a seed one is drawn from the operating system: a fixed default would let anyone with
the run rebuild the key.
"""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_write_bytes, atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.harness.evaluation.viewerdata import read_viewer_blob
from cassi.harness.rubric.model import RATINGS, TABLE_TOPICS, TABLES, rate, table_title
from cassi.harness.rubric.registry import CHECKS
from cassi.harness.rubric.tables import file_verdicts
from cassi.reports.agree import (CODE_ALPHABET, CODE_LENGTH, EXPORT_COLUMNS, FAULT_SEPARATOR,
                                 KEY_FORMAT)
from cassi.reports.report import _env as report_env
from cassi.reports.runio import Run, load_run
from cassi.reports.viewer import (STATIC_DIR, copy_static, version_payload, viewer_payload,
                                  write_viewer_page)

__all__ = ["SESSION_DIR", "KEY_FILE", "DEFAULT_TABLES", "session_cells", "write_session"]

SESSION_DIR = "session"
KEY_FILE = "key.json"
CELLS_DIR = "cells"
#: The tables a session rates unless told: the thesis's (F and G are cassi-farm's measures of
#: the recording, which a person watching the face cannot see).
DEFAULT_TABLES = tuple(t for t, (thesis, _) in TABLES.items() if thesis)
_SESSION_STATIC = ("rate.js",)


def _file(task: int, rep: int) -> str:
    return f"{int(task)}" if int(rep) == 1 else f"{int(task)}_{int(rep)}"


def session_cells(run: Run, tables=DEFAULT_TABLES) -> pd.DataFrame:
    """Every (subject, task file, version, table) a person can rate: the run judged the table
    there and kept the task file's viewer data for the version. Columns subject, task, rep,
    file, version, table, path (the viewer data), faults (the table's texts the run judged in
    that task file, in the registry's order, the same for every version)."""
    att = run.attachments
    att = att[att["name"] == "viewer"] if len(att) else att
    cols = ["subject", "task", "rep", "file", "version", "table", "path", "faults"]
    if not len(att):
        return pd.DataFrame(columns=cols)
    fv = file_verdicts(run.results)
    fv = fv[fv["table"].isin(list(tables))]
    order = {name: i for i, name in enumerate(CHECKS)}
    faults = {}
    for (subject, file, table), g in fv.groupby(["subject", "file", "table"]):
        names = sorted((c for c in set(g["check"]) if c in CHECKS and CHECKS[c].counted),
                       key=order.get)
        faults[(subject, file, table)] = list(dict.fromkeys(CHECKS[c].text for c in names))
    judged = set(zip(fv["subject"], fv["file"], fv["version"], fv["table"]))
    rows = []
    for r in att.sort_values(["subject", "task", "rep", "version"]).itertuples(index=False):
        file = _file(r.task, r.rep)
        for table in tables:
            if (r.subject, file, r.version, table) in judged:
                rows.append((r.subject, int(r.task), int(r.rep), file, r.version, table, r.path,
                             faults.get((r.subject, file, table), [])))
    return pd.DataFrame(rows, columns=cols)


def _codes(rng: np.random.Generator, n: int) -> list[str]:
    """``n`` distinct codes (letters of :data:`CODE_ALPHABET`, no digits, no vowels: no word,
    no version number)."""
    if n > len(CODE_ALPHABET) ** CODE_LENGTH // 4:
        raise CassiInputError(f"{n} animations are too many for one session; use --sample")
    out: dict[str, None] = {}
    while len(out) < n:
        out["".join(rng.choice(list(CODE_ALPHABET), CODE_LENGTH))] = None
    return list(out)


def _session_id(cells: list[dict]) -> str:
    """Names the session's saved progress in the browser: the same cells, the same id."""
    text = json.dumps([[c["subject"], c["file"], c["code"], c["table"]] for c in cells])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def write_session(run_dir: str | os.PathLike, out: str | os.PathLike, *,
                  tables=DEFAULT_TABLES, sample: int | None = None,
                  seed: int | None = None, env=None) -> tuple[Path, Path]:
    """Write the rating session of a run into ``out``; returns (``out/session/index.html``,
    ``out/key.json``).

    Raises
    ------
    CassiInputError
        An unknown table, a run without the task viewer's data, a bad ``sample``.
    """
    run = load_run(run_dir)
    tables = tuple(dict.fromkeys(str(t).strip().upper() for t in tables))
    unknown = [t for t in tables if t not in TABLES]
    if unknown:
        raise CassiInputError(f"unknown table(s) {', '.join(unknown)} (the rubric's tables: "
                              f"{', '.join(TABLES)})")
    cells = session_cells(run, tables)
    if not len(cells):
        raise CassiInputError("nothing to rate: the run kept no task viewer data for tables "
                              f"{', '.join(tables)} (cassi run keeps it with its geometry)",
                              path=run.root)
    if sample is not None and sample < 1:
        raise CassiInputError(f"--sample must be at least 1, got {sample}")
    if seed is None:
        seed = int(np.random.SeedSequence().entropy % 2 ** 63)
    rng = np.random.default_rng(seed)
    cells = cells.iloc[rng.permutation(len(cells))].reset_index(drop=True)
    if sample is not None:
        cells = cells.iloc[:sample]
    animations = list(dict.fromkeys(zip(cells["subject"], cells["task"], cells["rep"],
                                        cells["version"])))
    code_of = dict(zip(animations, _codes(rng, len(animations))))
    out = Path(out)
    session = out / SESSION_DIR
    if session.exists() and any(session.iterdir()):
        raise CassiInputError(f"{session} exists: a new session goes into a new directory (the "
                              "old one's key and its raters' saved progress belong to it)")
    env = env or report_env()
    copy_static(session)
    here = Path(__file__).parent / STATIC_DIR
    for name in _SESSION_STATIC:
        atomic_write_bytes(session / STATIC_DIR / name, (here / name).read_bytes())
    for (subject, task, rep, version), code in code_of.items():
        path = cells.loc[(cells["subject"] == subject) & (cells["task"] == task)
                         & (cells["rep"] == rep) & (cells["version"] == version), "path"].iloc[0]
        data = read_viewer_blob(Path(path).read_bytes())
        # no events, no renders: the rater sees the face, not the rubric's findings
        payload = viewer_payload(run, subject, task, rep, {code: version_payload(data, [], [])},
                                 data)
        write_viewer_page(session / CELLS_DIR / f"{code}.html", payload, env,
                          static=f"../{STATIC_DIR}", index=None, blind=True)
    shown = [{"id": f"{code_of[(r.subject, r.task, r.rep, r.version)]}-{r.table}",
              "subject": r.subject, "task": r.task, "rep": r.rep, "file": r.file,
              "code": code_of[(r.subject, r.task, r.rep, r.version)], "table": r.table,
              "topic": TABLE_TOPICS[r.table], "title": table_title(r.table),
              "faults": r.faults,
              "page": f"{CELLS_DIR}/{code_of[(r.subject, r.task, r.rep, r.version)]}.html"}
             for r in cells.itertuples(index=False)]
    sid = _session_id(shown)
    data = {"session": sid, "synthetic": run.synthetic, "scale": list(RATINGS),
            # the thesis counted negatives into words (Table 5.2): the hint beside each word
            "negatives": {rate(n): n for n in range(len(RATINGS))},
            "columns": list(EXPORT_COLUMNS), "fault_separator": FAULT_SEPARATOR,
            "cells": shown}
    atomic_write_text(session / "session.js", "window.CASSI_SESSION = "
                      + json.dumps(data, indent=1, allow_nan=False) + ";\n")
    index = session / "index.html"
    atomic_write_text(index, env.get_template("rate.html.j2").render(
        session=sid, synthetic=run.synthetic, static=STATIC_DIR, n=len(shown)))
    key = {"format": KEY_FORMAT, "session": sid, "seed": seed, "run": str(run.root),
           "tables": list(tables), "sample": sample,
           "codes": {code: {"subject": s, "task": int(t), "rep": int(p), "version": v}
                     for (s, t, p, v), code in code_of.items()}}
    atomic_write_text(out / KEY_FILE, json.dumps(key, indent=1) + "\n")
    return index, out / KEY_FILE
