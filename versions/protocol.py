"""The one protocol every CASSI version follows, and the staged pipeline the built-in versions
share.

A *version* turns one task recording into face vertex positions for every frame from the first
valid row on (thesis Figure 4.1: initialisation, then animation). The built-in versions are
:class:`StagedVersion` subclasses: a list of :class:`Stage` objects, each owning a part of the
face (jaw, lips, nose clearance, tongue). Every stage first *initialises* the starting face from
the first valid row (thesis 4.1.1), then *animates* all frames at once (frames as the leading
array axis, thesis 4.1.2). CASSI 2.0 is CASSI 1.0 with another lip stage; CASSI 2.1 is 2.0 with
another thickness rule inside that stage, so no version copies another's code.

Third-party versions only need :class:`Version` (a ``name`` and ``animate``); they need not use
the stages. A version that animates a face of its own (more or other vertices than the shared
face, for instance a tongue with thickness) also defines ``animated_face(face) -> FaceModel``:
the face it derives from the shared one and numbers its positions like. The harness renders and
checks every version's positions with :func:`version_face` (its own face, or the shared one), so
versions without the hook are untouched.
"""
from __future__ import annotations

import dataclasses
import inspect
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Iterator, Protocol, runtime_checkable

import numpy as np
import pandas as pd

from cassi.common.errors import CassiInputError
from cassi.versions.mapping import XrmbToParke
from cassi.data.face import numbering
from cassi.data.xrmb.files import PELLETS

if TYPE_CHECKING:  # only for annotations: the data layer owns these types
    from cassi.data.face.model import FaceModel
    from cassi.data.corpus.profile import SubjectProfile
    from cassi.data.xrmb.files import TaskRecording

__all__ = [
    "Animation",
    "Version",
    "Stage",
    "TaskContext",
    "StagedVersion",
    "PELLET_INDEX",
    "held_pellets",
    "version_face",
    "accepts_withheld",
]

#: Column of each pellet in ``TaskRecording.xy_mm`` (order of ``cassi.data.xrmb.files.PELLETS``).
PELLET_INDEX = {name: i for i, name in enumerate(PELLETS)}


@dataclass(frozen=True, eq=False)
class Animation:
    """The result of animating one task with one version.

    Attributes
    ----------
    version : str
        Registered name of the version that produced it.
    frames : int64 (F,)
        Rows of the recording animated: the first valid row and every row after it.
    time_us : int64 (F,)
        Time of each animated row, microseconds.
    positions : float32 (F, V, 3)
        Vertex positions in Parke units, numbered like ``FaceModel.vertices`` (row i is vertex
        i + 1), left half only.
    diagnostics : pandas.DataFrame
        One row per animated frame: ``frame`` (recording row), ``time_us``, jaw angle
        (``jaw_angle_rad``) and point of rotation (``jaw_point_x``, ``jaw_point_z``), the Table
        4.1 parameters ``param_55`` .. ``param_66``, ``held_<PELLET>`` flags for pellets held at
        their last valid value, and what later versions add (ellipse ``a``, ``b``, ``c``,
        ``c_prime``, ``currthick``, ``outer_abc_branch`` ...).
    """

    version: str
    frames: np.ndarray
    time_us: np.ndarray
    positions: np.ndarray
    diagnostics: pd.DataFrame

    def __post_init__(self) -> None:
        n = len(self.frames)
        if self.positions.ndim != 3 or self.positions.shape[0] != n or self.positions.shape[2] != 3:
            raise ValueError(f"positions must be (F={n}, V, 3), got {self.positions.shape}")
        if len(self.time_us) != n or len(self.diagnostics) != n:
            raise ValueError("frames, time_us and diagnostics must have one entry per frame")

    @property
    def n_frames(self) -> int:
        return int(len(self.frames))

    @property
    def n_vertices(self) -> int:
        return int(self.positions.shape[1])

    def vertex(self, number: int) -> np.ndarray:
        """Positions of Parke vertex ``number`` (1-based) over all frames, float32 (F, 3)."""
        return self.positions[:, number - 1, :]


@runtime_checkable
class Version(Protocol):
    """What the harness needs from a version: a name and ``animate``.

    Optional: ``animated_face(face) -> FaceModel``, the face the version animates when it is not
    the shared one (see :func:`version_face`); ``animate`` still receives the shared face.
    """

    name: str

    def animate(self, profile: "SubjectProfile", face: "FaceModel", rec: "TaskRecording") -> Animation:
        """Initialise from ``profile`` and the first valid row of ``rec``; animate every frame."""
        ...


