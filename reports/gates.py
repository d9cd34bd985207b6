"""Regression gates: image gates against golden renders and metric gates against a baseline run.

A gate passes, fails or is skipped, and always says why. Golden images change only through
:func:`update_golden` (``cassi golden``), never as a side effect of checking.
"""
from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_tmp_path, atomic_write_text, replacing, writable_dir
from cassi.common.errors import CassiInputError, first_few
from cassi.harness.farm.store import is_sha256, sha256_file_once
from cassi.reports.media import read_rgb8
from cassi.reports.runio import Run, load_run
from cassi.renderer.compare import MAX_CHANGED_SHARE, compare_images
from cassi.harness.rubric import CHECKS, verdicts

#: Image gates judge a render against its golden image by the renderer's one comparison rule
#: (:func:`cassi.renderer.compare.compare_images`: at most MAX_CHANGED_SHARE of the pixels may
#: differ by more than PIXEL_LEVELS levels), so a golden made on one machine and a night rendered
#: on another pass when nothing changed (the rule's module says why and what it was measured on).
#: What changed is shown where the evaluation looks: FLIP (perceived difference, 0..1) inside
#: the mouth region the renderer records with every PNG (``cassi:mouth_box``).
GATE_IMAGES = "gate-images"
#: Extra negatives a check may gain over the baseline before the metric gate fails, unless the
#: rubric declares its own ``gate_tolerance`` for that check.
DEFAULT_TOLERANCE = 0

GOLDEN_MARK = "golden.json"
#: A golden directory's list of its images (RENDER_COLUMNS less ``path``), so that a gate
#: sees the renders a run lacks.
GOLDEN_RENDERS = "renders.parquet"


@dataclass
class GateResult:
    gate: str          # "image" or "metric"
    subject: str
    version: str
    item: str          # view/frame for images, table/check for metrics
    status: str        # "pass", "fail", "skip"
    reason: str
    value: float | None = None
    threshold: float | None = None


_GATE_FIELDS = tuple(f.name for f in fields(GateResult))


def golden_key(row) -> Path:
    """Where a render lives in a golden directory: version/view/subject_task_rep_frame.png."""
    return Path(golden_name(row))


def golden_name(row) -> str:
    """:func:`golden_key` as a string (the image gates compare 50,000 of them a subject's full
    set: strings, not Paths)."""
    for name in ("version", "view", "subject"):
        value = str(row[name])
        if not value or "/" in value or "\\" in value or value in (".", ".."):
            raise CassiInputError(f"unsafe {name} {value!r} in render index")
    return (f"{row['version']}/{row['view']}/"
            f"{row['subject']}_{int(row['task']):03d}_{int(row['rep'])}_{int(row['frame']):05d}.png")


def mouth_box_of(path: str | os.PathLike,
                 shape: tuple[int, ...]) -> tuple[int, int, int, int] | None:
    """(row0, row1, col0, col1) of the mouth region recorded in a render's PNG, or None."""
    from PIL import Image  # noqa: PLC0415 - Pillow comes with imageio

    try:
        with Image.open(path) as im:
            box = json.loads(im.text.get("cassi:mouth_box", "null"))
    except (OSError, ValueError):
        return None
    if not (isinstance(box, list) and len(box) == 4):
        return None
    r0, r1, c0, c1 = (int(v) for v in box)
    if not (0 <= r0 < r1 <= shape[0] and 0 <= c0 < c1 <= shape[1]):
        return None
    return r0, r1, c0, c1


def image_metrics(rendered: np.ndarray, reference: np.ndarray,
                  box: tuple[int, int, int, int] | None = None) -> dict:
    """How two 8-bit RGB images of one shape differ.

    Returns
    -------
    dict
        ``comparison`` the :class:`~cassi.renderer.compare.ImageComparison` (the rule's verdict
        and reason), ``changed_px`` pixels differing by more than PIXEL_LEVELS levels in any
        channel, ``max_levels`` the largest difference, ``flip_mouth`` the mean FLIP error
        (0 = same, 1 = most different) inside ``box`` (the whole image when None) and
        ``flip_map`` its per-pixel map, float (h, w).
    """
    import flip_evaluator  # noqa: PLC0415

    comparison = compare_images(rendered, reference)
    r0, r1, c0, c1 = box or (0, rendered.shape[0], 0, rendered.shape[1])
    crop = [np.ascontiguousarray(im[r0:r1, c0:c1, :3], np.float32) / 255.0
            for im in (reference, rendered)]
    flip_map, flip_mean, _ = flip_evaluator.evaluate(crop[0], crop[1], "LDR", applyMagma=False)
    return {"comparison": comparison, "changed_px": comparison.changed_px,
            "max_levels": comparison.max_levels, "flip_mouth": float(flip_mean),
            "flip_map": np.asarray(flip_map, np.float32).squeeze()}


