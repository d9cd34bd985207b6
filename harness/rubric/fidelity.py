"""Table F, fidelity to the recording (cassi-farm's addition, not the thesis's).

The thesis's judges saw speech moving; a face that stands still commits none of Tables A-E's
geometric faults (Tables C and E judge its movement with the ranges below: ``tract_reach``).
Here the model's pellet sites -- 67 (UL), 49 (LL), 289-292 (T1-T4), 258 (MNI) and the
midpoint of 281 and 286 (MNM) -- are mapped back into the XRMB frame in millimetres with the
thesis's own mapping (:class:`cassi.versions.mapping.XrmbToParke`, section 4.1.1) and compared,
frame by frame, with the pellets the version animated.

Movement, not placement, is compared: both the virtual and the measured pellets are taken as
displacements from the first animated frame. Where the face starts is judged by Tables A, B and
D (the thesis's initialization); Table F asks whether it then does what the recording says.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from cassi.data.face import numbering as N
from cassi.data.face.model import jaw_pellet_sites
from cassi.data.xrmb.files import PELLETS
from cassi.common.errors import CassiInputError

from cassi.harness.rubric.frames import Frames
from cassi.harness.rubric.model import Measurement
from cassi.harness.rubric.registry import FIDELITY_MIN_RANGE_MM, RANGE_PERCENTILES

__all__ = ["ARTICULATORS", "TRACT_VARIABLES", "FidelityContext", "virtual_pellets",
           "tract_variables", "traces", "m_lips_error", "m_tongue_error", "m_jaw_error", "m_lip_aperture",
           "m_lip_aperture_range", "m_lip_protrusion", "m_jaw_opening", "m_jaw_opening_range",
           "m_lip_aperture_reach", "m_jaw_opening_reach"]

#: Which pellets make each articulator of Table F.
ARTICULATORS = {"lips": ("UL", "LL"), "tongue": ("T1", "T2", "T3", "T4"), "jaw": ("MNI", "MNM")}
#: Tract variables (XRMB frame, mm): name -> description.
TRACT_VARIABLES = {"lip_aperture": "UL y - LL y", "lip_protrusion": "(UL x + LL x) / 2",
                   "jaw_opening": "-MNI y"}


def virtual_pellets(positions: np.ndarray, mapping) -> np.ndarray:
    """The model's pellet sites in the XRMB frame.

    Parameters
    ----------
    positions : float (F, V, 3)
        Parke units (row i = vertex i + 1).
    mapping : cassi.versions.mapping.XrmbToParke
        The subject's map (scale p/d, origin at vertex 226).

    Returns
    -------
    float64 (F, 8, 2)
        x forward, y up, mm, pellets in :data:`PELLETS` order.
    """
    pos = np.asarray(positions, np.float64)
    rows = [N.UL, N.LL, *N.TONGUE_PELLETS]
    mani, manm = jaw_pellet_sites(pos)
    xz = np.concatenate([pos[:, [r - 1 for r in rows]][..., [0, 2]], mani[:, None], manm[:, None]],
                        axis=1)
    return mapping.to_xrmb(xz)


def tract_variables(xy: np.ndarray) -> dict[str, np.ndarray]:
    """Lip aperture, lip protrusion and jaw opening (mm, (F,) each) from pellets (F, 8, 2)."""
    ul, ll, mni = xy[:, 0], xy[:, 1], xy[:, 6]
    return {"lip_aperture": ul[:, 1] - ll[:, 1], "lip_protrusion": 0.5 * (ul[:, 0] + ll[:, 0]),
            "jaw_opening": -mni[:, 1]}


@dataclass
class FidelityContext:
    """Virtual and measured pellets of one animation, as displacements from the first frame.

    Only the displacements are kept (every measure here is a movement, a correlation or a
    range, none of which needs the absolute position), so a long task holds two (F, 8, 2)
    arrays and the error, not five.

    Attributes
    ----------
    model_moves, data_moves : float64 (F, 8, 2)
        mm, XRMB frame, minus the first animated frame; ``data_moves`` is NaN where the pellet
        was not valid.
    frames : int64 (F,)
        Recording rows.
    """

    model_moves: np.ndarray
    data_moves: np.ndarray
    frames: np.ndarray

    @classmethod
    def of(cls, anim, recording, mapping) -> "FidelityContext":
        """From an Animation, the TaskRecording it animated and the subject's XrmbToParke."""
        frames = np.asarray(anim.frames, np.int64)
        xy = np.asarray(recording.xy_mm, np.float64)
        if frames.size == 0 or frames.max() >= xy.shape[0] or frames.min() < 0:
            raise CassiInputError(f"the animation's frames ({frames.min() if frames.size else '-'}.."
                                  f"{frames.max() if frames.size else '-'}) are not rows of the "
                                  f"recording ({xy.shape[0]} rows)",
                                  path=getattr(recording, "path", None))
        data = xy[frames]  # fancy indexing: a copy, changed in place below
        data[~np.asarray(recording.valid, bool)[frames]] = np.nan
        positions = anim.positions
        model = (positions.series(virtual_pellets, mapping) if isinstance(positions, Frames)
                 else virtual_pellets(positions, mapping))
        data -= data[0].copy()
        model -= model[0].copy()
        return cls(model_moves=model, data_moves=data, frames=frames)

    @functools.cached_property
    def error(self) -> np.ndarray:
        """float (F, 8): distance between the model's and the data's movement, mm (NaN where the
        pellet was not valid)."""
        d = self.model_moves - self.data_moves
        np.square(d, out=d)
        return np.sqrt(d.sum(axis=-1))  # what np.linalg.norm(axis=-1) computes, one temporary less


