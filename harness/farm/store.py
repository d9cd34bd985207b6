"""Content-addressed, atomically written job outputs, a run lock, and resume checks.

Layout of an output directory::

    OUT/.cassi-run.lock          held (flock) by the run writing OUT; gone with the process
    OUT/objects/ab/abcdef...ext  blobs named by the SHA-256 of their bytes
    OUT/jobs/<job key>.json      a job's manifest: its input digest and {name: blob} map
    OUT/logs/<job key>.log       a job's log
    OUT/results.parquet|csv, ratings.parquet|csv, run.json, summary.json

A store may share a cache with other runs (``cache``: the nightly directory's ``store/``, or
``cassi run --cache DIR``)::

    CACHE/objects/ab/abcdef...ext    the blobs, once for every run that made them
    CACHE/manifests/ab/<digest>.json a job's manifest by its digest (inputs, settings, code)
    CACHE/memo/<name>/<key>.json     a blob derived from others (a night's combined results)
    CACHE/stamps.json                what the blobs hashed to, and their stat then (Stamps)

Then a blob is written into the cache and hard-linked into ``OUT/objects`` (copied where the
two are on different file systems), so a run directory stays whole by itself and costs no
more disk; a job whose digest the cache holds is reused from it (its manifest and blobs linked
into OUT) instead of run. :func:`collect_garbage` removes what no kept run links any more.
Blobs are read-only: a hard link shares its bytes with the store and every run that links
them, so a write into one run's copy would change them all (readers that trust a blob's name
verify it too: :func:`sha256_file_once`).

A job is done when its manifest exists, names the same input digest as the job about to run,
and every blob it lists exists and hashes to its name. The manifest is written last, so a
killed job leaves at most unreferenced blobs (harmless, reused) and temporary files (removed
at the next start), never a manifest that points at missing or partial data. Writing the same
job twice writes the same bytes to the same names, which is what makes retries (Ray is
at-least-once) idempotent.
"""
from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, Mapping

from cassi.common.atomic import atomic_write_bytes, atomic_write_text, link_or_copy, writable_dir
from cassi.common.errors import CassiInputError

LOCK_NAME = ".cassi-run.lock"
#: In a shared store: media a report made from content-addressed inputs, by their key.
MEDIA_DIR = "media"
#: In a shared store: memos of derived results (:meth:`OutputStore.memo`), by name and key.
MEMO_DIR = "memo"
#: In a shared store: held shared by every run using it, exclusively by the garbage collector.
STORE_LOCK_NAME = ".cassi-store.lock"


@contextlib.contextmanager
def store_lock(cache: str | os.PathLike, *, exclusive: bool) -> Iterator[None]:
    """Hold a shared store: runs share it (``exclusive=False``), :func:`collect_garbage` needs
    it alone; the other side gets a clear :class:`CassiInputError` at once, never a wait."""
    path = Path(cache) / STORE_LOCK_NAME
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as err:
        raise CassiInputError(f"cannot open the store lock: {err.strerror}", path=path) from err
    try:
        try:
            fcntl.flock(fd, (fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH) | fcntl.LOCK_NB)
        except BlockingIOError:
            raise CassiInputError(
                "a run is using this store: collect its garbage when no run is going" if exclusive
                else "the store's garbage is being collected: run again when it is done",
                path=Path(cache)) from None
        yield
    finally:
        with contextlib.suppress(OSError):
            fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)


_SHA256 = re.compile(r"[0-9a-f]{64}")


def is_sha256(name: str) -> bool:
    """Whether ``name`` is a SHA-256 digest as the store writes them (64 lowercase hex)."""
    return _SHA256.fullmatch(name) is not None


def _require_sha256(digest: str) -> str:
    if not is_sha256(digest):
        raise ValueError(f"not a SHA-256 digest: {digest!r}")
    return digest


