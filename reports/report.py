"""``cassi report``: a self-contained HTML report (plus CSV and Markdown tables) of one run.

Everything comes from the run's files; renders are stored beside the report once each, as
lossless WebP named by their content; every string from data files goes through Jinja2's
autoescaping; file names derived from data are slugged.
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import jinja2
import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_write_bytes, atomic_write_text
from cassi.common.cores import usable_cores
from cassi.reports import compare as cmp
from cassi.reports.agree import agreement, write_agreement
from cassi.reports import media, plots
from cassi.reports.runio import Run, load_run, order_versions
from cassi.harness.evaluation import frames as frame_policy
from cassi.harness.evaluation.frames import (COMPARED_TASKS, COMPARISON_VIEW, VIDEO_VIEWS,
                                             linked_frames, video_grid)
from cassi.harness.evaluation.provenance import rubric_digest
from cassi.harness.evaluation.stages import MASKS_OUTPUT
from cassi.harness.farm.executors import LocalExecutor
from cassi.harness.farm.workers import thread_env
from cassi.harness.rubric import (AGGREGATION_RULES, CHECKS, RATINGS, component_ratings,
                                  file_verdicts, negatives_text, rating_counts, table_c_rule,
                                  table_title, table_totals, shown_beside, verdicts,
                                  version_comparisons, version_totals)
from cassi.harness.rubric.paired import (BOOTSTRAP_N, BOOTSTRAP_SEED, TIE_TOLERANCE,
                                         bootstrap_median, paired_comparisons, paired_sentence,
                                         sign_test)
from cassi.reports.sensitivity import sensitivity_section
from cassi.harness.rubric.thesis_findings import reproduced
from cassi.reports.tables import markdown_table
from cassi.reports.memo import Memo
from cassi.reports.pagekeys import PageKeys
from cassi.reports.viewer import stored_overlay, viewer_href, write_viewers
from cassi.data.corpus.disk import Corpus
from cassi.data.xrmb.files import NOMINAL_PERIOD_US

#: How many fired checks per version and task file show the four views of their frame on a
#: subject page (the rest link to the frame's number only).
MAX_SHEETS_PER_VERSION = 12
#: A subject page shows a check's group of fault cards open when it holds at most this many
#: (a default night's few task files); larger groups (a full set's 120 files) start folded.
GROUP_OPEN_UP_TO = 4
#: A table longer than this many rows is embedded as data and drawn when it is opened (the
#: silent checks of a subject page, the index's per-file criterion table).
LAZY_ROWS = 200


def slug(text: str) -> str:
    """A file-name-safe form of ``text``; distinct texts give distinct slugs."""
    text = str(text)
    clean = re.sub(r"[^A-Za-z0-9_.-]+", "-", text).strip("-.")[:60] or "x"
    if clean == text:
        return clean
    return f"{clean}-{hashlib.sha1(text.encode()).hexdigest()[:6]}"


def _env() -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.FileSystemLoader(Path(__file__).parent),
                              autoescape=True, undefined=jinja2.StrictUndefined,
                              trim_blocks=True, lstrip_blocks=True)


def _write_table(df: pd.DataFrame, out: Path, stem: str) -> tuple[str, str]:
    csv, md = out / "tables" / f"{stem}.csv", out / "tables" / f"{stem}.md"
    atomic_write_text(csv, df.to_csv(lineterminator="\n"))
    atomic_write_text(md, markdown_table(df))
    return csv.relative_to(out).as_posix(), md.relative_to(out).as_posix()


def evidence_anchor(version: str, table: str) -> str:
    """The id of a version's evidence for one table on a subject page."""
    return f"{slug(version)}-table-{slug(table)}"


def evidence_href(subject: str, version: str, table: str) -> str:
    """A version's evidence for one table on a subject's page, relative to the report."""
    return f"subjects/{slug(subject)}.html#{evidence_anchor(version, table)}"


def _table_sections(run: Run, cr: pd.DataFrame, out: Path,
                    links: dict | None = None) -> list[dict]:
    """The thesis tables; each fault a cell names links to the viewer at its frame
    (``links``: :func:`_fault_links`)."""
    links = links or {}
    verdict_rows = {k: g for k, g in verdicts(run.results).groupby(
        ["subject", "version", "table", "component"], sort=True)}
    sections = []
    for table in sorted(cr["table"].unique()):
        tid = slug(table)
        counts = rating_counts(run.results, table, ratings=cr)
        counts_csv, counts_md = _write_table(counts, out, f"rating_counts_{tid}")
        plot = plots.rating_distribution(counts, out / "plots" / f"ratings_{tid}.png",
                                         title=table_title(table), synthetic=run.synthetic)
        sub = cr[cr["table"] == table]
        components = sorted(sub["component"].unique())
        versions = order_versions(sub["version"].unique())
        files = []
        for version in versions:
            cells = sub[sub["version"] == version]
            csv, md = _write_table(
                cells.set_index(["subject", "component"])[["negatives", "rating", "text", "reason"]],
                out, f"table_{tid}_{slug(version)}")
            files.append({"version": version, "csv": csv, "md": md})
        lookup = sub.set_index(["subject", "version", "component"])
        rows = []
        for subject in sorted(sub["subject"].unique()):
            page = f"subjects/{slug(subject)}.html"
            cells = []
            for version in versions:
                for c in components:
                    key = (subject, version, c)
                    cells.append(None if key not in lookup.index else {
                        "rating": lookup.at[key, "rating"], "text": lookup.at[key, "text"],
                        "reason": lookup.at[key, "reason"],
                        "level": RATINGS.index(lookup.at[key, "rating"]),
                        "href": f"{page}#{evidence_anchor(version, table)}",
                        "faults": _cell_faults(verdict_rows.get((subject, version, table, c),
                                                                pd.DataFrame(columns=["check",
                                                                                      "negatives"])),
                                               lookup.at[key, "text"], links,
                                               (subject, version, table, c))})
            rows.append({"subject": subject, "href": page, "cells": cells})
        grid = {"versions": versions, "components": components, "rows": rows, "files": files}
        sections.append({"id": tid, "table": table, "title": table_title(table),
                         "plot": plot.relative_to(out).as_posix(),
                         "counts_csv": counts_csv, "counts_md": counts_md, "grid": grid,
                         "fidelity": _fidelity_plots(run, out) if table == "F" else None})
    return sections


