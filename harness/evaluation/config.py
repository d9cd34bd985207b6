"""A run, declared: a TOML or YAML file, or the same fields as ``cassi run`` flags.

Example ``run.toml``::

    out = "runs/nightly"
    subjects = ["JW11", "JW12"]      # default: every subject of the evaluation set
    tasks = [19, 21]                 # default: the evaluation set (thesis Table 5.1 + 106, 118)
    versions = ["cassi-1.0", "cassi-2.1"]   # default: every registered version
    views = ["front", "half"]        # default: front, side, half, top; ["geometry"]: no renders
    stride = 50                      # render every 50th frame too (0: only first + extremes)
    extremes = 4                     # at most this many frames the checks point at, per task
    animate_stride = 0               # >0: also every N-th frame in all views, for task videos
    chunk = 16                       # frames per render job
    preset = "preview"
    executor = "local"               # or "ray" (with address = "host:port", else a local cluster)
    workers = 2                      # default: one per usable core
    threads = 1                      # CPU threads per worker (renderer); a worker is one core
    cache = "runs/store"             # optional: a store shared between runs (jobs reused)

Fields are checked when loaded (types and ranges, unknown keys with the list of valid ones);
names (subjects, tasks, versions, views, presets) are checked against what exists before any
work starts (:func:`check_names`). The resolved configuration is saved with the results
(:func:`resolved`), with the package version and the git revision.
"""
from __future__ import annotations

import dataclasses
import difflib
import re
import subprocess
import tomllib
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version as pkg_version
from pathlib import Path
from typing import Any, Mapping

import yaml

from cassi.common.cliargs import task_range
from cassi.common.cores import usable_cores
from cassi.common.errors import CassiInputError

from cassi.harness.farm.jobs import GEOMETRY_VIEW

EXECUTORS = ("local", "ray")
#: The named evaluation sets (``set`` in a run file, ``--set``): "thesis", the thesis's task
#: files (Table 5.1 and tasks 106, 118: :func:`~cassi.harness.evaluation.evalset.default_tasks`);
#: "full", every task file of every subject (:func:`~.evalset.full_tasks`). Explicit ``tasks``
#: take the place of either.
EVAL_SETS = ("thesis", "full")


#: At most this many "extreme" frames per task file and version (the worst frame of the checks
#: that fired, most negatives first), so renders stay bounded on long tasks.
DEFAULT_EXTREMES = 4

#: What a night renders (all four views, raycast preview): the first frame and the two frames
#: the checks point at per task file and version, in every view (the subject pages' four views
#: of a fault, the gates, the goldens); every NIGHTLY_ANIMATE_STRIDE-th row of every task file
#: in the front view for every version (the frames the image checks judge, with their masks,
#: the same for every version, and the versions' side-by-side video; real time: 145.6 / stride
#: frames per second). No version gets the other views on that grid by default (`cassi export
#: --format gltf` gives any view of any version from geometry); ``--video-versions`` asks for them
#: (frames.py says why; docs/farm.md gives the night's size and time).
NIGHTLY_STRIDE = 0
NIGHTLY_EXTREMES = 2
NIGHTLY_ANIMATE_STRIDE = 24
#: Nights ``cassi gc`` keeps by default: a month of nightly runs.
KEEP_NIGHTS = 30
#: Versions rendered in every view on the video grid for a four-view video of every task file:
#: none by default (cassi-2.1's were 10,968 of a night's 31,081 renders, 0.28 of its 1.87 GB
#: and half its report's encoding); ``cassi nightly --video-versions cassi-2.1`` brings them back.
NIGHTLY_VIDEO_VERSIONS: tuple[str, ...] = ()


