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

import ast
import functools
import hashlib
import importlib.util
import json
from importlib.metadata import PackageNotFoundError, entry_points
from importlib.metadata import version as pkg_version
from pathlib import Path
from typing import Iterable

import numpy as np
from cassi.harness.rubric import registry_table
from cassi.harness.evaluation.config import package_version
from cassi.common.digest import source_files, tree_digest
from cassi.harness.farm.store import sha256_file

#: The packages of cassi-farm whose code shapes a job's outputs. The reports and the benchmarks
#: never run inside a job (they read what jobs wrote), so changing them reuses every job.
CASSI_PACKAGES = ("cassi.common", "cassi.data", "cassi.versions", "cassi.renderer",
                  "cassi.harness")
EXCLUDED_PACKAGES = ("cassi.harness.bench",)
#: Third-party packages whose versions shape results: the numbers (numpy, scipy, pandas), the
#: tables' bytes (pyarrow), the renders (mitsuba, drjit) and the image checks (scikit-image).
#: Upgrading one recomputes every job.
RESULT_PACKAGES = ("numpy", "scipy", "pandas", "pyarrow", "mitsuba", "drjit", "scikit-image")
VERSIONS_PACKAGE = "cassi.versions"


def _package_dirs(name: str) -> list[Path]:
    spec = importlib.util.find_spec(name)
    if spec is None:
        raise ModuleNotFoundError(name)
    if spec.submodule_search_locations:
        return [Path(p) for p in spec.submodule_search_locations]
    return [Path(spec.origin)]


def _module_imports(path: Path, package: str) -> set[str]:
    """The modules of ``package`` that the module at ``path`` imports (absolute names)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                 else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level
                 else [])
        if isinstance(node, ast.ImportFrom) and not node.level:
            names += [f"{node.module}.{a.name}" for a in node.names]
        out.update(n for n in names if n == package or n.startswith(package + "."))
    return out


@functools.lru_cache(maxsize=None)
def _versions_modules() -> dict[str, Path]:
    """Module name -> file of every module of cassi.versions."""
    mods = {}
    for root in _package_dirs(VERSIONS_PACKAGE):
        for path in source_files(root):
            if path.suffix == ".py":
                stem = path.relative_to(root).with_suffix("").as_posix().replace("/", ".")
                mods[f"{VERSIONS_PACKAGE}.{stem}".removesuffix(".__init__")] = path
    return mods


def versions_closure(files: Iterable[Path]) -> frozenset[str]:
    """The modules of cassi.versions that ``files`` import, directly or through each other."""
    mods = _versions_modules()
    todo = [m for f in files for m in _module_imports(f, VERSIONS_PACKAGE) if m in mods]
    seen: set[str] = set()
    while todo:
        m = todo.pop()
        if m not in seen:
            seen.add(m)
            todo += [n for n in _module_imports(mods[m], VERSIONS_PACKAGE) if n in mods]
    return frozenset(seen)


def _version_sources(name: str) -> tuple[list[Path], list[Path]]:
    """(files of cassi.versions the version's entry module starts from, its own third-party
    package directories) for a registered version."""
    ep = {e.name: e for e in entry_points(group="cassi.versions")}.get(name)
    if ep is None:
        return [], []  # registered at run time (tests): shared code only
    module = ep.value.split(":")[0]
    if module.startswith(VERSIONS_PACKAGE + "."):
        return [_versions_modules()[module]], []
    dirs = _package_dirs(module.split(".")[0])
    return [f for d in dirs for f in source_files(d) if f.suffix == ".py"], dirs


@functools.lru_cache(maxsize=None)
def _closures() -> dict[str, frozenset[str]]:
    """Every registered version's closure in cassi.versions (its entry module included)."""
    out = {}
    for ep in entry_points(group="cassi.versions"):
        files, _ = _version_sources(ep.name)
        own = ({ep.value.split(":")[0]} if ep.value.startswith(VERSIONS_PACKAGE + ".") else set())
        out[ep.name] = versions_closure(files) | own
    return out


@functools.lru_cache(maxsize=None)
def code_digest() -> str:
    """Digest of the cassi code every job shares: every file of :data:`CASSI_PACKAGES` (source,
    templates, data) less :data:`EXCLUDED_PACKAGES` and less the modules of cassi.versions that
    belong to some version (:func:`version_digest` covers those, per version)."""
    return tree_digest(_shared_roots(), exclude=_shared_excluded())


def _shared_roots() -> list[Path]:
    return [d for name in CASSI_PACKAGES for d in _package_dirs(name)]


def _shared_excluded() -> list[Path]:
    mods = _versions_modules()
    owned = {mods[m] for c in _closures().values() for m in c}
    return [d for name in EXCLUDED_PACKAGES for d in _package_dirs(name)] + sorted(owned)


def shared_code_files() -> list[Path]:
    """The files :func:`code_digest` reads."""
    excluded = _shared_excluded()
    return [f for root in _shared_roots() for f in source_files(root, excluded)]


@functools.lru_cache(maxsize=None)
def version_digest(name: str) -> str:
    """Digest of the code only ``name`` runs: the modules of cassi.versions its entry module
    imports (directly or not; shared ones such as the protocol included) and, for a third-party
    version, its own package. A change to ``versions/cassi21.py`` changes the digests of
    cassi-2.1 and of the versions that import it, not cassi-1.0's."""
    files, dirs = _version_sources(name)
    mods = _versions_modules()
    own = _closures().get(name)
    if own is None:  # registered at run time (tests)
        own = versions_closure(files)
    return tree_digest([mods[m] for m in sorted(own)] + dirs)


def version_code_digest(versions: Iterable[str]) -> str:
    """One digest over the versions' own code (:func:`version_digest` of each)."""
    h = hashlib.sha256()
    for name in sorted(set(versions)):
        h.update(f"{name}\0{version_digest(name)}\0".encode())
    return h.hexdigest()


def package_versions() -> dict[str, str]:
    """The installed versions of :data:`RESULT_PACKAGES` (``"-"`` where one is missing)."""
    out = {}
    for name in RESULT_PACKAGES:
        try:
            out[name] = pkg_version(name)
        except PackageNotFoundError:
            out[name] = "-"
    return out


def rubric_digest() -> str:
    """Digest of the rubric registry: every check with its thresholds and negatives."""
    table = registry_table()
    return hashlib.sha256(table.to_csv(index=False).encode()).hexdigest()


def code_provenance(versions: Iterable[str]) -> dict:
    """The code a run's outputs come from (saved in run.json, part of every job digest): the
    shared code, the rubric, the packages that shape results, and per version its own code
    (``version_digests``; a job's digest takes only its version's)."""
    versions = sorted(set(versions))
    return {"package_version": package_version(), "code_digest": code_digest(),
            "versions_code_digest": version_code_digest(versions),
            "version_digests": {v: version_digest(v) for v in versions},
            "packages": package_versions(), "rubric_digest": rubric_digest()}


def shared_provenance(provenance: dict) -> dict:
    """The part of :func:`code_provenance` every job's digest takes (not the versions' own)."""
    return {k: v for k, v in provenance.items()
            if k not in ("versions_code_digest", "version_digests")}


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
