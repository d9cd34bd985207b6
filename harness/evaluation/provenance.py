"""What a run's outputs depend on besides the job itself: the code and the corpus files.

Every job's digest (:meth:`cassi.harness.farm.jobs.Job.digest`) includes

- the **code**: the package version, a digest of every file of the installed ``cassi``
  packages and of the modules of any third-party version the run uses, and a digest of the
  rubric registry (each check's thresholds, negatives, windows): :func:`code_provenance`;
- the **inputs** of its task file: the task file's bytes, the subject's files (PAL.DAT,
  PHA.DAT, Mis.dat, head measures) and the subject's profile (thesis 4.2: computed from up to
  20 of the subject's task files): :func:`task_inputs_digest`.

So a changed pellet, threshold or line of code recomputes exactly the jobs it can affect, and
a rerun into the same ``--out`` never reports old numbers as current.
"""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
from importlib.metadata import entry_points
from pathlib import Path
from typing import Iterable

import numpy as np
from cassi.harness.rubric import registry_table
from cassi.harness.evaluation.config import package_version
from cassi.harness.farm.store import sha256_file

#: The namespace packages of cassi-farm itself.
CASSI_PACKAGES = ("cassi.data", "cassi.versions", "cassi.renderer", "cassi.harness",
                  "cassi.reports")
_SKIP_DIRS = {"__pycache__"}


def _package_dirs(name: str) -> list[Path]:
    spec = importlib.util.find_spec(name)
    if spec is None:
        raise ModuleNotFoundError(name)
    if spec.submodule_search_locations:
        return [Path(p) for p in spec.submodule_search_locations]
    return [Path(spec.origin)]


def tree_digest(paths: Iterable[Path]) -> str:
    """SHA-256 over the relative names and bytes of every file under ``paths`` (sorted)."""
    h = hashlib.sha256()
    for root in paths:
        files = [root] if root.is_file() else sorted(
            p for p in root.rglob("*") if p.is_file() and not _SKIP_DIRS & set(p.parts)
            and p.suffix not in (".pyc", ".pyo"))
        for path in files:
            rel = path.name if path == root else path.relative_to(root).as_posix()
            h.update(f"{root.name}/{rel}\0".encode())
            h.update(path.read_bytes())
            h.update(b"\0")
    return h.hexdigest()


@functools.lru_cache(maxsize=None)
def code_digest() -> str:
    """Digest of every file of the installed cassi packages (source, templates, data)."""
    return tree_digest(d for name in CASSI_PACKAGES for d in _package_dirs(name))


def version_code_digest(versions: Iterable[str]) -> str:
    """Digest of the modules behind third-party versions (entry points outside cassi)."""
    eps = {ep.name: ep for ep in entry_points(group="cassi.versions")}
    dirs: list[Path] = []
    for name in sorted(set(versions)):
        ep = eps.get(name)
        if ep is None or ep.value.startswith("cassi."):
            continue  # built-in (in code_digest) or registered at run time (tests)
        top = ep.value.split(":")[0].split(".")[0]
        dirs += _package_dirs(top)
    return tree_digest(dirs)


def rubric_digest() -> str:
    """Digest of the rubric registry: every check with its thresholds and negatives."""
    table = registry_table()
    return hashlib.sha256(table.to_csv(index=False).encode()).hexdigest()


def code_provenance(versions: Iterable[str]) -> dict[str, str]:
    """The code a run's outputs come from (saved in run.json, part of every job digest)."""
    return {"package_version": package_version(), "code_digest": code_digest(),
            "versions_code_digest": version_code_digest(versions),
            "rubric_digest": rubric_digest()}


def _array_bytes(a) -> bytes:
    return b"" if a is None else np.ascontiguousarray(np.asarray(a, np.float64)).tobytes()


def profile_digest(profile) -> str:
    """Digest of a :class:`~cassi.data.corpus.profile.SubjectProfile`: every value the versions and
    the face read (maxprotru/lipthick values, jaw length, palate, head measures, the files
    selected)."""
    h = hashlib.sha256()
    scalars = {k: getattr(profile, k) for k in (
        "subject", "jaw_length_mm", "rest_ul", "rest_ll", "max_ul", "max_ll", "min_ul",
        "min_ll", "lipthick")}
    h.update(json.dumps(scalars, sort_keys=True, default=float).encode())
    h.update(json.dumps([list(k) for k in profile.selected]).encode())
    h.update(_array_bytes(profile.palate_mm))
    hm = profile.head_measures
    if hm is not None:
        h.update(_array_bytes([getattr(hm, f) for f in hm.__dataclass_fields__])
                 if hasattr(hm, "__dataclass_fields__") else repr(hm).encode())
    return h.hexdigest()


def file_digest(path: Path | None) -> str:
    if path is None:
        return "-"

    return sha256_file(path)


def task_inputs_digest(*, task_file: Path, subject_files: Iterable[Path | None],
                       profile) -> str:
    """Digest of everything a job of one task file reads."""
    parts = [file_digest(task_file), *(file_digest(p) for p in subject_files),
             profile_digest(profile) if profile is not None else "-"]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()
