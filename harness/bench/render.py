"""Render benchmarks: ``render`` in :data:`cassi.harness.bench.BENCHMARKS` (``bench_render``).

Figures (all on this machine's variant, one process):

- ``render_per_s``: {"view/preset": frames per second} of ``FaceRenderer.render`` (vertex update
  and the preset's passes) on a moving face;
- ``render_pipeline_efficiency``: the bare Mitsuba cost of a moving preview frame (the vertex
  upload with ``params.update()`` and the one ``mi.render`` of the aov pass, synchronised) divided
  by the renderer's end-to-end time per frame as the farm uses it (``FaceRenderer.render`` with
  its shading, the PNG encoded in memory and the mask and depth packed as ``.npz``), measured in
  alternating blocks so machine load hits both alike; per view, and the mean over the four views
  as the headline (goal >= 0.7). In JIT variants the renderer no longer calls that
  ``mi.render``: its own one pass (:mod:`cassi.renderer.raycast`, the same rays with the
  shading in the kernel) is cheaper, so beside it ``render_pipeline_efficiency_vs_own_pass``
  divides the upload plus that pass (numpy outputs included) by the same pipeline frame: the
  share of a frame that is rendering at all;
- ``render_rss_growth_mb``: resident memory growth over 2,000 consecutive pipeline frames (quick:
  80) after a warm-up, with the samples so flatness can be seen (goal < 50 MB).
"""
from __future__ import annotations

import io
import statistics

import numpy as np

from cassi.data.face.model import build_face, render_topology
from cassi.renderer.images import png_bytes
from cassi.renderer.render import FaceRenderer
from cassi.renderer.variant import choose_variant
from cassi.renderer.views import PRESET_NAMES, VIEW_NAMES

from cassi.harness.bench.measure import loadavg, rss_mb, time_loop
from cassi.harness.farm.workers import renderer_threads

__all__ = ["bench_render", "moving_positions", "bare_frame", "own_pass_frame", "pipeline_frame"]


def moving_positions(base: np.ndarray, k: int, *, period: int = 40, amplitude: float = 25.0) -> np.ndarray:
    """Frame ``k`` of a synthetic jaw-like motion: everything below the base's mid height moves
    down and forward by up to ``amplitude`` Parke units, smoothly, with period ``period`` frames."""
    base = np.asarray(base, np.float32)
    z = base[:, 2]
    zmid = 0.5 * (float(z.min()) + float(z.max()))
    weight = np.clip((zmid - z) / max(1.0, zmid - float(z.min())), 0.0, 1.0)
    s = 0.5 - 0.5 * np.cos(2 * np.pi * k / period)
    out = base.copy()
    out[:, 2] -= amplitude * s * weight
    out[:, 0] += 0.3 * amplitude * s * weight
    return out


def _neutral():
    face = build_face()
    base = np.asarray(face.vertices, np.float32)
    return (lambda half: render_topology(face, half=half)), base


def bare_frame(renderer, positions: np.ndarray) -> None:
    """The least Mitsuba work a moving frame needs: upload the vertices (``params.update()``)
    and run the preset's one colour-giving ``mi.render``, waiting for it to finish."""
    import drjit as dr  # noqa: PLC0415 - only once choose_variant has set DRJIT_LIBLLVM_PATH

    renderer.update(positions)
    dr.eval(renderer.render_pass())
    dr.sync_thread()


def own_pass_frame(renderer, positions: np.ndarray) -> None:
    """The renderer's own one pass of a moving frame: the vertex upload and
    ``FaceRenderer.render_aov`` (mask, depth and colour as numpy arrays)."""
    renderer.update(positions)
    renderer.render_aov()


def pipeline_frame(renderer, positions: np.ndarray, metadata: dict | None = None) -> tuple[bytes, bytes]:
    """One frame end to end as the farm's render stage makes it: render, PNG in memory, mask and
    depth as ``.npz`` bytes. Returns (png, npz)."""
    res = renderer.render(positions)
    png = png_bytes(res.srgb8(), metadata={**res.metadata(), **(metadata or {})}, linear=False)
    buf = io.BytesIO()
    np.savez(buf, mask=res.mask.astype(np.uint8), depth=res.depth,
             part_names=np.asarray(res.part_names, dtype=str))
    return png, buf.getvalue()


