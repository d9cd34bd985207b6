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

A rating session's export (:mod:`cassi.reports.rating_session`) adds ``rater``, ``faults`` (the
registry's texts the rater ticked, separated by :data:`FAULT_SEPARATOR`), ``note`` (faults in
the rater's own words) and ``session``; its ``version`` is a blinded code, which the session's
key (``--key``) turns back into the version. Several raters, in one file or several, are
compared with each other (Krippendorff's alpha, ordinal), the run with each rater and with their
consensus, and each check with the faults the raters ticked.
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

import krippendorff
import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.harness.rubric.agreement import (KAPPA_BOOTSTRAP_N, KAPPA_BOOTSTRAP_SEED,
                                            agreement_stats)
from cassi.harness.rubric.model import RATINGS, TABLES
from cassi.harness.rubric.registry import CHECKS
from cassi.harness.rubric.tables import file_verdicts, level_ratings
from cassi.reports.runio import Run, order_versions
from cassi.reports.tables import markdown_table

__all__ = ["RATING_FILE_COLUMNS", "SESSION_COLUMNS", "EXPORT_COLUMNS", "FAULT_SEPARATOR",
           "CODE_ALPHABET", "CODE_LENGTH", "KEY_FORMAT", "read_key", "read_human_ratings",
           "agreement", "write_agreement", "SYNTHETIC_NOTE"]

RATING_FILE_COLUMNS = ("subject", "task", "version", "table", "component", "rating")
#: What a rating session's export adds (each optional on reading).
SESSION_COLUMNS = ("rater", "faults", "note", "session")
EXPORT_COLUMNS = RATING_FILE_COLUMNS + SESSION_COLUMNS
#: Between the fault texts a rater ticked (no registry text holds it).
FAULT_SEPARATOR = " | "
#: A blinded code: CODE_LENGTH consonants (no word, no digit to read as a version number).
CODE_ALPHABET = "BCDFGHJKLMNPQRSTVWXZ"
CODE_LENGTH = 4
_CODE_RE = re.compile(f"[{CODE_ALPHABET}]{{{CODE_LENGTH}}}")
KEY_FORMAT = "cassi-rating-key/1"
SYNTHETIC_NOTE = ("Synthetic corpus: the run's ratings describe the software, not real speakers; "
                  "agreement with people who rated them says how the rubric reads the software.")
DISAGREEMENT_COLUMNS = ["file", "line", "rater", "subject", "task", "version", "table",
                        "component", "human", "run", "steps", "run_negatives", "evidence", "viewer"]
RATER_DISAGREEMENT_COLUMNS = ["subject", "task", "version", "table", "component", "ratings",
                              "spread", "consensus", "run", "viewer"]
_UNIT = ["subject", "task", "version", "table", "component"]


def _level(text: str) -> str:
    return " ".join(str(text).split())


def read_key(path: str | os.PathLike) -> dict:
    """A rating session's key (``key.json``): ``session``, ``seed`` and ``codes`` (code ->
    subject, task, rep, version).

    Raises
    ------
    CassiInputError
        Naming the file: missing, not JSON, not a session's key.
    """
    path = Path(path)
    try:
        key = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError as err:
        raise CassiInputError("no such key file", path=path) from err
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise CassiInputError(f"unreadable key file: {err}", path=path) from err
    if not isinstance(key, dict) or key.get("format") != KEY_FORMAT:
        raise CassiInputError(f"not a rating session's key (format {KEY_FORMAT!r}; "
                              "cassi rate writes it as DIR/key.json)", path=path)
    codes = key.get("codes")
    if not isinstance(codes, dict) or not all(
            isinstance(c, dict) and {"subject", "task", "rep", "version"} <= set(c)
            for c in codes.values()):
        raise CassiInputError("the key's codes are not code -> subject, task, rep, version",
                              path=path)
    return key


def read_human_ratings(path: str | os.PathLike, run: Run,
                       levels: pd.DataFrame | None = None, *, key: dict | None = None,
                       seen: dict | None = None) -> pd.DataFrame:
    """The ratings file, checked against the run (and un-blinded with a session's ``key``):
    one row per line with its ``file`` name and ``line`` number, the ``rater`` ("" when the
    file names none), the person's rating (``human``), the run's at the same level (``run``,
    ``run_negatives``), the ticked ``faults`` (None when the file has no faults column) and
    the rater's ``note``. ``seen`` carries the lines read from other files (duplicates).

    Raises
    ------
    CassiInputError
        Naming the file and line of the first bad line.
    """
    path = Path(path)
    rated = _RunLevels.of(level_ratings(run.results) if levels is None else levels)
    reader, header = _ratings_reader(path)
    col = {c: header.index(c) for c in EXPORT_COLUMNS if c in header}
    rows, seen = [], {} if seen is None else seen
    try:
        for cells in reader:
            line = reader.line_num
            if not any(c.strip() for c in cells):
                continue
            row = _rating_row(cells, header, col, rated, key, path=path, line=line)
            dup = (row["rater"], *(row[c] for c in _UNIT))
            if dup in seen:
                first, at = seen[dup]
                where = f"line {at}" if first == path else f"{first.name}:{at}"
                raise CassiInputError(f"duplicate of {where} (same rater, subject, task, "
                                      f"version, table and component)", path=path, line=line)
            seen[dup] = (path, line)
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


def _rating_row(cells: list[str], header: list[str], col: dict, rated: _RunLevels,
                key: dict | None, *, path: Path, line: int) -> dict:
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
    _unblind(v, key, bad)
    if v["version"] not in rated.versions:
        raise bad(f"unknown version {v['version']!r}: the run rated "
                  f"{', '.join(order_versions(rated.versions))}")
    where = (v["subject"], v["version"], table)
    if where not in rated.files:
        raise bad(f"the run has no Table {table} for {v['subject']}, {v['version']}")
    task = _task_file(v, table, rated.files[where], bad)
    if v.get("code") and task != v["code_file"]:
        raise bad(f"code {v['code']} is task file {v['code_file']} in the key, not "
                  f"{task or 'blank'}")
    component = v["component"].lower()
    if component and component not in rated.comps[where]:
        raise bad(f"unknown component {v['component']!r} of Table {table} (the run's: "
                  f"{', '.join(sorted(c for c in rated.comps[where] if c))})")
    key_ = (v["subject"], task, v["version"], table, component)
    if key_ not in rated.have:
        raise bad(f"the run has no rating at this level ({v['subject']}, task "
                  f"{task or 'all'}, {v['version']}, Table {table}, "
                  f"{component or 'whole table'})")
    run_rating, negatives = rated.have[key_]
    return dict(file=path.name, line=line, rater=v.get("rater", ""), subject=key_[0], task=task,
                version=key_[2], table=table, component=component, human=word, run=run_rating,
                run_negatives=negatives,
                faults=_faults(v["faults"], bad) if "faults" in v else None,
                note=v.get("note", ""))


_TEXTS = {c.text for c in CHECKS.values()}


def _faults(text: str, bad) -> tuple[str, ...]:
    """The fault texts a rater ticked; each must be one of the registry's."""
    ticked = tuple(t.strip() for t in text.split(FAULT_SEPARATOR.strip()) if t.strip())
    for t in ticked:
        if t not in _TEXTS:
            raise bad(f"unknown fault {t!r}: the faults a session lists are the rubric's texts "
                      "(its own words go in the note column)")
    return ticked


def _unblind(v: dict, key: dict | None, bad) -> None:
    """Replace a blinded code by its version (``v`` in place; ``code``, ``code_file`` kept to
    check the line's task against the key); refuse a code without its key."""
    session = v.get("session", "")
    if key is None:
        if session:
            raise bad(f"blinded ratings (session {session}): un-blind them with --key, the "
                      "key.json that cassi rate wrote beside the session")
        if _CODE_RE.fullmatch(v["version"]):
            raise bad(f"version {v['version']!r} looks like a blinded code: un-blind the file "
                      "with --key, the key.json that cassi rate wrote beside the session")
        return
    if session and session != key.get("session"):
        raise bad(f"session {session} is not the key's (session {key.get('session')})")
    entry = key["codes"].get(v["version"])
    if entry is None:
        if session:
            raise bad(f"code {v['version']!r} is not in the key")
        return
    if entry["subject"] != v["subject"]:
        raise bad(f"code {v['version']} is subject {entry['subject']} in the key, "
                  f"not {v['subject']}")
    v["code"], v["version"] = v["version"], str(entry["version"])
    v["code_file"] = (f"{int(entry['task'])}" if int(entry["rep"]) == 1
                      else f"{int(entry['task'])}_{int(entry['rep'])}")


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


_IDX = {w: i for i, w in enumerate(RATINGS)}


def agreement(run: Run, ratings_path, evidence_href: Callable[[str, str, str], str], *,
              key_path: str | os.PathLike | None = None,
              viewer_link: Callable[[str, str, str], str] | None = None) -> dict:
    """Per table and version: the statistics of :func:`.agreement_stats` (human rows, run
    columns), and every disagreement with its evidence (``evidence_href(subject, version,
    table)``, relative to the report's directory) and, for a task file's line, its task viewer
    (``viewer_link(subject, file, version)``).

    ``ratings_path``: one ratings file or several (one per rater, say); ``key_path``: the
    session's key that un-blinds their codes. With several raters: ``alpha`` (Krippendorff's,
    ordinal, between the raters), ``raters`` (the run against each), ``consensus`` (the run
    against the median rating of each unit), ``rater_disagreements``; with ticked faults,
    ``checks`` (each check's precision and recall against the ticks) and ``notes``.
    """
    paths = [ratings_path] if isinstance(ratings_path, (str, os.PathLike)) else list(ratings_path)
    key = read_key(key_path) if key_path is not None else None
    levels, seen = level_ratings(run.results), {}
    human = pd.concat([read_human_ratings(p, run, levels, key=key, seen=seen) for p in paths],
                      ignore_index=True)
    viewer_link = viewer_link or (lambda subject, file, version: "")
    groups = []
    for table in sorted(human["table"].unique()):
        t = human[human["table"] == table]
        for version in order_versions(t["version"].unique()):
            g = t[t["version"] == version]
            stats = agreement_stats(g["human"].map(_IDX), g["run"].map(_IDX))
            groups.append({"table": table, "version": version, **stats})
    dis = human[human["human"] != human["run"]].copy()
    # astype first: with no disagreement the mapped columns are empty and untyped
    dis["steps"] = dis["run"].map(_IDX).astype("int64") - dis["human"].map(_IDX).astype("int64")
    dis["evidence"] = [evidence_href(s, v, t) for s, v, t in
                       zip(dis["subject"], dis["version"], dis["table"])]
    dis["viewer"] = [viewer_link(s, f, v) if f else "" for s, f, v in
                     zip(dis["subject"], dis["task"], dis["version"])]
    raters = sorted(human["rater"].unique())
    several = len(raters) > 1
    units = _units(human) if several else pd.DataFrame()
    return {"run": run.name, "ratings_file": ", ".join(str(p) for p in paths),
            "key": str(key_path) if key_path is not None else "",
            "synthetic": run.synthetic,
            "note": SYNTHETIC_NOTE if run.synthetic else "",
            "bootstrap": {"n": KAPPA_BOOTSTRAP_N, "seed": KAPPA_BOOTSTRAP_SEED},
            "scale": list(RATINGS), "groups": groups,
            "disagreements": dis[DISAGREEMENT_COLUMNS].to_dict("records"),
            "rater_names": raters,
            "alpha": _alpha(human) if several else None,
            "raters": _per_rater(human) if several else [],
            "consensus": _consensus(units) if several else [],
            "rater_disagreements": _rater_disagreements(units, viewer_link) if several else [],
            "checks": _checks(human, run),
            "notes": human.loc[human["note"] != "", ["rater", *_UNIT, "note"]]
            .to_dict("records")}


def _units(human: pd.DataFrame) -> pd.DataFrame:
    """One row per unit (subject, task file, version, table, component) two or more raters
    rated: their ratings (rater -> word), the consensus (the median; of two middle ratings the
    milder, the scale's lower index) and the run's rating."""
    rows = []
    for unit, g in human.groupby(_UNIT, sort=True):
        if len(g) < 2:
            continue
        idx = sorted(g["human"].map(_IDX))
        rows.append((*unit, dict(zip(g["rater"], g["human"])), RATINGS[idx[(len(idx) - 1) // 2]],
                     idx[-1] - idx[0], g["run"].iloc[0]))
    return pd.DataFrame(rows, columns=[*_UNIT, "ratings", "consensus", "spread", "run"])


def _alpha_of(data: pd.DataFrame) -> float:
    """Krippendorff's alpha, ordinal on the scale's order, of (rater, unit) ratings; NaN when
    no unit has two ratings or every rating is the same."""
    m = data.pivot(index="rater", columns="unit", values="i").to_numpy(dtype=float)
    try:
        with np.errstate(invalid="ignore", divide="ignore"):
            return float(krippendorff.alpha(reliability_data=m, level_of_measurement="ordinal",
                                            value_domain=list(range(len(RATINGS)))))
    except ValueError:
        return float("nan")


def _alpha(human: pd.DataFrame) -> dict:
    """Alpha between the raters over all units, and per table; ``units``: how many units two or
    more raters rated."""
    d = human.assign(unit=[tuple(u) for u in human[_UNIT].itertuples(index=False)],
                     i=human["human"].map(_IDX))
    pairable = d.groupby("unit")["rater"].nunique()
    out = {"alpha": _alpha_of(d), "units": int((pairable > 1).sum()), "tables": []}
    for table, g in d.groupby("table", sort=True):
        n = int((g.groupby("unit")["rater"].nunique() > 1).sum())
        out["tables"].append({"table": table, "alpha": _alpha_of(g), "units": n})
    return out


def _per_rater(human: pd.DataFrame) -> list[dict]:
    """The run against each rater, per table (all versions together)."""
    out = []
    for (rater, table), g in human.groupby(["rater", "table"], sort=True):
        out.append({"rater": rater, "table": table,
                    **agreement_stats(g["human"].map(_IDX), g["run"].map(_IDX))})
    return out


def _consensus(units: pd.DataFrame) -> list[dict]:
    """The run against the raters' consensus, per table."""
    return [{"table": table, **agreement_stats(g["consensus"].map(_IDX), g["run"].map(_IDX))}
            for table, g in units.groupby("table", sort=True)]


def _rater_disagreements(units: pd.DataFrame, viewer_link) -> list[dict]:
    """Units the raters rated differently, the widest spread first."""
    d = units[units["spread"] > 0].sort_values(["spread", *_UNIT], ascending=[False] + [True] * 5,
                                               kind="mergesort")
    return [{**{c: r[c] for c in _UNIT}, "ratings": "; ".join(f"{k or '(unnamed)'}: {w}"
                                                              for k, w in r["ratings"].items()),
             "spread": int(r["spread"]), "consensus": r["consensus"], "run": r["run"],
             "viewer": viewer_link(r["subject"], r["task"], r["version"]) if r["task"] else ""}
            for _, r in d.iterrows()]


def _checks(human: pd.DataFrame, run: Run) -> list[dict]:
    """Per check, over the rated task-file cells that recorded ticks: ``cells`` (where the run
    judged it), ``fired`` (the run charged it a negative there), ``ticked`` (the rater ticked its
    text), ``both``; precision = both / ticked, recall = both / fired (NaN when 0 / 0)."""
    rows = human[human["faults"].notna() & (human["task"] != "")] \
        if "faults" in human else human.iloc[:0]
    if not len(rows):
        return []
    fv = file_verdicts(run.results)
    fv = fv[[c in CHECKS and CHECKS[c].counted for c in fv["check"]]]
    judged = {k: g for k, g in fv.groupby(["subject", "file", "version", "table"])}
    count: dict[tuple, list[int]] = {}
    for r in rows.itertuples(index=False):
        g = judged.get((r.subject, r.task, r.version, r.table))
        if g is None:
            continue
        if r.component:
            g = g[g["component"] == r.component]
        for check, n in g.groupby("check")["negatives"].max().items():
            fired, ticked = int(n) > 0, CHECKS[check].text in r.faults
            c = count.setdefault((r.table, check), [0, 0, 0, 0])
            c[0] += 1
            c[1] += fired
            c[2] += ticked
            c[3] += fired and ticked
    return [{"table": table, "check": check, "text": CHECKS[check].text, "cells": n,
             "fired": fired, "ticked": ticked, "both": both,
             "precision": both / ticked if ticked else float("nan"),
             "recall": both / fired if fired else float("nan")}
            for (table, check), (n, fired, ticked, both) in sorted(count.items())]


def _f(x: float, digits: int = 2) -> str:
    return "n/a" if x is None or x != x else f"{x:.{digits}f}"


def _markdown(result: dict) -> str:
    out = [f"# Agreement with human raters: {result['run']}", ""]
    if result["note"]:
        out += [f"**{result['note']}**", ""]
    out += [f"Ratings file: `{result['ratings_file']}`"
            + (f" (un-blinded with `{result['key']}`)" if result["key"] else "")
            + ". Per table and version: exact agreement "
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
    out += _raters_markdown(result) + _checks_markdown(result)
    out += ["## Disagreements", ""]
    if result["disagreements"]:
        out += ["Evidence and viewer links are relative to the run's report (`cassi report RUN "
                "--out DIR`).", "",
                markdown_table(pd.DataFrame(result["disagreements"]).set_index(["file", "line"])),
                ""]
    else:
        out += ["None.", ""]
    return "\n".join(out)


def _stats_row(g: dict) -> dict:
    return {"n": g["n"], "exact": _f(g["exact"]), "within one": _f(g["within_one"]),
            "kappa": _f(g["kappa"]), "95% interval": f"[{_f(g['kappa_low'])}, {_f(g['kappa_high'])}]"}


def _raters_markdown(result: dict) -> list[str]:
    """Between the raters, the run against each and against their consensus."""
    a = result["alpha"]
    if a is None:
        return []
    out = [f"## Between the raters ({', '.join(result['rater_names'])})", "",
           f"Krippendorff's alpha (ordinal, on the scale's order) over {a['units']} unit(s) "
           "(subject, task file, version, table, component) rated by two or more: "
           f"**{_f(a['alpha'])}** (1 perfect, 0 what chance gives; n/a: undefined).", "",
           markdown_table(pd.DataFrame([{"table": t["table"], "alpha": _f(t["alpha"]),
                                         "units": t["units"]} for t in a["tables"]])
                          .set_index("table")), "",
           "## The run against each rater", "",
           markdown_table(pd.DataFrame([{"rater": g["rater"], "table": g["table"],
                                         **_stats_row(g)} for g in result["raters"]])
                          .set_index(["rater", "table"])), ""]
    if result["consensus"]:
        out += ["## The run against the consensus", "",
                "The consensus of a unit is the median of its ratings (of two middle ratings, the "
                "milder).", "",
                markdown_table(pd.DataFrame([{"table": g["table"], **_stats_row(g)}
                                             for g in result["consensus"]]).set_index("table")),
                ""]
    out += ["## Disagreements between the raters", ""]
    if result["rater_disagreements"]:
        out += ["Widest spread (steps of the scale) first; viewer links are relative to the run's "
                "report.", "", markdown_table(pd.DataFrame(result["rater_disagreements"])
                                             .set_index(_UNIT)), ""]
    else:
        out += ["None.", ""]
    return out


def _checks_markdown(result: dict) -> list[str]:
    """Each check against the faults the raters ticked, and the faults they wrote."""
    out = []
    shown = [c for c in result["checks"] if c["fired"] or c["ticked"]]
    if result["checks"]:
        out += ["## The checks against the ticked faults", "",
                "Per check, over the rated task-file cells where the run judged it: fired = the "
                "run charged it a negative there, ticked = the rater ticked its text; precision "
                "= both / ticked, recall = both / fired. "
                f"{len(result['checks']) - len(shown)} check(s) neither fired nor ticked are left "
                "out (agreement.json has them).", ""]
    if shown:
        out += [markdown_table(pd.DataFrame([{**c, "precision": _f(c["precision"]),
                                              "recall": _f(c["recall"])} for c in shown])
                               .set_index(["table", "check"])), ""]
    if result["notes"]:
        out += ["## Faults in the raters' own words", "",
                markdown_table(pd.DataFrame(result["notes"]).set_index("rater")), ""]
    return out


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
