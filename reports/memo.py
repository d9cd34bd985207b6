"""Report pages reused by content: a page (or a group of files, such as the run's tables) whose
inputs hash to a key an earlier report wrote is linked from the media cache, not made again.

A key is the SHA-256 of a JSON document of everything the page is made of: the code (every
source file and template of the package, the libraries' versions: :func:`code_digest`), the
rows of the run's tables it reads (:func:`group_digests`, render and attachment paths by
content: :func:`content_ids`) and whatever else it shows. A key that cannot be made, or a
value that cannot be kept, means the page is made as it always was: a wrong reuse is far worse
than a slow report.

Layout under the cache (a nightly store's media): ``pages/<key>.json`` (the files the page
wrote, each by the SHA-256 of its bytes, and the value the page's function returned) and
``pages/blobs/<ab>/<sha256>`` (those files, hard-linked where one file system holds both).
"""
from __future__ import annotations

import functools
import hashlib
import importlib.metadata as md
import json
import os
import re
import sys
import tempfile
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_write_text, link_or_copy
from cassi.harness.farm.store import remove_stale_records, remove_unlinked, sha256_file_once

MEMO_DIR = "pages"
_BLOBS = "blobs"
#: The package's files a page can depend on (code, templates, the viewer's scripts).
_CODE_SUFFIXES = (".py", ".j2", ".js")
_NOT_CODE = {"tests", "docs", "__pycache__"}
#: Libraries whose versions change the bytes the report writes (CSV and number formatting,
#: templates, PNG and WebP encoders, plots).
_LIBRARIES = ("numpy", "pandas", "pyarrow", "jinja2", "markupsafe", "matplotlib", "pillow",
              "imageio", "imageio-ffmpeg")
#: A run's content-addressed object: ``objects/<ab>/<sha256>.<ext>`` (the farm's store).
_OBJECT = re.compile(r"(?:^|/)objects/([0-9a-f]{2})/(\1[0-9a-f]{62})\.[A-Za-z0-9]+$")
#: A report's picture, named by the SHA-256 of its bytes (:func:`.media.store_image`).
_IMAGE = re.compile(r"^images/([0-9a-f]{2})/(\1[0-9a-f]{62})\.webp$")


@functools.lru_cache(maxsize=None)
def code_digest() -> str:
    """Digest of every source file and template of the package (tests and docs aside), the
    Python version and the libraries' versions: any change makes every page anew."""
    from cassi.reports import media  # noqa: PLC0415 - media imports the store as we do

    root = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for dirpath, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in _NOT_CODE)
        for name in sorted(files):
            if name.endswith(_CODE_SUFFIXES):
                path = Path(dirpath) / name
                h.update(path.relative_to(root).as_posix().encode() + b"\0")
                h.update(hashlib.sha256(path.read_bytes()).digest())
    for lib in _LIBRARIES:
        try:
            version = md.version(lib)
        except md.PackageNotFoundError:
            version = "-"
        h.update(f"{lib}={version}\0".encode())
    h.update(sys.version.encode())
    for fast in (False, True):  # libwebp's own version, and the options of either kind of run
        h.update(media._webp_code(fast).encode())  # noqa: SLF001
    return h.hexdigest()


def content_ids(paths) -> list[str]:
    """Each file by its content: a run object's name (the store names objects by their
    SHA-256), any other file's SHA-256; "" for a file that is not there."""
    out = []
    for p in paths:
        p = str(p)
        m = _OBJECT.search(p.replace(os.sep, "/"))
        if m:
            out.append(m.group(2))
        else:
            try:
                out.append(sha256_file_once(p))
            except OSError:
                out.append("")
    return out


def _row_hashes(df: pd.DataFrame) -> np.ndarray:
    """Per row, a 64-bit hash of each column's value and whether it is missing."""
    parts = []
    for c in df.columns:
        s = df[c]
        parts.append(pd.util.hash_pandas_object(s, index=False, categorize=False).to_numpy())
        parts.append(s.isna().to_numpy().astype(np.uint64))
    return np.column_stack(parts) if parts else np.zeros((len(df), 0), np.uint64)


def _header(df: pd.DataFrame) -> bytes:
    return json.dumps([[str(c), str(df[c].dtype)] for c in df.columns]).encode()


class RowDigests:
    """Digests of a table's rows, in their order, every column (each row hashed once)."""

    def __init__(self, df: pd.DataFrame):
        self._df, self._rows, self._head = df, _row_hashes(df), _header(df)

    def whole(self) -> str:
        """SHA-256 of every row."""
        return hashlib.sha256(self._head + self._rows.tobytes()).hexdigest()

    def groups(self, by: list[str]) -> dict[tuple, str]:
        """(values of ``by``) -> SHA-256 of that group's rows (rows with a missing ``by`` value
        belong to no group)."""
        if not len(self._df):
            return {}
        out = {}
        for key, idx in self._df.groupby(by, sort=False).indices.items():
            key = key if isinstance(key, tuple) else (key,)
            out[tuple(k.item() if isinstance(k, np.generic) else k for k in key)] = \
                hashlib.sha256(self._head + self._rows[np.sort(idx)].tobytes()).hexdigest()
        return out


def group_digests(df: pd.DataFrame, by: list[str]) -> dict[tuple, str]:
    """:meth:`RowDigests.groups` of ``df``."""
    return RowDigests(df).groups(by)


def frame_digest(df: pd.DataFrame) -> str:
    """:meth:`RowDigests.whole` of ``df``."""
    return RowDigests(df).whole()