@dataclass(frozen=True)
class RunConfig:
    """Every setting of a run (see the module docstring); None means "the default set"."""

    out: Path | None = None
    corpus: Path | None = None
    #: A store shared with other runs (a nightly directory's ``store/``): jobs it holds with the
    #: same digest are reused, not run (:class:`cassi.harness.farm.store.OutputStore`).
    cache: Path | None = None
    subjects: tuple[str, ...] | None = None
    tasks: tuple[int, ...] | None = None
    #: Which task files when ``tasks`` is not given (:data:`EVAL_SETS`).
    set: str = "thesis"
    versions: tuple[str, ...] | None = None
    views: tuple[str, ...] | None = None
    # The default render budget: about 35 frames per task file, version and view, which keeps
    # `cassi run --subjects JW16,JW27` (~9,000 renders before, ~4,500 now) to a few minutes.
    stride: int = 50
    extremes: int = DEFAULT_EXTREMES
    animate_stride: int = 0
    #: Versions whose task videos show all four views (None: every version); the others are
    #: rendered at ``animate_stride`` in the view the image checks judge (front), so those
    #: checks judge every version on the same frames, and it shows the versions side by side.
    video_versions: tuple[str, ...] | None = None
    chunk: int = 16
    preset: str = "preview"
    variant: str | None = None
    executor: str = "local"
    address: str | None = None
    workers: int = field(default_factory=usable_cores)   # one worker per usable core
    threads: int = 1
    retries: int = 1
    #: Where each setting read from a run file was set (key -> ``{"path", "line"}``), so a
    #: name checked later against the corpus (:func:`check_names`) is refused at its line.
    #: Not a setting: never saved, never compared.
    where: Mapping[str, Mapping[str, Any]] = field(default_factory=dict, compare=False,
                                                   repr=False)

    def replace(self, **changes) -> "RunConfig":
        return dataclasses.replace(self, **changes)


FIELDS = tuple(f.name for f in dataclasses.fields(RunConfig) if f.name != "where")

#: ``cassi nightly``'s defaults (what a night renders, above): a run file and flags apply over
#: them as over :class:`RunConfig`'s for ``cassi run``.
NIGHTLY = RunConfig(workers=2, stride=NIGHTLY_STRIDE, extremes=NIGHTLY_EXTREMES,
                    animate_stride=NIGHTLY_ANIMATE_STRIDE, video_versions=NIGHTLY_VIDEO_VERSIONS)
#: A night's review (gates, history, report): the reports layer's, named by ``module:function``
#: where a night is composed (the command, the benchmark), so the harness never imports reports.
NIGHT_REVIEW = "cassi.reports.nightly:review_night"
#: The reports layer's part of ``cassi gc`` for a store's media (its page memo), named likewise.
MEDIA_GC = "cassi.reports.memo:collect_pages"
#: ``video_versions`` given as one word: every version (None) or none (an empty tuple).
EVERY_VERSION, NO_VERSION = "all", "none"


def settings(cfg: RunConfig) -> dict[str, Any]:
    """Every setting of ``cfg`` by name (its ``where`` left out)."""
    return {k: getattr(cfg, k) for k in FIELDS}
_LISTS = {"subjects": str, "tasks": int, "versions": str, "views": str, "video_versions": str}
_INTS = {"stride": 0, "extremes": 0, "animate_stride": 0, "chunk": 1, "workers": 1, "threads": 1, "retries": 0}   # name -> minimum
_STRS = ("preset", "variant", "executor", "address", "set")


def _line_of(text: str | None, key: str) -> int | None:
    """The line where ``key`` is set in a TOML/YAML text (for error messages)."""
    if not text:
        return None
    # a YAML key that is not text (1, true, null) is looked for as the file spells it
    names = [str(key)]
    if key is None:
        names += ["null", "~"]
    elif key is True:
        names += ["yes", "on", "y"]
    elif key is False:
        names += ["no", "off", "n"]
    alt = "|".join(re.escape(n) for n in names)
    pat = re.compile(rf"^\s*[\"']?(?:{alt})[\"']?\s*[=:]",
                     0 if isinstance(key, str) else re.IGNORECASE)
    for i, line in enumerate(text.splitlines(), 1):
        if pat.match(line):
            return i
    return None