def _fidelity_plots(run: Run, out: Path) -> list[dict]:
    """Table F's figures: the error per version and articulator over the task files, and one
    task's tract variables, model against recording (the traces the rubric keeps)."""
    figs = []
    res = run.results
    err = res[(res["frame"] == -1) & res["check"].isin(
        [c.name for c in CHECKS.values()
         if c.kind == "fidelity" and c.unit == "mm" and c.table == "F"])]
    if len(err):
        path = plots.fidelity_errors(err, out / "plots" / "fidelity_errors.png",
                                     versions=order_versions(err["version"].unique()),
                                     synthetic=run.synthetic)
        figs.append({"href": path.relative_to(out).as_posix(),
                     "alt": "RMSE of the virtual pellets per version and articulator"})
    tr = res[res["view"] == "trace"]
    if len(tr):
        first = tr.sort_values(["subject", "task", "rep"]).iloc[0]
        one = tr[(tr["subject"] == first["subject"]) & (tr["task"] == first["task"])
                 & (tr["rep"] == first["rep"])]
        path = plots.fidelity_traces(one, out / "plots" / "fidelity_traces.png",
                                     versions=order_versions(one["version"].unique()),
                                     title=f"{first['subject']} task {int(first['task'])}",
                                     synthetic=run.synthetic)
        figs.append({"href": path.relative_to(out).as_posix(),
                     "alt": f"model against recording, {first['subject']} task {int(first['task'])}"})
    return figs


def _criterion(run: Run, out: Path) -> dict | None:
    """CASSI 2.1's low-lips decision per task file (rows of view ``criterion``): the margin of
    the upper lip's starting inside edge below the threshold (> 0: adjusted), mm."""
    res = run.results
    rows = res[(res["view"] == "criterion") & (res["frame"] == -1)]
    if not len(rows):
        return None
    table = rows.sort_values(["version", "subject", "task", "rep"]).set_index(
        ["version", "subject", "task", "rep"])[["value", "detail"]].rename(
        columns={"value": "margin_mm"})
    csv, md = _write_table(table, out, "low_lips_criterion")
    rows = [{"version": v, "subject": s, "task": int(t), "rep": int(r), "margin": f"{m:+.2f}",
             "detail": d} for (v, s, t, r), (m, d) in zip(table.index, table.itertuples(index=False))]
    lazy = {"rows": [list(r.values()) for r in rows]} if len(rows) > LAZY_ROWS else None
    return {"csv": csv, "md": md, "rows": rows, "lazy": lazy}


def _comparison(run: Run, previous: Run | None, out: Path, diff: pd.DataFrame | None) -> dict | None:
    """The changes since ``previous`` (``diff``: :func:`cmp.compare_components` of the two)."""
    if previous is None:
        return None
    checks = cmp.compare_checks(previous.results, run.results)
    _write_table(checks.set_index(["version", "table", "subject", "component", "check"]),
                 out, "comparison_checks")
    changed = checks[checks["change"] != "= same"].copy()
    changed["subject_href"] = [f"subjects/{slug(s)}.html" for s in changed["subject"]]
    changed = changed.astype(object).where(changed.notna(), "")
    return {"name": previous.name,
            "summary": cmp.change_summary(diff).to_dict("records"),
            "changed": changed.to_dict("records")}


def _best(totals: pd.Series) -> dict:
    """The versions with the fewest negatives of ``totals`` (version -> negatives)."""
    low = int(totals.min())
    best = [v for v, n in totals.items() if int(n) == low]
    return {"versions": best, "negatives": low, "tie": len(best) > 1}


def _overview(run: Run, previous: Run | None, cr: pd.DataFrame, diff: pd.DataFrame | None,
              gate: dict | None, before_cr: pd.DataFrame | None = None) -> dict | None:
    """The report's first screen: negatives per version and table and overall (the rubric's
    one count, :func:`table_totals`), each table's ratings, the best version per table, the
    change since the previous run with a paired test over the table cells, and the gate
    (``before_cr``: the previous run's component ratings, when made already)."""
    totals = table_totals(run.results, ratings=cr)
    if totals.empty:
        return None
    tables = sorted(totals["table"].unique())
    versions = order_versions(totals["version"].unique())
    grid = totals.pivot(index="version", columns="table", values="negatives").reindex(versions)
    overall = version_totals(run.results, ratings=cr).set_index("version")["negatives"]
    before = before_overall = None
    if previous is not None:
        prev = table_totals(previous.results, ratings=before_cr)
        before = prev.set_index(["version", "table"])["negatives"] if len(prev) else None
        before_overall = prev.groupby("version")["negatives"].sum() if len(prev) else None
    counts = {t: rating_counts(run.results, t, ratings=cr) for t in tables}
    rows = []
    for v in versions:
        cells = []
        for t in tables:
            n = grid.at[v, t]
            if pd.isna(n):
                cells.append(None)
                continue
            c = counts[t].loc[v]
            was = before.get((v, t)) if before is not None else None
            cells.append({"negatives": int(n), "href": f"#table-{slug(t)}",
                          "delta": None if was is None else int(n) - int(was),
                          "ratings": ", ".join(f"{int(k)} {r}" for r, k in c.items() if k)})
        was = before_overall.get(v) if before_overall is not None else None
        rows.append({"version": v, "cells": cells, "negatives": int(overall[v]),
                     "delta": None if was is None else int(overall[v]) - int(was),
                     "change": _change(diff, v) if diff is not None else None})
    best = [_best(grid[t].dropna()) for t in tables]
    return {"tables": [{"id": slug(t), "name": t, "title": table_title(t)} for t in tables],
            "rows": rows, "best": best, "best_overall": _best(overall),
            "previous": previous.name if previous is not None else None,
            "n_boot": BOOTSTRAP_N, "seed": BOOTSTRAP_SEED, "gate": gate}


