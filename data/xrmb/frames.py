"""Frame sets: XRMB pellet frames kept as one matrix, without times.

Some public sets keep a speaker's XRMB frames as a plain array, one row per frame: 16 columns,
the (x, y) of UL LL T1 T2 T3 T4 MNI MNM (:data:`~cassi.data.xrmb.files.PELLETS`) in the XRMB
head frame, in millimetres (a task file's columns without the time, and in mm, not micrometres).
An example is the 43,260 frames of the speaker JW11 that Qin & Carreira-Perpiñán (ICASSP 2010)
took from the Wisconsin XRMB database (``dat/jw11.mat`` of the repository
eecqin/TongueReconstruction). The rows of such a set need not be consecutive, so only
distributions can be taken from them (:func:`cassi.data.corpus.stats.frame_set_stats`).

Read from a NumPy ``.npy`` file or a MATLAB ``.mat`` file (up to version 7.2; the file's one
array with 16 columns); NaN marks a bad value.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.files import PELLETS

__all__ = ["FRAME_SET_SUFFIXES", "is_frame_set", "read_frames"]

FRAME_SET_SUFFIXES = (".npy", ".mat")
_COLUMNS = 2 * len(PELLETS)
#: No pellet of the head frame lies this far (mm) from the incisors: larger values are
#: micrometres or bad-value markers (1000000), not millimetres.
_MAX_ABS_MM = 200.0


def is_frame_set(path: Path) -> bool:
    """Whether ``path`` names a frame set by its suffix (.npy, .mat; any case)."""
    return Path(path).suffix.lower() in FRAME_SET_SUFFIXES


def _mat_array(path: Path) -> np.ndarray:
    try:
        variables = scipy.io.loadmat(path)
    except NotImplementedError as err:      # MATLAB 7.3 files are HDF5
        raise CassiInputError(f"cannot read this .mat version ({err}); save it with "
                              "-v7 or as .npy", path=path) from None
    except (ValueError, TypeError, OSError) as err:
        raise CassiInputError(f"not a readable .mat file ({err})", path=path) from None
    arrays = {k: v for k, v in variables.items() if not k.startswith("__")
              and isinstance(v, np.ndarray) and v.ndim == 2 and v.shape[1] == _COLUMNS
              and np.issubdtype(v.dtype, np.number)}
    if len(arrays) != 1:
        names = ", ".join(f"{k} {getattr(v, 'shape', '')}" for k, v in variables.items()
                          if not k.startswith("__")) or "none"
        raise CassiInputError(f"expected exactly one array with {_COLUMNS} columns "
                              f"(frames x UL..MNM x, y in mm); variables: {names}", path=path)
    return next(iter(arrays.values()))


def read_frames(path) -> np.ndarray:
    """A frame set as float64 ``(F, 8, 2)`` millimetres (NaN where a value is bad).

    Raises
    ------
    CassiInputError : not a .npy/.mat file, unreadable, not ``(F, 16)`` numbers, or values
        beyond 200 mm (micrometres or bad-value markers, not millimetres).
    """
    p = Path(path)
    if not p.is_file():
        raise CassiInputError("not found", path=p)
    suffix = p.suffix.lower()
    if suffix == ".mat":
        raw = _mat_array(p)
    elif suffix == ".npy":
        try:
            raw = np.load(p, allow_pickle=False)
        except (ValueError, OSError) as err:
            raise CassiInputError(f"not a readable .npy file ({err})", path=p) from None
    else:
        raise CassiInputError("a frame set is a .npy or .mat file", path=p)
    if raw.ndim != 2 or raw.shape[1] != _COLUMNS or not np.issubdtype(raw.dtype, np.number):
        raise CassiInputError(f"expected frames x {_COLUMNS} numbers (x, y of "
                              f"{' '.join(PELLETS)} in mm), got {raw.shape} {raw.dtype}", path=p)
    xy = raw.astype(np.float64).reshape(-1, len(PELLETS), 2)
    big = np.abs(xy) > _MAX_ABS_MM
    if big.any():
        row = int(np.flatnonzero(big.any(axis=(1, 2)))[0])
        raise CassiInputError(f"frame {row + 1}: a coordinate beyond {_MAX_ABS_MM:.0f} mm "
                              "(frame sets are in millimetres; mark bad values NaN)", path=p)
    if not np.isfinite(xy).all(axis=2).all(axis=1).any():
        raise CassiInputError("no frame has all eight pellets valid", path=p)
    return xy