def _write_gate_images(out: Path, stem: Path, rendered: np.ndarray, reference: np.ndarray,
                       metrics: dict, box) -> list[str]:
    """rendered, reference, difference (x4) and FLIP (mouth region, magma) images of a failed
    gate under ``out``; returns their paths relative to ``out``."""
    import imageio.v3 as iio  # noqa: PLC0415
    from matplotlib import colormaps  # noqa: PLC0415

    diff = np.clip(np.abs(rendered.astype(np.int16) - reference.astype(np.int16)) * 4, 0, 255)
    flip = (colormaps["magma"](np.clip(metrics["flip_map"], 0, 1))[..., :3] * 255).astype(np.uint8)
    images = {"rendered": rendered, "reference": reference, "difference": diff.astype(np.uint8),
              "flip_mouth": flip}
    if box is not None:
        for name in ("rendered", "reference", "difference"):
            img = images[name].copy()
            r0, r1, c0, c1 = box
            img[[r0, r1 - 1], c0:c1] = (0, 200, 0)
            img[r0:r1, [c0, c1 - 1]] = (0, 200, 0)
            images[name] = img
    written = []
    for name, img in images.items():
        dest = out / GATE_IMAGES / stem.parent / f"{stem.stem}.{name}.png"
        with replacing(dest) as tmp:
            iio.imwrite(tmp, np.ascontiguousarray(img[..., :3], np.uint8), extension=".png")
        written.append(dest.relative_to(out).as_posix())
    return written


def _pngs(renders: pd.DataFrame) -> list[dict]:
    return [r for r in renders.to_dict("records") if str(r["path"]).endswith(".png")]


def image_gates(run: Run, reference_dir: Path | None = None, *, baseline: Run | None = None,
                images_dir: Path | None = None) -> list[GateResult]:
    """Compare every render of ``run`` with its counterpart: the golden image under
    ``reference_dir``, or the ``baseline`` run's render of the same view, task file, version
    and frame (read where the baseline's index puts it).

    A render without a counterpart is a skipped gate that says so; never a pass. A failed
    render gets its rendered, reference, difference and FLIP images under
    ``images_dir/gate-images`` (default: the run directory).
    """
    out = []
    images_dir = Path(images_dir or run.root)
    # Paths as strings (os.path), made Paths only where an image is decoded: the same texts
    theirs = None if baseline is None else {golden_name(r): os.fspath(Path(r["path"]))
                                            for r in _pngs(baseline.renders)}
    for row in _pngs(run.renders):
        item = f"{row['view']} task {int(row['task'])} frame {int(row['frame'])}"
        key = golden_name(row)
        path = os.fspath(row["path"])
        ref = os.fspath(reference_dir / key) if theirs is None else theirs.get(key)
        if ref is None or not os.path.isfile(ref):
            missing = (f"no golden image {ref}" if theirs is None else
                       f"no render of the baseline {baseline.root} at {key}")
            out.append(GateResult("image", row["subject"], row["version"], item, "skip",
                                  missing))
            continue
        corrupt = _not_its_name(path) or _not_its_name(ref)
        if corrupt:
            out.append(GateResult("image", row["subject"], row["version"], item, "fail", corrupt))
            continue
        ref = Path(ref)
        same = _same_bytes(path, ref)
        if same:
            # equal digests are equal images, nothing to decode
            out.append(GateResult("image", row["subject"], row["version"], item, "pass",
                                  f"the same bytes as {ref} (SHA-256 {same[:12]})", 0.0,
                                  MAX_CHANGED_SHARE))
            continue
        try:
            rendered, reference = read_rgb8(path), read_rgb8(ref)
            box = mouth_box_of(path, rendered.shape)
            m = image_metrics(rendered, reference, box)
        except (OSError, ValueError) as err:
            out.append(GateResult("image", row["subject"], row["version"], item, "fail", str(err)))
            continue
        c = m["comparison"]
        where = "mouth region" if box is not None else "whole image (no mouth region recorded)"
        reason = f"{c.reason}; FLIP in the {where} {m['flip_mouth']:.4f}"
        if not c.passed:
            files = _write_gate_images(images_dir, golden_key(row), rendered, reference, m, box)
            reason += "; images: " + ", ".join(files)
        out.append(GateResult("image", row["subject"], row["version"], item,
                              "pass" if c.passed else "fail", reason, c.changed_share,
                              MAX_CHANGED_SHARE))
    return out