def _change(diff: pd.DataFrame, version: str) -> dict | None:
    """A version's change over the table cells both runs rated: cells better and worse, the
    sign test on them, and the median change per cell with its bootstrap 95% interval (the
    paired comparisons' tests, :mod:`cassi.harness.rubric.paired`)."""
    d = diff[(diff["version"] == version) & diff["negatives_before"].notna()
             & diff["negatives_after"].notna()]["delta"].astype(float).to_numpy()
    if not len(d):
        return None
    low, high = bootstrap_median(d)
    better, worse = int((d < 0).sum()), int((d > 0).sum())
    return {"cells": len(d), "better": better, "worse": worse, "net": int(d.sum()),
            "median": float(np.median(d)), "low": low, "high": high,
            "p": sign_test(better, worse)}


def _worst_first(fv: pd.DataFrame) -> pd.DataFrame:
    """File verdicts, the most negatives first (the subject pages' order, and the fault a
    thesis table's cell opens in the viewer)."""
    return fv.sort_values(["negatives", "raw_negatives", "task", "rep", "check"],
                          ascending=[False, False, True, True, True], kind="mergesort")


def _image_store(out: Path, cache: Path | None, *, fast: bool = False):
    """``render path -> its copy beside the report``: content-addressed lossless WebP
    (:func:`media.store_image`; ``fast`` for a large run), which the subject pages and the
    viewer share; each render is encoded once per report."""
    @functools.lru_cache(maxsize=None)
    def place(src: str) -> Path:
        return media.store_image(src, out / "images", cache, fast=fast)
    return place


def _mask_dest(out: Path, subject: str, version: str, task: int, rep: int, frame: int,
               view: str) -> Path:
    """Where the masks an image check read at a frame are drawn beside the report."""
    return out / "images" / "masks" / slug(subject) / slug(version) / \
        f"{int(task):03d}_{int(rep)}_{int(frame):05d}_{slug(view)}.png"


def _fault_links(run: Run, fv: pd.DataFrame, viewers: dict) -> dict[tuple, str]:
    """(subject, version, table, component, check) -> the task viewer at the frame of the
    check's worst file, its event highlighted (relative to the report)."""
    evidence = linked_frames(run.results)
    present = set(fv["version"])
    out: dict[tuple, str] = {}
    for r in _worst_first(fv[fv["raw_negatives"] > 0]).itertuples(index=False):
        key = (r.subject, r.version, r.table, r.component, r.check)
        file = (r.subject, int(r.task), int(r.rep))
        frame = evidence.get((*file, r.version, r.check))
        if key in out or frame is None or file not in viewers:
            continue
        out[key] = viewer_href(slug(r.subject), *file[1:], frame=frame, a=r.version,
                               b=shown_beside(r.table, r.version, present), check=r.check)
    return out


def _cell_faults(v: pd.DataFrame, text: str, links: dict, key: tuple) -> list[dict]:
    """A table cell's text as its faults, each linked to its own frame (``links``:
    :func:`_fault_links`): the pieces of :func:`negatives_text`, one per charged check, then
    what the cell's text says beyond them (Table C's comparison), unlinked."""
    faults, said = [], []
    for r in v.itertuples(index=False):
        piece = negatives_text({"check": [r.check], "negatives": [r.negatives]})
        if piece:
            said.append(piece)
            faults.append({"text": piece, "href": links.get((*key, r.check))})
    joined = "; ".join(said)
    rest = text[len(joined):].lstrip("; ") if text.startswith(joined) else text
    if rest:
        faults.append({"text": rest, "href": None})
    return faults


def _large_run(run: Run) -> int | None:
    """The run's number of task files when it is a large run (:func:`~cassi.harness.evaluation.frames.large_run`, a full set:
    its viewer pages carry fewer renders and its videos are made on demand), else None. The
    usable task files the run planned, as its render plan counted them (``run.json``), else
    those with results."""
    planned = run.meta.get("tasks_resolved")
    if planned:
        files = sum(1 for t in planned if len(t) > 3 and t[3])
    else:
        files = len(run.results[["subject", "task", "rep"]].drop_duplicates())
    return files if frame_policy.large_run(files) else None


def _renders_rule(run: Run, fv: pd.DataFrame) -> tuple[set | None, str | None]:
    """For a run of more than :data:`ALL_RENDERS_UP_TO` task files: the (subject, task, rep,
    version, check) that earned negatives (the checks whose frames the viewer pages carry
    renders of) and the sentence each page says it with; (None, None) otherwise."""
    files = _large_run(run)
    if files is None:
        return None, None
    fired = fv[fv["raw_negatives"] > 0]
    keys = {(s, int(t), int(r), v, c) for s, t, r, v, c in zip(
        fired["subject"], fired["task"], fired["rep"], fired["version"], fired["check"])}
    return keys, (f"This run has {files} task files (more than {frame_policy.ALL_RENDERS_UP_TO}): the "
                  "renders here are the first frame's and those of the frames of checks that "
                  "earned negatives, not of silent checks' frames.")


