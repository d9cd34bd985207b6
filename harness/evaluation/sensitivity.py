"""``cassi sensitivity RUN``: each version-level finding of a finished run with its robustness.

Settings are one constant at one end of its declared range, one at a time (2 per constant, plus
the baseline; :mod:`cassi.harness.rubric.sensitivity` says what a finding is):

- a rubric threshold is re-applied to the run's stored values: no animation, no render;
- a version constant (:mod:`cassi.versions.ranges`) animates the run's task files again with
  every version of the run and runs the geometric checks (one geometry stage, on the run's
  corpus); the image checks keep the run's values, which only a render could change.

Writes ``sensitivity.json`` and ``sensitivity.md``.
"""
from __future__ import annotations

import hashlib
import json
import tempfile
import time
from pathlib import Path

import pandas as pd

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.harness.evaluation.caches import get_corpus, get_face, get_profile
from cassi.harness.evaluation.stages import checked_animation
from cassi.harness.farm.executors import LocalExecutor
from cassi.harness.farm.results import normalize, read_results
from cassi.harness.farm.workers import thread_env
from cassi.harness.rubric import sensitivity as S
from cassi.renderer.views import VIEW_NAMES
from cassi.versions.protocol import version_face
from cassi.versions.ranges import constant_set, ranged_constants
from cassi.versions.registry import get_version

__all__ = ["ONLY", "sensitivity", "sensitivity_markdown"]

#: What ``--only`` may name.
ONLY = ("thresholds", "versions")
JSON_NAME, MD_NAME = "sensitivity.json", "sensitivity.md"


def _read_run(run: Path) -> tuple[pd.DataFrame, dict]:
    meta_path, results_path = run / "run.json", run / "results.parquet"
    for p in (meta_path, results_path):
        if not p.is_file():
            raise CassiInputError("not a finished run directory (no such file)", path=p)
    try:
        meta = json.loads(meta_path.read_text())
    except (OSError, ValueError) as err:
        raise CassiInputError(f"cannot read the run's metadata: {err}", path=meta_path) from err
    return read_results(results_path), meta


def _fresh_face(corpus, subject, profile, version):
    """The face ``version`` animates, built under the setting (the worker cache's may not be)."""
    return version_face(version, get_face(corpus, subject, profile))


def _geometry_rows(corpus_dir: str, subject: str, task: int, rep: int, version: str,
                   constant: str, value: float) -> pd.DataFrame:
    """The geometry stage's rows of one task file and version with ``constant`` at ``value``
    (a worker process; the version is built while the setting holds)."""
    corpus = get_corpus(corpus_dir)
    profile = get_profile(corpus, subject)
    rec = corpus.subject(subject).load(task, rep, require_valid=False)
    with constant_set(constant, value), tempfile.TemporaryDirectory() as tmp:
        ver = get_version(version)
        _, _, rows = checked_animation(ver, corpus, subject, profile, rec, task=task, rep=rep,
                                       tmp=Path(tmp), version_face_of=_fresh_face)
    return rows


def _files(meta: dict) -> list[tuple[str, int, int]]:
    rows = meta.get("tasks_resolved")
    if rows is None:
        raise CassiInputError("run.json lists no task files (tasks_resolved): a run written "
                              "before they were recorded cannot be animated again")
    return [(str(s), int(t), int(r)) for s, t, r, usable, *_ in rows if usable]


def _with_geometry(results: pd.DataFrame, rows: list[pd.DataFrame], synthetic: bool) -> pd.DataFrame:
    """The run's results with every row the geometry stage wrote replaced by ``rows``; the
    image checks' rows (render views) stay as the run measured them."""
    kept = results[results["view"].isin(VIEW_NAMES)]
    new = normalize(pd.concat(rows, ignore_index=True), synthetic=synthetic)
    return pd.concat([kept, new], ignore_index=True)