def version_face(version: Any, face: "FaceModel") -> "FaceModel":
    """The face ``version`` animates, from the subject's shared ``face``.

    A version may define ``animated_face(face) -> FaceModel`` to animate a face of its own,
    derived from the shared one: the same vertices 1..V keep their meaning (the rubric, the
    fidelity measures and the jaw and lip stages address them by number), further vertices
    and other polygons may be added (a part's polygons are found by material). The
    version's ``Animation.positions`` are numbered like that face, and the harness renders and
    checks them with it. A version without the hook animates ``face`` itself.

    Parameters
    ----------
    version : Version
    face : FaceModel
        The subject's face (``cassi.data.face.model.build_face``).

    Returns
    -------
    FaceModel
        ``version.animated_face(face)``, or ``face``.

    Raises
    ------
    CassiInputError
        When the version's face drops or renumbers the shared face's vertices.
    """
    hook = getattr(version, "animated_face", None)
    if hook is None:
        return face
    own = hook(face)
    n = np.shape(face.vertices)[0]
    if np.shape(own.vertices)[0] < n:
        raise CassiInputError(f"version {getattr(version, 'name', version)!r} animates a face of "
                              f"{np.shape(own.vertices)[0]} vertices, fewer than the shared "
                              f"face's {n}: vertices 1..{n} must keep their numbers")
    return own


def held_pellets(xy_mm: np.ndarray, valid: np.ndarray, start: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``start:`` of the pellets, each invalid value replaced by that pellet's last valid one.

    Parameters
    ----------
    xy_mm : float64 (F, 8, 2)
        Pellet coordinates in mm (NaN where invalid).
    valid : bool (F, 8)
        Validity per row and pellet.
    start : int
        First row with all eight pellets valid (so every pellet has a value to hold).

    Returns
    -------
    held_xy : float64 (F - start, 8, 2)
    held : bool (F - start, 8)
        True where the value is a held one, for the diagnostics.
    """
    xy = np.asarray(xy_mm, dtype=np.float64)[start:]
    ok = np.asarray(valid, dtype=bool)[start:] & np.isfinite(xy).all(axis=-1)
    n = xy.shape[0]
    # Index of the last valid row at or before each row, per pellet (a running maximum).
    idx = np.where(ok, np.arange(n)[:, None], 0)
    np.maximum.accumulate(idx, axis=0, out=idx)
    out = np.take_along_axis(xy, idx[:, :, None], axis=0)
    return out, ~ok


@dataclass
class TaskContext:
    """Everything the stages of one ``animate`` call share.

    Attributes
    ----------
    profile, face, rec
        The inputs.
    mapping : XrmbToParke
        XRMB mm -> Parke units (thesis 4.1.1).
    rows : int64 (F,)
        Recording rows animated (first valid row on).
    pellets_mm : float64 (F, 8, 2)
        Pellets in XRMB mm, held where invalid.
    held : bool (F, 8)
    pellets : float64 (F, 8, 2)
        Pellets mapped to Parke (x, z).
    neutral : float64 (V, 3)
        The face as built (Parke's topology, the subject's palate).
    start : float64 (V, 3)
        The initialised face: written by the stages' ``initialise`` in order.
    diagnostics : dict[str, ndarray (F,)]
        Columns added by the stages.
    state : dict
        Values one stage leaves for a later one (for instance the jaw rotation per frame), and
        what a stage carries from one chunk of frames to the next.
    first : float64 (8, 2)
        The mapped pellets at the first valid row: the reference of every displacement, also
        in a window (:meth:`window`) that starts later.
    withheld : tuple of str
        Pellets the version animates without (leave-one-out, see
        :meth:`StagedVersion.animate_chunks`): their columns of ``pellets`` and ``pellets_mm``
        are what a stage's ``predict_withheld`` made of the others (NaN when no stage predicts
        one), ``held`` is True for them throughout.
    """

    profile: Any
    face: Any
    rec: Any
    mapping: "XrmbToParke"
    rows: np.ndarray
    pellets_mm: np.ndarray
    held: np.ndarray
    pellets: np.ndarray
    neutral: np.ndarray
    start: np.ndarray
    diagnostics: dict[str, np.ndarray] = field(default_factory=dict)
    state: dict[str, Any] = field(default_factory=dict)
    first: np.ndarray | None = None
    withheld: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.first is None:
            self.first = np.array(self.pellets[0], dtype=np.float64)

    @property
    def n_frames(self) -> int:
        return int(self.rows.shape[0])

    def pellet(self, name: str) -> np.ndarray:
        """Mapped pellet ``name`` over this context's frames, float64 (F, 2) Parke (x, z)."""
        return self.pellets[:, PELLET_INDEX[name], :]

    def first_pellet(self, name: str) -> np.ndarray:
        """Mapped pellet ``name`` at the first valid row, float64 (2,) Parke (x, z)."""
        return self.first[PELLET_INDEX[name]]

    def displacement(self, name: str) -> np.ndarray:
        """Pellet ``name`` minus its first-valid-row position, float64 (F, 2) Parke (x, z): the
        animation phase compares each line with the first one (thesis Figure 4.1)."""
        return self.pellet(name) - self.first_pellet(name)

    def window(self, start: int, stop: int) -> "TaskContext":
        """The frames ``start:stop`` of this context: same subject, start face and carried
        ``state``, its own ``diagnostics``."""
        sl = slice(start, stop)
        return dataclasses.replace(self, rows=self.rows[sl], pellets_mm=self.pellets_mm[sl],
                                   held=self.held[sl], pellets=self.pellets[sl], diagnostics={})