def traces(ctx: FidelityContext, *, step: int) -> list[dict]:
    """Every ``step``-th frame's tract variables, model and data (mm, displacement from the first
    frame), as results-table rows: view ``trace``, check ``trace_<variable>_<model|data>``, no
    table, never charged (the report's "model vs data" plot)."""
    m, d = tract_variables(ctx.model_moves), tract_variables(ctx.data_moves)
    rows = []
    for name in TRACT_VARIABLES:
        for side, series in (("model", m[name]), ("data", d[name])):
            for i in range(0, len(ctx.frames), step):
                rows.append(dict(view="trace", frame=int(ctx.frames[i]),
                                 check=f"trace_{name}_{side}", table=None, component=None,
                                 value=float(series[i]), unit="mm", threshold=float("nan"),
                                 detail=""))
    return rows


def articulator_error(ctx: FidelityContext, articulator: str) -> Measurement:
    """RMSE, 95th percentile and worst frame of one articulator's pellets (mm)."""
    idx = [PELLETS.index(p) for p in ARTICULATORS[articulator]]
    e = ctx.error[:, idx]
    ok = np.isfinite(e)
    if not ok.any():
        return Measurement(float("nan"), -1, "no valid pellet to compare with")
    per_frame = np.where(ok, e, -np.inf).max(axis=1)
    f = int(np.argmax(per_frame))
    rmse = float(np.sqrt(np.mean(e[ok] ** 2)))
    p95 = float(np.percentile(e[ok], 95))
    return Measurement(rmse, f, f"RMSE {rmse:.2f} mm, 95th percentile {p95:.2f} mm, worst "
                                f"{per_frame[f]:.2f} mm ({', '.join(ARTICULATORS[articulator])})",
                       frame_value=float(per_frame[f]))