def _content_name(path: str | os.PathLike) -> str | None:
    """The SHA-256 a content-addressed blob is named by (``objects/ab/<sha256>.png``, or a
    link to one), or None for another file."""
    stem = os.path.basename(path).split(".", 1)[0]
    if not is_sha256(stem):
        try:
            stem = os.path.basename(os.path.realpath(path)).split(".", 1)[0]
        except OSError:
            return None
    return stem if is_sha256(stem) else None


def _not_its_name(path: str | os.PathLike) -> str | None:
    """Why a content-addressed file is not what its name says (its bytes hash to another
    digest: a write into a blob the store and its runs share), or None (it is, or it is
    named otherwise). Hashed once per process (:func:`sha256_file_once`)."""
    name = _content_name(path)
    if name is None:
        return None
    try:
        digest = sha256_file_once(path)
    except OSError as err:
        return f"{path} cannot be read: {err.strerror or err}"
    if digest == name:
        return None
    return (f"{path} is corrupt: its bytes hash to {digest[:12]}, not to the digest it is "
            f"named by ({name[:12]}); every run that links this blob shares the damage (rerun "
            "without the damaged blob)")


def _same_bytes(a: str | os.PathLike, b: str | os.PathLike) -> str | None:
    """The SHA-256 both files share, or None (unequal or unreadable: the comparison rule
    then decides, or says why it cannot). Each file is hashed once per process: renders
    linked from one store blob are one file, hashed once."""
    try:
        digest = sha256_file_once(a)
        return digest if sha256_file_once(b) == digest else None
    except OSError:
        return None


def tolerance(check: str) -> int:
    """The rubric's gate tolerance for ``check`` (DEFAULT_TOLERANCE for a check it no longer has)."""
    entry = CHECKS.get(check)
    return DEFAULT_TOLERANCE if entry is None else int(entry.gate_tolerance)


def metric_gates(run: pd.DataFrame, baseline: pd.DataFrame) -> list[GateResult]:
    """Per version, table and check: the negatives summed over the task files may not grow
    beyond the check's tolerance (both tables cover the same task files: :func:`gate`). The
    negatives are the rubric's verdicts (:func:`cassi.harness.rubric.verdicts`: one charge per
    fault, Table C with Table A's lip rows)."""
    cur, base = verdicts(run), verdicts(baseline)
    # a check is gated in the table that declares it (Table C repeats Table A's lip rows)
    cur, base = (v[v["table"] == v["own_table"]] for v in (cur, base))
    keys = ["version", "table", "check"]
    a = cur.groupby(keys)["negatives"].sum()
    b = base.groupby(keys)["negatives"].sum()
    out = []
    for key in sorted(set(a.index) & set(b.index)):
        version, table, check = key
        now, before, tol = int(a[key]), int(b[key]), tolerance(check)
        status = "fail" if now - before > tol else "pass"
        out.append(GateResult("metric", "all", version, f"table {table} / {check}", status,
                              f"{now} negatives against {before} in the baseline (tolerance {tol})",
                              float(now), float(before + tol)))
    return out


#: What two runs must share for their gates to compare like with like.
LIKE_WITH_LIKE = ("tasks", "versions", "views", "preset")
_KEY = ["subject", "task", "rep", "version"]


class MismatchedBaseline(CassiInputError):
    """The baseline was run on other tasks, versions, views or preset than the run, or holds
    other checks or renders."""


