"""Matplotlib figures for reports: rating distributions, metric trends and Table F's fidelity
figures (PNG, atomic)."""
from __future__ import annotations

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # reports run headless (nightly jobs, CI)
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from cassi.common.atomic import replacing  # noqa: E402
from cassi.harness.rubric import CHECKS, RATINGS  # noqa: E402

#: One colour per rating, green (EXCELLENT) to red (UNACCEPTABLE).
RATING_COLOURS = ("#1a9850", "#66bd63", "#a6d96a", "#fee08b", "#fdae61", "#f46d43", "#d73027")


def _save(fig, path: Path) -> Path:
    try:
        with replacing(path) as tmp:
            fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png")
    finally:
        plt.close(fig)
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


def fidelity_errors(rows: pd.DataFrame, path: str | os.PathLike, *, versions: list[str],
                    synthetic: bool) -> Path:
    """Table F: per articulator, a box per version of the virtual pellets' RMSE (mm) over the
    task files (whole-task rows of the fidelity error checks), with the check's thresholds."""
    checks = [c for c in CHECKS.values()
              if c.kind == "fidelity" and c.unit == "mm" and c.table == "F"]
    fig, axes = plt.subplots(1, len(checks), figsize=(3.2 * len(checks), 3.2), squeeze=False)
    for ax, c in zip(axes[0], checks):
        sub = rows[rows["check"] == c.name]
        data = [sub.loc[sub["version"] == v, "value"].dropna().to_numpy() for v in versions]
        ax.boxplot(data, showfliers=True)
        ax.set_xticks(range(1, len(versions) + 1), versions, rotation=30, fontsize=7)
        for t, n in zip(c.thresholds, c.negatives):
            ax.axhline(t, color="#b42318", lw=0.8, ls="--")
            ax.text(0.55, t, f"{'-' * n}", color="#b42318", fontsize=8, va="bottom")
        ax.set_title(c.component, fontsize=9)
        ax.set_ylabel("RMSE of the movement, mm" if ax is axes[0][0] else "")
    fig.suptitle("Fidelity to the recording: virtual pellets against measured ones"
                 + (" (synthetic corpus)" if synthetic else ""), fontsize=10)
    return _save(fig, Path(path))


def fidelity_traces(rows: pd.DataFrame, path: str | os.PathLike, *, versions: list[str],
                    title: str, synthetic: bool) -> Path:
    """One task's tract variables (rows of view ``trace``): the recording against each
    version's model, displacement from the first frame, mm."""
    names = sorted({c[len("trace_"):].rsplit("_", 1)[0] for c in rows["check"]})
    fig, axes = plt.subplots(len(names), 1, figsize=(8, 1.9 * len(names)), sharex=True,
                             squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        for v in versions:
            m = rows[(rows["check"] == f"trace_{name}_model") & (rows["version"] == v)]
            ax.plot(m["frame"], m["value"], lw=1.2, label=v)
        # the recording last and dashed, so that a model lying on it does not hide it
        data = rows[(rows["check"] == f"trace_{name}_data") & (rows["version"] == versions[0])]
        ax.plot(data["frame"], data["value"], color="black", lw=1.0, ls="--", label="recording",
                zorder=5)
        ax.set_ylabel(f"{name.replace('_', ' ')}\nmm", fontsize=8)
    axes[0, 0].legend(fontsize=7, ncol=len(versions) + 1, loc="upper right")
    axes[-1, 0].set_xlabel("recording row")
    fig.suptitle(f"{title}: model against recording (movement from the first frame)"
                 + (" (synthetic corpus)" if synthetic else ""), fontsize=10)
    return _save(fig, Path(path))