def _viewer_images(run: Run, out: Path, place, cache: Path | None = None,
                   fired: set | None = None, note: str | None = None):
    """``(subject, task, rep, version) -> renders`` for the viewer: every view of the task
    file's first rendered frame and of each frame a check points at (the nearest rendered one
    where it has none, as on the subject pages), ``place``: :func:`_image_store`, hrefs relative
    to the viewer page; at the frames an image check points at, the masks it read
    (:func:`stored_overlay`, kept in ``cache``). The video grid's other renders stay in the run:
    the 3D view and the videos show those frames, and they were four fifths of a night's
    report. ``images.prefetch(keys)`` encodes the pictures of those (subject, task, rep,
    version) at once (the pages a report makes anew). ``fired`` (:func:`_renders_rule`): only
    the frames of those checks, besides the first, said by ``note``."""
    @functools.lru_cache(maxsize=None)
    def prepared():
        """(masks, evidence, chosen): made once, and only when a page is made."""
        rend = run.renders
        groups = {k: g for k, g in rend.groupby(["subject", "task", "rep", "version"])} \
            if len(rend) else {}
        att = run.attachments
        masks = {(a.subject, int(a.task), int(a.rep), a.version, a.view,
                  int(a.name[len(MASKS_OUTPUT):])): a.path
                 for a in att[att["name"].str.startswith(MASKS_OUTPUT)].itertuples(index=False)} \
            if len(att) else {}
        res = run.results
        judged = res[(res["frame"] >= 0) & res["table"].notna()
                     & ~res["view"].isin(["geometry", "trace"])]
        evidence = {(r.subject, int(r.task), int(r.rep), r.version, r.view, int(r.frame))
                    for r in judged.itertuples(index=False)}
        pointed: dict[tuple, set[int]] = {}
        for r in res[(res["frame"] >= 0) & res["table"].notna() & (res["view"] != "trace")] \
                .itertuples(index=False):
            if fired is not None and (r.subject, int(r.task), int(r.rep), r.version,
                                      r.check) not in fired:
                continue
            pointed.setdefault((r.subject, int(r.task), int(r.rep), r.version),
                               set()).add(int(r.frame))

        def shown(key, g: pd.DataFrame) -> pd.DataFrame:
            """The renders of a task file and version the viewer shows (see above)."""
            subject, task, rep, version = key
            frames = {int(g["frame"].min())} | {
                _nearest_rendered(g, f)
                for f in pointed.get((subject, int(task), int(rep), version), ())}
            return g[g["frame"].isin(frames)].sort_values(["frame", "view"])

        chosen = {k: shown(k, g) for k, g in groups.items()}
        return masks, evidence, chosen

    def prefetch(keys) -> None:
        # Encode every picture the pages will show first, on every core (libwebp releases the
        # GIL): a night's 6,400 take 85 s of one core; the subject pages' are nearly all among
        # them.
        chosen = prepared()[2]
        wanted = [str(p) for k in keys if k in chosen for p in chosen[k]["path"]]
        with ThreadPoolExecutor(usable_cores()) as pool:
            list(pool.map(place, dict.fromkeys(wanted)))

    def images(subject, task, rep, version) -> list[dict]:
        masks, evidence, chosen = prepared()
        g = chosen.get((subject, task, rep, version))
        if g is None:
            return []
        found = []
        for v in g.itertuples(index=False):
            dest = place(str(v.path))
            item = {"frame": int(v.frame), "view": str(v.view),
                    "href": os.path.relpath(dest, out / "viewer" / slug(subject))}
            key = (subject, int(task), int(rep), version, v.view, int(v.frame))
            if key in evidence and key in masks:
                over = _mask_dest(out, subject, version, task, rep, v.frame, v.view)
                over.parent.mkdir(parents=True, exist_ok=True)
                if not over.is_file():
                    stored_overlay(masks[key], int(v.frame), over, cache)
                item["mask"] = os.path.relpath(over, out / "viewer" / slug(subject))
            found.append(item)
        return found
    images.prefetch = prefetch
    images.note = note
    return images


def _nearest_rendered(renders: pd.DataFrame, frame: int) -> int | None:
    have = sorted(set(int(f) for f in renders["frame"]))
    return min(have, key=lambda h: abs(h - frame)) if have else None


def _views_at(run: Run, rend: pd.DataFrame, subject: str, task: int, rep: int, version: str,
              frame: int, out: Path, place) -> tuple[int | None, list[dict]]:
    """The four views of the rendered frame nearest ``frame`` (``place``: :func:`_image_store`)."""
    g = rend[(rend["task"] == task) & (rend["rep"] == rep) & (rend["version"] == version)] \
        if len(rend) else rend
    if not len(g):
        return None, []
    near = _nearest_rendered(g, frame)
    images = []
    for v in g[g["frame"] == near].sort_values("view").itertuples(index=False):
        dest = place(str(v.path))
        images.append({"href": os.path.relpath(dest, out / "subjects"),
                       "alt": f"{v.view} view, frame {near}", "view": v.view})
    return near, images


def _fmt(x) -> str:
    return "" if x is None or pd.isna(x) else f"{float(x):.4g}"


def _check_groups(fired: list[dict], anchor: str) -> list[dict]:
    """A version and table's fired checks, one group per check (most negatives, then most
    files first), its cards in the page's worst-first order; a group of at most
    :data:`GROUP_OPEN_UP_TO` cards is shown open."""
    groups: dict[str, dict] = {}
    for item in fired:
        g = groups.setdefault(item["check"], {
            "id": f"{anchor}--{slug(item['check'])}", "check": item["check"],
            "text": item["text"], "unit": item["unit"], "side": item["side"],
            "files": 0, "negatives": 0, "cards": []})
        g["files"] += 1
        g["negatives"] += item["negatives"]
        g["cards"].append(item)
    out = sorted(groups.values(), key=lambda g: (-g["negatives"], -g["files"], g["check"]))
    for g in out:
        g["open"] = len(g["cards"]) <= GROUP_OPEN_UP_TO
    return out


def _fired_summary(versions: list[dict]) -> dict:
    """The subject page's first screen: per table and check (rows) and version (columns), the
    task files where the check fired and the negatives charged, each linked to its group."""
    names = [v["version"] for v in versions]
    rows: dict[tuple, dict] = {}
    for i, v in enumerate(versions):
        for t in v["tables"]:
            for g in t["groups"]:
                row = rows.setdefault((t["table"], g["check"]), {
                    "table": t["table"], "check": g["check"], "text": g["text"],
                    "cells": [None] * len(names)})
                row["cells"][i] = {"files": g["files"], "negatives": g["negatives"],
                                   "href": f"#{g['id']}"}
    return {"versions": names, "rows": [rows[k] for k in sorted(rows)],
            "checks": sorted({c for _, c in rows}),
            "tables": sorted({t["table"] for v in versions for t in v["tables"]})}


