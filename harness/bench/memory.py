"""Peak memory of one worker on a long task: ``geometry_peak_rss_mb``, ``image_peak_rss_mb``.

A 100,000-row task file (about 11.5 minutes at 145.6 Hz) is made from a real-format task file
of the embedded corpus, its rows repeated with the time running on; each version's geometry
job (animation, geometric checks, key frames) then runs in a fresh process, whose peak resident
set size (``ru_maxrss``) is the figure. The image job of such a task judges the 2,000 frames the
default stride (50) renders of it: it runs in a fresh process on one real rendered frame's
masks, stored once and read back for every frame (what the farm's store gives it). The goal is
under 1 GB per worker for any legal file.
"""
from __future__ import annotations

import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from cassi.data.xrmb.files import NOMINAL_PERIOD_US, read_txy, task_file_name, write_txy
from cassi.versions.registry import available_versions

from cassi.harness.farm.jobs import Job, StageContext, npz_bytes
from cassi.harness.evaluation.caches import get_corpus, get_face, get_profile, get_renderer
from cassi.harness.evaluation.stages import geometry_stage, image_stage
from cassi.harness.bench.measure import json_child, peak_rss_mb

ROWS = 100_000  # about 11.5 minutes at 145.6 Hz: longer than any task file of the corpus
GOAL_MB = 1024.0  # the goal: under 1 GB per worker for any legal file
#: Frames an image job judges on a ROWS-row task at the default stride (every 50th row).
IMAGE_FRAMES = ROWS // 50


def long_task_corpus(root: Path, *, rows: int = ROWS, subject: str = "JW12", task: int = 2) -> Path:
    """A corpus in ``root`` holding ``subject`` of the embedded corpus with task ``task``
    lengthened to ``rows`` rows (copies: a corpus refuses links that lead outside it)."""
    # Not at the top: it pulls in scipy.signal (~65 MB), which would count in the peak RSS of
    # the fresh processes that import this module to measure one job.
    from cassi.data.synth.corpus import default_corpus  # noqa: PLC0415 - heavy, see above

    src = Path(default_corpus())
    dest = root / subject
    shutil.copytree(src / subject, dest)
    for name in ("corpus.json", "Headmeasures.txt"):
        if (src / name).exists():
            shutil.copy(src / name, root / name)
    rec = read_txy(src / subject / task_file_name(task))
    first = rec.first_valid_index
    reps = -(-rows // (rec.n_frames - first))
    idx = np.concatenate([np.arange(rec.n_frames)] +
                         [np.arange(first, rec.n_frames)] * reps)[:rows]
    long = type(rec)(None, rec.subject, task, 1,
                     np.arange(rows, dtype=np.int64) * NOMINAL_PERIOD_US + int(rec.time_us[0]),
                     rec.xy_mm[idx], rec.valid[idx])
    (dest / task_file_name(task)).unlink()
    write_txy(dest / task_file_name(task), long)
    return root


def child(corpus: str, subject: str, task: int, version: str) -> None:
    """In a fresh process: one geometry job; print peak RSS (MB), wall time and frames."""
    c = get_corpus(corpus)
    get_profile(c, subject)
    before = peak_rss_mb()
    t0 = time.perf_counter()
    out = geometry_stage(Job("geometry", subject, task, 1, version),
                         StageContext(out_dir=Path(corpus), corpus=Path(corpus)), {})
    wall = time.perf_counter() - t0
    peak = peak_rss_mb()
    print(json.dumps({"peak_rss_mb": round(peak, 1), "rss_before_mb": round(before, 1),
                      "seconds": round(wall, 2), "frames": out.meta.get("n_frames")}))


class _SameMasks(dict):
    """Parent outputs where every ``masks-<frame>`` is the same stored blob."""

    def __init__(self, blob: bytes):
        super().__init__()
        self.blob = blob

    def __getitem__(self, name: str) -> bytes:
        return self.blob


def image_child(frames: int, subject: str = "JW12", task: int = 2) -> None:
    """In a fresh process: one image job (front view) over ``frames`` stored frames; print its
    peak RSS (MB), the RSS before it and its wall time."""
    c = get_corpus(None)
    profile = get_profile(c, subject)
    face = get_face(c, subject, profile)
    res = get_renderer(c, subject, face, "front", "preview", None).render(
        np.asarray(face.vertices, np.float32))
    blob = npz_bytes(mask=np.asarray(res.mask, np.uint8), depth=np.asarray(res.depth, np.float32),
                     part_names=np.asarray(res.part_names, dtype=str))
    before = peak_rss_mb()
    t0 = time.perf_counter()
    job = Job("image", subject, task, 1, "cassi-2.1", view="front", frames=tuple(range(frames)))
    out = image_stage(job, StageContext(out_dir=Path("."), corpus=None), _SameMasks(blob))
    wall = time.perf_counter() - t0
    peak = peak_rss_mb()
    print(json.dumps({"peak_rss_mb": round(peak, 1), "rss_before_mb": round(before, 1),
                      "seconds": round(wall, 2), "frames": frames, "rows": len(out.rows)}))


def bench_image_memory(quick: bool = False, *, frames: int = IMAGE_FRAMES) -> dict:
    """Peak RSS of one image job over ``frames`` frames in a fresh process (``quick``: 200
    frames, and the figure is then not the headline one)."""
    frames = min(frames, 200) if quick else frames
    out = json_child(f"from cassi.harness.bench.memory import image_child; "
                     f"image_child({int(frames)})")
    if "error" in out:
        return out
    out["goal_mb"] = GOAL_MB
    if frames == IMAGE_FRAMES:
        out["image_peak_rss_mb"] = out["peak_rss_mb"]
    return out


def bench_geometry_memory(quick: bool = False, *, versions=None, rows: int = ROWS) -> dict:
    """Peak RSS of one geometry job per version on a ``rows``-row task (fresh process each);
    ``quick``: one version on 10,000 rows (the figure is then not the 100k-row one)."""
    versions = list(versions or (["cassi-2.1"] if quick else available_versions()))
    rows = min(rows, 10_000) if quick else rows
    tmp = Path(tempfile.mkdtemp(prefix="cassi-bench-mem-"))
    try:
        corpus = long_task_corpus(tmp / "corpus", rows=rows)
        per_version = {}
        for version in versions:
            per_version[version] = json_child(f"from cassi.harness.bench.memory import child; "
                                              f"child({str(corpus)!r}, 'JW12', 2, {version!r})")
        peaks = [v["peak_rss_mb"] for v in per_version.values() if "peak_rss_mb" in v]
        out = {"rows": rows, "versions": per_version, "goal_mb": GOAL_MB}
        if rows == ROWS:  # the headline figure is defined on 100,000 rows only
            out["geometry_peak_rss_mb"] = max(peaks) if peaks else None
        else:
            out["peak_rss_mb"] = max(peaks) if peaks else None
        return out
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
