"""Parke's face files: ``st1.pts`` / ``st2.pts`` (vertices) and ``stt.top`` (polygons).

Formats (thesis 3.1.1, Figures 3.2 and 3.3)::

    st1.pts - first vertices set FIP 10 May 90      <- description
    287 275                                         <- vertex count, vertices defined in the file
    1 45 0 -594                                     <- number x y z (Parke units)
    ...

    stt.top - simple face topology file FIP 10 May 90
    254                                             <- polygon count
    4 222.1 212.1 190.1                             <- material, 3 or 4 vertex numbers;
    4 223 224 225 226                                  ".1" selects a crease normal
    ...

Readers accept what real files in the wild contain (CRLF, tabs, runs of spaces, blank lines,
no newline at the end, integers or decimals) and raise :class:`CassiInputError` naming the file
and line for anything else. Writers are atomic and round-trip exactly (floats are written in
their shortest repr, integral values as integers, as Parke's files have them).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from os import PathLike

import numpy as np

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.data.xrmb.textlines import parse_int, read_bytes


@dataclass(frozen=True)
class Polygon:
    """One polygon of ``stt.top``.

    Attributes
    ----------
    material : int
        Parke's material number (1 flesh, 2 lips, 3 eyelash, 4 teeth; 5.. added by this project).
    vertices : tuple[int, ...]
        1-based vertex numbers in the file's order (3 or 4).
    crease : tuple[int, ...]
        Per vertex the suffix after the dot (``222.1`` -> 1), 0 where none: which of a crease
        vertex's normals the polygon uses.
    """

    material: int
    vertices: tuple[int, ...]
    crease: tuple[int, ...] = ()

    def __post_init__(self):
        if not self.crease:
            object.__setattr__(self, "crease", (0,) * len(self.vertices))
        if len(self.crease) != len(self.vertices):
            raise ValueError("crease flags must match the vertices")


@dataclass(frozen=True, eq=False)
class PtsFile:
    """Contents of a ``.pts`` file.

    Attributes
    ----------
    description : str
        The first line.
    vertices : float64 (N, 3)
        Row ``i`` is vertex ``i + 1``; NaN rows for vertices the file does not define.
    defined : bool (N,)
        Which vertices the file defines.
    """

    description: str
    vertices: np.ndarray
    defined: np.ndarray = field(default=None)

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices must be (N, 3), not {v.shape}")
        object.__setattr__(self, "vertices", v)
        d = ~np.isnan(v).any(axis=1) if self.defined is None else np.asarray(self.defined, bool)
        object.__setattr__(self, "defined", d)

    @property
    def count(self) -> int:
        return int(self.vertices.shape[0])


@dataclass(frozen=True)
class TopFile:
    """Contents of a ``.top`` file: the description line and the polygons in file order."""

    description: str
    polygons: tuple[Polygon, ...]


#: Parke's numbers as his files write them (ASCII digits; an exponent as ``repr`` writes one).
_NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]{1,3})?", re.ASCII)
#: No face has more vertices than this (Parke's has 287, cassi-farm's under 1,000): a larger
#: header count is a damaged file, not a face to allocate.
MAX_VERTICES = 1_000_000


def _lines(path: str | PathLike) -> list[str]:
    raw = read_bytes(path)  # regular files only, with the project's size limit
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _number(tok: str, path, line: int, what: str) -> float:
    if not _NUMBER_RE.fullmatch(tok):
        raise CassiInputError(f"{what} {tok[:40]!r} is not a number", path=path, line=line)
    v = float(tok)
    if not np.isfinite(v):
        raise CassiInputError(f"{what} {tok!r} is not finite", path=path, line=line)
    return v


def _int(tok: str, path, line: int, what: str) -> int:
    if len(tok) > 12:  # no count or number of a face runs to 13 digits
        raise CassiInputError(f"{what}: {tok[:40]!r} is not an integer", path=path, line=line)
    return parse_int(tok, what=what, path=path, line=line)


def read_pts(path: str | PathLike, *, strict: bool = True) -> PtsFile:
    """Read a Parke vertex file (``st1.pts`` / ``st2.pts``).

    ``strict=False`` accepts a file with fewer vertex lines than its header declares (an
    excerpt, like the thesis's Figure 3.2); every line present is still checked.

    Returns
    -------
    PtsFile
        With ``vertices`` float64 (N, 3), N from the header's first number; undefined vertices NaN.

    Raises
    ------
    CassiInputError
        Missing header, a malformed line, a vertex number outside 1..N or defined twice, or a
        count of defined vertices different from the header's second number.
    """
    lines = _lines(path)
    if not lines or not lines[0].strip() and len(lines) < 2:
        raise CassiInputError("empty file: expected a description line", path=path, line=1)
    description = lines[0].rstrip()
    k = 1
    while k < len(lines) and not lines[k].strip():
        k += 1
    if k >= len(lines):
        raise CassiInputError("missing the 'count defined' line", path=path, line=2)
    head = lines[k].split()
    if len(head) not in (1, 2):
        raise CassiInputError(f"expected 'vertex-count defined-count', got {lines[k].strip()!r}",
                              path=path, line=k + 1)
    total = _int(head[0], path, k + 1, "vertex count")
    declared = _int(head[1], path, k + 1, "defined count") if len(head) == 2 else None
    if total <= 0 or (declared is not None and not 0 <= declared <= total):
        raise CassiInputError(f"bad counts {lines[k].strip()!r}", path=path, line=k + 1)
    if total > MAX_VERTICES:
        raise CassiInputError(f"vertex count {total} is beyond any face's ({MAX_VERTICES})",
                              path=path, line=k + 1)
    verts = np.full((total, 3), np.nan)
    seen = np.zeros(total, bool)
    for i in range(k + 1, len(lines)):
        toks = lines[i].split()
        if not toks:
            continue
        if len(toks) != 4:
            raise CassiInputError(f"expected 'number x y z', got {lines[i].strip()!r}",
                                  path=path, line=i + 1)
        n = _int(toks[0], path, i + 1, "vertex number")
        if not 1 <= n <= total:
            raise CassiInputError(f"vertex number {n} outside 1..{total}", path=path, line=i + 1)
        if seen[n - 1]:
            raise CassiInputError(f"vertex {n} defined twice", path=path, line=i + 1)
        verts[n - 1] = [_number(t, path, i + 1, "coordinate") for t in toks[1:]]
        seen[n - 1] = True
    if strict and declared is not None and int(seen.sum()) != declared:
        raise CassiInputError(f"header says {declared} vertices are defined, file has "
                              f"{int(seen.sum())}", path=path, line=k + 1)
    return PtsFile(description, verts, seen)


def _fmt(v: float) -> str:
    v = float(v)
    if v == int(v) and abs(v) < 1e15:
        return str(int(v))
    return repr(v)


def write_pts(path: str | PathLike, pts: PtsFile | np.ndarray, description: str | None = None,
              *, defined: np.ndarray | None = None) -> None:
    """Write a Parke vertex file atomically.

    Parameters
    ----------
    pts
        A :class:`PtsFile` or float (N, 3) vertices (NaN rows are left out as undefined).
    description
        First line; defaults to the PtsFile's or ``"cassi-farm face vertices"``.
    defined
        Optional bool (N,) mask of vertices to write (default: the non-NaN rows).
    """
    if isinstance(pts, PtsFile):
        verts, mask = pts.vertices, pts.defined if defined is None else defined
        description = pts.description if description is None else description
    else:
        verts = np.asarray(pts, dtype=np.float64)
        mask = ~np.isnan(verts).any(axis=1) if defined is None else np.asarray(defined, bool)
    description = "cassi-farm face vertices" if description is None else description
    if "\n" in description or "\r" in description:
        raise CassiInputError("description must be one line")
    out = [description, f"{len(verts)} {int(mask.sum())}"]
    for i in np.flatnonzero(mask):
        x, y, z = verts[i]
        out.append(f"{i + 1} {_fmt(x)} {_fmt(y)} {_fmt(z)}")
    atomic_write_text(path, "\n".join(out) + "\n")


def read_top(path: str | PathLike, *, vertex_count: int | None = None,
             strict: bool = True) -> TopFile:
    """Read a Parke topology file (``stt.top``).

    Parameters
    ----------
    vertex_count
        When given, vertex numbers above it are an error.
    strict
        False accepts fewer polygon lines than the header declares (an excerpt).

    Raises
    ------
    CassiInputError
        A malformed line, fewer than 3 vertices, a bad vertex number, or a polygon count
        different from the header's.
    """
    lines = _lines(path)
    description = lines[0].rstrip() if lines else ""
    k = 1
    while k < len(lines) and not lines[k].strip():
        k += 1
    if k >= len(lines) or not lines[k].strip():
        raise CassiInputError("missing the polygon count line", path=path, line=2)
    head = lines[k].split()
    if len(head) != 1:
        raise CassiInputError(f"expected the polygon count, got {lines[k].strip()!r}",
                              path=path, line=k + 1)
    count = _int(head[0], path, k + 1, "polygon count")
    polys = []
    for i in range(k + 1, len(lines)):
        toks = lines[i].split()
        if not toks:
            continue
        if not 4 <= len(toks) <= 5:  # Parke's polygons are triangles and quads
            raise CassiInputError(f"expected 'material v v v [v]', got {lines[i].strip()!r}",
                                  path=path, line=i + 1)
        mat = _int(toks[0], path, i + 1, "material")
        if mat < 1:
            raise CassiInputError(f"material {mat} is not a material number (1, 2, ...)",
                                  path=path, line=i + 1)
        vs, cs = [], []
        for t in toks[1:]:
            num, dot, crease = t.partition(".")
            n = _int(num, path, i + 1, "vertex number")
            c = _int(crease, path, i + 1, "crease suffix") if dot else 0
            if n < 1 or (vertex_count is not None and n > vertex_count):
                raise CassiInputError(f"vertex number {n} out of range", path=path, line=i + 1)
            if c < 0:
                raise CassiInputError(f"bad crease suffix in {t!r}", path=path, line=i + 1)
            vs.append(n)
            cs.append(c)
        if len(set(vs)) != len(vs):
            raise CassiInputError(f"polygon repeats a vertex: {lines[i].strip()!r}",
                                  path=path, line=i + 1)
        polys.append(Polygon(mat, tuple(vs), tuple(cs)))
    if len(polys) != count and (strict or len(polys) > count):
        raise CassiInputError(f"header says {count} polygons, file has {len(polys)}",
                              path=path, line=k + 1)
    return TopFile(description, tuple(polys))


def write_top(path: str | PathLike, top: TopFile | list[Polygon],
              description: str | None = None) -> None:
    """Write a Parke topology file atomically (same layout as :func:`read_top` reads)."""
    if isinstance(top, TopFile):
        polys = top.polygons
        description = top.description if description is None else description
    else:
        polys = tuple(top)
    description = "cassi-farm face topology" if description is None else description
    if "\n" in description or "\r" in description:
        raise CassiInputError("description must be one line")
    out = [description, str(len(polys))]
    for p in polys:
        toks = [str(int(p.material))]
        for v, c in zip(p.vertices, p.crease):
            toks.append(f"{int(v)}.{int(c)}" if c else str(int(v)))
        out.append(" ".join(toks))
    atomic_write_text(path, "\n".join(out) + "\n")