class IncompleteRun(CassiInputError):
    """A run (or the baseline) with failed or missing jobs where the gate compares."""


class NothingCompared(CassiInputError):
    """No metric or image gate could be applied: nothing compared is not a pass."""


def run_scope(meta: dict) -> dict[str, set]:
    """A run's scope from its resolved config (run.json): task files (subject, task, rep),
    versions, views and preset."""
    return {"tasks": {(str(s), int(t), int(r)) for s, t, r, *_ in meta.get("tasks_resolved") or []},
            "versions": set(meta.get("versions_resolved") or []),
            "views": set(meta.get("views_resolved") or []),
            "preset": {meta.get("preset")}}


def input_digests(meta: dict) -> dict[tuple, str] | None:
    """(subject, task, rep) -> the digest of the corpus files its jobs read (run.json's
    ``tasks_resolved``, sixth field), or None when the run does not record them."""
    rows = meta.get("tasks_resolved") or []
    if not rows or any(len(r) < 6 for r in rows):
        return None
    return {(str(s), int(t), int(r)): str(d) for s, t, r, _, _, d, *_ in rows if d}


def _job_task(key: str) -> tuple | None:
    """(subject, task, rep, version) of a farm job key ``JW11/019-1/cassi-2.0/...``."""
    parts = key.split("/")
    try:
        task, rep = parts[1].split("-")
        return parts[0], int(task), int(rep), parts[2]
    except (IndexError, ValueError):
        return None


def incomplete_jobs(meta: dict, summary: dict, results: pd.DataFrame | None,
                    keys: set[tuple] | None = None) -> tuple[list[str], list[str]]:
    """What a run lacks among ``keys`` (subject, task, rep, version; None: all it planned):
    its failed jobs (``job: reason``) and the task files and versions its plan holds that have
    neither results nor a failed or skipped job (``task/version``)."""
    def wanted(key: str) -> bool:
        where = _job_task(key)
        return keys is None or where is None or where in keys

    failed = [f"{k} failed: {why}" for k, why in sorted((summary.get("failed") or {}).items())
              if wanted(k)]
    missing = []
    if results is not None and meta.get("tasks_resolved") is not None:
        accounted = {_job_task(k) for k in (*(summary.get("failed") or {}),
                                            *(summary.get("skipped") or {}))}
        present = set(zip(results["subject"].astype(str), results["task"].astype(int),
                          results["rep"].astype(int), results["version"].astype(str)))
        for s, t, r, usable, *_ in meta["tasks_resolved"]:
            for v in meta.get("versions_resolved") or []:
                key = (str(s), int(t), int(r), str(v))
                if (usable and (keys is None or key in keys) and key not in present
                        and key not in accounted):
                    missing.append(f"{s}/{int(t):03d}-{int(r)}/{v}: no results and no job record")
    return failed, missing


def _fmt(items: set) -> str:
    items = sorted(items, key=str)
    text = ", ".join("/".join(map(str, i)) if isinstance(i, tuple) else str(i) for i in items[:6])
    return text + (f" and {len(items) - 6} more" if len(items) > 6 else "")


def scope_differences(run: dict, base: dict) -> list[str]:
    """What differs between two scopes (:func:`run_scope`), one sentence per setting."""
    out = []
    for key in LIKE_WITH_LIKE:
        only_run, only_base = run[key] - base[key], base[key] - run[key]
        if only_run or only_base:
            parts = [f"only in the run: {_fmt(only_run)}" if only_run else "",
                     f"only in the baseline: {_fmt(only_base)}" if only_base else ""]
            out.append(f"{key} differ ({'; '.join(p for p in parts if p)})")
    return out


def _restrict(df: pd.DataFrame, keys: set[tuple], views: set) -> pd.DataFrame:
    if df.empty:
        return df
    idx = pd.MultiIndex.from_frame(df[_KEY].astype({"task": int, "rep": int}))
    keep = idx.isin(list(keys)) & (df["view"].isin(views | {"geometry"}))
    return df[keep].reset_index(drop=True)


def job_gates(run: Run) -> list[GateResult]:
    """A failed job fails the gate (its results are missing); a skipped job is listed."""
    out = [GateResult("jobs", "all", "all", key, "fail", f"job failed: {why}")
           for key, why in sorted(run.failed.items())]
    out += [GateResult("jobs", "all", "all", key, "skip", f"job skipped: {why}")
            for key, why in sorted(run.skipped.items())]
    return out