def _memo_key(run: Path, meta: dict, only: str | None) -> str:
    """What an analysis depends on: the results table's bytes, the code and rubric that graded
    them and that re-grade them (the run's provenance digests), the packages, ``only``. The
    versions' own code only where the analysis animates them again: re-grading the same
    results under other thresholds reads no version's code (a version's code changed without
    changing its results, as in a refactor, reuses it)."""
    prov = meta.get("provenance") or {}
    names = ("code_digest", "rubric_digest", "packages") + (
        () if only == "thresholds" else ("versions_code_digest",))
    doc = {k: prov.get(k) for k in names}
    if None in doc.values():
        return ""   # a run without provenance: nothing to recognise it by, always computed
    h = hashlib.sha256((run / "results.parquet").read_bytes())
    h.update(json.dumps({**doc, "only": only, "format": 1}, sort_keys=True).encode())
    return h.hexdigest()


def _write(doc: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / JSON_NAME, json.dumps(doc, indent=1) + "\n")
    atomic_write_text(out / MD_NAME, sensitivity_markdown(doc))


def sensitivity(run: str | Path, out: str | Path | None = None, *, only: str | None = None,
                workers: int | None = None, log=print, memo: str | Path | None = None) -> dict:
    """Evaluate every setting on the run in ``run``; write :data:`JSON_NAME` and
    :data:`MD_NAME` into ``out`` (default ``run``) and return what the JSON holds.

    With ``memo`` (a folder kept across runs: a nightly store's), an analysis of the same
    results table by the same code and rubric is taken from there, saying so
    (``reused_from``), instead of computed again.
    """
    run, out = Path(run), Path(out) if out is not None else Path(run)
    if only is not None and only not in ONLY:
        raise CassiInputError(f"--only takes {' or '.join(ONLY)}, not {only!r}")
    results, meta = _read_run(run)
    key = _memo_key(run, meta, only) if memo is not None else ""
    kept = Path(memo) / f"{key}.json" if key else None
    if kept is not None and kept.is_file():
        earlier = json.loads(kept.read_text())
        doc = {**earlier, "run": str(run.resolve()),
               "reused_from": earlier.get("reused_from") or earlier["run"]}
        _write(doc, out)
        log(f"robustness: the same results table and code as {doc['reused_from']}: reused")
        return doc
    S.verify_grades(results, str(run / "results.parquet"))
    t0 = time.perf_counter()
    base = S.findings(results)
    timing = {"baseline_s": round(time.perf_counter() - t0, 2)}
    evaluated: list[tuple[S.Setting, dict]] = []
    if only in (None, "thresholds"):
        t0 = time.perf_counter()
        base_totals = {k: v for k, v in base.items() if k[0] == "totals"}
        for setting, check in S.threshold_settings():
            reached = S.tables_reached(check)
            rows = results[results["table"].isin(reached)]
            found = {k: v for k, v in base_totals.items() if k[1] not in reached}
            found.update(S.findings(S.regraded(rows, check), kinds=("totals",)))
            evaluated.append((setting, found))
        n = sum(s.kind == "threshold" for s, _ in evaluated)
        timing["threshold_settings"] = n
        timing["threshold_s_each"] = round((time.perf_counter() - t0) / max(n, 1), 2)
    if only in (None, "versions"):
        evaluated += _version_settings(results, meta, workers, timing, log)
    doc = dict(run=str(run.resolve()), synthetic=bool(meta.get("synthetic")), only=only,
               settings_per_constant=2, timing=timing,
               constants=_constants(only),
               findings=S.robustness(base, evaluated),
               note="the generator's calibration is not among the constants; under a version "
                    "setting the image checks keep the run's values (a render would be needed)")
    _write(doc, out)
    if kept is not None:
        kept.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(kept, json.dumps(doc, indent=1) + "\n")
    return doc


