"""A fixed run gives the results and renders it gave before the redesign of issue 20.

``tests/golden/identity/`` holds the ``results.csv`` and ``renders.csv`` (each render named by
the SHA-256 of its bytes) of one run (``machine.json``: its command, the code it was recorded
with, the CPU and the packages). On a machine like that one (same CPU features and model, same
numpy / Mitsuba / Dr.Jit / pandas / pyarrow, the llvm variant) both files must be byte-identical.
Elsewhere LLVM- and SIMD-compiled kernels round differently in the last bits (AVX2 against
AVX-512, fused multiply-add), so there the comparison is: the same rows, the same negatives and
ratings, the same rendered frames, and every value within 1e-6 relative (geometry: far below
the 0.1 mm a check can resolve) or, for counts of mask pixels, within 1% + 2 px (a grazing ray
flips a silhouette pixel or two between code paths; see tests/renderer/test_render_golden.py).

It also checks the run's ratings files against the report's tables: one aggregation.

Regenerate (only when a result is meant to change, and say why in the commit):
``CASSI_REGEN_IDENTITY=1 python -m pytest tests/harness/evaluation/test_run_identity.py``.
"""
from __future__ import annotations

import importlib.metadata as md
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from testpaths import GOLDEN
from cassi.harness.cli import main as cli_main

pytestmark = pytest.mark.render

HERE = GOLDEN / "identity"
REGEN = os.environ.get("CASSI_REGEN_IDENTITY", "") not in ("", "0")
PACKAGES = ("numpy", "mitsuba", "drjit", "pandas", "pyarrow")
VALUE_RTOL = 1e-6        # geometry values: last-bit rounding, far below any check's resolution
PIXELS_RTOL, PIXELS_ATOL = 0.01, 2.0   # mask pixel counts: a grazing ray flips a pixel or two


def _cpu() -> tuple[list[str], str]:
    flags, model = set(), ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags") and not flags:
                flags = set(line.split(":", 1)[1].split())
            if line.startswith("model name") and not model:
                model = line.split(":", 1)[1].strip()
    except OSError:
        pass
    return sorted(f for f in flags if f.startswith(("avx", "fma", "sse4"))), model


def _same_machine(meta: dict, run_meta: dict) -> bool:
    features, model = _cpu()
    return (features == meta["cpu_features"] and model == meta["cpu_model"]
            and run_meta.get("variant_resolved") == meta["variant"]
            and all(md.version(p) == meta["packages"][p] for p in PACKAGES))


@pytest.fixture(scope="module")
def identity_run(tmp_path_factory):
    meta = json.loads((HERE / "machine.json").read_text())
    out = tmp_path_factory.mktemp("identity") / "run"
    assert cli_main([*meta["command"], "--out", str(out)]) == 0
    return meta, out


def test_fixed_run_gives_the_recorded_results_and_renders(identity_run):
    meta, out = identity_run
    run_meta = json.loads((out / "run.json").read_text())
    if REGEN:
        for name in ("results.csv", "renders.csv"):
            shutil.copyfile(out / name, HERE / name)
        pytest.skip("regenerated tests/golden/identity (update machine.json by hand)")
    if _same_machine(meta, run_meta):
        for name in ("results.csv", "renders.csv"):
            assert (out / name).read_bytes() == (HERE / name).read_bytes(), name
        return
    want, got = pd.read_csv(HERE / "results.csv"), pd.read_csv(out / "results.csv")
    keys = ["subject", "task", "rep", "version", "view", "frame", "check", "component"]
    assert list(got.columns) == list(want.columns)
    assert got[keys].equals(want[keys]), "the same rows (checks, frames) as recorded"
    assert (got["negatives"] == want["negatives"]).all()
    pixels = got["unit"].astype(str).eq("px").to_numpy()
    g, w = got["value"].to_numpy(float), want["value"].to_numpy(float)
    assert np.allclose(g[~pixels], w[~pixels], rtol=VALUE_RTOL, atol=1e-9, equal_nan=True)
    assert np.allclose(g[pixels], w[pixels], rtol=PIXELS_RTOL, atol=PIXELS_ATOL, equal_nan=True)
    frames = ["subject", "task", "rep", "version", "view", "frame"]
    assert pd.read_csv(out / "renders.csv")[frames].equals(pd.read_csv(HERE / "renders.csv")[frames])


def test_ratings_files_are_the_reports_tables(identity_run, tmp_path):
    """ratings.csv holds, cell for cell, what the report's thesis tables show."""
    _, out = identity_run
    report = tmp_path / "report"
    assert cli_main(["report", str(out), "--out", str(report)]) == 0
    ratings = pd.read_csv(out / "ratings.csv", keep_default_na=False)
    assert {"A", "C"} <= set(ratings["table"])
    tables = sorted((report / "tables").glob("table_*_*.csv"))
    assert tables
    cols = ["subject", "component", "negatives", "rating", "text", "reason"]
    seen = 0
    for path in tables:
        table, version = path.stem.split("_", 2)[1:]
        shown = pd.read_csv(path, keep_default_na=False)[cols].reset_index(drop=True)
        mine = ratings[(ratings["table"] == table) & (ratings["version"] == version)]
        mine = mine[cols].sort_values(["subject", "component"], kind="mergesort").reset_index(drop=True)
        pd.testing.assert_frame_equal(shown.sort_values(["subject", "component"], kind="mergesort")
                                      .reset_index(drop=True), mine, check_dtype=False)
        seen += len(mine)
    assert seen == len(ratings)
