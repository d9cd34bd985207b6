"""Matplotlib figures for reports: rating distributions and metric trends (PNG, atomic)."""
from __future__ import annotations

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # reports run headless (nightly jobs, CI)
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from cassi.data.atomic import atomic_tmp_path  # noqa: E402
from cassi.reports.tables import RATINGS  # noqa: E402

#: One colour per rating, green (EXCELLENT) to red (UNACCEPTABLE).
RATING_COLOURS = ("#1a9850", "#66bd63", "#a6d96a", "#fee08b", "#fdae61", "#f46d43", "#d73027")


def _save(fig, path: Path) -> Path:
    tmp = atomic_tmp_path(path)
    fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png")
    plt.close(fig)
    os.replace(tmp, path)
    return path


def rating_distribution(counts: pd.DataFrame, path: str | os.PathLike, *, title: str,
                        synthetic: bool) -> Path:
    """Stacked horizontal bars: per version (rows of ``counts``), how many cells got each rating."""
    fig, ax = plt.subplots(figsize=(7, 0.6 + 0.45 * max(1, len(counts))))
    left = pd.Series(0, index=counts.index, dtype=float)
    for rating, colour in zip(RATINGS, RATING_COLOURS):
        values = counts.get(rating, pd.Series(0, index=counts.index)).astype(float)
        ax.barh(list(counts.index), values, left=left, color=colour, label=rating)
        left += values
    ax.invert_yaxis()
    ax.set_xlabel("subject x component cells")
    ax.set_title(title + (" (synthetic corpus)" if synthetic else ""), fontsize=10)
    ax.legend(ncol=1, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return _save(fig, Path(path))


def metric_trend(history: pd.DataFrame, path: str | os.PathLike, *, synthetic: bool) -> Path:
    """Total negatives per version over the nights of ``history`` (columns night, version,
    negatives)."""
    fig, ax = plt.subplots(figsize=(7, 3))
    for version, g in history.groupby("version", sort=False):
        ax.plot(g["night"], g["negatives"], marker="o", label=version)
    ax.set_ylabel("total negatives (fewer is better)")
    ax.set_title("Negatives per night" + (" (synthetic corpus)" if synthetic else ""), fontsize=10)
    ax.tick_params(axis="x", labelrotation=30, labelsize=7)
    ax.legend(fontsize=7)
    return _save(fig, Path(path))
