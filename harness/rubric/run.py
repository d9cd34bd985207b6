"""Running checks: one animation (geometry and fidelity) or one view's rendered frames (image)
into rows of the long results table.

Results are rows of ``cassi.harness.farm.results.COLUMNS``: one whole-task row (``frame == -1``) per
check with the negatives, plus one evidence row at the worst frame (negatives 0) so the farm can
render the frame a check points at.
"""
from __future__ import annotations

from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from cassi.common.errors import CassiInputError

from cassi.harness.rubric import geometry as G
from cassi.harness.rubric.frames import ArrayFrames, Frames, LastRead
from cassi.harness.rubric.measures import CRITERION_DIAGNOSTICS, GeometryContext
from cassi.harness.rubric.model import Check, Measurement
from cassi.harness.rubric.registry import TRACE_STEP_MS, TRACE_TASKS, checks_for, get_check
from cassi.data.face.model import build_face
from cassi.data.xrmb.files import recording_period_us, rows_spanning
from cassi.versions.mapping import XrmbToParke
from cassi.harness.rubric.fidelity import FidelityContext, traces
from cassi.harness.rubric.leaveout import LeaveOutContext
from cassi.harness.rubric.shape import ShapeContext

__all__ = ["criterion_rows", "run_geometry_checks", "run_image_checks"]

def _rows(check: Check, m: Measurement, view: str, ids: dict) -> list[dict]:
    neg = m.negatives if m.negatives is not None else check.grade(m.value)
    detail = m.detail
    if not check.counted:
        if check.fires(m.value):
            detail = f"fired (not counted); {detail}"
        neg = 0
    if m.frame >= 0:
        detail = f"{detail}; worst frame {m.frame}" if detail else f"worst frame {m.frame}"
    base = dict(ids, view=view, check=check.name, table=check.table, component=check.component,
                unit=check.unit, threshold=check.threshold)
    rows = [dict(base, frame=-1, value=m.value, negatives=int(neg), detail=detail)]
    if m.frame >= 0 and m.frame_value is not None:
        rows.append(dict(base, frame=int(m.frame), value=m.frame_value, negatives=0,
                         detail="evidence: the worst frame"))
    return rows


def _frame_numbers(anim, n: int) -> np.ndarray:
    frames = getattr(anim, "frames", None)
    return np.asarray(frames) if frames is not None and len(frames) == n else np.arange(n)