def _both(ctx: FidelityContext, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    m = tract_variables(ctx.model_moves)[name]
    d = tract_variables(ctx.data_moves)[name]
    ok = np.isfinite(d) & np.isfinite(m)
    return m, d, ok


def _spread(x: np.ndarray) -> float:
    """The range of ``x`` (``RANGE_PERCENTILES``), 0 when empty."""
    if not x.size:
        return 0.0
    lo, hi = np.percentile(x, RANGE_PERCENTILES)
    return float(hi - lo)


def tract_correlation(ctx: FidelityContext, name: str) -> Measurement:
    """Pearson r of the model's and the data's tract variable; a model that does not move
    scores 0 (it shares no movement with the speaker)."""
    m, d, ok = _both(ctx, name)
    if ok.sum() < 3 or _spread(d[ok]) < FIDELITY_MIN_RANGE_MM:
        return Measurement(float("nan"), -1, f"the recording's {name.replace('_', ' ')} moves less "
                                             f"than {FIDELITY_MIN_RANGE_MM} mm: nothing to follow")
    mo, do = m[ok], d[ok]
    r = 0.0 if np.ptp(mo) == 0 else float(np.corrcoef(mo, do)[0, 1])
    miss = np.abs((mo - mo.mean()) - (do - do.mean()))
    f = int(np.flatnonzero(ok)[np.argmax(miss)])
    return Measurement(r, f, f"{name.replace('_', ' ')} ({TRACT_VARIABLES[name]}): r = {r:.2f}; "
                             f"frame shown: largest difference from the recording",
                       frame_value=r)


def _reach(ctx: FidelityContext, name: str):
    """(q, model range, data range, frame of the recording's extreme): q = model range / data
    range (5th-95th percentile); None where the recording gives nothing to follow."""
    m, d, ok = _both(ctx, name)
    if ok.sum() < 3 or _spread(d[ok]) < FIDELITY_MIN_RANGE_MM:
        return None
    dm, dd = _spread(m[ok]), _spread(d[ok])
    f = int(np.flatnonzero(ok)[np.argmax(np.abs(d[ok] - np.median(d[ok])))])
    return dm / dd, dm, dd, f


def _still(name: str) -> Measurement:
    return Measurement(float("nan"), -1, f"the recording's {name.replace('_', ' ')} moves less "
                                         f"than {FIDELITY_MIN_RANGE_MM} mm: nothing to follow")


def tract_range(ctx: FidelityContext, name: str) -> Measurement:
    """Range agreement min(q, 1/q), q = model range / data range (5th-95th percentile)."""
    r = _reach(ctx, name)
    if r is None:
        return _still(name)
    q, dm, dd, f = r
    agree = min(q, 1.0 / q) if q > 0 else 0.0
    return Measurement(agree, f, f"{name.replace('_', ' ')} range: model {dm:.1f} mm, recording "
                                 f"{dd:.1f} mm (ratio {q:.2f}); frame shown: the recording's extreme",
                       frame_value=agree)


def tract_reach(ctx: FidelityContext, name: str) -> Measurement:
    """q itself, one-sided (the under-opening side of :func:`tract_range`, the same range):
    how much of the recording's opening the model shows; 0 for a face that does not move."""
    r = _reach(ctx, name)
    if r is None:
        return _still(name)
    q, dm, dd, f = r
    return Measurement(q, f, f"{name.replace('_', ' ')}: the model opens {dm:.1f} mm of the "
                             f"recording's {dd:.1f} mm ({q:.0%}); frame shown: the recording's extreme",
                       frame_value=q)


def m_lips_error(ctx):
    return articulator_error(ctx, "lips")


def m_tongue_error(ctx):
    return articulator_error(ctx, "tongue")


def m_jaw_error(ctx):
    return articulator_error(ctx, "jaw")


def m_lip_aperture(ctx):
    return tract_correlation(ctx, "lip_aperture")


def m_lip_aperture_range(ctx):
    return tract_range(ctx, "lip_aperture")


def m_lip_protrusion(ctx):
    return tract_correlation(ctx, "lip_protrusion")


def m_jaw_opening(ctx):
    return tract_correlation(ctx, "jaw_opening")


def m_jaw_opening_range(ctx):
    return tract_range(ctx, "jaw_opening")


def m_lip_aperture_reach(ctx):
    return tract_reach(ctx, "lip_aperture")


def m_jaw_opening_reach(ctx):
    return tract_reach(ctx, "jaw_opening")
