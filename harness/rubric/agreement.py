"""Agreement of two raters on the thesis's ordinal scale (:data:`~.model.RATINGS`): exact
agreement, agreement within one step, quadratic weighted Cohen's kappa with a percentile
bootstrap interval, and the confusion matrix.

Ratings are indices into the scale (0 = EXCELLENT ... 6 = UNACCEPTABLE). Quadratic weights are
``(i - j)**2``; kappa = 1 - sum(w * observed) / sum(w * expected), with ``expected`` the outer
product of the two raters' marginals over the number of pairs. Unused categories change nothing
(their rows and columns are zero), so the kappa over the whole scale equals the kappa over the
categories used. Kappa is undefined (NaN) when the expected weighted disagreement is zero: both
raters gave one and the same rating to every item.
"""
from __future__ import annotations

import numpy as np

from cassi.harness.rubric.model import RATINGS

__all__ = ["KAPPA_BOOTSTRAP_N", "KAPPA_BOOTSTRAP_SEED", "confusion", "quadratic_kappa",
           "bootstrap_kappa", "agreement_stats"]

#: Bootstrap resamples and seed of kappa's interval (stated wherever shown).
KAPPA_BOOTSTRAP_N = 2000
KAPPA_BOOTSTRAP_SEED = 0


def confusion(first, second, k: int = len(RATINGS)) -> np.ndarray:
    """(k, k) counts: rows ``first``'s rating, columns ``second``'s."""
    m = np.zeros((k, k), dtype=int)
    np.add.at(m, (np.asarray(first, int), np.asarray(second, int)), 1)
    return m


def _kappa_from(m: np.ndarray) -> float:
    n = m.sum()
    if n == 0:
        return float("nan")
    k = m.shape[0]
    i = np.arange(k)
    w = (i[:, None] - i[None, :]) ** 2
    expected = np.outer(m.sum(axis=1), m.sum(axis=0)) / n
    denom = float((w * expected).sum())
    if denom == 0:
        return float("nan")
    return 1.0 - float((w * m).sum()) / denom


def quadratic_kappa(first, second, k: int = len(RATINGS)) -> float:
    """Quadratic weighted Cohen's kappa of two raters' indices (NaN when undefined)."""
    return _kappa_from(confusion(first, second, k))


def bootstrap_kappa(first, second, *, n: int = KAPPA_BOOTSTRAP_N, seed: int = KAPPA_BOOTSTRAP_SEED,
                    level: float = 0.95, k: int = len(RATINGS)) -> tuple[float, float]:
    """Percentile bootstrap interval of the kappa, resampling the rated items; resamples where
    kappa is undefined are left out (NaN, NaN when all are)."""
    a, b = np.asarray(first, int), np.asarray(second, int)
    if not len(a):
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, len(a), size=(int(n), len(a)))
    ks = np.array([quadratic_kappa(a[j], b[j], k) for j in idx])
    ks = ks[np.isfinite(ks)]
    if not len(ks):
        return float("nan"), float("nan")
    tail = (1 - level) / 2 * 100
    lo, hi = np.percentile(ks, [tail, 100 - tail])
    return float(lo), float(hi)


def agreement_stats(first, second, *, n_boot: int = KAPPA_BOOTSTRAP_N,
                    seed: int = KAPPA_BOOTSTRAP_SEED) -> dict:
    """n, exact (share of equal ratings), within_one (share at most one step apart), kappa,
    kappa_low, kappa_high, confusion (rows ``first``, columns ``second``, over :data:`RATINGS`)."""
    a, b = np.asarray(first, int), np.asarray(second, int)
    lo, hi = bootstrap_kappa(a, b, n=n_boot, seed=seed)
    return {"n": int(len(a)),
            "exact": float(np.mean(a == b)) if len(a) else float("nan"),
            "within_one": float(np.mean(np.abs(a - b) <= 1)) if len(a) else float("nan"),
            "kappa": quadratic_kappa(a, b), "kappa_low": lo, "kappa_high": hi,
            "confusion": confusion(a, b).tolist()}