def bench_render(quick: bool = False, *, topology_for=None, positions=None,
                 variant: str | None = None) -> dict:
    """Run the render benchmarks; see the module docstring. Returns a JSON-ready dict.

    ``topology_for(half: bool)`` and ``positions`` (V, 3) default to the neutral face of
    ``cassi.data.face.model``.
    """
    if topology_for is None or positions is None:
        topology_for, positions = _neutral()
    variant = choose_variant(variant)  # before drjit starts: it sets DRJIT_LIBLLVM_PATH
    # One core, as a farm worker has: the figures then compare with the farm's per worker.
    with renderer_threads(1):
        return _bench_render(quick, topology_for, positions, variant)


def _bench_render(quick, topology_for, positions, variant) -> dict:
    out: dict = {"variant": variant, "threads": 1, "quick": quick, "render_per_s": {}, "efficiency_by_view": {},
                 "efficiency_vs_own_pass_by_view": {},
                 "ms_per_image": {}, "load_average_before": loadavg()}
    n_preview = 6 if quick else 40
    renderers = {}
    for preset in PRESET_NAMES:
        for view in VIEW_NAMES:
            if preset == "final" and quick and view != "front":
                continue
            r = FaceRenderer(topology_for(view == "half"), view, preset, variant)
            renderers[(view, preset)] = r
            r.render(moving_positions(positions, 0))  # load + compile kernels
            n = n_preview if preset == "preview" else (1 if quick else 3)
            dt = time_loop(lambda k: r.render(moving_positions(positions, k + 1)), n)
            out["render_per_s"][f"{view}/{preset}"] = round(1.0 / dt, 2)

    # --- efficiency: bare Mitsuba frame vs the whole pipeline, alternating blocks -------------
    block, rounds = (5, 2) if quick else (20, 4)
    for view in VIEW_NAMES:
        r = renderers[(view, "preview")]
        frames = [moving_positions(positions, k) for k in range(block)]
        bare_t, own_t, pipe_t = [], [], []
        for _ in range(rounds):
            bare_t.append(time_loop(lambda k: bare_frame(r, frames[k]), block))
            own_t.append(time_loop(lambda k: own_pass_frame(r, frames[k]), block))
            pipe_t.append(time_loop(lambda k: pipeline_frame(r, frames[k]), block))
        b, o, p = (statistics.median(t) for t in (bare_t, own_t, pipe_t))
        out["efficiency_by_view"][view] = round(b / p, 3)
        out["efficiency_vs_own_pass_by_view"][view] = round(o / p, 3)
        out["ms_per_image"][view] = {"bare_render": round(1000 * b, 2),
                                     "own_pass": round(1000 * o, 2),
                                     "pipeline": round(1000 * p, 2)}
    out["render_pipeline_efficiency"] = round(statistics.mean(out["efficiency_by_view"].values()), 3)
    out["render_pipeline_efficiency_vs_own_pass"] = round(
        statistics.mean(out["efficiency_vs_own_pass_by_view"].values()), 3)
    out["preview_pipeline_frames_per_s"] = round(1000 / statistics.mean(
        v["pipeline"] for v in out["ms_per_image"].values()), 2)
    out["bare_mi_render_frames_per_s"] = round(1000 / statistics.mean(
        v["bare_render"] for v in out["ms_per_image"].values()), 2)

    # --- memory: many consecutive pipeline frames of one renderer --------------------------
    n_frames = 80 if quick else 2000
    r = renderers[("front", "preview")]
    samples = []
    for k in range(n_frames):
        pipeline_frame(r, moving_positions(positions, k))
        if k == 50 or (k > 50 and k % max(1, n_frames // 10) == 0) or k == n_frames - 1:
            samples.append((k, round(rss_mb(), 1)))
    base = samples[0][1]
    out["render_rss_growth_mb"] = round(max(s for _, s in samples) - base, 1)
    out["rss_samples_mb"] = samples
    out["rss_frames"] = n_frames
    out["scene_loads"] = {f"{v}/{p}": r.loads for (v, p), r in renderers.items()}
    out["load_average_after"] = loadavg()
    return out
