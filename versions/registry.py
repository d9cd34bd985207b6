"""Names -> versions, with "did you mean" errors and third-party versions from entry points.

:class:`Registry` is generic (names map to objects, or to lazy ``"module:attr"`` strings imported
on first use) and can be frozen after start-up. The version registry below holds the four
built-in versions; other packages add theirs to the ``cassi.versions`` entry point group::

    [project.entry-points."cassi.versions"]
    my-version = "my_package.module:MyVersion"

where ``MyVersion`` is a class (instantiated without arguments) or an object with ``name`` and
``animate(profile, face, rec) -> Animation`` (see :mod:`cassi.versions.protocol`).
"""
from __future__ import annotations

import difflib
import threading
from importlib.metadata import entry_points
from types import MappingProxyType
from typing import Any, Generic, Iterator, TypeVar

from cassi.common.errors import CassiInputError
from cassi.common.lazy import resolve

__all__ = ["Registry", "VERSIONS", "BUILT_IN_VERSIONS", "get_version", "available_versions", "register_version"]

T = TypeVar("T")


class Registry(Generic[T]):
    """A name -> object map with lazy ``"module:attr"`` entries.

    Parameters
    ----------
    kind : str
        What the entries are, for messages ("version").
    entry_point_group : str, optional
        Entry points of this group are added (lazily, never replacing a built-in name) the first
        time the registry is read.
    """

    def __init__(self, kind: str, *, entry_point_group: str | None = None):
        self.kind = kind
        self.entry_point_group = entry_point_group
        self._entries: dict[str, Any] = {}
        self._lazy: dict[str, str] = {}
        self._frozen = False
        self._entry_points_loaded = entry_point_group is None
        self._lock = threading.RLock()

    # --- writing -------------------------------------------------------------------------
    def register(self, name: str, obj: Any = None, *, lazy: str | None = None,
                 replace: bool = False) -> Any:
        """Register ``obj`` (or the lazy target ``"module:attr"``) under ``name``.

        Without ``obj`` and ``lazy`` it returns a decorator. Raises ``ValueError`` for a taken
        name (unless ``replace``) and ``RuntimeError`` once frozen.
        """
        if obj is None and lazy is None:
            def decorator(target: Any) -> Any:
                self.register(name, target, replace=replace)
                return target
            return decorator
        if (obj is None) == (lazy is None):
            raise ValueError("give either an object or a lazy 'module:attr' string, not both")
        if not name or not isinstance(name, str) or name != name.strip():
            raise ValueError(f"bad {self.kind} name {name!r}")
        if lazy is not None and ":" not in lazy:
            raise ValueError(f"lazy target must read 'module:attr', got {lazy!r}")
        with self._lock:
            if self._frozen:
                raise RuntimeError(f"the {self.kind} registry is frozen; cannot add {name!r}")
            if not replace and (name in self._entries or name in self._lazy):
                raise ValueError(f"{self.kind} {name!r} is already registered")
            self._entries.pop(name, None)
            self._lazy.pop(name, None)
            if lazy is not None:
                self._lazy[name] = lazy
            else:
                self._entries[name] = obj
        return obj if obj is not None else lazy

    def freeze(self) -> None:
        """Refuse further registrations (after loading the entry points, so they stay visible)."""
        with self._lock:
            self._load_entry_points()
            self._frozen = True

    @property
    def frozen(self) -> bool:
        return self._frozen

    # --- reading -------------------------------------------------------------------------
    def _load_entry_points(self) -> None:
        if self._entry_points_loaded:
            return
        self._entry_points_loaded = True
        for ep in entry_points(group=self.entry_point_group):
            if ep.name not in self._entries and ep.name not in self._lazy:
                self._lazy[ep.name] = ep.value

    def names(self) -> list[str]:
        """Every registered name, sorted."""
        with self._lock:
            self._load_entry_points()
            return sorted(set(self._entries) | set(self._lazy))

    def __contains__(self, name: object) -> bool:
        return name in self.names()

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self.names())

    def get(self, name: str) -> T:
        """The object registered as ``name``, importing a lazy one on first use.

        Raises
        ------
        CassiInputError
            For an unknown name, suggesting close matches and listing every known name.
        """
        with self._lock:
            self._load_entry_points()
            if name in self._entries:
                return self._entries[name]
            if name in self._lazy:
                target = self._lazy[name]
                try:
                    obj = resolve(target)
                except (ImportError, AttributeError, ValueError) as err:
                    raise CassiInputError(
                        f"{self.kind} {name!r} is registered as {target!r}, which cannot be "
                        f"loaded: {type(err).__name__}: {err}") from err
                # Cache the resolved object (allowed when frozen: it is the same entry).
                self._entries[name] = obj
                del self._lazy[name]
                return obj
            known = self.names()
        raise CassiInputError(self.unknown_message(name, known))

    def unknown_message(self, name: str, known: list[str] | None = None) -> str:
        known = self.names() if known is None else known
        close = difflib.get_close_matches(str(name), known, n=3, cutoff=0.5)
        hint = f" Did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        return f"unknown {self.kind} {name!r}.{hint} Known: {', '.join(known) or '(none)'}."


#: The built-in versions, in the order the thesis compares them (Table C: "compared with the
#: previous version"): Parke's own face first, then CASSI 1.0, 2.0 and 2.1.
BUILT_IN_VERSIONS = MappingProxyType({"parke-1974": "cassi.versions.parke1974:Parke1974",
                                       "cassi-1.0": "cassi.versions.cassi10:Cassi10",
                                       "cassi-2.0": "cassi.versions.cassi20:Cassi20",
                                       "cassi-2.1": "cassi.versions.cassi21:Cassi21"})

#: The version registry: built-ins here, third-party ones from the ``cassi.versions`` group.
VERSIONS: Registry[Any] = Registry("version", entry_point_group="cassi.versions")
for _name, _target in BUILT_IN_VERSIONS.items():
    VERSIONS.register(_name, lazy=_target)


def register_version(name: str, obj: Any = None, *, lazy: str | None = None,
                     replace: bool = False) -> Any:
    """Register a version (class, factory or instance) at run time; see :class:`Registry`."""
    return VERSIONS.register(name, obj, lazy=lazy, replace=replace)


def available_versions() -> list[str]:
    """Names of every registered version, sorted."""
    return VERSIONS.names()


def get_version(name: str) -> Any:
    """A ready :class:`~cassi.versions.protocol.Version` for ``name``.

    A registered class (or zero-argument factory) is called; an object with ``animate`` is
    returned as it is. The instance's ``name`` is the registered name when it has none.
    """
    obj = VERSIONS.get(name)
    if isinstance(obj, type) or (callable(obj) and not hasattr(obj, "animate")):
        obj = obj()
    if not hasattr(obj, "animate"):
        raise CassiInputError(f"version {name!r} has no animate(profile, face, rec) method")
    if not getattr(obj, "name", None):
        try:
            obj.name = name
        except AttributeError:
            pass
    return obj
