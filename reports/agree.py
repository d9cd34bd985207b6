"""``cassi agree``: a run's ratings against ratings people gave.

The ratings file (CSV, UTF-8, a header line) has the columns ``subject,task,version,table,
component,rating`` (others, e.g. a rater's name or a note, are ignored):

- ``table``: the rubric's table letter (A .. F);
- ``rating``: a word of the thesis's scale (EXCELLENT, VERY GOOD, GOOD, FAIR, POOR, VERY POOR,
  UNACCEPTABLE; any case);
- ``task`` blank: the rating covers all the subject's files (the subject's rating, as the
  report's tables give it); a task number (``21``, or ``21_2`` for repetition 2): that file;
- ``component`` blank: the whole table (the components' negatives summed, rated).

Each line is compared with the run's rating at the same level
(:func:`cassi.harness.rubric.tables.level_ratings`). A bad line (unknown word, subject, version,
table, task, component; a level the run did not rate; a duplicate; a line with fewer fields than
the header, or a filled field beyond it) is refused with its line. Blank fields beyond the header
(a spreadsheet's trailing commas) are read as nothing.
"""
from __future__ import annotations

import csv
import io
import json
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pandas as pd

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.harness.rubric.agreement import (KAPPA_BOOTSTRAP_N, KAPPA_BOOTSTRAP_SEED,
                                            agreement_stats)
from cassi.harness.rubric.model import RATINGS, TABLES
from cassi.harness.rubric.tables import level_ratings
from cassi.reports.runio import Run, order_versions
from cassi.reports.tables import markdown_table

__all__ = ["RATING_FILE_COLUMNS", "read_human_ratings", "agreement", "write_agreement",
           "SYNTHETIC_NOTE"]

RATING_FILE_COLUMNS = ("subject", "task", "version", "table", "component", "rating")
SYNTHETIC_NOTE = ("Synthetic corpus: the run's ratings describe the software, not real speakers; "
                  "agreement with people who rated them says how the rubric reads the software.")
DISAGREEMENT_COLUMNS = ["line", "subject", "task", "version", "table", "component", "human", "run",
                        "steps", "run_negatives", "evidence"]


def _level(text: str) -> str:
    return " ".join(str(text).split())


def read_human_ratings(path: str | os.PathLike, run: Run,
                       levels: pd.DataFrame | None = None) -> pd.DataFrame:
    """The ratings file, checked against the run: one row per line with its ``line`` number,
    the person's rating (``human``) and the run's at the same level (``run``, ``run_negatives``).

    Raises
    ------
    CassiInputError
        Naming the file and line of the first bad line.
    """
    path = Path(path)
    rated = _RunLevels.of(level_ratings(run.results) if levels is None else levels)
    reader, header = _ratings_reader(path)
    col = {c: header.index(c) for c in RATING_FILE_COLUMNS}
    rows, seen = [], {}
    try:
        for cells in reader:
            line = reader.line_num
            if not any(c.strip() for c in cells):
                continue
            row = _rating_row(cells, header, col, rated, path=path, line=line)
            key = tuple(row[c] for c in ("subject", "task", "version", "table", "component"))
            if key in seen:
                raise CassiInputError(f"duplicate of line {seen[key]} (same subject, task, "
                                      f"version, table and component)", path=path, line=line)
            seen[key] = line
            rows.append(row)
    except csv.Error as err:
        raise CassiInputError(f"malformed CSV: {err}", path=path, line=reader.line_num) from err
    if not rows:
        raise CassiInputError("no ratings: the file has a header and nothing else", path=path,
                              line=1)
    return pd.DataFrame(rows)


@dataclass(frozen=True)
class _RunLevels:
    """What the run rated: each level's rating, and the names a ratings line may use."""

    have: dict        # (subject, file, version, table, component) -> (rating, negatives)
    subjects: set
    versions: set
    files: dict       # (subject, version, table) -> the task files it judged
    comps: dict       # (subject, version, table) -> its components

    @classmethod
    def of(cls, levels: pd.DataFrame) -> "_RunLevels":
        """Index :func:`level_ratings`'s rows."""
        have = {(r.subject, r.file, r.version, r.table, r.component): (r.rating, int(r.negatives))
                for r in levels.itertuples(index=False)}
        files = {(r.subject, r.version, r.table): set() for r in levels.itertuples(index=False)}
        comps = {key: set() for key in files}
        for r in levels.itertuples(index=False):
            files[(r.subject, r.version, r.table)].add(r.file)
            comps[(r.subject, r.version, r.table)].add(r.component)
        return cls(have, set(levels["subject"]), set(levels["version"]), files, comps)


