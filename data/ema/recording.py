"""One EMA file through its coil map: an XRMB :class:`~cassi.data.xrmb.files.TaskRecording`.

The file's own sample times are kept (MOCHA-TIMIT: 500 Hz), rounded to whole microseconds. A
pellet is invalid (NaN, ``valid`` False: XRMB's missing pellet) where its coil is NaN, the frame
is an EST break, or a reference coil is missing (the head cannot be followed there).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError
from cassi.data.ema.coilmap import ORIGIN, CoilMap
from cassi.data.ema.derive import derive_pellets
from cassi.data.ema.est import read_est
from cassi.data.ema.headframe import frame_axes, head_correct, kabsch, to_head_frame
from cassi.data.ema.pos import read_pos
from cassi.data.ema.table import read_table
from cassi.data.ema.track import CoilTrack
from cassi.data.xrmb.files import PELLETS, TaskRecording

#: A valid pellet farther than this from the upper incisor means a wrong unit or a wrong coil
#: (as for XRMB frame sets, :mod:`cassi.data.xrmb.frames`).
MAX_ABS_MM = 200.0
_AXES = "xyz"


def read_track(path: str | os.PathLike, cmap: CoilMap) -> CoilTrack:
    """The file read by the reader its map's format names."""
    try:
        if cmap.format == "est":
            return read_est(path)
        if cmap.format == "pos":
            return read_pos(path, channels=cmap.channels, rate_hz=cmap.rate_hz)
        return read_table(path, delimiter="," if cmap.format == "csv" else "\t",
                          time_column=cmap.time_column, time_unit=cmap.time_unit)
    except OSError as err:
        raise CassiInputError(f"cannot read: {err.strerror or err}", path=path) from None


def coil_positions(track: CoilTrack, cmap: CoilMap, coil: str) -> np.ndarray:
    """float64 (F, D) mm of one coil: its declared channels, else ``<coil>_x, _y[, _z]``."""
    declared = cmap.coils.get(coil)
    if cmap.format == "pos":
        if declared is None:
            raise cmap.error(f"coil {coil!r} has no channel number under 'coils'", "coils")
        names = [f"{declared}_{a}" for a in _AXES]
    elif declared is not None:
        names = list(declared)
    else:
        names = [f"{coil}_{a}" for a in _AXES if f"{coil}_{a}" in track.channels]
    unknown = [n for n in names if n not in track.channels]
    if unknown or len(names) < 2:
        what = unknown[0] if unknown else f"{coil}_x, {coil}_y"
        more = ", ..." if len(track.channels) > 16 else ""
        raise cmap.error(f"coil {coil!r}: no channel {what} in {track.path} (channels: "
                         f"{', '.join(track.channels[:16])}{more})", *_where(cmap, coil))
    xyz = np.stack([track.column(n) for n in names], axis=1) * cmap.unit_mm
    xyz[~track.valid] = np.nan
    return xyz


def _where(cmap: CoilMap, coil: str) -> tuple[str, ...]:
    """The key path of the map line that names ``coil`` (for the error)."""
    if coil in cmap.coils:
        return ("coils", coil)
    for section in ("pellets", "references"):
        for key, value in getattr(cmap, section).items():
            if value == coil:
                return (section, key)
    return ("head_frame",)


def to_recording(track: CoilTrack, cmap: CoilMap, *, subject: str, task: int, rep: int = 1,
                 bite: CoilTrack | None = None, require_valid: bool = True) -> TaskRecording:
    """The recording in the XRMB head frame (see the module docstring)."""
    path = track.path
    if cmap.rate_hz is not None and track.rate_hz is not None and \
            abs(track.rate_hz - cmap.rate_hz) > 0.01 * cmap.rate_hz:
        raise CassiInputError(f"sampled at {track.rate_hz:.4g} Hz, the coil map says "
                              f"{cmap.rate_hz:g} Hz", path=path)
    head = in_head_frame(track, cmap, cmap.coil_names(), bite=bite)
    xy = np.full((track.n_frames, len(PELLETS), 2), np.nan)
    for pellet, coil in cmap.pellets.items():
        xy[:, PELLETS.index(pellet)] = head[coil]
    rule_coils = {r["coil"]: head[r["coil"]] for r in cmap.derive.values() if "coil" in r}
    derive_pellets(xy, cmap.derive, rule_coils)
    valid = np.isfinite(xy).all(axis=2)
    far = valid & (np.abs(xy) > MAX_ABS_MM).any(axis=2)
    if far.any():
        f, p = np.argwhere(far)[0]
        raise CassiInputError(f"pellet {PELLETS[p]} at {np.round(xy[f, p], 1).tolist()} mm in "
                              f"frame {f + 1}, farther than {MAX_ABS_MM:g} mm from the upper "
                              f"incisor: is unit_mm ({cmap.unit_mm:g}) right?", path=path)
    time_us = np.rint(track.time_s * 1e6).astype(np.int64)
    if (np.diff(time_us) <= 0).any():
        raise CassiInputError("samples closer than a microsecond", path=path)
    if require_valid and not valid.all(axis=1).any():
        never = [PELLETS[p] for p in range(len(PELLETS)) if not valid[:, p].any()]
        raise CassiInputError("no frame has all eight pellets valid" +
                              (f" (never valid: {', '.join(never)})" if never else ""), path=path)
    return TaskRecording(path=Path(path), subject=subject, task=task, rep=rep, time_us=time_us,
                         xy_mm=xy, valid=valid,
                         derived=tuple(p for p in PELLETS if p in cmap.derive))