def run_geometry_checks(anim, face, profile=None, *, task: int, subject: str | None = None,
                        rep: int = 1, parts: G.MouthParts | None = None,
                        mm_per_unit: float | None = None, neutral=None, recording=None,
                        withheld: dict | None = None,
                        checks: Iterable[str] | None = None) -> pd.DataFrame:
    """Run every geometric check that applies to ``task`` on one animation, and with
    ``recording`` the fidelity checks (Table F).

    Parameters
    ----------
    anim : cassi.versions.protocol.Animation
        ``positions`` float32 (F, V, 3) Parke units, ``diagnostics``, ``frames``, ``version``.
    face : cassi.data.face.model.FaceModel
        The face the version animated (its ``vertices`` are the rest shape).
    profile : cassi.data.corpus.profile.SubjectProfile or None
        Gives the subject and the jaw length (mm per Parke unit).
    task : int
        Task number (118 and 106 add Tables D and E).
    parts, mm_per_unit, neutral : optional
        Overrides (tests); by default from the face, the profile and ``build_face()``.
    recording : cassi.data.xrmb.files.TaskRecording, optional
        The recording the version animated: its pellets are what Table F compares the face
        with (needs ``face`` and the profile's jaw length for the 4.1.1 mapping). Without it
        Table F is not measured.
    withheld : dict, optional
        Pellet name -> :class:`~cassi.harness.rubric.leaveout.WithheldSite`, the version
        animated with that pellet withheld (:func:`cassi.harness.evaluation.withheld.withheld_sites`;
        empty: the version cannot be, and its rows say so). Without it (None) Table G's
        leave-one-out checks are not measured.
    checks : iterable of str, optional
        Only these checks.

    Returns
    -------
    DataFrame
        Results-table rows (``frame`` are recording rows; -1 = whole task), view ``geometry``.
    """
    positions = anim.positions
    # every check reads the positions through one LastRead: a short task is read once
    pos = LastRead(positions if isinstance(positions, Frames) else ArrayFrames(positions))
    anim = _Reading(anim, pos)
    rest = np.asarray(face.vertices, dtype=np.float64) if face is not None else None
    face_parts = None  # the face's own mouth parts, when computed
    if parts is None:
        if face is None:
            raise CassiInputError("run_geometry_checks needs a face or explicit parts")
        parts = face_parts = G.mouth_parts(face)
    if mm_per_unit is None:
        jaw = getattr(profile, "jaw_length_mm", None) if profile is not None else None
        mm_per_unit = G.mm_per_unit(rest if rest is not None else pos.frame(0), jaw)
    if neutral is None and face is not None:
        neutral = build_face().vertices
    ctx = GeometryContext(pos, parts, rest=rest, mm_per_unit=mm_per_unit,
                          diagnostics=getattr(anim, "diagnostics", None), neutral=neutral, task=task,
                          period_us=_period_us(anim, recording))
    ids = dict(subject=subject or getattr(profile, "subject", None), task=int(task), rep=int(rep),
               version=getattr(anim, "version", None))
    wanted = None if checks is None else {get_check(c).name for c in checks}
    frame_no = _frame_numbers(anim, pos.n_frames)
    rows = _measured_rows(checks_for(kind="geometry", task=task), ctx, ids, wanted, frame_no)
    if recording is not None:
        rows.extend(_fidelity_rows(anim, face, profile, recording, ids, wanted, frame_no,
                                   withheld, face_parts))
    if wanted is None:
        rows.extend(criterion_rows(ctx.diagnostics, ids, mm_per_unit))
    return _frame(rows)


class _Reading:
    """An animation as its checks read it: its positions through the checks' one
    :class:`~cassi.harness.rubric.frames.LastRead`, everything else its own."""

    def __init__(self, anim, positions: Frames):
        self._anim, self.positions = anim, positions

    def __getattr__(self, name):
        return getattr(self._anim, name)


def _period_us(anim, recording) -> float:
    """The animated recording's period: from the recording's times, else the animation's (a
    test's stand-ins may carry neither: then XRMB's)."""
    for source in (recording, anim):
        times = getattr(source, "time_us", None)
        if times is not None:
            return recording_period_us(times)
    return recording_period_us(())


def criterion_rows(diagnostics, ids: dict, mm_per_unit: float) -> list[dict]:
    """CASSI 2.1's low-lips decision (thesis 4.3.1) as one whole-task row, view ``criterion``:
    the signed margin, mm, by which the upper lip's starting inside edge lies below the
    threshold (> 0: the lips were adjusted); no table, never charged. Empty for versions that
    make no such decision."""
    if diagnostics is None or not all(c in diagnostics for c in CRITERION_DIAGNOSTICS):
        return []
    first = {c: np.asarray(diagnostics[c])[:1] for c in CRITERION_DIAGNOSTICS}
    if not all(len(v) for v in first.values()):
        return []
    margin, edge = float(first["low_lips_margin"][0]), float(first["low_lips_inside_edge"][0])
    reading = str(first["low_lips_reading"][0])
    at = edge + margin  # the threshold's height above 226, units
    detail = (f"reading {reading}: inside edge {edge * mm_per_unit:+.2f} mm ({edge:+.1f} units) "
              f"from 226, threshold {at * mm_per_unit:+.2f} mm ({at:+.1f} units); margin "
              f"{margin:+.1f} units: {'adjusted' if margin > 0 else 'as 2.0'}")
    return [dict(ids, view="criterion", frame=-1, check="low_lips_margin", table=None,
                 component=None, value=margin * mm_per_unit, unit="mm", threshold=0.0,
                 negatives=0, detail=detail)]