def _lazy_rows(silent: list[dict]) -> dict:
    """A long silent-check table as data the page renders when it is opened: the checks'
    words, unit and side once, then per row task, check, value and threshold."""
    checks = sorted({r["check"] for r in silent})
    ix = {c: i for i, c in enumerate(checks)}
    words = {r["check"]: [r["text"], r["unit"], r["side"]] for r in silent}
    return {"checks": [[c, *words[c]] for c in checks],
            "rows": [[r["task"], ix[r["check"]], r["value"], r["threshold"]] for r in silent]}


#: The pages' script (long tables drawn when opened, the subject pages' filters), beside the
#: viewer's.
REPORT_SCRIPT = "report.js"


def _copy_report_script(out: Path) -> None:
    data = (Path(__file__).parent / "static" / REPORT_SCRIPT).read_bytes()
    dest = out / "static" / REPORT_SCRIPT
    if not dest.is_file() or dest.read_bytes() != data:
        dest.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(dest, data)


def _subject_page(run: Run, subject: str, fv: pd.DataFrame, cr: pd.DataFrame,
                  rule: pd.DataFrame, out: Path, env, place,
                  viewers: dict | None = None) -> tuple[str, list[Path]]:
    """Per version and table: the checks that earned negatives first (value, threshold and its
    side, the thesis's words, the four views of the frame pointed at), silent checks folded.
    Returns the page (relative to ``out``) and every file it shows that lies in the report."""
    evidence = linked_frames(run.results[run.results["subject"] == subject])
    rend = run.renders[run.renders["subject"] == subject] if len(run.renders) else run.renders
    mine = fv[fv["subject"] == subject]
    present = set(mine["version"])
    versions = []
    for version in order_versions(mine["version"].unique()):
        tables = []
        sheets = 0
        for table in sorted(mine.loc[mine["version"] == version, "table"].unique()):
            rows = _worst_first(mine[(mine["version"] == version) & (mine["table"] == table)])
            fired, silent = [], []
            for r in rows.itertuples(index=False):
                c = CHECKS.get(r.check)
                item = {"task": r.file, "check": r.check, "component": r.component,
                        "text": c.text if c else r.check, "value": _fmt(r.value),
                        "unit": r.unit or "", "threshold": _fmt(r.threshold),
                        "side": c.side if c else "", "negatives": int(r.negatives),
                        "note": r.note, "frame": None, "images": [], "viewer": None}
                if r.raw_negatives > 0:
                    frame = evidence.get((subject, int(r.task), int(r.rep), version, r.check))
                    if frame is not None:
                        item["frame"] = frame
                        if (subject, int(r.task), int(r.rep)) in (viewers or {}):
                            item["viewer"] = viewer_href(
                                slug(subject), int(r.task), int(r.rep), frame=frame, a=version,
                                b=shown_beside(table, version, present), check=r.check,
                                base="../")
                        if sheets < MAX_SHEETS_PER_VERSION:
                            near, item["images"] = _views_at(run, rend, subject, int(r.task),
                                                             int(r.rep), version, frame, out,
                                                             place)
                            item["rendered"] = near
                            sheets += bool(item["images"])
                    fired.append(item)
                else:
                    silent.append(item)
            cells = cr[(cr["subject"] == subject) & (cr["version"] == version) & (cr["table"] == table)]
            rating = "; ".join(f"{c.component}: {c.rating}" for c in cells.itertuples(index=False))
            comparison = ""
            if table == "C" and len(rule):
                rr = rule[(rule["subject"] == subject) & (rule["version"] == version)]
                if len(rr) and rr.iloc[0]["reason"]:
                    adj = int(rr.iloc[0]["adjust"])
                    comparison = (f"{'+1' if adj > 0 else '-1' if adj < 0 else 'no change'}: "
                                  f"{rr.iloc[0]['reason']}")
            anchor = evidence_anchor(version, table)
            tables.append({"id": anchor, "table": table, "title": table_title(table),
                           "rating": rating, "fired": fired, "silent": silent,
                           "groups": _check_groups(fired, anchor),
                           "silent_lazy": _lazy_rows(silent) if len(silent) > LAZY_ROWS else None,
                           "comparison": comparison})
        versions.append({"version": version, "id": slug(version), "tables": tables})
    page = out / "subjects" / f"{slug(subject)}.html"
    atomic_write_text(page, env.get_template("subject.html.j2").render(
        subject=subject, versions=versions, synthetic=run.synthetic,
        summary=_fired_summary(versions), open_up_to=GROUP_OPEN_UP_TO, lazy_rows=LAZY_ROWS,
        derived={k: v for k, v in run.derived.items() if k == subject}))
    shown = [Path(os.path.normpath(page.parent / image["href"])) for v in versions
             for t in v["tables"] for item in t["fired"] + t["silent"]
             for image in item["images"]]
    return page.relative_to(out).as_posix(), [page, *shown]


def _run_corpus(run: Run) -> Corpus | None:
    """The run's corpus, or None when it cannot be opened (moved or removed since)."""
    root = run.meta.get("corpus_resolved")
    try:
        return Corpus(root) if root else None
    except Exception:  # noqa: BLE001 - a moved corpus must not stop the report
        return None


def _audio_for(run: Run):
    """``(subject, task, rep) -> WAV path or None`` from the run's corpus (None when the corpus
    cannot be opened: the videos are then silent, and say so)."""
    return _corpus_file(run, "audio_path")


def _alignment_for(run: Run):
    """``(subject, task, rep) -> the file of the task's labels or None`` from the run's corpus
    (the viewer pages read them from it)."""
    return _corpus_file(run, "alignment_path")


def _corpus_file(run: Run, method: str):
    corpus = _run_corpus(run)

    def find(subject: str, task: int, rep: int):
        if corpus is None:
            return None
        try:
            return getattr(corpus.subject(subject), method)(task, rep)
        except Exception:  # noqa: BLE001
            return None
    return find