def sha256_bytes(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def sha256_file(path: str | os.PathLike) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


#: (device, inode, size, mtime, ctime) -> SHA-256 of the files hashed by sha256_file_once.
_HASHED: dict[tuple[int, ...], str] = {}


def _identity(st: os.stat_result) -> tuple[int, ...]:
    return st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns


def sha256_file_once(path: str | os.PathLike) -> str:
    """:func:`sha256_file`, hashed once per process while the file stays the same (its
    device, inode, size, modification and change times: any write changes the change time),
    so a blob linked under several names (a store and the runs linking it) is read once.
    A store's stamps (:class:`Stamps`) carry what earlier processes hashed."""
    before = _identity(os.stat(path))
    digest = _HASHED.get(before)
    if digest is None:
        digest = sha256_file(path)
        if _identity(os.stat(path)) == before:  # not written to while it was read
            _HASHED[before] = digest
    return digest


class Stamps:
    """What a shared store's blobs hashed to, with the identity each file had then (inode,
    size, modification and change times): ``CACHE/stamps.json``. A blob whose identity is
    unchanged since it was hashed is not read again, the way make and git trust a file's stat:
    any write into it changes its change time (and a link made or removed does too, so the
    blobs this process linked are stamped again once linked, if their size and modification
    time are still what was hashed). A missing, unreadable or foreign file only costs hashing.
    """

    NAME = "stamps.json"

    def __init__(self, cache: Path):
        self.path = cache / self.NAME
        self.cache = cache
        #: relpath -> identity at which it hashed to its name, for this process's linking
        self.seen: dict[str, tuple[int, ...]] = {}

    def _read(self) -> tuple[int | None, dict]:
        """(the store's device, relpath -> [inode, size, mtime, ctime]) as stamped; nothing
        for a missing or unreadable file, or one stamped on another file system (a copied
        store: its inode numbers mean nothing here)."""
        try:
            doc = json.loads(self.path.read_text(encoding="utf-8"))
            dev = os.stat(self.cache).st_dev
            blobs = doc["blobs"] if doc.get("dev") == dev else {}
            return dev, dict(blobs)
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            return None, {}

    def load(self) -> None:
        """Teach :func:`sha256_file_once` the stamped blobs."""
        dev, blobs = self._read()
        try:
            for rel, (ino, size, mtime, ctime) in blobs.items():
                _HASHED[(dev, int(ino), int(size), int(mtime), int(ctime))] = _name_digest(rel)
        except (ValueError, TypeError):
            return

    def verified(self, rel: str, path: str) -> bool:
        """Whether the store's blob ``rel`` (at ``path``) hashes to its name; hashed only when
        its identity is not one hashed before."""
        try:
            st = os.stat(path)
            digest = _HASHED.get(_identity(st))
            if digest is None:
                # the identity before reading: a write while or after it was read leaves a
                # stat that save() finds changed, and the blob is not stamped
                digest = sha256_file_once(path)
        except OSError:
            return False
        if digest != _name_digest(rel):
            return False
        self.seen[rel] = _identity(st)
        return True

    def wrote(self, rel: str, path: str) -> None:
        """``rel`` was just written from bytes that hash to its name."""
        with contextlib.suppress(OSError):
            self.seen[rel] = _identity(os.stat(path))

    def save(self) -> None:
        """Stamp every blob verified or written here with its identity now (after this
        process's links), merged with the stamps already there; best effort."""
        dev, blobs = self._read()
        for rel, then in self.seen.items():
            try:
                st = os.stat(self.cache / rel)
            except OSError:
                blobs.pop(rel, None)
                continue
            now = _identity(st)
            if now[:4] != then[:4]:  # written into since it was hashed: not stamped
                blobs.pop(rel, None)
                continue
            dev = now[0]
            _HASHED[now] = _name_digest(rel)
            blobs[rel] = list(now[1:])
        if dev is None:
            return
        with contextlib.suppress(OSError):
            atomic_write_text(self.path, json.dumps({"dev": dev, "blobs": blobs}))


def _name_digest(rel: str) -> str:
    """The SHA-256 a blob's store path names (``objects/ab/<sha256>.ext``)."""
    return os.path.basename(rel).split(".", 1)[0]


def _safe_key(key: str) -> str:
    """Check a job key before it becomes a path: relative, no '..', plain characters."""
    parts = key.split("/")
    if not key or any(p in ("", ".", "..") for p in parts) or any(
            not all(ch.isalnum() or ch in "-_.+" for ch in p) for p in parts):
        raise ValueError(f"unsafe job key {key!r}")
    return key


@dataclass(frozen=True)
class BlobRef:
    """A stored output: its SHA-256 and file suffix (``.parquet``, ``.npz``, ``.png`` ...)."""

    sha256: str
    suffix: str
    #: ``objects/<ab>/<sha256><suffix>``, made once: the store's sets, the stamps and the run's
    #: indexes hold it for every blob (a full-set night made 330,000 copies of 80,000 names)
    relpath: str = field(init=False, compare=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "relpath", f"objects/{self.sha256[:2]}/{self.sha256}{self.suffix}")


def _read_only(path: str | os.PathLike) -> None:
    """Take the write permissions off a blob (where this user may: else it stays as it is)."""
    with contextlib.suppress(OSError):
        mode = os.stat(path).st_mode
        if mode & 0o222:
            os.chmod(path, mode & ~0o222)


class OutputStore:
    """The outputs of one run directory (see the module docstring for the layout), with an
    optional ``cache`` shared between runs."""

    def __init__(self, root: str | os.PathLike, cache: str | os.PathLike | None = None):
        self.root = Path(root)
        self.cache = None if cache is None else Path(cache)
        # Blobs this object has written or hashed: each is hashed at most once per run.
        self._good: set[str] = set()
        self._cache_good: set[str] = set()
        self.stamps = None if self.cache is None else Stamps(self.cache)
        #: Keys of the jobs reused from the cache (not from this run directory).
        self.reused: set[str] = set()

    # -- set-up -------------------------------------------------------------------------------
    def prepare(self) -> None:
        """Create the directory and prove it writable; a clear :class:`CassiInputError` if not."""
        writable_dir(self.root, subdirs=("objects", "jobs", "logs"))
        if self.cache is not None:
            writable_dir(self.cache, "cache directory", subdirs=("objects", "manifests"))
            self.stamps.load()

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the run lock for OUT; a second run on the same OUT fails at once.

        ``flock`` is released by the kernel when the holder dies, even by ``kill -9``, so a
        stale lock file never blocks a rerun.
        """
        path = self.root / LOCK_NAME
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as err:
            raise CassiInputError(f"cannot create the run lock: {err.strerror}", path=path) from err
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "?"
                raise CassiInputError(
                    f"another cassi run (pid {holder}) is writing this output directory",
                    path=self.root) from None
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
            if self.cache is None:
                yield
            else:
                with store_lock(self.cache, exclusive=False):
                    yield
        finally:
            with contextlib.suppress(OSError):
                fcntl.flock(fd, fcntl.LOCK_UN)
            os.close(fd)

    def remove_partials(self) -> list[Path]:
        """Delete temporary files a killed writer left (``.<name>.*.tmp*``); call under the lock."""
        removed = []
        for path in self.root.rglob(".*"):
            if path.is_file() and ".tmp" in path.name and path.name != LOCK_NAME:
                with contextlib.suppress(FileNotFoundError):
                    path.unlink()
                    removed.append(path)
        return removed

    # -- blobs --------------------------------------------------------------------------------
    def put(self, data: bytes, suffix: str) -> BlobRef:
        """Store ``data``; an existing blob with the right hash is left alone.

        Written atomically but not fsynced (two fsyncs cost about 4 ms of a 20 ms preview
        frame): a blob is trusted only after it hashes to its name (:meth:`get` on every read,
        :meth:`verified` before a job counts as done on resume), so one that a power loss left
        short is found and its job run again. Manifests, which say a job is done, stay fsynced.
        """
        ref = BlobRef(sha256_bytes(data), suffix)
        if self.cache is not None:
            if not self._cache_blob_ok(ref):
                atomic_write_bytes(self.cache / ref.relpath, data, durable=False, read_only=True)
                self._cache_good.add(ref.relpath)
                self.stamps.wrote(ref.relpath, os.path.join(self.cache, ref.relpath))
            if not self._blob_ok(ref):
                self._link_from_cache(ref)
            return ref
        if not self._blob_ok(ref):
            atomic_write_bytes(self.root / ref.relpath, data, durable=False, read_only=True)
            self._good.add(ref.relpath)
        return ref

    def _cache_blob_ok(self, ref: BlobRef) -> bool:
        return self._stamped_ok(self.cache, ref, self._cache_good)

    def _stamped_ok(self, base: Path, ref: BlobRef, good: set[str]) -> bool:
        """Whether ``base``'s blob exists and hashes to its name: by its stamp where it has one
        (a run's blob is a link to the store's, the same file, or across file systems a copy,
        another file: not stamped, :meth:`Stamps.save`), else hashed once per process (a run
        without a shared store keeps no stamps); remembered in ``good``."""
        path = os.path.join(base, ref.relpath)
        if ref.relpath in good:
            return os.path.isfile(path)
        if self.stamps is not None:
            ok = self.stamps.verified(ref.relpath, path)
        else:
            try:
                ok = sha256_file_once(path) == ref.sha256
            except OSError:
                ok = False
        if ok:
            good.add(ref.relpath)
        return ok

    # -- memos: results derived from blobs, by a key the caller makes of its inputs ---------
    def _memo_path(self, name: str, key: str) -> Path:
        return self.cache / MEMO_DIR / _safe_key(name) / f"{_require_sha256(key)}.json"

    def memo(self, name: str, key: str) -> bytes | None:
        """The bytes :meth:`remember` kept under ``name``/``key`` in the shared store, if its
        blob still verifies (linked into this run, which keeps it from the garbage
        collector); None without a store or a memo."""
        if self.cache is None:
            return None
        try:
            doc = json.loads(self._memo_path(name, key).read_text(encoding="utf-8"))
            ref = BlobRef(doc["sha256"], doc["suffix"])
        except (OSError, ValueError, KeyError, TypeError):
            return None
        if not self._cache_blob_ok(ref):
            return None
        if not self._blob_ok(ref):
            self._link_from_cache(ref)
        try:
            return (self.root / ref.relpath).read_bytes()
        except OSError:
            return None

    def remember(self, name: str, key: str, data: bytes, suffix: str) -> None:
        """Keep ``data`` as a blob of this run and the shared store, found by :meth:`memo`."""
        if self.cache is None:
            return
        ref = self.put(data, suffix)
        atomic_write_text(self._memo_path(name, key),
                          json.dumps({"sha256": ref.sha256, "suffix": ref.suffix}))

    def save_stamps(self) -> None:
        """Keep what this store's blobs hashed to for the next run (:class:`Stamps`)."""
        if self.stamps is not None:
            self.stamps.save()

    def _link_from_cache(self, ref: BlobRef) -> None:
        """Put the cache's (verified) blob into this run directory: a hard link, or a copy
        where the cache is on another file system; atomic either way, read-only (a blob a
        store from before read-only blobs holds is made so first)."""
        src, dest = os.path.join(self.cache, ref.relpath), os.path.join(self.root, ref.relpath)
        _read_only(src)
        try:
            os.link(src, dest)  # the common case first: strings, not Paths (40,000 a night)
        except OSError:
            link_or_copy(src, dest)  # its folder missing, the name taken, another file system
        self._good.add(ref.relpath)

    def _blob_ok(self, ref: BlobRef) -> bool:
        return self._stamped_ok(self.root, ref, self._good)

    def get(self, ref: BlobRef) -> bytes:
        data = (self.root / ref.relpath).read_bytes()
        if sha256_bytes(data) != ref.sha256:
            raise OSError(f"corrupt blob {ref.relpath}")
        return data

    def path(self, ref: BlobRef) -> Path:
        return self.root / ref.relpath

    # -- manifests ----------------------------------------------------------------------------
    def manifest_path(self, key: str) -> Path:
        return self.root / "jobs" / f"{_safe_key(key)}.json"

    def log_path(self, key: str) -> Path:
        return self.root / "logs" / f"{_safe_key(key)}.log"

    def write_manifest(self, key: str, digest: str, outputs: Mapping[str, BlobRef],
                       meta: Mapping | None = None) -> None:
        """Record a finished job (after its blobs are stored)."""
        doc = {"key": key, "digest": digest,
               "outputs": {n: {"sha256": r.sha256, "suffix": r.suffix}
                           for n, r in sorted(outputs.items())},
               "meta": dict(meta or {})}
        text = json.dumps(doc, indent=1, sort_keys=True)
        if self.cache is not None:
            atomic_write_text(self._cache_manifest(digest), text)
        atomic_write_text(self.manifest_path(key), text)

    def _cache_manifest(self, digest: str) -> Path:
        return self.cache / "manifests" / digest[:2] / f"{_require_sha256(digest)}.json"

    def read_manifest(self, key: str) -> dict | None:
        path = self.manifest_path(key)
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (FileNotFoundError, json.JSONDecodeError, UnicodeDecodeError):
            return None
        doc["outputs"] = {n: BlobRef(o["sha256"], o["suffix"]) for n, o in doc["outputs"].items()}
        return doc

    def verified(self, key: str, digest: str) -> dict | None:
        """The manifest of ``key`` if it was made from the same inputs and every blob verifies."""
        doc = self.read_manifest(key)
        if doc is not None and doc.get("digest") == digest and all(
                self._blob_ok(ref) for ref in doc["outputs"].values()):
            return doc
        return self._from_cache(key, digest)

    def _from_cache(self, key: str, digest: str) -> dict | None:
        """The cache's manifest of ``digest`` with its blobs linked in, or None."""
        if self.cache is None:
            return None
        try:
            doc = json.loads(self._cache_manifest(digest).read_text(encoding="utf-8"))
            outputs = {n: BlobRef(o["sha256"], o["suffix"]) for n, o in doc["outputs"].items()}
        except (OSError, ValueError, KeyError, TypeError):
            return None
        if doc.get("digest") != digest or not all(self._cache_blob_ok(r) for r in outputs.values()):
            return None
        for ref in outputs.values():
            if not self._blob_ok(ref):
                self._link_from_cache(ref)
        if doc.get("key") == key:
            # the store's own file, linked: the same bytes write_manifest wrote (read-only
            # stores aside, nobody writes into a manifest; a rerun replaces it atomically)
            link_or_copy(self._cache_manifest(digest), self.manifest_path(key))
        else:
            # Not fsynced: the store's own manifest is; one lost in a crash is linked again.
            atomic_write_bytes(self.manifest_path(key), json.dumps(
                {**doc, "key": key}, indent=1, sort_keys=True).encode(), durable=False)
        self.reused.add(key)
        return {**doc, "key": key, "outputs": outputs}


def remove_unlinked(paths) -> list[tuple[Path, int]]:
    """Remove each of ``paths`` that is a file with no other name (no run or report links it
    any more); returns the removed ones with their sizes."""
    out = []
    for path in sorted(paths):
        try:
            st = path.stat()
        except FileNotFoundError:
            continue
        if path.is_file() and st.st_nlink <= 1:
            path.unlink()
            out.append((path, st.st_size))
    return out


def remove_stale_records(paths, blobs_of, present=os.path.isfile) -> int:
    """Remove each JSON record of ``paths`` that cannot be read or names a blob that is gone
    (``blobs_of(record)``: the paths of the blobs it names, each kept while ``present`` says
    so); returns how many were removed."""
    stale = 0
    for path in sorted(paths):
        try:
            blobs = [os.fspath(b) for b in blobs_of(json.loads(path.read_text(encoding="utf-8")))]
        except (OSError, ValueError, KeyError, TypeError):
            blobs = None  # unreadable: of no use to anyone
        if blobs is None or not all(present(b) for b in blobs):
            path.unlink(missing_ok=True)
            stale += 1
    return stale


@dataclass(frozen=True)
class Collected:
    """What :func:`collect_garbage` removed: blobs and manifests, and the bytes freed."""

    blobs: int
    manifests: int
    bytes: int


def collect_garbage(cache: str | os.PathLike) -> Collected:
    """Remove from a shared store every blob no run directory links any more (its only name is
    the store's) and every manifest that names a removed blob.

    Run directories hold hard links to the blobs they use, so a blob that a kept run needs has
    more than one link and stays; a run directory on another file system holds copies and never
    depends on the store. Call it holding :func:`store_lock` exclusively (runs hold it shared):
    a run writing into the store meanwhile could have a new blob removed before it links it.
    """
    root = Path(cache)
    removed, freed = set(), 0
    # unlinking a run's copies changes its blobs' change times: their stamps would only miss
    (root / Stamps.NAME).unlink(missing_ok=True)
    for path, size in remove_unlinked((root / "objects").glob("*/*")):
        removed.add(path.relative_to(root).as_posix())
        freed += size
    # report media (cassi.reports.media; its page memo is the reports' own: MEDIA_GC)
    freed += sum(size for _, size in remove_unlinked((root / MEDIA_DIR).glob("*")))
    # a removed blob is no longer a file: the records naming it go
    manifests = remove_stale_records(
        (root / "manifests").glob("*/*.json"),
        lambda doc: [root / BlobRef(o["sha256"], o["suffix"]).relpath
                     for o in doc["outputs"].values()])
    remove_stale_records((root / MEMO_DIR).glob("*/*.json"),
                         lambda doc: [root / BlobRef(doc["sha256"], doc["suffix"]).relpath])
    return Collected(len(removed), manifests, freed)