@dataclass
class _Baseline:
    """What a gate compares a run with: a baseline run (``run``, whose renders are the
    reference images) or a golden directory (``golden``, with the results snapshot
    :func:`update_golden` stores, if any)."""

    path: Path
    meta: dict
    results: pd.DataFrame | None
    summary: dict
    #: RENDER_COLUMNS less ``path``; None for a golden directory that does not list them
    renders: pd.DataFrame | None
    run: Run | None = None
    golden: Path | None = None


def load_baseline(path: Path) -> _Baseline:
    """A run directory or a golden directory; a clear refusal for anything else."""
    if (path / GOLDEN_MARK).is_file():
        meta = json.loads((path / GOLDEN_MARK).read_text(encoding="utf-8")).get("run", {})
        snap, listed = path / "results.parquet", path / GOLDEN_RENDERS
        # cassi golden refuses runs with failed jobs: a golden directory has none
        return _Baseline(path, meta, pd.read_parquet(snap) if snap.is_file() else None, {},
                         pd.read_parquet(listed) if listed.is_file() else None, golden=path)
    if (path / "results.parquet").is_file():
        run = load_run(path)
        return _Baseline(path, run.meta, run.results, run.summary, run.renders, run=run)
    raise CassiInputError("baseline is neither a run directory (results.parquet) nor a "
                          f"golden directory ({GOLDEN_MARK})", path=path)


@dataclass
class _Comparison:
    """What a gate compares: the run's results and renders and the baseline's results, all
    restricted to ``keys`` (subject, task, rep, version; None: everything) when the two differ
    and ``--common-only`` allows it; ``differences`` says how they differ, ``notes`` what
    gate.md says about the comparison."""

    results: pd.DataFrame
    renders: pd.DataFrame
    base_results: pd.DataFrame | None
    base_renders: pd.DataFrame | None
    keys: set[tuple] | None = None
    differences: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _like_with_like(run: Run, base: _Baseline, common_only: bool) -> _Comparison:
    """Compare the scopes and the corpus files of the run and its baseline; refuse when they
    differ (unless ``common_only``: then only what both share is compared)."""
    out = _Comparison(run.results, run.renders, base.results, base.renders)
    scope, base_scope = run_scope(run.meta), run_scope(base.meta)
    known = all(m.get("tasks_resolved") is not None for m in (run.meta, base.meta))
    out.differences = scope_differences(scope, base_scope) if known else []
    digests, base_digests = input_digests(run.meta), input_digests(base.meta)
    changed: set[tuple] = set()
    if digests is None or base_digests is None:
        who = " and ".join(w for w, d in (("the run", digests), ("the baseline", base_digests))
                           if d is None)
        out.notes.append(f"The corpus files were not compared: {who} does not record their "
                         "digests (run.json from before they were recorded).")
    else:
        changed = {t for t in set(digests) & set(base_digests) if digests[t] != base_digests[t]}
        if changed:
            out.differences.append(f"corpus files differ for {len(changed)} task file(s) "
                                   f"({_fmt(changed)}): the runs read other data")
    if out.differences and not common_only:
        raise MismatchedBaseline("the baseline does not cover what the run covers, so their "
                                 "gates cannot compare like with like: "
                                 + "; ".join(out.differences) + " (rerun with the same "
                                 "settings, or pass --common-only to compare only what both "
                                 "share)", path=base.path)
    if out.differences:
        out.keys = {(s, t, r, v) for s, t, r in (scope["tasks"] & base_scope["tasks"]) - changed
                    for v in scope["versions"] & base_scope["versions"]}
        views = scope["views"] & base_scope["views"]
        out.results = _restrict(out.results, out.keys, views)
        out.base_results = (None if out.base_results is None
                            else _restrict(out.base_results, out.keys, views))
        out.renders = _restrict(out.renders, out.keys, views)
        out.base_renders = (None if out.base_renders is None
                            else _restrict(out.base_renders, out.keys, views))
        out.notes.append("Compared on the common task files, versions and views only "
                         "(--common-only): " + "; ".join(out.differences) + ".")
    return out