class Stage(Protocol):
    """One part of the face in a :class:`StagedVersion`.

    Optional: ``predicts`` (pellet names) and ``predict_withheld(ctx, name) -> float64 (F, 2)``
    Parke (x, z): where this stage's model puts pellet ``name``'s site from the other pellets,
    for a leave-one-out animation (``ctx.pellets[:, k]`` of a withheld pellet is NaN until then).
    """

    name: str

    def initialise(self, ctx: TaskContext) -> None:
        """Adjust ``ctx.start`` (float64 (V, 3)) for the subject and the first valid row."""
        ...

    def animate(self, ctx: TaskContext, positions: np.ndarray) -> None:
        """Write this stage's vertices of ``positions`` (float32 (F, V, 3), every frame starting
        as ``ctx.start`` plus what earlier stages wrote) in place, for all frames at once.
        Compute in float64 (``ctx.start`` is float64) and store; the store rounds to float32."""
        ...


class StagedVersion:
    """A version built from stages: initialise in order, then animate in order.

    Subclasses set ``name`` and return their stages from :meth:`stages`. Stages run in list
    order in both phases, so a later stage sees what earlier ones did (the nose clearance sees the
    placed lips; the 2.0 lips see the rotated teeth).
    """

    name: str = ""

    def stages(self) -> list[Stage]:  # pragma: no cover - abstract
        raise NotImplementedError

    # --- the shared skeleton (thesis Figure 4.1) ---------------------------------------------
    def context(self, profile: "SubjectProfile", face: "FaceModel", rec: "TaskRecording", *,
                withheld: tuple[str, ...] = ()) -> TaskContext:
        """Find the first valid row, hold missing pellets, map to Parke space (4.1.1), on the
        face this version animates (:func:`version_face`). A ``withheld`` pellet counts as
        missing in every row: the first valid row is the first with all the others valid, and
        its columns are NaN (the stages predict them, :meth:`animate_chunks`)."""
        face = version_face(self, face)
        unknown = sorted(set(withheld) - set(PELLET_INDEX))
        if unknown:
            raise CassiInputError(f"cannot withhold {', '.join(unknown)}: pellets are "
                                  f"{', '.join(PELLET_INDEX)}")
        out = [PELLET_INDEX[p] for p in withheld]

        xy_mm = np.asarray(rec.xy_mm)
        if xy_mm.ndim != 3 or xy_mm.shape[1:] != (8, 2):
            raise CassiInputError(f"pellets must be (F, 8, 2) mm, got {xy_mm.shape}",
                                  path=getattr(rec, "path", None))

        n_vertices = np.shape(face.vertices)[0]
        if n_vertices < numbering.CORNER_MIDDLE:
            raise CassiInputError(f"the face has {n_vertices} vertices; CASSI needs Parke's 287, "
                                  f"the tongue and vertex {numbering.CORNER_MIDDLE}")
        kept = np.delete(np.asarray(rec.valid, dtype=bool), out, axis=1).all(axis=1)
        if not kept.any():
            raise CassiInputError("no row with all eight pellets valid: nothing to animate"
                                  if not out else f"no row with every pellet but "
                                  f"{', '.join(withheld)} valid: nothing to animate",
                                  path=getattr(rec, "path", None))
        first = int(np.argmax(kept))
        xy, held = held_pellets(rec.xy_mm, rec.valid, first)
        xy[:, out] = np.nan                 # what the stages predict (_predict_withheld)
        held[:, out] = True
        neutral = np.array(face.vertices, dtype=np.float64)
        mapping = XrmbToParke.from_face(neutral, profile.jaw_length_mm)
        rows = np.arange(first, xy.shape[0] + first, dtype=np.int64)
        return TaskContext(profile=profile, face=face, rec=rec, mapping=mapping, rows=rows,
                           pellets_mm=xy, held=held, pellets=mapping.to_parke(xy), neutral=neutral,
                           start=neutral.copy(), withheld=tuple(withheld))

    def animate(self, profile: "SubjectProfile", face: "FaceModel", rec: "TaskRecording") -> Animation:
        return next(self.animate_chunks(profile, face, rec, frames=None))

    def animate_chunks(self, profile: "SubjectProfile", face: "FaceModel", rec: "TaskRecording",
                       *, frames: int | None, withheld: tuple[str, ...] = ()) -> Iterator[Animation]:
        """Animate ``frames`` frames at a time (None: all at once), one :class:`Animation` per
        chunk, in order; together they equal :meth:`animate` exactly (stages carry what a
        frame needs from the previous one in ``ctx.state``), in memory bounded by the chunk.

        ``withheld``: pellets animated without (leave-one-out): a stage that ``predicts`` one
        places it from the others (:meth:`Stage.predict_withheld`), and every stage then runs
        on that. A version none of whose stages reads the pellet (Parke's still tongue) needs no
        prediction; one that reads it unpredicted would animate NaN, which is refused."""
        ctx = self.context(profile, face, rec, withheld=withheld)
        stages = self.stages()
        _predict_withheld(ctx, stages)
        for stage in stages:            # initialisation phase: the subject's starting face
            stage.initialise(ctx)
        n = ctx.n_frames
        step = n if frames is None else int(frames)
        if step < 1:
            raise ValueError(f"frames per chunk must be at least 1, not {frames}")
        for a in range(0, n, step):
            window = ctx if step >= n else ctx.window(a, min(n, a + step))
            # float32 from the start: the result's dtype, and half the memory traffic of float64
            # on a long task (the stages compute in float64 and store here).
            positions = np.empty((window.n_frames,) + ctx.start.shape, dtype=np.float32)
            positions[...] = ctx.start
            for stage in stages:        # animation phase: every line against the first line
                stage.animate(window, positions)
            if withheld and not np.isfinite(positions).all():
                raise CassiInputError(f"{self.name} reads {', '.join(withheld)}, withheld, and "
                                      f"none of its stages predicts it")
            yield self.finish(window, positions)

    def finish(self, ctx: TaskContext, positions: np.ndarray) -> Animation:
        time_us = np.asarray(ctx.rec.time_us, dtype=np.int64)[ctx.rows]
        columns: dict[str, np.ndarray] = {"frame": ctx.rows, "time_us": time_us}
        for name, idx in PELLET_INDEX.items():
            columns[f"held_{name}"] = ctx.held[:, idx]
        columns.update(ctx.diagnostics)
        return Animation(version=self.name, frames=ctx.rows, time_us=time_us,
                         positions=positions.astype(np.float32, copy=False),
                         diagnostics=pd.DataFrame(columns))

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"


def _predict_withheld(ctx: TaskContext, stages: list) -> None:
    """Fill each withheld pellet's columns with the first stage's prediction that ``predicts``
    it (from the pellets kept), and the first row's reference with them."""
    for name in ctx.withheld:
        stage = next((s for s in stages if name in getattr(s, "predicts", ())), None)
        if stage is None:
            continue
        k = PELLET_INDEX[name]
        xz = np.asarray(stage.predict_withheld(ctx, name), dtype=np.float64)
        ctx.pellets[:, k] = xz
        ctx.pellets_mm[:, k] = ctx.mapping.to_xrmb(xz)
    ctx.first = np.array(ctx.pellets[0], dtype=np.float64)


def accepts_withheld(version: Any) -> bool:
    """Whether ``version`` can animate with pellets withheld (its ``animate_chunks`` takes
    ``withheld``): every :class:`StagedVersion` can; the protocol does not ask it of others."""
    chunks = getattr(version, "animate_chunks", None)
    if chunks is None:
        return False
    try:
        return "withheld" in inspect.signature(chunks).parameters
    except (TypeError, ValueError):
        return False