def _period_for(run: Run):
    """``(subject, task, rep) -> the recording's period, us`` from the run's corpus (XRMB's
    6866 us when the recording cannot be read: a moved corpus must not stop the report)."""
    corpus = _run_corpus(run)

    def period(subject: str, task: int, rep: int) -> float:
        try:
            return corpus.subject(subject).load(task, rep).period_us
        except Exception:  # noqa: BLE001
            return float(NOMINAL_PERIOD_US)
    return period


#: Processes that encode a report's videos at once (each video is one ffmpeg stream, the
#: report's longest part: 57 task files' four-view and comparison videos took most of 155 s).
REPORT_WORKERS = usable_cores()


class _Encoding:
    """A report's videos, started before its pages and tables so that encoding overlaps them:
    a video the media cache holds is linked at once (no process is started for it, and none at
    all when every video is cached, as on a night after an unchanged one); the others encode on
    :data:`REPORT_WORKERS` processes when there are several (the farm's workers are done by the
    time a report is made), else here when :meth:`results` is asked."""

    def __init__(self, specs, out: Path, *, stride: int, media_cache: Path | None):
        self._specs, self._out = specs, out
        self._calls = [dict(renders=g, dest=dest, stride=stride, audio=audio, cache=media_cache,
                            columns=columns, period_us=period)
                       for _, _, dest, g, audio, columns, period in specs]
        self._done: dict[int, dict | None] = {}
        todo = []
        for i, c in enumerate(self._calls):
            if media.cached_video(c["renders"], stride=stride, columns=c["columns"],
                                  audio=c["audio"], cache=media_cache,
                                  period_us=c["period_us"]) is not None:
                self._done[i] = media.task_video(**c)
            else:
                todo.append(i)
        self._pool, self._sent = None, []
        if REPORT_WORKERS >= 2 and len(todo) >= 2:
            # the farm's process pool (spawned workers, a crashed one replaced), not a run
            self._pool = LocalExecutor(min(REPORT_WORKERS, len(todo)), env=thread_env(1))
            self._pool.start()
            for i in todo:
                self._pool.submit(str(i), _task_video, self._calls[i])
            self._sent = todo
        self._todo = [i for i in todo if i not in self._sent]

    def videos(self) -> list[dict]:
        """The report's description of every video made (waits for the encoding)."""
        videos = []
        for (kind, label, dest, *_), result in zip(self._specs, self.results()):
            if result is not None:
                videos.append({"kind": kind, "label": label,
                               "href": dest.relative_to(self._out).as_posix(),
                               "fps": result["fps"], "frames": result["frames"],
                               "seconds": result["seconds"], "audio": result["audio"]})
        return videos

    def close(self, *, abort: bool = True) -> None:
        """Stop the encoding processes (by default at once: the report failed); no worker
        outlives the report."""
        if self._pool is not None:
            self._pool.close(abort=abort)
            self._pool = None

    def results(self) -> list[dict | None]:
        """:func:`media.task_video` of every spec, in order."""
        try:
            for i in self._todo:
                self._done[i] = media.task_video(**self._calls[i])
            while self._pool is not None and self._pool.pending():
                for item in self._pool.wait():
                    if not item.ok:
                        raise RuntimeError(f"encoding a video failed: {item.error}")
                    self._done[int(item.key)] = item.value
        except BaseException:
            self.close()
            raise
        self.close(abort=False)
        return [self._done[i] for i in range(len(self._calls))]


def _task_video(kwargs: dict) -> dict | None:
    return media.task_video(**kwargs)


def _start_videos(run: Run, out: Path, media_cache: Path | None = None):
    """From the renders on the run's ``animate_stride`` grid: a four-view video per task file
    and version that was rendered in every view, and the versions side by side wherever
    several versions were rendered in the comparison view, encoding while the caller goes on
    (:class:`_Encoding`)."""
    stride = int(run.meta.get("animate_stride") or 0)
    if not len(run.renders) or stride < 1:
        return _Encoding([], out, stride=stride, media_cache=None)
    audio_for, period_for = _audio_for(run), _period_for(run)
    specs = []  # (kind, label, dest, renders, audio, columns, period), encoded together below

    def add(kind, label, g, dest, audio, columns, period):
        specs.append((kind, label, dest, g, audio, columns, period))

    large = _large_run(run)
    for (subject, task, rep), g in run.renders.groupby(["subject", "task", "rep"]):
        task, rep = int(task), int(rep)
        if large is not None and task not in COMPARED_TASKS:
            continue  # made on demand: videos_note
        audio, period = audio_for(subject, task, rep), period_for(subject, task, rep)
        stem = f"{slug(subject)}_{task:03d}_{rep}"
        name = f"{subject} task {task}" + (f" rep {rep}" if rep != 1 else "")
        all_views = [v for v in VIDEO_VIEWS if v in set(g["view"])]
        # A (version, view) was rendered for a video when its grid frames run unbroken (a
        # first frame and a check frame that happen to fall on the grid are no video).
        on_grid = {}
        for (version, view), frames in g.groupby(["version", "view"])["frame"]:
            # media.video_frames of one panel, without its per-panel groupby (1,254 a night)
            grid = video_grid(set(frames.tolist()), first=int(frames.min()), stride=stride)
            if len(grid) >= 3 and all(b - a == stride for a, b in zip(grid, grid[1:])):
                on_grid.setdefault(version, set()).add(view)
        versions = order_versions(on_grid)
        for version in versions:
            if on_grid[version] != set(all_views):
                continue  # rendered for the comparisons only
            dest = out / "videos" / f"{stem}_{slug(version)}.mp4"
            add("task", f"{name}, {version}", g, dest, audio,
                [(version, v) for v in all_views], period)
        compared = [v for v in versions if COMPARISON_VIEW in on_grid[v]]
        if len(compared) > 1:
            dest = out / "animations" / f"{stem}_{COMPARISON_VIEW}.mp4"
            add("comparison", f"{name}, {COMPARISON_VIEW} view ({', '.join(compared)})", g,
                dest, audio, [(v, COMPARISON_VIEW) for v in compared], period)
    return _Encoding(specs, out, stride=stride, media_cache=media_cache)


#: The command the index gives for a task file's video that a large run does not make.
ANIMATE_COMMAND = "cassi animate --subject S --task T --version V --views front,side --stride 24 --out video.mp4"