def _require_complete(run: Run, base: _Baseline, keys: set[tuple] | None) -> None:
    """Refuse a baseline with failed or missing jobs among ``keys``, and a run with missing
    ones (the run's failed jobs are failed gates)."""
    base_failed, base_missing = incomplete_jobs(base.meta, base.summary, base.results, keys)
    if base_failed or base_missing:
        raise IncompleteRun("the baseline has failed or missing jobs, so its results cannot "
                            "stand for what the run is compared with: "
                            + first_few(base_failed + base_missing) + " (gate against a "
                            "complete run or golden directory)", path=base.path)
    _, missing = incomplete_jobs(run.meta, run.summary, run.results, keys)
    if missing:
        raise IncompleteRun("the run lacks jobs it planned (neither results nor a job record): "
                            + first_few(missing), path=run.root)


def _check_rows(results: pd.DataFrame):
    """Each row's (subject, task, rep, version, view, check), in order."""
    return zip(results["subject"].astype(str), results["task"].astype(int),
               results["rep"].astype(int), results["version"].astype(str),
               results["view"].astype(str), results["check"].astype(str))


def _checks(results: pd.DataFrame | None, failed: set[tuple]) -> set[tuple] | None:
    """(subject, task, rep, version, view, check) of every check in ``results`` outside the
    ``failed`` (subject, task, rep, version)."""
    return None if results is None else {k for k in _check_rows(results) if k[:4] not in failed}


def _render_keys(renders: pd.DataFrame | None, failed: set[tuple]) -> set[tuple] | None:
    """(subject, task, rep, version, view, frame) of every PNG render outside ``failed``."""
    if renders is None:
        return None
    if "path" in renders:
        renders = renders[renders["path"].astype(str).str.endswith(".png")]
    return {(str(s), int(t), int(r), str(v), str(view), int(f)) for s, t, r, v, view, f in
            zip(*(renders[c] for c in ("subject", "task", "rep", "version", "view", "frame")))
            if (str(s), int(t), int(r), str(v)) not in failed}


def _lacking(what: str, unit: str, run: set[tuple], base: set[tuple]) -> str:
    """One sentence on the ``what`` (checks, renders) one side has and the other lacks, by
    task file, version and view (``unit``: what the last field names); '' when both have the
    same."""
    def grouped(keys: set[tuple]) -> str:
        by: dict[str, list[str]] = {}
        for s, t, r, v, view, item in sorted(keys, key=str):
            by.setdefault(f"{s}/{int(t):03d}-{int(r)}/{v}/{view}", []).append(str(item))
        return first_few([f"{k} ({unit} {i[0]})" if len(i) == 1 else
                          f"{k} ({len(i)} {unit}s: {', '.join(i[:3])}{', ...' * (len(i) > 3)})"
                          for k, i in by.items()])

    parts = [f"only in the run: {grouped(run - base)}" if run - base else "",
             f"only in the baseline: {grouped(base - run)}" if base - run else ""]
    return f"{what} differ ({'; '.join(p for p in parts if p)})" if any(parts) else ""


def _same_coverage(run: Run, base: _Baseline, what: _Comparison, common_only: bool) -> None:
    """Refuse when one side lacks checks or renders the other has (a job that animated
    nothing, a version that dropped a check): compared on the rest, it would pass what it never
    saw. With ``common_only`` only the checks both have are compared; a render the baseline
    lacks is a skipped gate. The run's failed jobs are failed gates of their own."""
    failed = {k for k in map(_job_task, run.failed) if k is not None}
    checks = (_checks(what.results, failed), _checks(what.base_results, failed))
    renders = (_render_keys(what.renders, failed), _render_keys(what.base_renders, failed))
    found = [_lacking(name, unit, *sides) for name, unit, sides in
             (("checks", "check", checks), ("renders", "frame", renders)) if None not in sides]
    found = [f for f in found if f]
    if renders[1] is None:
        what.notes.append("The renders were not compared as sets: the golden directory does "
                          f"not list its images (no {GOLDEN_RENDERS}: written before goldens "
                          "listed them); a render it lacks is a skipped gate.")
    if found and not common_only:
        raise MismatchedBaseline("the run and its baseline do not hold the same checks and "
                                 "renders, so a gate on the rest would pass what it never saw: "
                                 + "; ".join(found) + " (find why a side lacks them, or pass "
                                 "--common-only to compare only what both have)",
                                 path=base.path)
    if found:
        common = checks[0] & checks[1] if None not in checks else None
        if common is not None:
            what.results, what.base_results = (
                df[np.fromiter((k in common or k[:4] in failed for k in _check_rows(df)), bool,
                               count=len(df))].reset_index(drop=True)
                for df in (what.results, what.base_results))
        what.differences += found
        what.notes.append("Compared on the checks and renders both have only (--common-only): "
                          + "; ".join(found) + ".")


