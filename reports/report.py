"""``cassi report``: a self-contained HTML report (plus CSV and Markdown tables) of one run.

Everything comes from the run's files; images are copied beside the report; every string from
data files goes through Jinja2's autoescaping; file names derived from data are slugged.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
from pathlib import Path

import jinja2
import pandas as pd

from cassi.data.atomic import atomic_write_text
from cassi.reports import compare as cmp
from cassi.reports import media, plots
from cassi.reports.runio import Run, load_run, order_versions
from cassi.reports.tables import (RATINGS, component_ratings, markdown_table, rating_counts,
                                  table_title, version_summaries)

#: How many frames per check and version get thumbnails on a subject page.
MAX_SHEETS_PER_VERSION = 6
#: The view in which versions are compared side by side (where the farm rendered the video
#: frames of several versions in it: tasks 106 and 118 in a nightly).
COMPARISON_VIEW = "front"
#: The order of a task video's panels.
VIDEO_VIEWS = ("front", "side", "half", "top")


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


def _table_sections(run: Run, out: Path) -> list[dict]:
    cr = component_ratings(run.results)
    sections = []
    for table in sorted(cr["table"].unique()):
        tid = slug(table)
        counts = rating_counts(run.results, table)
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
                cells.set_index(["subject", "component"])[["negatives", "rating", "text"]],
                out, f"table_{tid}_{slug(version)}")
            files.append({"version": version, "csv": csv, "md": md})
        lookup = sub.set_index(["subject", "version", "component"])
        rows = []
        for subject in sorted(sub["subject"].unique()):
            cells = []
            for version in versions:
                for c in components:
                    key = (subject, version, c)
                    cells.append(None if key not in lookup.index else {
                        "rating": lookup.at[key, "rating"], "text": lookup.at[key, "text"],
                        "level": RATINGS.index(lookup.at[key, "rating"])})
            rows.append({"subject": subject, "href": f"subjects/{slug(subject)}.html", "cells": cells})
        grid = {"versions": versions, "components": components, "rows": rows, "files": files}
        sections.append({"id": tid, "title": table_title(table), "plot": plot.relative_to(out).as_posix(),
                         "counts_csv": counts_csv, "counts_md": counts_md, "grid": grid})
    return sections


def _comparison(run: Run, previous: Run | None, out: Path) -> dict | None:
    if previous is None:
        return None
    checks = cmp.compare_checks(previous.results, run.results)
    _write_table(checks.set_index(["version", "table", "subject", "component", "check"]),
                 out, "comparison_checks")
    changed = checks[checks["change"] != "= same"].copy()
    changed["subject_href"] = [f"subjects/{slug(s)}.html" for s in changed["subject"]]
    changed = changed.astype(object).where(changed.notna(), "")
    return {"name": previous.name,
            "summary": cmp.change_summary(cmp.compare_components(previous.results, run.results))
            .to_dict("records"),
            "changed": changed.to_dict("records")}


def _check_frames(results: pd.DataFrame) -> pd.DataFrame:
    """Per (subject, task, rep, version, check): the frames where the check found a fault."""
    per_frame = results[(results["frame"] >= 0) & (results["negatives"] > 0)]
    return (per_frame.groupby(["subject", "task", "rep", "version", "check"])["frame"]
            .agg(lambda s: sorted(set(int(f) for f in s))).rename("frames").reset_index())


def _nearest_rendered(renders: pd.DataFrame, frames: list[int]) -> list[int]:
    have = sorted(set(int(f) for f in renders["frame"]))
    if not have:
        return []
    return sorted({min(have, key=lambda h: abs(h - f)) for f in frames})


def _subject_page(run: Run, subject: str, frames_by_check: pd.DataFrame, out: Path, env) -> str:
    res = run.results[(run.results["subject"] == subject) & (run.results["frame"] == -1)]
    rend = run.renders[run.renders["subject"] == subject] if len(run.renders) else run.renders
    fired = frames_by_check[frames_by_check["subject"] == subject]
    versions = []
    for version in order_versions(res["version"].unique()):
        rows = res[res["version"] == version].sort_values(["task", "rep", "table", "check"])
        checks = []
        for r in rows.itertuples(index=False):
            f = fired[(fired["task"] == r.task) & (fired["rep"] == r.rep) & (fired["version"] == version)
                      & (fired["check"] == r.check)]["frames"]
            frames = f.iloc[0] if len(f) else []
            checks.append({"task": r.task if r.rep == 1 else f"{r.task}_{r.rep}", "table": r.table,
                           "component": r.component, "check": r.check,
                           "value": "" if pd.isna(r.value) else f"{r.value:.4g}", "unit": r.unit or "",
                           "threshold": "" if pd.isna(r.threshold) else f"{r.threshold:.4g}",
                           "negatives": int(r.negatives), "detail": r.detail or "",
                           "frames": ", ".join(map(str, frames[:12])) + (" …" if len(frames) > 12 else "")})
        sheets = []
        vrend = rend[rend["version"] == version] if len(rend) else rend
        for (task, rep), g in (vrend.groupby(["task", "rep"]) if len(vrend) else []):
            wanted = sorted({fr for fs in fired[(fired["task"] == task) & (fired["rep"] == rep) &
                                                (fired["version"] == version)]["frames"] for fr in fs})
            picks = _nearest_rendered(g, wanted) or sorted(set(g["frame"]))[:1]
            for frame in picks[:MAX_SHEETS_PER_VERSION]:
                images = []
                for v in g[g["frame"] == frame].sort_values("view").itertuples(index=False):
                    dest = out / "images" / slug(subject) / slug(version) / \
                        f"{int(task):03d}_{int(rep)}_{int(frame):05d}_{slug(v.view)}.png"
                    media.copy_image(v.path, dest)
                    images.append({"href": os.path.relpath(dest, out / "subjects"),
                                   "alt": f"{v.view} view, frame {frame}"})
                reason = "first frame" if frame == min(g["frame"]) and not wanted else "check frame"
                sheets.append({"label": f"task {task}, frame {frame} ({reason})", "images": images})
        versions.append({"version": version, "checks": checks, "sheets": sheets})
    page = out / "subjects" / f"{slug(subject)}.html"
    atomic_write_text(page, env.get_template("subject.html.j2").render(
        subject=subject, versions=versions, synthetic=run.synthetic))
    return page.relative_to(out).as_posix()


def _audio_for(run: Run):
    """``(subject, task, rep) -> WAV path or None`` from the run's corpus (None when the corpus
    cannot be opened: the videos are then silent, and say so)."""
    root = run.meta.get("corpus_resolved")
    try:
        from cassi.data.corpus import Corpus  # noqa: PLC0415

        corpus = Corpus(root) if root else None
    except Exception:  # noqa: BLE001 - a moved corpus must not stop the report
        corpus = None

    def find(subject: str, task: int, rep: int):
        if corpus is None:
            return None
        try:
            return corpus.subject(subject).audio_path(task, rep)
        except Exception:  # noqa: BLE001
            return None
    return find


def _videos(run: Run, out: Path) -> list[dict]:
    """From the renders on the run's ``animate_stride`` grid: a four-view video per task file
    and version that was rendered in every view, and the versions side by side wherever
    several versions were rendered in the comparison view."""
    stride = int(run.meta.get("animate_stride") or 0)
    if not len(run.renders) or stride < 1:
        return []
    audio_for = _audio_for(run)
    videos = []

    def add(kind, label, result, dest):
        if result is not None:
            videos.append({"kind": kind, "label": label, "href": dest.relative_to(out).as_posix(),
                           "fps": result["fps"], "frames": result["frames"],
                           "seconds": result["seconds"], "audio": result["audio"]})

    for (subject, task, rep), g in run.renders.groupby(["subject", "task", "rep"]):
        task, rep = int(task), int(rep)
        audio = audio_for(subject, task, rep)
        stem = f"{slug(subject)}_{task:03d}_{rep}"
        name = f"{subject} task {task}" + (f" rep {rep}" if rep != 1 else "")
        all_views = [v for v in VIDEO_VIEWS if v in set(g["view"])]
        # A (version, view) was rendered for a video when its grid frames run unbroken (a
        # first frame and a check frame that happen to fall on the grid are no video).
        on_grid = {}
        for (version, view), p in g.groupby(["version", "view"]):
            grid = media.video_frames(p, stride=stride)
            if len(grid) >= 3 and all(b - a == stride for a, b in zip(grid, grid[1:])):
                on_grid.setdefault(version, set()).add(view)
        versions = order_versions(on_grid)
        for version in versions:
            if on_grid[version] != set(all_views):
                continue  # rendered for the comparisons only
            dest = out / "videos" / f"{stem}_{slug(version)}.mp4"
            add("task", f"{name}, {version}",
                media.task_video(g, dest, stride=stride, audio=audio,
                                 columns=[(version, v) for v in all_views]), dest)
        compared = [v for v in versions if COMPARISON_VIEW in on_grid[v]]
        if len(compared) > 1:
            dest = out / "animations" / f"{stem}_{COMPARISON_VIEW}.mp4"
            add("comparison", f"{name}, {COMPARISON_VIEW} view ({', '.join(compared)})",
                media.task_video(g, dest, stride=stride, audio=audio,
                                 columns=[(v, COMPARISON_VIEW) for v in compared]), dest)
    return videos


def _meta_items(run: Run) -> list[tuple[str, str]]:
    keys = ("started", "finished", "package_version", "git_revision", "variant", "preset", "stride",
            "executor", "corpus_resolved")
    return [(k, str(run.meta[k])) for k in keys if run.meta.get(k) not in (None, "")]


def write_report(run_dir: str | os.PathLike, out_dir: str | os.PathLike, *,
                 compare: str | os.PathLike | None = None,
                 history: pd.DataFrame | None = None) -> Path:
    """Write ``out_dir/index.html`` (+ subject pages, tables, plots, images) for a run.

    Parameters
    ----------
    run_dir : path
        A run directory (``cassi run --out``).
    out_dir : path
        Where the report goes (created).
    compare : path, optional
        A previous run to compare with.
    history : DataFrame, optional
        Columns night, version, negatives: a trend plot over nights (``cassi nightly``).
    """
    run = load_run(run_dir)
    previous = load_run(compare) if compare else None
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    env = _env()
    frames_by_check = _check_frames(run.results)
    subjects = sorted(run.results["subject"].dropna().unique())
    subject_links = [{"name": s, "href": _subject_page(run, s, frames_by_check, out, env)}
                     for s in subjects]
    trend = None
    if history is not None and history["night"].nunique() > 1:
        trend = plots.metric_trend(history, out / "plots" / "trend.png",
                                   synthetic=run.synthetic).relative_to(out).as_posix()
    gate_path = run.root / "gate.json"
    gate = json.loads(gate_path.read_text()) if gate_path.is_file() else None
    if gate is not None:
        atomic_write_text(out / "gate.md", (run.root / "gate.md").read_text()
                          if (run.root / "gate.md").is_file() else "")
    html = env.get_template("index.html.j2").render(
        run_name=run.name, meta_items=_meta_items(run), synthetic=run.synthetic,
        summaries=version_summaries(run.results), comparison=_comparison(run, previous, out),
        tables=_table_sections(run, out), videos=_videos(run, out),
        subjects=subject_links, trend=trend, gate=gate)
    index = out / "index.html"
    atomic_write_text(index, html)
    return index