def _videos_note(run: Run) -> dict | None:
    """What a large run's index says of the videos it does not make (None: it makes them all)."""
    files = _large_run(run)
    if files is None or not len(run.renders):
        return None
    compared = " and ".join(str(t) for t in COMPARED_TASKS)
    made = sorted(set(int(t) for t in run.renders["task"]) & set(COMPARED_TASKS))
    here = (f"here task{'s' if len(made) > 1 else ''} {' and '.join(map(str, made))}" if made
            else "and it has none of them")
    return {"text": f"This run has {files} task files (more than {frame_policy.ALL_RENDERS_UP_TO}): it makes "
                    "videos only for the tasks whose versions the thesis compares side by side "
                    f"({compared}), {here}. Any other task file's video is made on demand: its "
                    "task viewer plays every version in any view, and this command writes one:",
            "command": ANIMATE_COMMAND}


def _summaries(run: Run) -> list[dict]:
    """The "versions compared" sentences grouped by table, each group linked to its table."""
    groups: dict[str, list[str]] = {}
    for table, sentence in version_comparisons(run.results):
        groups.setdefault(table, []).append(sentence)
    return [{"id": slug(t), "title": table_title(t), "sentences": s} for t, s in groups.items()]


def _paired(run: Run, out: Path) -> dict:
    """The paired comparisons per pair of versions, only the measures where the pair differs
    in at least one file, most significant first (the full table goes to tables/)."""
    p = paired_comparisons(run.results)
    csv, md = _write_table(p.set_index(["a", "b", "measure"]), out, "paired_comparisons")
    shown = p[(p["wins"] + p["losses"]) > 0]
    pairs = []
    for (a, b), g in shown.groupby(["a", "b"], sort=False):
        pairs.append({"a": a, "b": b, "sentences": [paired_sentence(r) for _, r in g.iterrows()]})
    return {"pairs": pairs, "csv": csv, "md": md, "n_boot": BOOTSTRAP_N, "seed": BOOTSTRAP_SEED,
            "tie": TIE_TOLERANCE, "same": int(len(p) - len(shown))}


def _meta_items(run: Run) -> list[tuple[str, str]]:
    keys = ("started", "finished", "package_version", "git_revision", "variant", "preset", "stride",
            "executor", "corpus_resolved")
    return [(k, str(run.meta[k])) for k in keys if run.meta.get(k) not in (None, "")]


def _frames_judged(run: Run) -> str | None:
    """Which frames the run's checks judged, said on the index so that a run on a sparser grid
    (``--animate-stride``) can never pass for the default one."""
    meta = run.meta
    if not meta.get("tasks_resolved"):
        return None
    grid, extremes = int(meta.get("animate_stride") or 0), int(meta.get("extremes") or 0)
    stride = int(meta.get("stride") or 0)
    views = set(meta.get("views_resolved") or meta.get("views") or ())
    if "front" not in views:  # the view every image check judges (frames.image_views)
        return "The geometric checks read every row; the front view was not rendered, so no " \
               "image check judged."
    first = next((t for t in meta["tasks_resolved"] if t[3]), None)
    seconds = ""
    if first is not None and grid > 0:
        period = _period_for(run)(first[0], int(first[1]), int(first[2]))
        seconds = f" ({grid * period / 1e6:.3f} s at {1e6 / period:.1f} Hz)"
    picked = ["the first frame"]
    if grid > 0:
        picked.append(f"{_every(grid)}{seconds}")
    if stride > 0:
        picked.append(_every(stride))
    if extremes > 0:
        picked.append(f"up to {extremes} frame{'s' if extremes != 1 else ''} the geometric "
                      "checks point at")
    return ("The geometric checks read every row. In each task file and version the image checks "
            "judge the front view at " + ", ".join(picked[:-1])
            + (" and " if len(picked) > 1 else "") + picked[-1] + ".")


def _every(n: int) -> str:
    """``every 24th row``, ``every 2nd row``, ``every row``."""
    if n == 1:
        return "every row"
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"every {n}{suffix} row"


def _rescored(run: Run, cr: pd.DataFrame) -> list[str]:
    """Why the tables below may not be what the run itself concluded: the rubric registry
    changed since the run (its check values and negatives come from the old one, their
    aggregation from today's), or the run's ratings file differs from today's aggregation of
    its results. Empty when the run and today agree."""
    notes = []
    then = (run.meta.get("provenance") or {}).get("rubric_digest")
    if then and then != rubric_digest():
        notes.append("the rubric registry (thresholds, negatives, windows) changed since this run: "
                     "its values and negatives are the run's, the aggregation and texts today's; "
                     "rerun `cassi run` into the same --out to rescore (only the affected jobs "
                     "run again)")
    key = ["version", "table", "subject", "component"]
    if run.ratings is not None and len(run.ratings) and {*key, "negatives", "rating"} <= set(
            run.ratings.columns):
        both = run.ratings.merge(cr, on=key, how="outer", suffixes=("_run", "_now"), indicator=True)
        differ = int(((both["_merge"] != "both")
                      | (both["negatives_run"] != both["negatives_now"])
                      | (both["rating_run"] != both["rating_now"])).sum())
        if differ:
            notes.append(f"{differ} cell(s) of the run's ratings.parquet differ from today's "
                         "aggregation of its results (rubric.tables): the tables below are today's")
    return notes


def _thesis_findings(cr: pd.DataFrame, out: Path) -> dict | None:
    """What the run reproduces of the judges' findings (rubric.thesis_findings' rules), also as
    tables/thesis_findings.md and .csv; None when the run has none of CASSI's versions."""
    table = reproduced(pd.DataFrame(), ratings=cr)
    if (table["reproduced"] == "not judged").all():
        return None
    csv, md = out / "tables" / "thesis_findings.csv", out / "tables" / "thesis_findings.md"
    atomic_write_text(csv, table.to_csv(index=False, lineterminator="\n"))
    atomic_write_text(md, markdown_table(table.set_index("table")))
    return {"rows": table.to_dict("records"), "csv": csv.relative_to(out).as_posix(),
            "md": md.relative_to(out).as_posix()}


