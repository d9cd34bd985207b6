"""The one long results table of a run (its ratings come from the pipeline: the rubric's
aggregation, :func:`cassi.harness.rubric.ratings_table`).

Every measurement of a run is one row: which task file (subject, task, rep), which version and
view, which frame (-1 = the whole-task aggregate), which rubric check, its value and unit, the
threshold it was compared with and the negatives it earned. Reports and gates are groupbys over
this table, so it has real columns, never keys packed into strings.
"""
from __future__ import annotations

import io
import os
from typing import Iterable

import pandas as pd


#: Columns of the results table, in order.
#: The index of a run's renders (``renders.parquet``).
RENDER_COLUMNS = ("subject", "task", "rep", "version", "view", "frame", "path")
#: The index of the outputs a pipeline names as attachments (``attachments.parquet``): files a
#: job keeps for the readers of a run (the report's task viewer data), found without manifests.
ATTACHMENT_COLUMNS = ("subject", "task", "rep", "version", "view", "name", "path")
COLUMNS = ("subject", "task", "rep", "version", "view", "frame", "check", "table", "component",
           "value", "unit", "threshold", "negatives", "detail", "synthetic")

_DTYPES = {"subject": "string", "task": "int64", "rep": "int64", "version": "string",
           "view": "string", "frame": "int64", "check": "string", "table": "string",
           "component": "string", "value": "float64", "unit": "string", "threshold": "float64",
           "negatives": "int64", "detail": "string", "synthetic": "bool"}

#: Columns that identify one row; a retried job can never add a second row with the same key.
KEY = ("subject", "task", "rep", "version", "view", "frame", "check", "component")

def normalize(rows: pd.DataFrame | Iterable[dict], **defaults) -> pd.DataFrame:
    """Return ``rows`` as a results table: every column present, fixed dtypes, column order.

    Parameters
    ----------
    rows : DataFrame or iterable of dicts
        Rows from a check function; missing columns are taken from ``defaults`` or left empty
        (NaN / ``<NA>``; ``negatives`` 0, ``frame`` -1).
    **defaults
        Values for columns the rows lack or leave missing (e.g. ``subject="JW11"``).
    """
    df = rows.copy() if isinstance(rows, pd.DataFrame) else pd.DataFrame(list(rows))
    unknown = [c for c in df.columns if c not in _DTYPES]
    if unknown:
        # Extra fields are not lost: they are folded into `detail` as key=value text.
        extra = df[unknown].astype(str).apply(
            lambda r: "; ".join(f"{k}={v}" for k, v in r.items()), axis=1)
        base = df["detail"].fillna("").astype(str) if "detail" in df else ""
        df["detail"] = (base + ("; " if "detail" in df else "") + extra).str.strip("; ")
        df = df.drop(columns=unknown)
    for col in COLUMNS:
        if col in defaults:
            if col not in df:
                df[col] = defaults[col]
            else:
                df[col] = df[col].where(df[col].notna(), defaults[col])
        elif col not in df:
            df[col] = {"frame": -1, "negatives": 0, "synthetic": False}.get(col, pd.NA)
    df["frame"] = df["frame"].fillna(-1)
    df["negatives"] = df["negatives"].fillna(0)
    df["synthetic"] = df["synthetic"].fillna(False)
    for col, dtype in _DTYPES.items():
        if dtype == "float64":
            df[col] = pd.to_numeric(df[col], errors="coerce").astype("float64")
        else:
            df[col] = df[col].astype(dtype)
    return df[list(COLUMNS)].reset_index(drop=True)


def empty() -> pd.DataFrame:
    """An empty results table with the right columns and dtypes."""
    return normalize(pd.DataFrame(columns=list(COLUMNS)))


def combine(frames: Iterable[pd.DataFrame]) -> pd.DataFrame:
    """Concatenate job tables into one, sorted by key, duplicates (same key) removed.

    Sorting makes the table independent of the order in which jobs finished, so an interrupted
    and resumed batch yields the same table as an uninterrupted one.
    """
    frames = [f for f in frames if f is not None and len(f)]  # normalised where they were made
    if not frames:
        return empty()
    df = pd.concat(frames, ignore_index=True)
    df = df.drop_duplicates(subset=list(KEY), keep="last")
    return df.sort_values(list(KEY), kind="mergesort").reset_index(drop=True)


def to_parquet_bytes(df: pd.DataFrame) -> bytes:
    """Serialize a normalised results table to Parquet bytes (deterministic for equal tables)."""
    buf = io.BytesIO()
    df.to_parquet(buf, index=False, engine="pyarrow")
    return buf.getvalue()


def from_parquet_bytes(data: bytes) -> pd.DataFrame:
    """A table written by :func:`to_parquet_bytes` (Parquet keeps the columns and dtypes)."""
    return pd.read_parquet(io.BytesIO(data), engine="pyarrow")


def read_results(path: str | os.PathLike) -> pd.DataFrame:
    """Read a results table (Parquet) of a run's table set (:mod:`.tableset`)."""
    return normalize(pd.read_parquet(path, engine="pyarrow"))


def empty_ratings() -> pd.DataFrame:
    """The ratings table of a pipeline that rates nothing (no columns, no rows)."""
    return pd.DataFrame()