def by_content(index: pd.DataFrame) -> pd.DataFrame:
    """A render or attachment index with ``path`` as its files' content (:func:`content_ids`):
    the same files under another run's folder give the same rows."""
    if not len(index):
        return index
    return index.assign(path=content_ids(index["path"]))


def _plain(o):
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"not kept: {type(o).__name__}")


class Memo:
    """The pages of one report (``out``) kept in and reused from ``cache`` (None: none kept)."""

    def __init__(self, cache: Path | None, out: Path):
        self.dir = None if cache is None else Path(cache) / MEMO_DIR
        self.out = Path(out)
        self._placed: set[str] = set()

    def key(self, kind: str, doc: dict) -> str | None:
        """The key of a page of ``kind`` made of ``doc`` (None without a cache)."""
        if self.dir is None:
            return None
        text = json.dumps({"kind": kind, "code": code_digest(), "doc": doc}, sort_keys=True,
                          default=_plain)
        return hashlib.sha256(text.encode()).hexdigest()

    def _blob(self, digest: str) -> Path:
        return self.dir / _BLOBS / digest[:2] / digest

    def reuse(self, key: str | None) -> tuple[bool, object]:
        """(True, the page's value) with its files linked into the report, when ``key`` was
        kept and every file is still there; else (False, None) and nothing linked."""
        if key is None:
            return False, None
        try:
            doc = json.loads((self.dir / f"{key}.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return False, None
        blobs = [(rel, self._blob(digest)) for rel, digest in doc["files"]]
        if not all(b.is_file() for _, b in blobs):
            return False, None
        for rel, blob in blobs:
            self._place(blob, rel)
        return True, doc["value"]

    def _place(self, blob: Path, rel: str) -> None:
        if rel in self._placed:
            return
        dest = self.out / rel
        try:
            os.link(blob, dest)
        except FileExistsError:
            if not os.path.samefile(blob, dest):
                link_or_copy(blob, dest)
        except OSError:
            link_or_copy(blob, dest)  # no folder yet, or another file system
        self._placed.add(rel)

    def keep(self, key: str | None, files, value, *, root: Path | None = None) -> None:
        """Keep the files a page wrote (paths under ``root``, by default the report) and its
        value under ``key``; a value JSON cannot hold is not kept (the page is made again)."""
        if key is None:
            return
        root = self.out if root is None else root
        try:
            value_text = json.dumps(value, default=_plain, allow_nan=True)
        except (TypeError, ValueError):
            return
        entries = []
        for f in dict.fromkeys(Path(f) for f in files):
            rel = f.relative_to(root).as_posix()
            named = _IMAGE.match(rel)
            digest = named.group(2) if named else sha256_file_once(f)
            blob = self._blob(digest)
            if not blob.is_file():
                blob.parent.mkdir(parents=True, exist_ok=True)
                link_or_copy(f, blob)
            entries.append([rel, digest])
        atomic_write_text(self.dir / f"{key}.json",
                          '{"files": ' + json.dumps(entries) + ', "value": ' + value_text + "}")

    def page(self, kind: str, doc: dict | None, make: Callable[[], tuple[object, list]]):
        """``make()`` -> (value, files written under the report), or the value kept under the
        key of ``doc`` (None: no key could be made) with its files linked."""
        key = self.key(kind, doc) if doc is not None else None
        found, value = self.reuse(key)
        if found:
            return value
        value, files = make()
        self.keep(key, files, value)
        return value

    def staged(self, kind: str, doc: dict | None, make: Callable[[Path], object]):
        """``make(folder)`` writes its files into ``folder`` (paths relative to it, as in the
        report) and returns a value: made in a fresh folder beside the cache, kept, then
        linked into the report; or reused. Without a cache, made in the report itself."""
        key = self.key(kind, doc) if doc is not None else None
        found, value = self.reuse(key)
        if found:
            return value
        if key is None:
            return make(self.out)
        self.dir.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix=".stage-", dir=self.dir) as tmp:
            stage = Path(tmp)
            value = make(stage)
            files = [p for p in sorted(stage.rglob("*")) if p.is_file()]
            self.keep(key, files, value, root=stage)
            for f in files:
                rel = f.relative_to(stage).as_posix()
                (self.out / rel).parent.mkdir(parents=True, exist_ok=True)
                self._placed.discard(rel)
                self._place(f, rel)
        return value


#: A staging folder older than this was left by a killed report (a report takes minutes).
STALE_STAGE_S = 6 * 3600


def collect_pages(media: str | os.PathLike) -> int:
    """``cassi gc``'s part for the page memo under a store's ``media``: remove every kept file
    no report links any more (its only name is the memo's), every page record that names a
    removed file, and staging folders a killed report left. Returns the bytes freed. Called
    holding the store's lock exclusively, as the store's own collection is."""
    import shutil  # noqa: PLC0415 - gc only
    import time  # noqa: PLC0415

    pages = Path(media) / MEMO_DIR
    freed = sum(size for _, size in remove_unlinked((pages / _BLOBS).glob("*/*")))
    remove_stale_records(pages.glob("*.json"),
                         lambda doc: [pages / _BLOBS / d[:2] / d for _, d in doc["files"]])
    for stage in pages.glob(".stage-*"):
        try:
            if time.time() - stage.stat().st_mtime > STALE_STAGE_S:
                shutil.rmtree(stage, ignore_errors=True)
        except OSError:
            continue
    return freed

