"""The head-measures file: gonion and gnathion per subject.

The thesis (4.1.1, "Chin and Jaw Adjustments") shapes the jaw and chin from "the measured positions of
the gonion and gnathion, as given in the Headmeasures.txt file" but never prints that file. This
module defines its format for cassi-farm.

Format (``Headmeasures.txt``, cassi-farm head measures, version 1)
-------------------------------------------------------------------
Plain ASCII text, whitespace separated (tabs or spaces, LF or CRLF, final newline optional)::

    # cassi-farm head measures v1: XRMB head frame, micrometres
    Subject GONION_X GONION_Y GNATHION_X GNATHION_Y
    JW11    -81200   -49800   -6100      -41700
    JW12    -78400   -52300   -4300      -44900

- Lines starting with ``#`` are comments; blank lines are ignored.
- The header line ``Subject GONION_X GONION_Y GNATHION_X GNATHION_Y`` is optional (any case).
- Every other line: subject name (letters and digits, e.g. ``JW45``) and four numbers, the
  gonion (angle of the jaw) x, y and gnathion (point of the chin) x, y, in micrometres, in the same
  XRMB head frame as the task files (thesis 3.2.3: origin between the tips of the upper central
  incisors, +x out of the mouth along the maxillary occlusal plane, +y toward the roof of the
  mouth), so both points lie below the origin (negative y) and the gonion behind the gnathion
  (a prominent chin may put the gnathion's x slightly in front of the incisors, x > 0); a row
  that breaks this is refused. Integers, like the other XRMB files; decimals are read too.
- One line per subject; a subject listed twice is an error.

The file may sit in the corpus root (all subjects) or in a subject's directory (that subject; it
takes precedence). :func:`read_head_measures` returns ``{subject: HeadMeasures}`` with millimetres.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.data.subject_name import SUBJECT_NAME_RE
from cassi.data.xrmb.textlines import decode_ascii, parse_num, read_bytes, split_lines, tokens

HEAD_MEASURES_FILE = "Headmeasures.txt"
HEADER = ("SUBJECT", "GONION_X", "GONION_Y", "GNATHION_X", "GNATHION_Y")
_MAX_ABS_UM = 500_000


@dataclass(frozen=True, eq=False)
class HeadMeasures:
    """Gonion and gnathion of one subject.

    Attributes
    ----------
    gonion_mm : float64 (2,)
        Angle of the jaw, (x, y) mm in the XRMB head frame.
    gnathion_mm : float64 (2,)
        Point of the chin, (x, y) mm in the XRMB head frame.
    """

    gonion_mm: np.ndarray
    gnathion_mm: np.ndarray

    def __eq__(self, other):
        if not isinstance(other, HeadMeasures):
            return NotImplemented
        return (np.array_equal(self.gonion_mm, other.gonion_mm)
                and np.array_equal(self.gnathion_mm, other.gnathion_mm))

    __hash__ = None  # mutable arrays inside


def parse_head_measures(data: bytes | str, *,
                        path: str | os.PathLike | None = None) -> dict[str, HeadMeasures]:
    """Parse head-measures text (see the module docstring) -> ``{subject: HeadMeasures}``."""
    text = decode_ascii(data, path=path)
    out: dict[str, HeadMeasures] = {}
    seen_line: dict[str, int] = {}
    for line_no, line in enumerate(split_lines(text), start=1):
        if line.lstrip().startswith("#"):
            continue
        toks = tokens(line)
        if not toks:
            continue
        if tuple(t.upper() for t in toks) == HEADER:
            if out:
                raise CassiInputError("header line after data lines", path=path, line=line_no)
            continue
        if len(toks) != 5:
            raise CassiInputError(
                f"expected 5 columns (subject gonion_x gonion_y gnathion_x gnathion_y), found "
                f"{len(toks)}", path=path, line=line_no)
        subject = toks[0]
        if not SUBJECT_NAME_RE.fullmatch(subject):
            raise CassiInputError(f"bad subject name {subject[:40]!r}", path=path, line=line_no)
        key = subject.upper()
        if key in seen_line:
            raise CassiInputError(f"subject {subject} listed twice (first at line "
                                  f"{seen_line[key]})", path=path, line=line_no)
        vals = [parse_num(t, what=f"column {k} ({HEADER[k - 1].lower()})", path=path, line=line_no)
                for k, t in enumerate(toks[1:], start=2)]
        if any(abs(v) > _MAX_ABS_UM for v in vals):
            raise CassiInputError("coordinate implausibly far from the origin (micrometres "
                                  "expected)", path=path, line=line_no)
        gox, goy, gnx, gny = vals
        if not (goy < 0 and gny < 0 and gox < gnx):
            raise CassiInputError(f"gonion ({gox:g}, {goy:g}) and gnathion ({gnx:g}, {gny:g}) um "
                                  f"are not a jaw: both lie below the incisor tips (y < 0), the "
                                  f"gonion behind the gnathion", path=path, line=line_no)
        seen_line[key] = line_no
        arr = np.asarray(vals, dtype=np.float64) / 1000.0
        out[key] = HeadMeasures(gonion_mm=arr[:2].copy(), gnathion_mm=arr[2:].copy())
    return out


def read_head_measures(path: str | os.PathLike) -> dict[str, HeadMeasures]:
    """Read a head-measures file -> ``{SUBJECT: HeadMeasures}`` (subject names upper-cased)."""
    return parse_head_measures(read_bytes(path), path=path)


def format_head_measures(measures: dict[str, HeadMeasures]) -> str:
    lines = ["# cassi-farm head measures v1: XRMB head frame, micrometres",
             "Subject GONION_X GONION_Y GNATHION_X GNATHION_Y"]
    for subject in sorted(measures):
        if not SUBJECT_NAME_RE.fullmatch(subject):
            raise CassiInputError(f"bad subject name {subject!r}")
        hm = measures[subject]
        vals = np.concatenate([np.asarray(hm.gonion_mm, float).reshape(2),
                               np.asarray(hm.gnathion_mm, float).reshape(2)])
        if not np.isfinite(vals).all():
            raise CassiInputError(f"{subject}: non-finite head measure")
        um = np.rint(vals * 1000.0).astype(np.int64).tolist()
        lines.append(f"{subject} {um[0]} {um[1]} {um[2]} {um[3]}")
    return "\n".join(lines) + "\n"


def write_head_measures(path: str | os.PathLike, measures: dict[str, HeadMeasures]) -> None:
    """Write a head-measures file (atomic), subjects sorted, values rounded to micrometres."""
    atomic_write_text(path, format_head_measures(measures))