def _compare(run: Run, base: _Baseline, what: _Comparison) -> list[GateResult]:
    """The metric gates (where the baseline has results) and the image gates; a gate that
    compared nothing refuses."""
    results = [] if what.base_results is None else metric_gates(what.results, what.base_results)
    images = image_gates(Run(run.root, what.results, run.ratings, run.meta, what.renders),
                         base.golden, baseline=None if base.golden else base.run)
    if not any(r.status != "skip" for r in results + images):
        where = " on what both share (--common-only)" if what.differences else ""
        raise NothingCompared(
            f"nothing was compared with the baseline {base.path}{where}: {len(what.results)} "
            f"result rows and {len(what.renders)} renders gave no metric or image gate "
            f"({len(images)} renders without a baseline image); a gate that compares nothing "
            "is not a pass", path=run.root)
    return results + images


def gate(run_dir: str | os.PathLike | Run, baseline: str | os.PathLike, *,
         out_dir: str | os.PathLike | None = None,
         common_only: bool = False, jobs: bool = True) -> tuple[bool, list[GateResult]]:
    """Apply the gates of run ``run_dir`` (or the run already loaded) against ``baseline`` (a
    run directory or a golden directory), write ``gate.json`` and ``gate.md`` into ``out_dir``
    (default: the run), and return (passed, results).

    A baseline run gives metric gates and, through its renders, image gates; a golden
    directory gives image gates (and metric gates from the results snapshot that
    :func:`update_golden` stores). The baseline must have the run's scope (task files,
    versions, views, preset); with ``common_only`` only what both share is compared, and
    gate.md says so. Failed jobs of the run fail the gate; skipped ones are listed (``jobs``
    False leaves the job gates to the caller).

    Raises
    ------
    MismatchedBaseline
        When the scopes or the corpus files (their digests) differ, or one side lacks checks
        or renders the other has (outside the run's failed jobs), and ``common_only`` is False
        (the message says what differs).
    IncompleteRun
        When the baseline has failed or missing jobs among what is compared, or the run has
        missing ones (its failed jobs are failed gates, listed).
    NothingCompared
        When no metric or image gate could be applied.
    """
    run = run_dir if isinstance(run_dir, Run) else load_run(run_dir)  # a caller's loaded run
    base = load_baseline(Path(baseline))
    results, notes = compared(run, base, common_only=common_only, jobs=jobs)
    passed = not any(r.status == "fail" for r in results)
    write_gate_report(Path(out_dir or run.root), passed, results, baseline=str(base.path),
                      notes=notes)
    return passed, results


def compared(run: Run, base: "_Baseline", *, common_only: bool = False,
             jobs: bool = True) -> tuple[list[GateResult], list[str]]:
    """:func:`gate`'s results and gate.md's notes, written nowhere: for a caller that writes
    one gate report over several baselines (the nightly). Raises as :func:`gate` does."""
    what = _like_with_like(run, base, common_only)
    _require_complete(run, base, what.keys)
    _same_coverage(run, base, what, common_only)
    return (job_gates(run) if jobs else []) + _compare(run, base, what), what.notes


