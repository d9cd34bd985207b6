"""Reading a finished run directory: the results table, ratings, metadata and render index.

Reports read harness results only (files a run wrote), never re-render or recompute geometry.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.harness.farm.results import read_results
from cassi.harness.farm.results import ATTACHMENT_COLUMNS, RENDER_COLUMNS  # indexes the farm writes
from cassi.harness.farm.tableset import OPTIONAL_TABLES, SUMMARY_FILE, verify_table_set
from cassi.harness.rubric.tables import order_versions as rubric_order


@dataclass
class Run:
    """One run directory, loaded.

    Attributes
    ----------
    root : Path
    results : DataFrame
        The long results table (cassi.harness.farm.results.COLUMNS).
    ratings : DataFrame
        The run's ``ratings.parquet`` as the run aggregated it (:func:`cassi.harness.rubric.
        ratings_table`: per version, table, subject and component, negatives and rating). The
        report aggregates ``results`` again with today's rubric and says where the two differ.
    meta : dict
        The run's ``run.json`` (resolved config, package version, git revision, ...).
    renders : DataFrame
        RENDER_COLUMNS; ``path`` is absolute. Empty when the run rendered nothing.
    summary : dict
        The run's ``summary.json``: job counts by state, and the reason of every skipped and
        failed job.
    attachments : DataFrame
        ATTACHMENT_COLUMNS (the task viewer data: name ``viewer``); ``path`` is absolute.
        Empty for runs written before the index.
    """

    root: Path
    results: pd.DataFrame
    ratings: pd.DataFrame
    meta: dict = field(default_factory=dict)
    renders: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=RENDER_COLUMNS))
    summary: dict = field(default_factory=dict)
    attachments: pd.DataFrame = field(
        default_factory=lambda: pd.DataFrame(columns=ATTACHMENT_COLUMNS))

    @property
    def failed(self) -> dict[str, str]:
        """Failed job -> reason: results of a run with failures are incomplete."""
        return dict(self.summary.get("failed", {}))

    @property
    def skipped(self) -> dict[str, str]:
        """Skipped job -> reason (unusable inputs)."""
        return dict(self.summary.get("skipped", {}))

    @property
    def synthetic(self) -> bool:
        if "synthetic" in self.meta:
            return bool(self.meta["synthetic"])
        return bool(len(self.results)) and bool(self.results["synthetic"].any())

    @property
    def derived(self) -> dict[str, list[str]]:
        """Subject -> its derived pellets' rules (EMA coil maps), as the run recorded them."""
        return {str(k): [str(x) for x in v]
                for k, v in (self.meta.get("derived_pellets") or {}).items()}

    @property
    def name(self) -> str:
        return self.root.name

    @property
    def versions(self) -> list[str]:
        return order_versions(self.results["version"].dropna().unique())


def order_versions(names) -> list[str]:
    """The thesis's order of versions (the rubric's); others (third-party) follow by name."""
    return rubric_order({str(n) for n in names})


def _read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {}
    except (OSError, json.JSONDecodeError) as err:
        raise CassiInputError(f"unreadable run metadata: {err}", path=path) from err


def _read_index(root: Path, name: str, columns) -> pd.DataFrame:
    """A path index of the run (renders, attachments), paths checked and made absolute; an
    index the run did not write (older runs had no attachments) is empty."""
    path = root / f"{name}.parquet"
    optional = name in OPTIONAL_TABLES
    if optional and not path.is_file():
        return pd.DataFrame(columns=list(columns))
    df = pd.read_parquet(path)
    missing = [c for c in columns if c not in df]
    if missing and optional and not len(df):  # left out by the writer: written without columns
        return pd.DataFrame(columns=list(columns))
    if missing:
        raise CassiInputError(f"{name} index lacks columns {missing}", path=path)
    df = df[list(columns)].copy()
    df["path"] = _all_inside(root, df["path"])
    return df.reset_index(drop=True)


def _all_inside(root: Path, rels) -> list[str]:
    """:func:`_inside` for many paths: a night's index holds 20,000-40,000, in a few hundred
    folders, so each folder is resolved and checked once, and each file only checked for being
    a link (a plain name in a folder inside the run is inside it). Strings, not Paths: the
    Path objects cost more than the checks."""
    base = os.fspath(root)
    real = os.path.realpath(base)
    folders: dict[str, str] = {}
    out = []
    for rel in rels:
        rel = str(rel)
        head, name = os.path.split(rel)
        if name in ("", ".", "..") or os.path.islink(os.path.join(base, rel)):
            out.append(str(_inside(root, rel, Path(real))))
            continue
        folder = folders.get(head)
        if folder is None:
            folder = os.path.realpath(os.path.join(base, head))
            if os.path.commonpath([folder, real]) != real:
                raise CassiInputError(f"indexed path {rel!r} escapes the run directory", path=root)
            folders[head] = folder
        out.append(os.path.join(folder, name))
    return out


def _inside(root: Path, rel: str, real: Path | None = None) -> Path:
    """Resolve a path the run recorded, refusing anything outside the run directory
    (``real``: ``root`` resolved)."""
    real = root.resolve() if real is None else real
    path = (root / rel).resolve()
    if os.path.commonpath([path, real]) != str(real):
        raise CassiInputError(f"indexed path {rel!r} escapes the run directory", path=root)
    return path


def load_run(path: str | os.PathLike) -> Run:
    """Load a run directory written by ``cassi run``.

    Raises
    ------
    CassiInputError
        When ``path`` is not a run directory (no results table), or its tables are not one
        complete set (:class:`~cassi.harness.farm.tableset.TableSetError`).
    """
    root = Path(path)
    if not (root / "results.parquet").is_file():
        raise CassiInputError("not a run directory: no results.parquet (run `cassi run` first)",
                              path=root)
    verify_table_set(root)  # one complete set of tables, or a clear refusal
    return Run(root=root, results=read_results(root / "results.parquet"),
               ratings=pd.read_parquet(root / "ratings.parquet"),
               meta=_read_json(root / "run.json"),
               renders=_read_index(root, "renders", RENDER_COLUMNS),
               summary=_read_json(root / SUMMARY_FILE),
               attachments=_read_index(root, "attachments", ATTACHMENT_COLUMNS))
