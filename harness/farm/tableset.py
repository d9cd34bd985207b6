"""A run's tables, written and read as one set.

``results``, ``ratings``, ``renders`` and ``attachments`` (Parquet + CSV each) and
``summary.json`` belong together: ratings are derived from the results, the render and
attachment indexes from the same jobs. They are
written aside, renamed into place, and only then is ``tables.json`` written, naming the SHA-256
of every file of the set. A reader checks every file against it, so a set interrupted between
two renames (a crash, a full disk) is refused instead of read as a mix of old and new.

``tables.json`` also names the digest of the run's configuration (``run.json`` without the keys
the run adds once its tables are written), so tables left from an earlier run under a newer
``run.json`` (a rerun into the same directory, killed before it wrote its tables) are refused.
"""
from __future__ import annotations

import io
import json
import os
from pathlib import Path
from typing import Mapping

import pandas as pd

from cassi.common.atomic import atomic_tmp_path, atomic_write_text
from cassi.common.errors import CassiInputError

from cassi.harness.farm.store import sha256_bytes, sha256_file

SET_FILE = "tables.json"
#: The tables of a run, each written as ``NAME.parquet`` and ``NAME.csv``.
TABLE_NAMES = ("results", "ratings", "renders", "attachments")
#: Tables a caller may leave out (written empty): runs before the attachment index had none.
OPTIONAL_TABLES = ("attachments",)
SUMMARY_FILE = "summary.json"
CONFIG_FILE = "run.json"
#: Keys the run writes into its config file after the tables (they are not the configuration).
CONFIG_FINAL_KEYS = ("summary", "finished")


class TableSetError(CassiInputError):
    """The run's tables are missing or do not belong to one set."""


def _encode(tables: Mapping[str, pd.DataFrame], summary: Mapping) -> dict[str, bytes]:
    files: dict[str, bytes] = {}
    for name in TABLE_NAMES:
        df = tables[name] if name in tables or name not in OPTIONAL_TABLES else pd.DataFrame()
        buf = io.BytesIO()
        df.to_parquet(buf, index=False, engine="pyarrow")
        files[f"{name}.parquet"] = buf.getvalue()
        files[f"{name}.csv"] = df.to_csv(index=False, lineterminator="\n").encode("utf-8")
    files[SUMMARY_FILE] = (json.dumps(dict(summary), indent=1, sort_keys=True, default=str)
                           + "\n").encode("utf-8")
    return files


def config_digest(root: str | os.PathLike) -> str | None:
    """SHA-256 of ``root``'s configuration (:data:`CONFIG_FILE` less :data:`CONFIG_FINAL_KEYS`,
    as canonical JSON), or None when the run has no config file.

    Raises
    ------
    TableSetError
        The config file is unreadable or not a JSON object.
    """
    path = Path(root) / CONFIG_FILE
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as err:
        raise TableSetError(f"unreadable run configuration: {err}", path=path) from err
    if not isinstance(doc, dict):
        raise TableSetError("the run configuration is not a JSON object", path=path)
    config = {k: v for k, v in doc.items() if k not in CONFIG_FINAL_KEYS}
    return sha256_bytes(json.dumps(config, sort_keys=True, default=str).encode("utf-8"))


def write_table_set(root: str | os.PathLike, tables: Mapping[str, pd.DataFrame],
                    summary: Mapping) -> Path:
    """Write ``tables`` (every name of :data:`TABLE_NAMES`, :data:`OPTIONAL_TABLES` may be
    left out) and ``summary`` into ``root`` as
    one set; returns the path of ``tables.json``.

    Raises
    ------
    OSError
        With the path that could not be written; the previous set then fails verification
        (or is intact, when nothing was renamed yet).
    """
    root = Path(root)
    files = _encode(tables, summary)
    config = config_digest(root)  # the run.json these tables come from
    aside: dict[str, Path] = {}
    try:
        for name, data in files.items():
            tmp = atomic_tmp_path(root / name)
            aside[name] = tmp
            _write_synced(tmp, data)
        for name, tmp in aside.items():
            os.replace(tmp, root / name)
    except OSError as err:
        if not err.filename:
            err.filename = str(root)
        raise
    finally:
        for tmp in aside.values():
            if tmp.exists():
                tmp.unlink()
    doc = {"files": {name: sha256_bytes(data) for name, data in sorted(files.items())},
           "config": config}
    atomic_write_text(root / SET_FILE, json.dumps(doc, indent=1, sort_keys=True) + "\n")
    return root / SET_FILE


def _write_synced(path: Path, data: bytes) -> None:
    with open(path, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())


def verify_table_set(root: str | os.PathLike) -> dict[str, str]:
    """Check that ``root``'s tables are one complete set; returns {file: sha256}.

    Raises
    ------
    TableSetError
        No ``tables.json`` (the run never finished writing its tables), or a file missing or
        different from the set it names (a half-written set), or a ``run.json`` other than
        the one the tables were written under.
    """
    root = Path(root)
    path = root / SET_FILE
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        files = dict(doc["files"])
    except FileNotFoundError:
        raise TableSetError(f"no {SET_FILE}: the run's tables were never completed (rerun the "
                            "same `cassi run` command to finish them)", path=root) from None
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise TableSetError(f"unreadable table set: {err}", path=path) from err
    for name, sha in files.items():
        try:
            ok = sha256_file(root / name) == sha
        except OSError:
            ok = False
        if not ok:
            raise TableSetError(f"{name} is missing or not the one {SET_FILE} names: the "
                                "tables are a half-written set (rerun the same `cassi run` "
                                "command to rewrite them)", path=root / name)
    if "config" not in doc:
        raise TableSetError(f"{SET_FILE} names no run configuration (written before tables "
                            "recorded it), so the tables cannot be tied to run.json; rerun the "
                            "same `cassi run` command to rewrite them", path=path)
    if config_digest(root) != doc["config"]:
        raise TableSetError(f"{CONFIG_FILE} does not describe these tables (its configuration "
                            f"is not the one {SET_FILE} was written under: a later run into "
                            "this directory started and did not finish); rerun that run's "
                            "`cassi run` command to finish its tables", path=root / CONFIG_FILE)
    return files