def _did_you_mean(name: str, valid) -> str:
    close = difflib.get_close_matches(str(name), [str(v) for v in valid], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


#: No setting is an integer beyond this (task numbers, strides, workers, seeds): a longer one is
#: a typing error, and Python refuses to read one of more than 4300 digits at all.
_MAX_INT = 10 ** 9


def _as_int(value: Any, key: str, where: dict) -> int:
    if isinstance(value, bool):
        raise CassiInputError(f"{key}: expected an integer, got {value!r}", **where)
    if isinstance(value, str) and re.fullmatch(r"\s*[+-]?[0-9]{1,10}\s*", value):  # ASCII digits
        value = int(value)
    if not isinstance(value, int):
        raise CassiInputError(f"{key}: expected an integer, got {repr(value)[:40]}", **where)
    if abs(value) > _MAX_INT:  # no str(value): a hex literal may have more digits than str allows
        raise CassiInputError(f"{key}: out of range (at most {_MAX_INT})", **where)
    return value


def _as_ints(value: Any, key: str, where: dict) -> list[int]:
    """One list item: an integer, or task numbers as a range (``"1-118"``, ``"102-105,13"``)."""
    if key == "tasks" and isinstance(value, str) and re.fullmatch(r"[0-9, -]+", value, re.ASCII) \
            and re.search(r"[-,]", value.strip().lstrip("+-")):
        try:
            return task_range(value)
        except ValueError as err:
            raise CassiInputError(f"{key}: {err}", **where) from None
    return [_as_int(value, key, where)]


class _UniqueKeyLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing a key set twice in one mapping (PyYAML keeps the last)."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":  # '<<: *base' merges, it sets no key
                continue
            key = self.construct_object(key_node, deep=deep)
            try:
                first = seen.get(key)
                seen.setdefault(key, key_node.start_mark.line + 1)
            except TypeError:  # an unhashable key: PyYAML's own error follows
                continue
            if first is not None:
                raise yaml.constructor.ConstructorError(
                    None, None, f"{key!r} is set twice (first on line {first})",
                    key_node.start_mark)
        return super().construct_mapping(node, deep=deep)


def validate(raw: Mapping[str, Any], *, source: str | Path | None = None,
             text: str | None = None) -> RunConfig:
    """Check types and ranges of raw fields and build a :class:`RunConfig`.

    Raises
    ------
    CassiInputError
        Unknown key (with the valid ones), wrong type, value out of range, unknown executor.
    """
    values: dict[str, Any] = {}
    origin: dict[str, dict[str, Any]] = {}
    for key, value in raw.items():
        where = {"path": source, "line": _line_of(text, key)} if source else {}
        if where and isinstance(key, str):
            origin[key] = where
        if not isinstance(key, str) or key not in FIELDS:
            raise CassiInputError(f"unknown setting {key!r}{_did_you_mean(key, FIELDS)}; valid "
                                  f"settings: {', '.join(FIELDS)}", **where)
        if value is None:
            continue
        if key in _LISTS:
            items = [value] if isinstance(value, (str, int)) and not isinstance(value, bool) else value
            if not isinstance(items, (list, tuple)):
                raise CassiInputError(f"{key}: expected a list, got {value!r}", **where)
            if key == "video_versions" and list(items) in ([], [NO_VERSION], [EVERY_VERSION]):
                # the one list where 'none' (or []) and 'all' mean something of their own
                values[key] = None if list(items) == [EVERY_VERSION] else ()
                continue
            if _LISTS[key] is int:
                items = [n for v in items for n in _as_ints(v, key, where)]
            else:
                bad = [v for v in items if not isinstance(v, str) or not v.strip()]
                if bad:
                    raise CassiInputError(f"{key}: expected names, got {bad[0]!r}", **where)
                items = [v.strip() for v in items]
            if not items:
                raise CassiInputError(f"{key}: the list is empty", **where)
            values[key] = tuple(dict.fromkeys(items))  # order kept, repeats dropped
        elif key in _INTS:
            n = _as_int(value, key, where)
            if n < _INTS[key]:
                raise CassiInputError(f"{key}: must be at least {_INTS[key]}, got {n}", **where)
            values[key] = n
        elif key in ("out", "corpus", "cache"):
            if not isinstance(value, (str, Path)) or not str(value).strip():
                raise CassiInputError(f"{key}: expected a path, got {value!r}", **where)
            path = Path(str(value)).expanduser()
            if source is not None and not path.is_absolute():
                path = Path(source).parent / path  # relative to the config file
            values[key] = path
        else:
            if not isinstance(value, str):
                raise CassiInputError(f"{key}: expected text, got {value!r}", **where)
            values[key] = value.strip()
    cfg = RunConfig(**values, where=origin)
    if cfg.executor not in EXECUTORS:
        raise CassiInputError(f"unknown executor {cfg.executor!r}; valid: {', '.join(EXECUTORS)}",
                              path=source, line=_line_of(text, "executor"))
    if cfg.address and cfg.executor != "ray":
        raise CassiInputError("address is only used with executor 'ray'", path=source,
                              line=_line_of(text, "address"))
    if cfg.set not in EVAL_SETS:
        raise CassiInputError(f"unknown evaluation set {cfg.set!r}; valid: {', '.join(EVAL_SETS)}"
                              + _did_you_mean(cfg.set, EVAL_SETS), path=source,
                              line=_line_of(text, "set"))
    return cfg


def load_config(path: str | Path) -> RunConfig:
    """Read and validate a ``.toml``, ``.yaml`` or ``.yml`` run file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise CassiInputError(f"cannot read the run configuration: {err}", path=path) from err
    suffix = path.suffix.lower()
    if suffix == ".toml":
        try:
            raw = tomllib.loads(text)
        except tomllib.TOMLDecodeError as err:
            m = re.search(r"line (\d+)", str(err))
            raise CassiInputError(f"not valid TOML: {err}", path=path,
                                  line=int(m.group(1)) if m else None) from err
        except ValueError as err:  # e.g. an integer too long for Python to read, a bad date
            raise CassiInputError(f"not valid TOML: {str(err)[:160]}", path=path) from None
    elif suffix in (".yaml", ".yml"):
        try:
            raw = yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a safe loader
        except yaml.YAMLError as err:
            mark = getattr(err, "problem_mark", None)
            raise CassiInputError(f"not valid YAML: {getattr(err, 'problem', err)}", path=path,
                                  line=mark.line + 1 if mark else None) from err
        except ValueError as err:  # e.g. an integer too long for Python to read, a bad date
            raise CassiInputError(f"not valid YAML: {str(err)[:160]}", path=path) from None
        raw = {} if raw is None else raw
    else:
        raise CassiInputError("run configuration must be .toml, .yaml or .yml", path=path)
    if not isinstance(raw, dict):
        raise CassiInputError("run configuration must be a table of settings", path=path)
    if "run" in raw and isinstance(raw["run"], dict) and len(raw) == 1:
        raw = raw["run"]  # a [run] table is accepted as well as top-level keys
    return validate(raw, source=path, text=text)


def merge(base: RunConfig, overrides: Mapping[str, Any]) -> RunConfig:
    """``base`` with every non-None override applied (CLI flags over a config file)."""
    raw = {k: v for k, v in settings(base).items()
           if v is not None and v != getattr(RunConfig(), k)}
    given = {k: v for k, v in overrides.items() if v is not None}
    raw.update(given)
    # a setting the flags did not change keeps the run file's line
    return validate(raw).replace(where={k: v for k, v in base.where.items() if k not in given})


@dataclass(frozen=True)
class Catalog:
    """What exists: the names a configuration may use."""

    subjects: tuple[str, ...]
    tasks: Mapping[str, tuple[int, ...]] = field(default_factory=dict)  # subject -> task numbers
    versions: tuple[str, ...] = ()
    views: tuple[str, ...] = ()
    presets: tuple[str, ...] = ()


def _unknown(kind: str, names, valid, where: Mapping[str, Any] | None = None) -> None:
    bad = [n for n in names if n not in valid]
    if bad:
        hint = _did_you_mean(bad[0], valid)
        raise CassiInputError(f"unknown {kind} {', '.join(map(str, bad))}{hint}; valid "
                              f"{kind}s: {', '.join(map(str, valid)) or '(none)'}",
                              **(where or {}))


def check_names(cfg: RunConfig, catalog: Catalog) -> None:
    """Fail before any work when a name is unknown, listing the valid names (and, for a name
    read from a run file, the file and line that set it)."""
    w = cfg.where.get
    if cfg.subjects is not None:
        _unknown("subject", cfg.subjects, catalog.subjects, w("subjects"))
    if cfg.tasks is not None and catalog.tasks:
        subjects = cfg.subjects or catalog.subjects
        valid = sorted({t for s in subjects for t in catalog.tasks.get(s, ())})
        _unknown("task", cfg.tasks, valid, w("tasks"))
    if cfg.versions is not None:
        _unknown("version", cfg.versions, catalog.versions, w("versions"))
    if cfg.video_versions is not None:
        _unknown("version", cfg.video_versions, catalog.versions, w("video_versions"))
    if cfg.views is not None:
        _unknown("view", cfg.views, tuple(catalog.views) + (GEOMETRY_VIEW,), w("views"))
    if catalog.presets:
        _unknown("preset", [cfg.preset], catalog.presets, w("preset"))


def package_version() -> str:
    try:
        return pkg_version("cassi-farm")
    except PackageNotFoundError:
        return "unknown"


def git_revision(where: Path | None = None) -> str | None:
    """The checkout's commit (with ``-dirty`` when it has changes), or None outside git."""
    where = where or Path(__file__).resolve().parent
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=where, capture_output=True,
                             text=True, timeout=10)
        if rev.returncode != 0:
            return None
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=where, capture_output=True, text=True, timeout=10)
        return rev.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return None


def resolved(cfg: RunConfig, **extra) -> dict:
    """The configuration as saved with the results: every field, plus provenance."""
    doc = {k: (str(v) if isinstance(v, Path) else list(v) if isinstance(v, tuple) else v)
           for k, v in settings(cfg).items()}
    doc["package_version"] = package_version()
    doc["git_revision"] = git_revision()
    doc.update(extra)
    return doc
