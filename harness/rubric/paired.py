"""Paired version comparisons: every pair of versions on every per-file measure, over the task
files both versions ran.

A per-file measure is a whole-task row (``frame == -1``) of the results table: a check's value
in one task file. The registry says which side of a check is a fault (``Check.direction``), so
it says which of two values is better. Per pair (``a`` the later version in the thesis's order,
``b`` the earlier) and measure, over the task files where both have a finite value:

- wins / losses / ties: files where ``a``'s value is better / worse / equal (within
  :data:`TIE_TOLERANCE`); a tie is neither a win nor a loss;
- the median of the differences ``a - b`` (in the check's unit), with a percentile bootstrap
  95 % interval (:data:`BOOTSTRAP_N` resamples of the files, seed :data:`BOOTSTRAP_SEED`);
- a two-sided sign test on wins against losses (ties left out): ``scipy.stats.binomtest``.
"""
from __future__ import annotations

from itertools import combinations

import numpy as np
import pandas as pd
from scipy.stats import binomtest

from cassi.harness.rubric.registry import CHECKS
from cassi.harness.rubric.tables import order_versions

__all__ = ["PAIRED_COLUMNS", "BOOTSTRAP_N", "BOOTSTRAP_SEED", "TIE_TOLERANCE", "bootstrap_median",
           "sign_test", "paired_comparisons", "paired_sentence"]

#: Bootstrap resamples and seed of the median's interval (stated wherever shown).
BOOTSTRAP_N = 2000
BOOTSTRAP_SEED = 0
#: Two values closer than this (in the check's unit) are a tie: floating-point noise between
#: versions sharing code must not count as a win.
TIE_TOLERANCE = 1e-9

PAIRED_COLUMNS = ["a", "b", "measure", "check", "view", "table", "unit", "direction", "files",
                  "wins", "losses", "ties", "median", "low", "high", "p"]


def bootstrap_median(d, *, n: int = BOOTSTRAP_N, seed: int = BOOTSTRAP_SEED,
                     level: float = 0.95) -> tuple[float, float]:
    """Percentile bootstrap interval of the median of ``d`` (resampling its values)."""
    d = np.asarray(d, dtype=float)
    if not len(d):
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    medians = np.median(d[rng.integers(0, len(d), size=(int(n), len(d)))], axis=1)
    tail = (1 - level) / 2 * 100
    lo, hi = np.percentile(medians, [tail, 100 - tail])
    return float(lo), float(hi)


def sign_test(wins: int, losses: int) -> float:
    """Two-sided sign test of wins against losses (ties already left out); 1.0 with neither."""
    if wins + losses == 0:
        return 1.0
    return float(binomtest(int(wins), int(wins + losses), 0.5, alternative="two-sided").pvalue)


def _measures(results: pd.DataFrame) -> pd.DataFrame:
    """The whole-task rows of registered checks: one value per version, subject, task file,
    check and view (a check judged in several render views is one measure per view)."""
    if results is None or not len(results):
        return pd.DataFrame(columns=["version", "subject", "task", "rep", "check", "view",
                                     "value", "measure"])
    fv = results[(results["frame"] == -1) & results["check"].isin(list(CHECKS))].copy()
    for c in ("version", "subject", "check", "view"):
        fv[c] = fv[c].astype("object").where(fv[c].notna(), "")
    views = fv.groupby("check")["view"].nunique()
    fv["measure"] = [f"{c} ({v})" if views[c] > 1 else c for c, v in zip(fv["check"], fv["view"])]
    return fv


def paired_comparisons(results: pd.DataFrame, *, n_boot: int = BOOTSTRAP_N,
                       seed: int = BOOTSTRAP_SEED) -> pd.DataFrame:
    """Every pair of versions and every measure: :data:`PAIRED_COLUMNS`.

    ``a`` is the later version of the pair in the thesis's order, ``b`` the earlier; ``median``,
    ``low``, ``high`` are of ``a - b``; ``files`` the task files where both have a value. Rows
    are ordered most significant first (``p``, then the larger ``|median|``).
    """
    fv = _measures(results)
    rows = []
    if fv.empty:
        return pd.DataFrame(columns=PAIRED_COLUMNS)
    fv = fv[np.isfinite(fv["value"].astype(float))]
    key = ["subject", "task", "rep"]
    for b, a in combinations(order_versions(fv["version"].unique()), 2):
        va, vb = fv[fv["version"] == a], fv[fv["version"] == b]
        both = va.merge(vb[key + ["measure", "value"]], on=key + ["measure"], suffixes=("_a", "_b"))
        for measure, g in both.groupby("measure", sort=True):
            check = CHECKS[g["check"].iloc[0]]
            d = g["value_a"].to_numpy(float) - g["value_b"].to_numpy(float)
            tie = np.abs(d) <= TIE_TOLERANCE
            # higher = worse: a wins where its value is lower
            better = (d < 0) if check.direction == "higher" else (d > 0)
            wins, ties = int((better & ~tie).sum()), int(tie.sum())
            losses = len(d) - wins - ties
            lo, hi = bootstrap_median(d, n=n_boot, seed=seed)
            rows.append(dict(a=a, b=b, measure=measure, check=check.name, view=g["view"].iloc[0],
                             table=check.table, unit=check.unit, direction=check.direction,
                             files=len(d), wins=wins, losses=losses, ties=ties,
                             median=float(np.median(d)), low=lo, high=hi,
                             p=sign_test(wins, losses)))
    out = pd.DataFrame(rows, columns=PAIRED_COLUMNS)
    if out.empty:
        return out
    out["_size"] = -out["median"].abs()
    out = out.sort_values(["p", "_size", "a", "b", "measure"], kind="mergesort")
    return out.drop(columns="_size").reset_index(drop=True)


def _num(x: float) -> str:
    return f"{x:+.3g}" if x else "0"


def paired_sentence(r) -> str:
    """``cassi-2.1 beats cassi-2.0 on lip_aperture in 41 of 57 files (12 worse, 4 tied), median
    -0.8 mm [-1.1, -0.5] (lower is better), sign test p = 0.003``.

    The sentence names the version that wins more files first; its median and interval are of
    that version's value minus the other's.
    """
    a, b, sign = r["a"], r["b"], 1.0
    wins, losses = int(r["wins"]), int(r["losses"])
    if losses > wins:
        a, b, sign, wins, losses = b, a, -1.0, losses, wins
    lo, hi = sorted((sign * r["low"], sign * r["high"]))
    unit = f" {r['unit']}" if r["unit"] else ""
    better = "lower" if r["direction"] == "higher" else "higher"
    return (f"{a} beats {b} on {r['measure']} in {wins} of {int(r['files'])} files ({losses} "
            f"worse, {int(r['ties'])} tied), median {a} − {b} {_num(sign * r['median'])}{unit} "
            f"[{_num(lo)}, {_num(hi)}] ({better} is better), sign test p = {r['p']:.3g}")