def write_gate_report(out_dir: Path, passed: bool, results: list[GateResult], *, baseline: str,
                      notes: list[str] = (), baseline_recorded: bool = False) -> None:
    """``gate.json`` and ``gate.md``; ``baseline_recorded``: a first night with nothing to
    compare with, which says so instead of "0 passed, 0 failed"."""
    counts = {s: sum(r.status == s for r in results) for s in ("pass", "fail", "skip")}
    payload = {"passed": passed, "baseline": baseline, "counts": counts, "notes": list(notes),
               "baseline_recorded": baseline_recorded,
               # the fields of a flat dataclass, as asdict gives them, without its deep copy
               # (a full set's night has about 100,000 gates)
               "gates": [{f: getattr(r, f) for f in _GATE_FIELDS} for r in results]}
    atomic_write_text(out_dir / "gate.json", json.dumps(payload, indent=2, default=str) + "\n")
    if baseline_recorded:
        lines = ["# Gates: baseline recorded", "",
                 "The first night: no previous night and no golden images to compare with, so "
                 "no regression gate ran. This night is the baseline the next one is gated "
                 "against.", ""]
    else:
        lines = [f"# Gates: {'PASSED' if passed else 'FAILED'}", "",
                 f"Baseline: `{baseline}`. {counts['pass']} passed, {counts['fail']} failed, "
                 f"{counts['skip']} skipped.", "", *[f"**Note.** {n}\n" for n in notes]]
    for status in ("fail", "skip"):
        rows = [r for r in results if r.status == status]
        if rows:
            lines += [f"## {status}", ""]
            lines += [f"- {r.gate} {r.version} {r.subject} {r.item}: {r.reason}" for r in rows]
            lines.append("")
    atomic_write_text(out_dir / "gate.md", "\n".join(lines))


def update_golden(run_dir: str | os.PathLike, golden_dir: str | os.PathLike) -> int:
    """Make ``run_dir``'s renders and results the golden baseline (the only way goldens change).

    A run with failed or missing jobs, or one that evaluated nothing, is refused; so is a render
    that is not what its name says or that does not decode, before any golden image changes.
    Returns the number of images written.
    """
    run = load_run(run_dir)
    failed, missing = incomplete_jobs(run.meta, run.summary, run.results)
    if failed or missing:
        raise IncompleteRun("a run with failed or missing jobs cannot be the golden baseline: "
                            + first_few(failed + missing) + " (rerun it to completion first)",
                            path=run.root)
    if run.results.empty:
        skipped = [f"{k}: {why}" for k, why in sorted(run.skipped.items())]
        raise IncompleteRun("the run evaluated nothing (0 result rows"
                            + (f"; every job skipped: {first_few(skipped)}" if skipped else "")
                            + "), so it cannot be the golden baseline", path=run.root)
    golden = writable_dir(golden_dir, "golden directory")
    listed = run.renders[run.renders["path"].astype(str).str.endswith(".png")]
    for tmp, dest in _staged_images(listed, golden):
        os.replace(tmp, dest)
    with replacing(golden / "results.parquet") as tmp:
        run.results.to_parquet(tmp, index=False)
    with replacing(golden / GOLDEN_RENDERS) as tmp:
        listed.drop(columns="path").to_parquet(tmp, index=False)
    scope = {k: run.meta.get(k) for k in ("tasks_resolved", "versions_resolved",
                                          "views_resolved", "preset")}
    atomic_write_text(golden / GOLDEN_MARK, json.dumps(
        {"from_run": str(Path(run_dir).resolve()), "images": len(listed),
         "synthetic": run.synthetic, "run": scope}, indent=2) + "\n")
    return len(listed)


def _staged_images(renders: pd.DataFrame, golden: Path) -> list[tuple[Path, Path]]:
    """Each render copied to a temporary name beside its golden image, checked against its
    name and decoded as written: (temporary, golden image) pairs, or a refusal naming the
    render with every temporary removed."""
    staged: list[tuple[Path, Path]] = []
    try:
        for _, row in renders.iterrows():
            src, dest = Path(row["path"]), golden / golden_key(row)
            corrupt = _not_its_name(src)
            if corrupt:  # names the render
                raise CassiInputError(f"{corrupt}; a golden image must be what the run rendered")
            staged.append((atomic_tmp_path(dest), dest))
            shutil.copyfile(src, staged[-1][0])
            try:
                read_rgb8(staged[-1][0])
            except Exception as err:  # noqa: BLE001 - any decoder error: the image is unusable
                raise CassiInputError(f"the render does not decode ({err}); a golden image "
                                      "must be one", path=src) from err
    except BaseException:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
        raise
    return staged
