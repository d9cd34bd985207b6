"""Regression gates: image gates against golden renders and metric gates against a baseline run.

A gate passes, fails or is skipped, and always says why. Golden images change only through
:func:`update_golden` (``cassi golden``), never as a side effect of checking.
"""
from __future__ import annotations

import json
import os
import shutil
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from skimage.filters import gaussian
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

from cassi.data.atomic import atomic_tmp_path, atomic_write_text
from cassi.data.errors import CassiInputError
from cassi.reports.media import read_rgb8
from cassi.reports.runio import Run, load_run
from cassi.harness.rubric import CHECKS, verdicts

#: Image gate thresholds. Preview renders carry Monte Carlo noise that is not bit-reproducible
#: across processes (see the renderer), and raw SSIM of two noise patterns of the same image is
#: only ~0.95. SSIM is therefore taken after a Gaussian blur of NOISE_SIGMA px, as the renderer's
#: golden tests do: the same image twice scores ~0.997, the face moved by 3 px ~0.946, so 0.97
#: separates noise from change. PSNR (raw) >= 32 dB catches broad colour or lighting changes.
NOISE_SIGMA = 1.5
SSIM_MIN = 0.97
PSNR_MIN_DB = 32.0
#: Extra negatives a check may gain over the baseline before the metric gate fails, unless the
#: rubric declares its own ``gate_tolerance`` for that check.
DEFAULT_TOLERANCE = 0

GOLDEN_MARK = "golden.json"


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


def golden_key(row) -> Path:
    """Where a render lives in a golden directory: version/view/subject_task_rep_frame.png."""
    for name in ("version", "view", "subject"):
        value = str(row[name])
        if not value or "/" in value or "\\" in value or value in (".", ".."):
            raise CassiInputError(f"unsafe {name} {value!r} in render index")
    return Path(str(row["version"]), str(row["view"]),
                f"{row['subject']}_{int(row['task']):03d}_{int(row['rep'])}_{int(row['frame']):05d}.png")


def image_metrics(rendered: np.ndarray, reference: np.ndarray) -> tuple[float, float]:
    """SSIM of the images blurred by NOISE_SIGMA px, and PSNR (dB) of the raw images; both
    8-bit RGB of the same shape."""
    if rendered.shape != reference.shape:
        raise ValueError(f"image shapes differ: {rendered.shape} vs {reference.shape}")
    a, b = (gaussian(im.astype(np.float64) / 255.0, sigma=NOISE_SIGMA, channel_axis=-1)
            for im in (rendered, reference))
    ssim = structural_similarity(a, b, channel_axis=-1, data_range=1.0)
    if np.array_equal(rendered, reference):
        return float(ssim), float("inf")
    return float(ssim), float(peak_signal_noise_ratio(reference, rendered, data_range=255))


def image_gates(run: Run, reference_dir: Path, *, ssim_min: float = SSIM_MIN,
                psnr_min: float = PSNR_MIN_DB) -> list[GateResult]:
    """Compare every render of ``run`` with its golden counterpart under ``reference_dir``.

    A render without a golden image is a skipped gate that says so; never a pass.
    """
    out = []
    for _, row in run.renders.iterrows():
        if not str(row["path"]).endswith(".png"):
            continue
        item = f"{row['view']} task {int(row['task'])} frame {int(row['frame'])}"
        ref = reference_dir / golden_key(row)
        if not ref.is_file():
            out.append(GateResult("image", row["subject"], row["version"], item, "skip",
                                  f"no golden image {ref}"))
            continue
        try:
            ssim, psnr = image_metrics(read_rgb8(Path(row["path"])), read_rgb8(ref))
        except (OSError, ValueError) as err:
            out.append(GateResult("image", row["subject"], row["version"], item, "fail", str(err)))
            continue
        ok = ssim >= ssim_min and psnr >= psnr_min
        reason = (f"SSIM {ssim:.4f} (blurred {NOISE_SIGMA} px; min {ssim_min}), PSNR {psnr:.1f} dB "
                  f"(min {psnr_min})")
        out.append(GateResult("image", row["subject"], row["version"], item,
                              "pass" if ok else "fail", reason, ssim, ssim_min))
    return out


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
    """The baseline was run on other tasks, versions, views or preset than the run."""


def run_scope(meta: dict) -> dict[str, set]:
    """A run's scope from its resolved config (run.json): task files (subject, task, rep),
    versions, views and preset."""
    return {"tasks": {(str(s), int(t), int(r)) for s, t, r, *_ in meta.get("tasks_resolved") or []},
            "versions": set(meta.get("versions_resolved") or []),
            "views": set(meta.get("views_resolved") or []),
            "preset": {meta.get("preset")}}


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