def _ratings_reader(path: Path) -> tuple:
    """Open the ratings file and check its header; the CSV reader after it, and the header."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError as err:
        raise CassiInputError("no such ratings file", path=path) from err
    except (OSError, UnicodeDecodeError) as err:
        raise CassiInputError(f"unreadable ratings file: {err}", path=path) from err
    # only \n and \r end a line (str.splitlines would also split at \f, \v, \x85 ...); strict: an
    # unterminated quote is an error, not a field running to the end of the file
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    try:
        header = [h.strip().lower() for h in next(reader)]
    except StopIteration:
        raise CassiInputError("empty ratings file: expected the header "
                              + ",".join(RATING_FILE_COLUMNS), path=path, line=1) from None
    except csv.Error as err:
        raise CassiInputError(f"malformed CSV: {err}", path=path, line=reader.line_num) from err
    twice = sorted({h for h in header if h and header.count(h) > 1})
    if twice:
        raise CassiInputError(f"the header names column(s) {', '.join(twice)} more than once",
                              path=path, line=1)
    missing = [c for c in RATING_FILE_COLUMNS if c not in header]
    if missing:
        raise CassiInputError(f"the header lacks column(s) {', '.join(missing)} (expected "
                              f"{','.join(RATING_FILE_COLUMNS)})", path=path, line=1)
    return reader, header


_WORDS = {w.upper(): w for w in RATINGS}


def _rating_row(cells: list[str], header: list[str], col: dict, rated: _RunLevels, *,
                path: Path, line: int) -> dict:
    """Check one line's fields against the run; its row, with the run's rating beside it."""
    def bad(why: str):
        return CassiInputError(why, path=path, line=line)
    # blank cells beyond the header are a spreadsheet's trailing commas; a filled one
    # or a missing one is a comma out of place, which would shift the columns
    if len(cells) < len(header) or any(c.strip() for c in cells[len(header):]):
        raise bad(f"{len(cells)} fields, the header has {len(header)}")
    v = {c: cells[i].strip() for c, i in col.items()}
    for need in ("subject", "version", "table", "rating"):
        if not v[need]:
            raise bad(f"no {need}")
    word = _WORDS.get(_level(v["rating"]).upper())
    if word is None:
        raise bad(f"unknown rating {v['rating']!r}: a word of the thesis's scale "
                  f"({', '.join(RATINGS)})")
    table = v["table"].upper()
    if table not in TABLES:
        raise bad(f"unknown table {v['table']!r} (the rubric's tables: {', '.join(TABLES)})")
    if v["subject"] not in rated.subjects:
        raise bad(f"unknown subject {v['subject']!r}: the run rated "
                  f"{', '.join(sorted(rated.subjects))}")
    if v["version"] not in rated.versions:
        raise bad(f"unknown version {v['version']!r}: the run rated "
                  f"{', '.join(order_versions(rated.versions))}")
    where = (v["subject"], v["version"], table)
    if where not in rated.files:
        raise bad(f"the run has no Table {table} for {v['subject']}, {v['version']}")
    task = _task_file(v, table, rated.files[where], bad)
    component = v["component"].lower()
    if component and component not in rated.comps[where]:
        raise bad(f"unknown component {v['component']!r} of Table {table} (the run's: "
                  f"{', '.join(sorted(c for c in rated.comps[where] if c))})")
    key = (v["subject"], task, v["version"], table, component)
    if key not in rated.have:
        raise bad(f"the run has no rating at this level ({v['subject']}, task "
                  f"{task or 'all'}, {v['version']}, Table {table}, "
                  f"{component or 'whole table'})")
    run_rating, negatives = rated.have[key]
    return dict(line=line, subject=key[0], task=task, version=key[2], table=table,
                component=component, human=word, run=run_rating, run_negatives=negatives)


def _task_file(v: dict, table: str, judged: set, bad) -> str:
    """A line's task as the run names its files ("" for all; ``21``, ``21_2``), if judged."""
    task = v["task"]
    if task:
        parts = task.split("_")
        if not all(re.fullmatch(r"[0-9]{1,4}", p) for p in parts) or len(parts) > 2:
            raise bad(f"task {task!r} is not a task number (21) or task_repetition (21_2)")
        task = str(int(parts[0])) if len(parts) == 1 or int(parts[1]) == 1 else \
            f"{int(parts[0])}_{int(parts[1])}"
        if task not in judged:
            raise bad(f"the run judged no task file {v['task']} in Table {table} for "
                      f"{v['subject']}, {v['version']}")
    return task