def _run_tables(run: Run, fv: pd.DataFrame, cr: pd.DataFrame, viewers: dict, out: Path) -> dict:
    """What index.html shows of the run alone (its tables, plots and their files, the paired
    comparisons, the criterion, the judges' findings, the sensitivity section), written into
    ``out``: nothing here reads the previous run or the history."""
    return {"summaries": _summaries(run), "paired": _paired(run, out),
            "tables": _table_sections(run, cr, out, _fault_links(run, fv, viewers)),
            "criterion": _criterion(run, out), "sensitivity": sensitivity_section(run.root, out),
            "thesis": _thesis_findings(cr, out)}


def _index_html(run: Run, previous: Run | None, out: Path, env, agree, history,
                encoding: "_Encoding", media_cache: Path | None) -> str:
    """Subject pages, tables and plots, then index.html's text (the videos awaited last). With
    ``media_cache``, every part made before of the same inputs (:mod:`.pagekeys`) is linked
    from there (:mod:`.memo`); what reads the previous run or the history is made each time."""
    memo = Memo(media_cache, out)
    fv = file_verdicts(run.results)
    cr = component_ratings(run.results)
    subjects = sorted(fv["subject"].dropna().unique())
    place = _image_store(out, media_cache, fast=_large_run(run) is not None)
    audio_for = _audio_for(run)
    fired, note = _renders_rule(run, fv)
    keys = PageKeys(run, audio_for=audio_for, labels_for=_alignment_for(run), renders_note=note)
    viewers = write_viewers(run, out, env, slug=slug, audio_for=audio_for,
                            images=_viewer_images(run, out, place, media_cache, fired, note),
                            memo=memo, key_of=keys.viewer)
    rule = functools.lru_cache(maxsize=None)(lambda: table_c_rule(run.results, fv=fv))
    _copy_report_script(out)

    def subject_page(subject: str) -> str:
        return memo.page("subject", keys.subject(subject, viewers), lambda: _subject_page(
            run, subject, fv, cr, rule(), out, env, place, viewers))

    subject_links = [{"name": s, "href": subject_page(s),
                      "viewers": [{"task": k[1], "rep": k[2], "href": v}
                                  for k, v in sorted(viewers.items()) if k[0] == s]}
                     for s in subjects]
    own = memo.staged("tables", keys.tables(viewers),
                      lambda folder: _run_tables(run, fv, cr, viewers, folder))
    trend = None
    if history is not None and history["night"].nunique() > 1:
        trend = memo.staged("trend", keys.trend(history, run.synthetic),
                            lambda folder: plots.metric_trend(
                                history, folder / "plots" / "trend.png",
                                synthetic=run.synthetic).relative_to(folder).as_posix())
    gate_path = run.root / "gate.json"
    gate = json.loads(gate_path.read_text()) if gate_path.is_file() else None
    if gate is not None:
        atomic_write_text(out / "gate.md", (run.root / "gate.md").read_text()
                          if (run.root / "gate.md").is_file() else "")
    before = component_ratings(previous.results) if previous is not None else None
    diff = cmp.compare_components(previous.results, run.results, ratings=(before, cr)) \
        if previous is not None else None
    return env.get_template("index.html.j2").render(
        run_name=run.name, meta_items=_meta_items(run), synthetic=run.synthetic,
        frames_judged=_frames_judged(run), videos_note=_videos_note(run),
        derived=run.derived,
        overview=_overview(run, previous, cr, diff, gate, before),
        summaries=own["summaries"], paired=own["paired"], agreement=agree,
        comparison=_comparison(run, previous, out, diff),
        tables=own["tables"],
        criterion=own["criterion"], rescored=_rescored(run, cr),
        sensitivity=own["sensitivity"],
        thesis=own["thesis"],
        videos=encoding.videos(),
        rules=AGGREGATION_RULES, lazy_rows=LAZY_ROWS,
        subjects=subject_links, trend=trend, gate=gate,
        jobs={"counts": run.summary.get("counts", {}), "failed": run.failed,
              "skipped": run.skipped} if run.summary else None)


def write_report(run_dir: str | os.PathLike | Run, out_dir: str | os.PathLike, *,
                 compare: str | os.PathLike | Run | None = None,
                 history: pd.DataFrame | None = None,
                 media_cache: str | os.PathLike | None = None,
                 ratings: str | os.PathLike | None = None) -> Path:
    """Write ``out_dir/index.html`` (+ subject pages, tables, plots, images) for a run.

    Parameters
    ----------
    run_dir : path or Run
        A run directory (``cassi run --out``), or the run a caller already loaded.
    out_dir : path
        Where the report goes (created).
    compare : path or Run, optional
        A previous run to compare with (or that run, loaded).
    history : DataFrame, optional
        Columns night, version, negatives: a trend plot over nights (``cassi nightly``).
    media_cache : path, optional
        Videos made before from the same renders, sound and code, and renders' WebP copies
        made before from the same PNG and codec (a nightly store's media): linked instead of
        encoded again.
    ratings : path, optional
        Ratings people gave (:mod:`cassi.reports.agree`): the report's agreement section, and
        agreement.json / .md / .csv beside index.html.
    """
    run = run_dir if isinstance(run_dir, Run) else load_run(run_dir)  # a caller's loaded run
    previous = compare if isinstance(compare, Run) else (load_run(compare) if compare else None)
    # a bad ratings file is refused before anything is written
    agree = agreement(run, ratings, evidence_href) if ratings is not None else None
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if agree is not None:
        write_agreement(agree, out)
    env = _env()
    # first, so that the videos encode while the pages and tables below are written
    cache = None if media_cache is None else Path(media_cache)
    encoding = _start_videos(run, out, cache)
    try:
        html = _index_html(run, previous, out, env, agree, history, encoding, cache)
    except BaseException:
        encoding.close()
        raise
    index = out / "index.html"
    atomic_write_text(index, html)
    return index
