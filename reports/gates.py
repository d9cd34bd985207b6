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

from cassi.data.atomic import atomic_tmp_path, atomic_write_text
from cassi.data.errors import CassiInputError
from cassi.reports.media import read_rgb8
from cassi.reports.runio import Run, load_run
from cassi.reports.tables import verdicts

#: Image gate thresholds. Preview renders are one ray per pixel centre with no sampling, so a
#: frame is the same bytes in every run of a variant; llvm and scalar_rgb differ by at most one
#: 8-bit level except where a ray grazes a silhouette edge (one pixel per view seen). A render
#: fails when more than MAX_CHANGED_PX pixels differ from the golden image by more than
#: LEVELS levels: lowering the jaw by 1 Parke unit (0.25 mm) already changes hundreds.
LEVELS = 1
MAX_CHANGED_PX = 16
#: What changed is shown where the evaluation looks: FLIP (perceived difference, 0..1) inside
#: the mouth region the renderer records with every PNG (``cassi:mouth_box``).
GATE_IMAGES = "gate-images"
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


def mouth_box_of(path: Path, shape: tuple[int, ...]) -> tuple[int, int, int, int] | None:
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
        ``changed_px`` pixels differing by more than LEVELS levels in any channel,
        ``max_levels`` the largest difference, ``flip_mouth`` the mean FLIP error (0 = same,
        1 = most different) inside ``box`` (the whole image when None) and ``flip_map`` its
        per-pixel map, float (h, w).
    """
    import flip_evaluator  # noqa: PLC0415

    if rendered.shape != reference.shape:
        raise ValueError(f"image shapes differ: {rendered.shape} vs {reference.shape}")
    diff = np.abs(rendered.astype(np.int16) - reference.astype(np.int16)).max(axis=2)
    r0, r1, c0, c1 = box or (0, rendered.shape[0], 0, rendered.shape[1])
    crop = [np.ascontiguousarray(im[r0:r1, c0:c1, :3], np.float32) / 255.0
            for im in (reference, rendered)]
    flip_map, flip_mean, _ = flip_evaluator.evaluate(crop[0], crop[1], "LDR", applyMagma=False)
    return {"changed_px": int((diff > LEVELS).sum()), "max_levels": int(diff.max(initial=0)),
            "flip_mouth": float(flip_mean), "flip_map": np.asarray(flip_map, np.float32).squeeze()}


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
        dest.parent.mkdir(parents=True, exist_ok=True)
        tmp = atomic_tmp_path(dest)
        iio.imwrite(tmp, np.ascontiguousarray(img[..., :3], np.uint8), extension=".png")
        os.replace(tmp, dest)
        written.append(dest.relative_to(out).as_posix())
    return written


def image_gates(run: Run, reference_dir: Path, *, max_changed_px: int = MAX_CHANGED_PX,
                images_dir: Path | None = None) -> list[GateResult]:
    """Compare every render of ``run`` with its golden counterpart under ``reference_dir``.

    A render without a golden image is a skipped gate that says so; never a pass. A failed
    render gets its rendered, reference, difference and FLIP images under
    ``images_dir/gate-images`` (default: the run directory).
    """
    out = []
    images_dir = Path(images_dir or run.root)
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
            rendered, reference = read_rgb8(Path(row["path"])), read_rgb8(ref)
            box = mouth_box_of(Path(row["path"]), rendered.shape)
            m = image_metrics(rendered, reference, box)
        except (OSError, ValueError) as err:
            out.append(GateResult("image", row["subject"], row["version"], item, "fail", str(err)))
            continue
        ok = m["changed_px"] <= max_changed_px
        where = "mouth region" if box is not None else "whole image (no mouth region recorded)"
        reason = (f"{m['changed_px']} px differ by more than {LEVELS} level (max {m['max_levels']}; "
                  f"allowed {max_changed_px}); FLIP in the {where} {m['flip_mouth']:.4f}")
        if not ok:
            files = _write_gate_images(images_dir, golden_key(row), rendered, reference, m, box)
            reason += "; images: " + ", ".join(files)
        out.append(GateResult("image", row["subject"], row["version"], item,
                              "pass" if ok else "fail", reason, float(m["changed_px"]),
                              float(max_changed_px)))
    return out


def tolerance(check: str) -> int:
    try:
        from cassi.harness.rubric import CHECKS  # noqa: PLC0415
    except ImportError:
        return DEFAULT_TOLERANCE
    entry = CHECKS.get(check) if hasattr(CHECKS, "get") else None
    return int(getattr(entry, "gate_tolerance", DEFAULT_TOLERANCE))


def metric_gates(run: pd.DataFrame, baseline: pd.DataFrame) -> list[GateResult]:
    """Per version, table and check: the negatives summed over subjects may not grow beyond the
    check's tolerance. Only versions and subjects present in both runs are compared."""
    cur, base = verdicts(run), verdicts(baseline)
    common = set(cur["subject"]) & set(base["subject"])
    cur, base = cur[cur["subject"].isin(common)], base[base["subject"].isin(common)]
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


def gate(run_dir: str | os.PathLike, baseline: str | os.PathLike, *,
         out_dir: str | os.PathLike | None = None) -> tuple[bool, list[GateResult]]:
    """Apply the gates of run ``run_dir`` against ``baseline`` (a run directory or a golden
    directory), write ``gate.json`` and ``gate.md`` into ``out_dir`` (default: the run), and
    return (passed, results). A baseline run gives metric gates and, through its renders,
    image gates; a golden directory gives image gates (and metric gates when it holds the
    results snapshot that :func:`update_golden` stores)."""
    run = load_run(run_dir)
    base_path = Path(baseline)
    if (base_path / GOLDEN_MARK).is_file():
        results = [*image_gates(run, base_path)]
        snap = base_path / "results.parquet"
        if snap.is_file():
            results += metric_gates(run.results, pd.read_parquet(snap))
    elif (base_path / "results.parquet").is_file():
        base_run = load_run(base_path)
        results = metric_gates(run.results, base_run.results)
        results += image_gates(run, _renders_as_golden(base_run, run.root / ".gate-baseline"))
    else:
        raise CassiInputError("baseline is neither a run directory (results.parquet) nor a "
                              f"golden directory ({GOLDEN_MARK})", path=base_path)
    passed = not any(r.status == "fail" for r in results)
    write_gate_report(Path(out_dir or run.root), passed, results, baseline=str(base_path))
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


def write_gate_report(out_dir: Path, passed: bool, results: list[GateResult], *, baseline: str) -> None:
    counts = {s: sum(r.status == s for r in results) for s in ("pass", "fail", "skip")}
    payload = {"passed": passed, "baseline": baseline, "counts": counts,
               "gates": [asdict(r) for r in results]}
    atomic_write_text(out_dir / "gate.json", json.dumps(payload, indent=2, default=str) + "\n")
    lines = [f"# Gates: {'PASSED' if passed else 'FAILED'}", "",
             f"Baseline: `{baseline}`. {counts['pass']} passed, {counts['fail']} failed, "
             f"{counts['skip']} skipped.", ""]
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
    atomic_write_text(golden / GOLDEN_MARK, json.dumps(
        {"from_run": str(Path(run_dir).resolve()), "images": n, "synthetic": run.synthetic},
        indent=2) + "\n")
    return n