def agreement(run: Run, ratings_path: str | os.PathLike,
              evidence_href: Callable[[str, str, str], str]) -> dict:
    """Per table and version: the statistics of :func:`.agreement_stats` (human rows, run
    columns), and every disagreement with its evidence (``evidence_href(subject, version,
    table)``, relative to the report's directory)."""
    human = read_human_ratings(ratings_path, run)
    idx = {w: i for i, w in enumerate(RATINGS)}
    groups = []
    for table in sorted(human["table"].unique()):
        t = human[human["table"] == table]
        for version in order_versions(t["version"].unique()):
            g = t[t["version"] == version]
            stats = agreement_stats(g["human"].map(idx), g["run"].map(idx))
            groups.append({"table": table, "version": version, **stats})
    dis = human[human["human"] != human["run"]].copy()
    # astype first: with no disagreement the mapped columns are empty and untyped
    dis["steps"] = dis["run"].map(idx).astype("int64") - dis["human"].map(idx).astype("int64")
    dis["evidence"] = [evidence_href(s, v, t) for s, v, t in
                       zip(dis["subject"], dis["version"], dis["table"])]
    return {"run": run.name, "ratings_file": str(ratings_path), "synthetic": run.synthetic,
            "note": SYNTHETIC_NOTE if run.synthetic else "",
            "bootstrap": {"n": KAPPA_BOOTSTRAP_N, "seed": KAPPA_BOOTSTRAP_SEED},
            "scale": list(RATINGS), "groups": groups,
            "disagreements": dis[DISAGREEMENT_COLUMNS].to_dict("records")}


def _f(x: float, digits: int = 2) -> str:
    return "n/a" if x is None or x != x else f"{x:.{digits}f}"


def _markdown(result: dict) -> str:
    out = [f"# Agreement with human raters: {result['run']}", ""]
    if result["note"]:
        out += [f"**{result['note']}**", ""]
    out += [f"Ratings file: `{result['ratings_file']}`. Per table and version: exact agreement "
            "(share of equal ratings), within one step of the scale, quadratic weighted Cohen's "
            f"kappa with a percentile bootstrap 95% interval ({result['bootstrap']['n']} resamples "
            f"of the rated items, seed {result['bootstrap']['seed']}).", ""]
    summary = pd.DataFrame([{"table": g["table"], "version": g["version"], "n": g["n"],
                             "exact": _f(g["exact"]), "within one": _f(g["within_one"]),
                             "kappa": _f(g["kappa"]),
                             "95% interval": f"[{_f(g['kappa_low'])}, {_f(g['kappa_high'])}]"}
                            for g in result["groups"]])
    out += [markdown_table(summary.set_index(["table", "version"])), ""]
    for g in result["groups"]:
        m = pd.DataFrame(g["confusion"], index=pd.Index(result["scale"], name="people \\ run"),
                         columns=result["scale"])
        m = m.loc[(m.sum(axis=1) > 0).to_numpy(), (m.sum(axis=0) > 0).to_numpy()]
        out += [f"## Table {g['table']}, {g['version']}: confusion (rows: people, columns: the run)",
                "", markdown_table(m), ""]
    out += ["## Disagreements", ""]
    if result["disagreements"]:
        out += ["Evidence links are relative to the run's report (`cassi report RUN --out DIR`).",
                "", markdown_table(pd.DataFrame(result["disagreements"]).set_index("line")), ""]
    else:
        out += ["None.", ""]
    return "\n".join(out)


def _plain(x):
    """JSON-ready: numpy scalars as Python's, NaN (an undefined kappa) as null."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if hasattr(x, "item"):
        x = x.item()
    return None if isinstance(x, float) and x != x else x


def write_agreement(result: dict, out: str | os.PathLike) -> list[Path]:
    """``agreement.json``, ``agreement.md`` and ``agreement.csv`` (the disagreements) in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "agreement.json", out / "agreement.md", out / "agreement.csv"]
    atomic_write_text(paths[0], json.dumps(_plain(result), indent=2, allow_nan=False) + "\n")
    atomic_write_text(paths[1], _markdown(result))
    atomic_write_text(paths[2], pd.DataFrame(result["disagreements"], columns=DISAGREEMENT_COLUMNS)
                      .to_csv(index=False, lineterminator="\n"))
    return paths