def gate(run_dir: str | os.PathLike, baseline: str | os.PathLike, *,
         out_dir: str | os.PathLike | None = None,
         common_only: bool = False, jobs: bool = True) -> tuple[bool, list[GateResult]]:
    """Apply the gates of run ``run_dir`` against ``baseline`` (a run directory or a golden
    directory), write ``gate.json`` and ``gate.md`` into ``out_dir`` (default: the run), and
    return (passed, results).

    A baseline run gives metric gates and, through its renders, image gates; a golden
    directory gives image gates (and metric gates from the results snapshot that
    :func:`update_golden` stores). The baseline must have the run's scope (task files,
    versions, views, preset); with ``common_only`` only what both share is compared, and
    gate.md says so. Failed jobs of the run fail the gate; skipped ones are listed (``jobs``
    False leaves the job gates to the caller).

    Raises
    ------
    MismatchedBaseline
        When the scopes differ and ``common_only`` is False (the message says what differs).
    """
    run = load_run(run_dir)
    base_path = Path(baseline)
    if (base_path / GOLDEN_MARK).is_file():
        base_meta = json.loads((base_path / GOLDEN_MARK).read_text(encoding="utf-8")).get("run", {})
        snap = base_path / "results.parquet"
        base_results = pd.read_parquet(snap) if snap.is_file() else None
        reference = base_path
    elif (base_path / "results.parquet").is_file():
        base_run = load_run(base_path)
        base_meta, base_results = base_run.meta, base_run.results
        reference = None
    else:
        raise CassiInputError("baseline is neither a run directory (results.parquet) nor a "
                              f"golden directory ({GOLDEN_MARK})", path=base_path)
    notes: list[str] = []
    run_results, renders = run.results, run.renders
    scope, base_scope = run_scope(run.meta), run_scope(base_meta)
    known = all(m.get("tasks_resolved") is not None for m in (run.meta, base_meta))
    differences = scope_differences(scope, base_scope) if known else []
    if differences and not common_only:
        raise MismatchedBaseline("the baseline does not cover what the run covers, so their "
                                 "gates cannot compare like with like: " + "; ".join(differences)
                                 + " (rerun with the same settings, or pass --common-only to "
                                 "compare only what both share)", path=base_path)
    if differences:
        keys = {(s, t, r, v) for s, t, r in scope["tasks"] & base_scope["tasks"]
                for v in scope["versions"] & base_scope["versions"]}
        views = scope["views"] & base_scope["views"]
        run_results = _restrict(run_results, keys, views)
        base_results = None if base_results is None else _restrict(base_results, keys, views)
        renders = _restrict(renders, keys, views)
        notes.append("Compared on the common task files, versions and views only (--common-only): "
                     + "; ".join(differences) + ".")
    results = job_gates(run) if jobs else []
    if base_results is not None:
        results += metric_gates(run_results, base_results)
    if reference is None:
        reference = _renders_as_golden(base_run, run.root / ".gate-baseline")
    results += image_gates(Run(run.root, run_results, run.ratings, run.meta, renders), reference)
    passed = not any(r.status == "fail" for r in results)
    write_gate_report(Path(out_dir or run.root), passed, results, baseline=str(base_path),
                      notes=notes)
    return passed, results


def _renders_as_golden(run: Run, scratch: Path) -> Path:
    """A baseline run's renders laid out like a golden directory: links in ``scratch`` (inside
    the run being gated, so the baseline run is never written to), made anew each time."""
    shutil.rmtree(scratch, ignore_errors=True)
    for _, row in run.renders.iterrows():
        dest = scratch / golden_key(row)
        if not dest.exists():
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.symlink(row["path"], dest)
    return scratch


def write_gate_report(out_dir: Path, passed: bool, results: list[GateResult], *, baseline: str,
                      notes: list[str] = ()) -> None:
    counts = {s: sum(r.status == s for r in results) for s in ("pass", "fail", "skip")}
    payload = {"passed": passed, "baseline": baseline, "counts": counts, "notes": list(notes),
               "gates": [asdict(r) for r in results]}
    atomic_write_text(out_dir / "gate.json", json.dumps(payload, indent=2, default=str) + "\n")
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

    Returns the number of images written.
    """
    run = load_run(run_dir)
    golden = Path(golden_dir)
    n = 0
    for _, row in run.renders.iterrows():
        if not str(row["path"]).endswith(".png"):
            continue
        dest = golden / golden_key(row)
        dest.parent.mkdir(parents=True, exist_ok=True)
        tmp = atomic_tmp_path(dest)
        shutil.copyfile(row["path"], tmp)
        os.replace(tmp, dest)
        n += 1
    tmp = atomic_tmp_path(golden / "results.parquet")
    run.results.to_parquet(tmp, index=False)
    os.replace(tmp, golden / "results.parquet")
    scope = {k: run.meta.get(k) for k in ("tasks_resolved", "versions_resolved",
                                          "views_resolved", "preset")}
    atomic_write_text(golden / GOLDEN_MARK, json.dumps(
        {"from_run": str(Path(run_dir).resolve()), "images": n, "synthetic": run.synthetic,
         "run": scope}, indent=2) + "\n")
    return n
