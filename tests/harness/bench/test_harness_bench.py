"""`cassi bench`'s one registry (cassi.harness.bench.BENCHMARKS): every name runs a function,
figures come from measurements and structured output (never from log text), failures are
entries, and the farm's job times travel as data from the worker."""
from __future__ import annotations

import ast
import inspect
import pkgutil
import time
from pathlib import Path

import cassi.harness.bench as bench
from cassi.common.lazy import resolve
from cassi.harness.bench import BENCHMARKS, headline
from cassi.harness.bench.farm import bench_farm, cpu_stage
from cassi.harness.bench.jobcost import PARTS, bench_job_cost
from cassi.harness.bench.measure import guarded
from cassi.harness.farm.jobs import Job, StageContext, State, execute_job

#: The names `cassi bench --only` takes, as docs/benchmarks.md and `cassi bench --help` list them.
NAMES = ["geometry", "render", "geometry_memory", "image_memory", "farm_preview", "farm",
         "job_cost", "incremental_night", "full_set"]


def test_every_registered_benchmark_is_a_function_of_quick():
    assert list(BENCHMARKS) == NAMES
    for name, target in BENCHMARKS.items():
        fn = resolve(target)
        assert callable(fn), name
        first = next(iter(inspect.signature(fn).parameters.values()))
        assert first.name == "quick" and first.default is False, name
        # Each lives in the benchmark package, not in the layer it measures.
        assert fn.__module__.startswith("cassi.harness.bench."), (name, fn.__module__)


def _package_sources() -> dict[str, str]:
    return {info.name: (Path(bench.__path__[0]) / f"{info.name}.py").read_text()
            for info in pkgutil.iter_modules(bench.__path__)} | {
        "__init__": Path(bench.__file__).read_text()}


def test_no_benchmark_reads_log_text():
    """No module of the package touches a job's ``log`` lines or a log file, nor matches text
    with ``re``: figures are measured here or read from data (outcome fields, JSON lines)."""
    sources = _package_sources()
    assert {"farm", "geometry", "memory", "render", "measure", "__init__"} <= set(sources)
    for name, text in sources.items():
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Attribute):
                assert node.attr not in ("log", "log_path"), (name, node.lineno)
            if isinstance(node, ast.Import):
                assert "re" not in [a.name for a in node.names], (name, node.lineno)
            if isinstance(node, ast.ImportFrom):
                assert node.module not in ("re", "progress") and "write_job_log" not in [
                    a.name for a in node.names], (name, node.lineno)


def test_a_failing_benchmark_is_an_error_entry_not_numbers():
    def broken(quick):
        raise RuntimeError("no scene")

    entry = guarded(broken, True)
    assert entry["error"] == "RuntimeError: no scene" and entry["traceback"]
    assert guarded(lambda quick: 3, True) == {"result": 3}


def test_a_job_outcome_carries_its_cpu_seconds(tmp_path):
    ctx = StageContext(out_dir=tmp_path, ship=True, options=(("work", 0.05),))
    c0 = time.process_time()
    out = execute_job(cpu_stage, Job("geometry", "BENCH", 1, 1, "bench"), ctx, "d")
    spent = time.process_time() - c0
    assert out.state is State.DONE
    # The stage spins on one core for 0.05 s: its CPU time is there, and no more than this
    # process spent over the call.
    assert 0.0 < out.cpu_seconds <= spent + 1e-6 and out.seconds >= 0.05


def test_the_farm_times_jobs_from_their_records():
    farm = bench_farm(True, workload="cpu", ray=False, repeats=1)
    assert farm["local_1"]["jobs"] == farm["local_2"]["jobs"] == 8
    assert farm["local_1"]["failed"] == farm["local_2"]["failed"] == 0
    assert farm["speedup_2_workers"] > 0 and "cpu-bound" in farm["workload"]
    # The workers' CPU seconds reached the records: a share of the jobs' wall time.
    for n in (1, 2):
        assert 0 < farm[f"local_{n}"]["job_cpu_share"] <= 1.05, farm[f"local_{n}"]


def test_bench_headline_keys_come_from_the_entries_that_have_them():
    out = headline({"geometry": {"geometry_frames_per_s": {"cassi-1.0": 5.0}},
                    "render": {"error": "mitsuba missing"}})
    assert out == {"geometry_frames_per_s": {"cassi-1.0": 5.0}}
    out = headline({"geometry": {"error": "x"},
                    "render": {"render_per_s": {"front/preview": 2.0},
                               "render_pipeline_efficiency": 0.8, "render_rss_growth_mb": 1.0}})
    assert set(out) == {"render_per_s", "render_pipeline_efficiency", "render_rss_growth_mb"}
    # The farm's speed-up is copied to the top under the name docs/benchmarks.md gives it.
    out = headline({"farm": {"speedup_2_workers": 1.8, "ray_overhead_vs_local": 0.1}})
    assert out == {"farm_speedup_2_workers": 1.8, "ray_overhead_vs_local": 0.1}


def test_a_geometry_jobs_cost_is_split_into_its_parts():
    entry = bench_job_cost(True)
    assert "error" not in entry, entry
    assert len(entry["by_version"]) == 2
    for version, v in entry["by_version"].items():
        assert v["job_s"] > 0 and all(v[k] > 0 for k in PARTS), version
        assert abs(v["job_s"] - sum(v[k] for k in (*PARTS, "rest_s"))) < 0.01, version
    assert entry["job_overhead_share"] == round(entry["total"]["rest_s"]
                                                / entry["total"]["job_s"], 3)


def test_the_full_set_estimate_scales_a_measured_night_by_usable_files():
    """Quick: three task files of one subject, two versions, the front view; the estimate is
    that night's seconds times the whole corpus's usable files over the night's, and says so."""
    from cassi.harness.bench.fullset import bench_full_set
    entry = bench_full_set(True, subject="JW45")
    assert entry["usable_files_run"] == 3 and entry["usable_files_full_set"] > 1000
    scale = entry["usable_files_full_set"] / 3
    assert entry["full_set_estimate_s"] == round(entry["night_s"] * scale, 0) or \
        abs(entry["full_set_estimate_s"] - entry["night_s"] * scale) <= 0.5 + 0.05 * scale
    assert {"run", "gates", "report (tables, pages, videos)"} <= set(entry["stage_seconds"])
    assert "x" in entry["full_set_estimate_basis"] and entry["gates_passed"]
