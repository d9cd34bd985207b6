"""``cassi bench``: the registered benchmarks (:data:`BENCHMARKS`) in one JSON document.

- ``geometry``: frames per second of every version on one long task (:mod:`.geometry`);
- ``render``: the renderer's frames per second, its share of bare Mitsuba work and its memory
  over many frames (:mod:`.render`);
- ``geometry_memory`` and ``image_memory``: peak RSS of one worker on a 100,000-row task
  (:mod:`.memory`, ``geometry_peak_rss_mb``, ``image_peak_rss_mb``);
- ``farm_preview`` and ``farm``: preview frames per second end to end in the farm, and jobs per
  second with 1 and 2 local workers and with Ray (:mod:`.farm`);
- ``job_cost``: a geometry job's seconds split into the version's own computation, the
  rubric's work and the rest (:mod:`.jobcost`, ``job_overhead_share``);
- ``incremental_night``: a second night with nothing changed over the first, side by side in
  one run (:mod:`.night`, ``incremental_night_fraction``, ``second_night_s``);
- ``full_set``: a first night of the whole corpus, estimated from one subject's full set
  (:mod:`.fullset`, ``full_set_estimate_s``).

Every figure is measured in-process or read from structured output (a job's timing fields, a
fresh process's JSON line), never parsed from log text (:mod:`.measure`). A benchmark that fails
is reported as ``{"error": ...}``, never replaced by made-up numbers.
"""
from __future__ import annotations

import os
import platform

from cassi.common.lazy import resolve
from cassi.common.cores import usable_cores
from cassi.harness.bench.measure import guarded
from cassi.renderer.variant import choose_variant

__all__ = ["BENCHMARKS", "HEADLINE", "headline", "run_benchmarks"]

#: The benchmarks of ``cassi bench``, in the order they run (``--only`` picks some): name ->
#: the ``"module:function"`` of ``quick`` returning the benchmark's JSON-ready entry. Named, not
#: imported: a memory benchmark's fresh process imports its own module only, so its peak is a
#: worker's, not a worker's plus every other benchmark's imports.
BENCHMARKS = {"geometry": "cassi.harness.bench.geometry:bench_geometry",
              "render": "cassi.harness.bench.render:bench_render",
              "geometry_memory": "cassi.harness.bench.memory:bench_geometry_memory",
              "image_memory": "cassi.harness.bench.memory:bench_image_memory",
              "farm_preview": "cassi.harness.bench.farm:bench_farm_preview",
              "farm": "cassi.harness.bench.farm:bench_farm",
              "job_cost": "cassi.harness.bench.jobcost:bench_job_cost",
              "incremental_night": "cassi.harness.bench.night:bench_incremental_night",
              "full_set": "cassi.harness.bench.fullset:bench_full_set"}


def _same(*keys: str) -> dict[str, str]:
    return {key: key for key in keys}


#: Figures copied to the top of the document, under the keys the issues name: benchmark ->
#: {key in its entry: key in the document}.
HEADLINE = {"geometry": _same("geometry_frames_per_s"),
            "geometry_memory": _same("geometry_peak_rss_mb"),
            "image_memory": _same("image_peak_rss_mb"),
            "render": _same("render_per_s", "render_pipeline_efficiency",
                            "render_pipeline_efficiency_vs_own_pass", "render_rss_growth_mb",
                            "bare_mi_render_frames_per_s"),
            "farm_preview": _same("farm_preview_frames_per_s", "farm_preview_cpu_frames_per_s"),
            "farm": {"speedup_2_workers": "farm_speedup_2_workers",
                     **_same("ray_overhead_vs_local")},
            "job_cost": _same("job_overhead_share"),
            "incremental_night": _same("incremental_night_fraction", "second_night_s"),
            "full_set": _same("full_set_estimate_s")}


def headline(benchmarks: dict) -> dict:
    """The headline figures of the benchmark entries that produced them (errors have none)."""
    out = {}
    for name, keys in HEADLINE.items():
        entry = benchmarks.get(name)
        for key, top in keys.items():
            if isinstance(entry, dict) and key in entry:
                out[top] = entry[key]
    return out


def _variant() -> str:
    try:
        return choose_variant()
    except Exception as err:  # noqa: BLE001 - the document says which variant failed and why
        return f"error: {type(err).__name__}: {err}"


def run_benchmarks(*, quick: bool = False, only=None) -> dict:
    """Every benchmark (or those named in ``only``); the document ``cassi bench`` writes."""
    chosen = tuple(BENCHMARKS if only is None else (n for n in BENCHMARKS if n in set(only)))
    report = {"quick": quick, "cpu_count": os.cpu_count(),
              "cpus_usable": usable_cores(),
              "python": platform.python_version(), "machine": platform.machine(),
              "variant": _variant(), "benchmarks": {}, "only": list(chosen)}
    for name in chosen:
        report["benchmarks"][name] = guarded(lambda q, target=BENCHMARKS[name]: resolve(target)(q),
                                             quick)
    report.update(headline(report["benchmarks"]))
    return report
