"""The frame policy: which frames a job renders, which it keeps, which views show them.

One home for every rule that picks frames, read by the geometry stage (what it keeps and asks
to render), the run's render budget (said before any work starts), the render stage (which
views keep masks) and the report (which views a task's video shows).

What a night keeps, and why (measured on the default nightly, docs/farm.md "Disk"):

- every view: the first frame and the check frames of every task file and version: the
  subject pages' four views of a fault, and with every render the gates' comparisons with the
  previous night and the goldens;
- the front view on the ``animate_stride`` grid for every version: the frames the image checks
  judge (their masks, the only masks kept) on the same frames for every version, and the
  versions side by side in one front-view video per task file. A large run (a full set,
  :func:`large_run`) makes videos of the :data:`COMPARED_TASKS` only, so the other files' grid
  frames are rendered as masks only (:func:`masks_only`): no picture, only the region that
  holds what the image checks read, the same masks at about 2.7 ms a frame against 6;
- the side, half and top views on that grid only for the ``video_versions`` (a four-view
  video each): none by default, since the report's task viewer (and `cassi export --format
  gltf`) shows any view of any version from geometry. cassi-2.1's four-view grid was 10,968
  of 31,081 renders and half the report's video encoding; ``--video-versions cassi-2.1``
  restores it. Final-quality (path-traced) videos are not made: a 512² frame costs 5-15 s
  against a preview's 15 ms;
- the evidence frames (:func:`evidence_frames`): the frame every link of the report points at
  (a charged check's evidence frame, :func:`linked_frames`), in the view the check is judged
  from, so that the viewer and the subject pages show that very frame rendered. They are
  rendered only: no image check judges them (those judge the frames above, the same for every
  version; adding a version's own evidence frames would change their results);
- the viewer's geometry (:func:`viewer_frames`): every :data:`VIEWER_STRIDE`-th row and every
  check's frame, quantised (:mod:`cassi.harness.evaluation.viewerdata`).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from cassi.data.xrmb.files import JAW_WAGGING_TASK, MAX_PROTRUSION_TASK, NOMINAL_PERIOD_US, rows_spanning
from cassi.harness.evaluation.config import DEFAULT_EXTREMES
from cassi.harness.rubric import CHECKS, checks_for

#: The views a task file's video shows side by side; with ``animate_stride`` each of them is
#: rendered at that stride (views a run leaves out are not rendered).
VIDEO_VIEWS = ("front", "side", "half", "top")
#: Tasks whose versions are compared side by side (front view) in the nightly report.
COMPARED_TASKS = (JAW_WAGGING_TASK, MAX_PROTRUSION_TASK)
COMPARISON_VIEW = "front"
#: A run of more than this many usable task files is a large one (a full set: 1,800): its
#: report's viewer pages carry the renders of first frames and of the frames of checks that
#: earned negatives only (the frames every link opens; the pictures were two thirds of a full
#: set's report), it makes videos of the :data:`COMPARED_TASKS` only, and so the other task
#: files' video grid is rendered as masks only where the image checks judge it
#: (:func:`masks_only`). A default night (57 files) keeps them all.
ALL_RENDERS_UP_TO = 100


def large_run(files: int) -> bool:
    """Whether a run of ``files`` usable task files is a large one (:data:`ALL_RENDERS_UP_TO`)."""
    return files > ALL_RENDERS_UP_TO


def judged_views(tasks, views) -> frozenset:
    """(subject, task, rep, view) of the usable task files' :func:`image_views` among
    ``views``: the views an image job follows
    (:attr:`cassi.harness.farm.plan.BatchPlan.judged`)."""
    return frozenset((t.subject, t.task, t.rep, view) for t in tasks if t.usable
                     for view in views if view in image_views(t.task))


def masks_only(tasks, views) -> frozenset:
    """(subject, task, rep, view) whose judged frames beyond the first and the check frames get
    no picture (:attr:`cassi.harness.farm.plan.BatchPlan.masks_only`): in a large run, the
    judged views of every task file but the :data:`COMPARED_TASKS`, whose videos it does not
    make. A night of 1,696 task files otherwise encodes and stores 800,000 pictures nobody
    sees."""
    if not large_run(sum(1 for t in tasks if t.usable)):
        return frozenset()
    return frozenset(k for k in judged_views(tasks, views) if k[1] not in COMPARED_TASKS)


def select_frames(first: int, last: int, *, stride: int, extremes=()) -> list[int]:
    """Frames to render: the first animated frame, the extremes the checks point at, a stride.

    Parameters
    ----------
    first, last : int
        First and last animated recording rows (inclusive).
    stride : int
        Every ``stride``-th row from ``first``; 0 or less: no stride frames.
    extremes : iterable of int
        Rows the geometric checks point at (outside ``first..last`` are dropped).
    """
    picked = {int(first)}
    if stride > 0:
        picked.update(range(int(first), int(last) + 1, int(stride)))
    picked.update(int(f) for f in extremes if first <= int(f) <= last)
    return sorted(picked)


def video_grid(frames, *, first: int, stride: int) -> list[int]:
    """Of ``frames``, those on the video grid: ``first`` + k * ``stride`` (a video's time base;
    frames off the grid, such as a check's extreme, would break it)."""
    if stride < 1:
        return []
    return sorted(int(f) for f in frames if (int(f) - first) % stride == 0)


def image_views(task: int) -> set[str]:
    """The views the task's image checks judge (the front view): the only views whose masks are
    kept, and the views every version renders on the video grid, so that the image checks
    judge every version on the same frames."""
    return {c.view for c in checks_for(kind="image", task=task)}


def video_views(task: int, version: str, video_versions=None) -> tuple[str, ...]:
    """The views in which ``version`` renders task ``task`` on the video grid.

    Every task file is also shown as a video (four views side by side): the video versions
    (``video_versions``; None: every version) get every view; the others the views the image
    checks judge (else those checks would judge the video versions on every grid frame and the
    others on a first frame and an extreme or two) and the front view of the compared tasks;
    the same frames for every version, so videos of a task compare frame for frame.
    """
    if video_versions is None or version in video_versions:
        return VIDEO_VIEWS
    judged = image_views(task)
    return tuple(v for v in VIDEO_VIEWS
                 if v in judged or (task in COMPARED_TASKS and v == COMPARISON_VIEW))


def extreme_frames(rows: pd.DataFrame, *, limit: int = DEFAULT_EXTREMES) -> list[int]:
    """Frames the geometric checks point at.

    The rubric gives each check a whole-task row (``frame == -1``, with the negatives) and an
    evidence row at the check's worst frame. The worst frames of the checks that earned
    negatives come first (most negatives first), then those of the other checks, up to
    ``limit`` frames.
    """
    if rows is None or not len(rows) or "frame" not in rows:
        return []
    rows = rows.copy()
    rows["negatives"] = pd.to_numeric(rows["negatives"], errors="coerce").fillna(0)
    fired = rows[rows["frame"] == -1].groupby("check")["negatives"].max()
    # Evidence rows only: the fidelity traces (view "trace") are per-frame data, not a fault.
    traces = rows["view"] == "trace" if "view" in rows else False
    evidence = rows[(rows["frame"] >= 0) & ~traces].copy()
    if evidence.empty:
        return []
    evidence["fired"] = evidence["check"].map(fired).fillna(0)
    evidence = evidence.sort_values(["fired", "check", "frame"], ascending=[False, True, True])
    picked: list[int] = []
    for f in evidence["frame"]:
        if int(f) not in picked:
            picked.append(int(f))
        if len(picked) >= limit:
            break
    return sorted(picked)


def frames_to_render(frames: np.ndarray, rows: pd.DataFrame, *, task: int, version: str,
                     stride: int, extremes: int, animate_stride: int = 0,
                     video_versions=None) -> tuple[list[int], dict[str, list[int]]]:
    """What a geometry job asks to render: (frames in every view, frames per video view).

    ``frames`` are the animated recording rows, ``rows`` the checks' rows (their extremes).
    Every view renders the first frame, every ``stride``-th row and up to ``extremes`` check
    frames; the :func:`video_views` also every ``animate_stride``-th row.
    """
    first, last = int(frames[0]), int(frames[-1])
    animated = set(frames.tolist())
    pick = [f for f in select_frames(first, last, stride=stride,
                                     extremes=extreme_frames(rows, limit=extremes))
            if f in animated]
    by_view: dict[str, list[int]] = {}
    if animate_stride > 0:
        grid = {f for f in select_frames(first, last, stride=animate_stride) if f in animated}
        by_view = {view: sorted(set(pick) | grid)
                   for view in video_views(task, version, video_versions)}
    return pick, by_view


def linked_frames(results: pd.DataFrame) -> dict[tuple, int]:
    """(subject, task, rep, version, check) -> the frame the report links the check to.

    Only charged checks are linked (their whole-task row, ``frame == -1``, holds negatives):
    the thesis tables' faults and the subject pages' negatives open the task viewer there. The
    frame is the check's evidence row (``frame >= 0`` in a rubric table; the fidelity traces
    have none). The report's links and the render policy (:func:`evidence_frames`) both read
    this, so every link has its render.
    """
    if results is None or not len(results) or "frame" not in results:
        return {}
    keys = ["subject", "task", "rep", "version", "check"]
    ruled = results[results["table"].notna()]
    whole = ruled[ruled["frame"] == -1]
    charged = {(s, int(t), int(p), v, c) for s, t, p, v, c, n in
               whole[[*keys, "negatives"]].itertuples(index=False, name=None)
               if pd.notna(n) and int(n) > 0}
    out = {}
    for s, t, p, v, c, f in ruled[ruled["frame"] >= 0][[*keys, "frame"]].itertuples(
            index=False, name=None):
        key = (s, int(t), int(p), v, c)
        if key in charged:
            out[key] = int(f)
    return out


def linked_view(check: str) -> str | None:
    """The view a link to ``check``'s frame opens in: the one the check is judged from (its
    registry ``view``); None for a name the registry lacks."""
    c = CHECKS.get(check)
    return c.view if c is not None else None


def evidence_frames(rows: pd.DataFrame, frames: np.ndarray) -> dict[str, list[int]]:
    """Per view, the animated ``frames`` the report links to: :func:`linked_frames` of a
    geometry job's ``rows``, each in its :func:`linked_view`. Those a view does not render
    anyway are rendered for the report only
    (:meth:`cassi.harness.farm.plan.BatchPlan.evidence_jobs`): no image check judges them."""
    animated = set(np.asarray(frames).tolist())
    out: dict[str, set[int]] = {}
    for (*_, check), frame in linked_frames(rows).items():
        view = linked_view(check)
        if view is not None and frame in animated:
            out.setdefault(view, set()).add(frame)
    return {view: sorted(f) for view, f in sorted(out.items())}


def evidence_budget(task: int) -> dict[str, int]:
    """Per view, at most how many evidence frames a task file and version adds: one per check
    of the geometry job (the image checks' frames are rendered anyway) judged from that view."""
    out: dict[str, int] = {}
    for c in checks_for(task=task):
        if c.kind != "image":
            out[c.view] = out.get(c.view, 0) + 1
    return out


#: The report's task viewer keeps a recording row every VIEWER_STEP_US (every VIEWER_STRIDE-th
#: XRMB row: 145.6 / 4 = 36 Hz, above a video's 30 frames a second: a bilabial closure of
#: 50-100 ms spans 2-3 kept frames); a recording at another rate keeps as many rows a second
#: (:func:`viewer_stride`: every 14th of a 500 Hz EMA recording).
VIEWER_STRIDE = 4
VIEWER_STEP_US = VIEWER_STRIDE * NOMINAL_PERIOD_US


def viewer_stride(period_us: float) -> int:
    """Every how many rows of a recording sampled every ``period_us`` the viewer keeps."""
    return rows_spanning(VIEWER_STEP_US, period_us)


def viewer_frames(frames: np.ndarray, rows: pd.DataFrame | None, *,
                  stride: int = VIEWER_STRIDE) -> list[int]:
    """The recording rows the task viewer keeps: every ``stride``-th animated row, the last,
    and every frame a check points at (its evidence rows), so that a negative opens the viewer
    on the very frame that earned it."""
    frames = np.asarray(frames, np.int64)
    keep = set(frames[::max(1, stride)].tolist()) | {int(frames[-1])}
    if rows is not None and len(rows) and "frame" in rows:
        ev = rows[rows["frame"] >= 0]
        if "view" in ev:
            ev = ev[ev["view"] != "trace"]
        keep |= set(int(f) for f in ev["frame"]) & set(frames.tolist())
    return sorted(keep)


def render_budget(rows_of, tasks, versions, views, *, stride: int, extremes: int,
                  animate_stride: int, video_versions=None) -> int:
    """At most how many frames a run renders (said before any work starts).

    ``rows_of`` maps ``(subject, task, rep)`` to the task file's rows
    (:attr:`cassi.harness.evaluation.inputs.CheckedInputs.rows`: the files are not read again).
    Per usable task file of R rows, version and view: the first frame, every ``stride``-th row
    and up to ``extremes`` check frames; plus every ``animate_stride``-th row in the
    :func:`video_views`, and the :func:`evidence_budget` (overlaps counted twice: an upper
    bound).
    """
    total = 0
    for t in tasks:
        if not t.usable:
            continue
        rows = rows_of[(t.subject, t.task, t.rep)]
        base = 1 + (rows // stride if stride > 0 else 0) + max(0, extremes)
        video = rows // animate_stride + 1 if animate_stride > 0 else 0
        evidence = evidence_budget(t.task)
        for version in versions:
            shown = set(video_views(t.task, version, video_versions))
            total += sum(base + (video if view in shown else 0) + evidence.get(view, 0)
                         for view in views)
    return total