def in_head_frame(track: CoilTrack, cmap: CoilMap, coils: list[str], *,
                  bite: CoilTrack | None = None) -> dict[str, np.ndarray]:
    """``{coil: float64 (F, 2) mm}`` in the XRMB head frame, head-corrected (``coils`` must
    include every coil the head frame needs: :meth:`CoilMap.coil_names`)."""
    positions = {c: coil_positions(track, cmap, c) for c in coils}
    dims = {c: v.shape[1] for c, v in positions.items()}
    if len(set(dims.values())) != 1:
        raise cmap.error(f"coils mix 2-D and 3-D channels: {dims}", "coils")
    d = next(iter(dims.values()))
    names = list(positions)
    stack = np.stack([positions[c] for c in names], axis=1)  # (F, N, D)
    refs = [c for c in cmap.references.values() if c != ORIGIN]
    template = {}
    if refs:
        if len(refs) < d:
            raise cmap.error(f"{d}-D coils need {d} reference coils or more to follow the head, "
                             f"the map names {len(refs)}", "references")
        try:
            stack, fitted, _ = head_correct(stack, stack[:, [names.index(c) for c in refs]])
        except CassiInputError as err:
            raise CassiInputError(err.reason, path=track.path) from None
        template = dict(zip(refs, fitted))
    origin, axes = _head_frame(cmap, stack, names, template, bite, d)
    return {c: to_head_frame(stack[:, k], origin, axes) for k, c in enumerate(names)}


def _head_frame(cmap, stack, names, template, bite, d) -> tuple[np.ndarray, np.ndarray]:
    """The head frame's origin and axes (rows) in head-corrected recording coordinates."""
    ui = cmap.references["upper_incisor"]
    origin = np.zeros(d) if ui == ORIGIN else template[ui]
    frame = cmap.head_frame
    if "occlusal" in frame:
        occ = frame["occlusal"]
        if "file" in occ:
            front, back = _bite_points(bite, cmap, template, d)
        else:
            front, back = (np.nanmean(stack[:, names.index(occ[k])], axis=0)
                           for k in ("front", "back"))
        refs = cmap.references
        lateral = None
        if "mastoid_left" in refs and "mastoid_right" in refs and d == 3:
            lateral = template[refs["mastoid_right"]] - template[refs["mastoid_left"]]
        up = template[refs["nose_bridge"]] if "nose_bridge" in refs else None
        if up is None:  # both mastoids: up is taken as the side of the mastoids' midpoint
            up = 0.5 * (template[refs["mastoid_right"]] + template[refs["mastoid_left"]])
        return origin, frame_axes(origin=origin, forward=front - back, toward_up=up,
                                  lateral=lateral)
    axes = np.zeros((d, d))
    rows = []
    for k, key in enumerate(("forward", "up")):
        spec = str(frame[key])
        axis = _AXES.index(spec[-1])
        if axis >= d:
            raise cmap.error(f"head_frame {key}: the coils have no {spec[-1]} axis",
                             "head_frame", key)
        sign = -1.0 if spec.startswith("-") else 1.0
        if len(spec) == 1:
            sign = _found_sign(stack, names, cmap, origin, axis, key)
        axes[k, axis] = sign
        rows.append(axis)
    if d == 3:
        axes[2, 3 - sum(rows)] = 1.0
    return origin, axes


def _found_sign(stack, names, cmap, origin, axis: int, key: str) -> float:
    """Forward: the sign that puts the upper incisor ahead of the tongue coils. Up: the sign
    that puts the nose bridge above the upper incisor."""
    if key == "forward":
        tongue = [cmap.pellets[p] for p in ("T1", "T2", "T3", "T4") if p in cmap.pellets]
        if not tongue:
            raise cmap.error("head_frame forward without a sign needs tongue coils", "head_frame")
        behind = np.nanmean(stack[:, [names.index(c) for c in tongue], axis])
        return 1.0 if origin[axis] > behind else -1.0
    nb = cmap.references.get("nose_bridge")
    if nb is None:
        raise cmap.error("head_frame up without a sign needs the nose bridge reference",
                         "head_frame", "up")
    return 1.0 if np.nanmean(stack[:, names.index(nb), axis]) > origin[axis] else -1.0


def _bite_points(bite, cmap, template, d) -> tuple[np.ndarray, np.ndarray]:
    """The bite plane's front and back coils, moved onto this recording's references."""
    if bite is None:
        raise cmap.error("the occlusal plane's file was not read", "head_frame", "occlusal")
    occ = cmap.head_frame["occlusal"]
    refs = [c for c in cmap.references.values() if c != ORIGIN]
    names = refs + [occ["front"], occ["back"]]
    stack = np.stack([coil_positions(bite, cmap, c) for c in names], axis=1)
    if stack.shape[2] != d:
        raise CassiInputError(f"{d}-D recordings, {stack.shape[2]}-D bite-plane file",
                              path=bite.path)
    try:
        stack, _, _ = head_correct(stack, stack[:, :len(refs)])
    except CassiInputError as err:
        raise CassiInputError(err.reason, path=bite.path) from None
    ok = np.isfinite(stack).all(axis=(1, 2))
    if not ok.any():
        raise CassiInputError("no frame has the references and both bite-plane coils valid",
                              path=bite.path)
    mean = stack[ok].mean(axis=0)
    rot, t = kabsch(mean[None, :len(refs)], np.stack([template[c] for c in refs]))
    moved = mean[len(refs):] @ rot[0].T + t[0]
    return moved[0], moved[1]