def _measured_rows(checks, ctx, ids: dict, wanted, frame_no) -> list[dict]:
    """Rows of ``checks`` measured on ``ctx`` (those in ``wanted`` when given); a measure's
    frame index becomes the recording row."""
    rows: list[dict] = []
    for c in checks:
        if wanted is not None and c.name not in wanted:
            continue
        m = c.func(ctx)
        if m.frame >= 0:
            m = Measurement(m.value, int(frame_no[m.frame]), m.detail, m.negatives, m.frame_value)
        rows.extend(_rows(c, m, "geometry", ids))
    return rows


def _fidelity_rows(anim, face, profile, recording, ids, wanted, frame_no,
                   withheld=None, parts=None) -> list[dict]:
    jaw = getattr(profile, "jaw_length_mm", None)
    if face is None or jaw is None:
        raise CassiInputError("fidelity checks need the face and the subject's jaw length "
                              "(profile.jaw_length_mm) to map the model back to the recording")
    mapping = XrmbToParke.from_face(face.vertices, jaw)
    ctx = FidelityContext.of(anim, recording, mapping)
    # every table's fidelity checks (F, G, and C/E's movement), each on its measure's context
    todo = [c for c in checks_for(kind="fidelity", task=ids["task"])
            if wanted is None or c.name in wanted]
    rows = _measured_rows([c for c in todo if c.measure.startswith("fidelity:")], ctx, ids,
                          wanted, frame_no)
    shape = [c for c in todo if c.measure.startswith("shape:")]
    if shape:  # the lips' shape between the pellets, against the same recording
        sctx = ShapeContext.of(anim, recording, mapping,
                               G.mouth_parts(face) if parts is None else parts)
        rows.extend(_measured_rows(shape, sctx, ids, wanted, frame_no))
    leave = [c for c in todo if c.measure.startswith("leaveout:")]
    if leave and withheld is not None:  # the tongue between the pellets, one withheld at a time
        rows.extend(_measured_rows(leave, LeaveOutContext(withheld, recording), ids, wanted,
                                   frame_no))
    if ids["task"] in TRACE_TASKS and wanted is None:
        step = rows_spanning(TRACE_STEP_MS * 1000, _period_us(anim, recording))
        rows.extend(dict(ids, negatives=0, **r) for r in traces(ctx, step=step))
    return rows


def _frame(rows: list[dict]) -> pd.DataFrame:
    cols = ["subject", "task", "rep", "version", "view", "frame", "check", "table", "component",
            "value", "unit", "threshold", "negatives", "detail"]
    df = pd.DataFrame(rows, columns=cols)
    df["negatives"] = df["negatives"].astype("int64")
    df["frame"] = df["frame"].astype("int64")
    df["value"] = df["value"].astype("float64")
    return df


def run_image_checks(results_by_view: Mapping[str, Any], *, task: int, subject: str | None = None,
                     rep: int = 1, version: str | None = None,
                     checks: Iterable[str] | None = None) -> pd.DataFrame:
    """Run the image checks that apply to ``task`` on rendered frames.

    Parameters
    ----------
    results_by_view : mapping view -> frames
        Frames as a mapping ``frame -> RenderResult`` or an iterable of ``(frame, RenderResult)``
        pairs (read once, one frame at a time);
        a RenderResult has ``mask`` int (H, W) part ids, ``part_names`` and ``depth``.
    task : int

    Returns
    -------
    DataFrame of results-table rows (view = the render view each check judges).
    """
    from cassi.harness.rubric import image as I  # noqa: PLC0415 - scikit-image only where images are judged

    ids = dict(subject=subject, task=int(task), rep=int(rep), version=version)
    wanted = None if checks is None else {get_check(c).name for c in checks}
    rows: list[dict] = []
    contexts: dict[str, Any] = {}  # one mask analysis per view, shared by its checks
    for c in checks_for(kind="image", task=task):
        if wanted is not None and c.name not in wanted:
            continue
        frames = results_by_view.get(c.view) if hasattr(results_by_view, "get") else None
        if not frames:
            continue
        if c.view not in contexts:
            contexts[c.view] = I.ImageContext.of(frames)
        rows.extend(_rows(c, c.func(contexts[c.view]), c.view, ids))
    return _frame(rows)
