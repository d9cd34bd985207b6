"""Small hand-built run directories for the reports tests (a results table as `cassi run`
writes it, with a render index and PNG renders)."""
from __future__ import annotations

import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pandas as pd

from cassi.harness.farm.results import normalize
from cassi.harness.rubric import ratings_table as ratings
from cassi.harness.farm.results import RENDER_COLUMNS
from cassi.harness.farm.tableset import write_table_set

VERSIONS = ("cassi-1.0", "cassi-2.0", "cassi-2.1")


def results_rows(negatives: dict, *, subjects=("JW11", "JW12"), synthetic=True) -> pd.DataFrame:
    """Whole-task rows for checks of tables A and C; ``negatives[(version, subject, check)]``
    gives the negatives (default 0). Two tasks per subject; the fault shows in the first."""
    rows = []
    checks = [("A", "lips", "lip_gap_start"), ("A", "tongue", "tongue_through_teeth"),
              ("C", "lips", "lower_lip_below_teeth")]
    for version in VERSIONS:
        for subject in subjects:
            for i, task in enumerate((19, 21)):
                for table, component, check in checks:
                    neg = negatives.get((version, subject, check), 0) if i == 0 else 0
                    rows.append(dict(subject=subject, task=task, rep=1, version=version,
                                     view="geometry", frame=-1, check=check, table=table,
                                     component=component, value=float(neg), unit="mm",
                                     threshold=0.5, negatives=neg, detail="", synthetic=synthetic))
                    if neg:
                        rows.append({**rows[-1], "frame": 7, "negatives": neg})
    return normalize(rows)


def image(seed: int, shape=(48, 64)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    base = np.zeros((*shape, 3), np.uint8)
    base[8:40, 10:50] = (200, 150, 120)
    return np.clip(base + rng.integers(0, 6, base.shape), 0, 255).astype(np.uint8)


def write_run(root: Path, results: pd.DataFrame, *, images: dict | None = None,
              meta: dict | None = None, summary: dict | None = None) -> Path:
    """Write a run directory; ``images[(subject, task, version, view, frame)] = array``."""
    root.mkdir(parents=True, exist_ok=True)
    (root / "run.json").write_text(json.dumps({"synthetic": bool(results["synthetic"].any()),
                                               **(meta or {})}))
    rows = []
    for (subject, task, version, view, frame), arr in (images or {}).items():
        rel = Path("objects") / f"{subject}_{task}_{version}_{view}_{frame}.png"
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(root / rel, arr)
        rows.append(dict(subject=subject, task=task, rep=1, version=version, view=view,
                         frame=frame, path=str(rel)))
    write_table_set(root, {"results": results, "ratings": ratings(results),
                           "renders": pd.DataFrame(rows, columns=list(RENDER_COLUMNS))},
                    {"synthetic": bool(results["synthetic"].any()), **(summary or {})})
    return root


def rewrite_results(root: Path, results: pd.DataFrame) -> None:
    """Replace a run's results (and the ratings derived from them) as a new table set."""
    renders = pd.read_parquet(root / "renders.parquet")
    summary = json.loads((root / "summary.json").read_text())
    write_table_set(root, {"results": results, "ratings": ratings(results), "renders": renders},
                    summary)