def _in_order(pool: LocalExecutor, fn, calls: list[tuple]) -> list:
    """``fn(*args)`` for every call on the pool's workers, the values in the calls' order; a
    failed call fails the analysis with its reason."""
    for i, args in enumerate(calls):
        pool.submit(str(i), fn, *args)
    values: dict[int, object] = {}
    while pool.pending():
        for item in pool.wait():
            if not item.ok:
                raise RuntimeError(f"a geometry setting failed: {item.error}")
            values[int(item.key)] = item.value
    return [values[i] for i in range(len(calls))]


def _version_settings(results, meta, workers, timing, log) -> list[tuple[S.Setting, dict]]:
    files = _files(meta)
    versions = [v for v in meta.get("versions_resolved") or results["version"].unique()]
    corpus = meta.get("corpus_resolved") or meta.get("corpus")
    jobs = [(s, t, r, v) for s, t, r in files for v in versions]
    synthetic = bool(meta.get("synthetic"))
    evaluated, spent = [], []
    workers = workers or int(meta.get("workers_resolved") or 1)
    with LocalExecutor(workers, env=thread_env(1)) as pool:   # the farm's process pool
        for c in ranged_constants().values():
            for end in (c.low, c.high):
                t0 = time.perf_counter()
                rows = _in_order(pool, _geometry_rows,
                                 [(corpus, s, t, r, v, c.name, end) for s, t, r, v in jobs])
                evaluated.append((S.Setting("version", c.name, end, c.value),
                                  S.findings(_with_geometry(results, rows, synthetic))))
                spent.append(time.perf_counter() - t0)
                log(f"{c.name} = {end:g}: {spent[-1]:.1f} s ({len(jobs)} animations)")
    timing.update(version_settings=len(spent), geometry_jobs_each=len(jobs), workers=workers,
                  version_s_each=round(sum(spent) / max(len(spent), 1), 1))
    return evaluated


def _constants(only: str | None) -> list[dict]:
    """The ranged constants the analysis moved, with their ranges and reasons."""
    rows = S.threshold_ranges() if only in (None, "thresholds") else []
    if only in (None, "versions"):
        rows += [dict(kind="version", constant=c.name, value=c.value, low=c.low, high=c.high,
                      reason=c.reason) for c in ranged_constants().values()]
    return rows


def _md_cell(x) -> str:
    return str(x).replace("|", "\\|") if x not in (None, "") else ""


def sensitivity_markdown(doc: dict) -> str:
    """The document as Markdown: the findings with their robustness, then the constants."""
    t = S.robustness_table(doc)
    lines = ["# Robustness of the version-level findings", "",
             f"Run: `{doc['run']}`" + (" (synthetic corpus: results describe the software, not "
                                       "real speakers)" if doc.get("synthetic") else ""), "",
             f"Each setting moves one constant to one end of its declared range; {doc['note']}.",
             "A finding holds in k of n settings (the baseline is one); paired findings are "
             "judged under version settings only (a threshold changes no measured value).", "",
             "| " + " | ".join(S.TABLE_COLUMNS) + " |", "|" + "---|" * len(S.TABLE_COLUMNS)]
    lines += ["| " + " | ".join(_md_cell(r[c]) for c in S.TABLE_COLUMNS) + " |"
              for _, r in t.iterrows()]
    lines += ["", "## Constants and their ranges", "",
              "| constant | kind | value | low | high | reason |", "|---|---|---|---|---|---|"]
    lines += [f"| {c['constant']} | {c['kind']} | {c['value']:g} | {c['low']:g} | {c['high']:g} "
              f"| {_md_cell(c['reason'])} |" for c in doc["constants"]]
    tm = doc["timing"]
    lines += ["", "## Cost", "", "; ".join(f"{k}: {v}" for k, v in tm.items()), ""]
    if doc.get("reused_from"):
        lines += [f"Reused from `{doc['reused_from']}`: the same results table (by its bytes), "
                  "code and rubric; the cost above is that analysis's.", ""]
    return "\n".join(lines)
