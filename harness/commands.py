"""``cassi run`` (a batch of subjects x tasks x versions x views), ``cassi nightly``,
``cassi bench``, ``cassi gc`` and ``cassi sensitivity``."""
from __future__ import annotations

import argparse
from pathlib import Path

from cassi.common.cliargs import ascii_int
from cassi.common.errors import CassiInputError

from cassi.harness.evaluation import config as C
from cassi.harness.evaluation.config import KEEP_NIGHTS


def add_run_options(p: argparse.ArgumentParser, defaults: C.RunConfig) -> None:
    """The settings of a run (:class:`~cassi.harness.evaluation.config.RunConfig`), shared by
    every command that starts one; the help gives ``defaults``, the command's own
    (:func:`config_from_args` applies a run file and the flags over them)."""
    d = defaults
    p.add_argument("--config", type=Path, help="a run file (.toml, .yaml); flags override it")
    p.add_argument("--corpus", type=Path, help="corpus directory (default: the embedded synthetic "
                                                "corpus)")
    p.add_argument("--subjects", nargs="+", metavar="NAME", help="default: every subject")
    p.add_argument("--tasks", nargs="+", metavar="N",
                   help="task numbers or ranges, e.g. 19 21 or 1-118 (default: the thesis's "
                        "evaluation set, Table 5.1 + 106, 118)")
    p.add_argument("--set", choices=C.EVAL_SETS,
                   help="the task files when --tasks is not given: 'thesis' (Table 5.1 + 106, "
                        "118) or 'full' (every task file of every subject; default "
                        f"{d.set})")
    p.add_argument("--versions", nargs="+", metavar="NAME", help="default: every version")
    p.add_argument("--views", nargs="+", metavar="NAME",
                   help="front side half top (default: all four); 'geometry' alone: no renders")
    p.add_argument("--stride", help=f"also render every Nth frame (default {d.stride}; 0: the "
                                    "first frame and the frames the checks point at only)")
    p.add_argument("--extremes", help="render at most N frames the checks point at, per task "
                                      f"file and version (default {d.extremes})")
    p.add_argument("--animate-stride", dest="animate_stride",
                   help="also render every Nth row for each task file's video: the front view "
                        "for every version (the image checks judge it), every view for the "
                        f"--video-versions (default {d.animate_stride}; 0: no videos)")
    every = d.video_versions is None
    p.add_argument("--video-versions", dest="video_versions", metavar="NAMES",
                   help="versions rendered in all four views on the video grid, for a four-view "
                        "video of every task file: comma-separated names, 'all' or 'none' "
                        f"(default {'all' if every else ','.join(d.video_versions) or 'none'}; "
                        "`cassi export --format gltf` gives any view of any version)")
    p.add_argument("--chunk", help=f"frames per render job (default {d.chunk})")
    p.add_argument("--preset", help=f"render preset (default {d.preset})")
    p.add_argument("--variant", help="Mitsuba variant (default: the renderer's choice)")
    p.add_argument("--executor", choices=C.EXECUTORS, help="local processes (default) or ray")
    p.add_argument("--address", help="Ray cluster address (default: start a local cluster)")
    p.add_argument("--workers", help="worker processes (default: "
                   + ("one per usable core)" if d.workers == C.RunConfig().workers
                      else f"{d.workers})"))
    p.add_argument("--threads", help=f"CPU threads per worker process (default {d.threads})")
    p.add_argument("--retries", help=f"retries of a job whose worker died (default {d.retries})")


def _add_run(sub) -> None:
    p = sub.add_parser(
        "run", help="evaluate subjects x tasks x versions x views (resumable batch)",
        description="Run the rubric over a batch: geometry and geometric checks on every frame, "
                    "renders at keyframes and a stride, image checks, ratings. Rerunning into "
                    "the same --out reuses every finished job whose outputs verify.")
    add_run_options(p, C.RunConfig())
    p.add_argument("--out", type=Path, help="output directory (required here or in --config)")
    p.add_argument("--cache", type=Path, help="a store shared between runs: jobs it holds with "
                                              "the same inputs and code are reused, not run")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func="cassi.harness.actions:cmd_run")


def _add_nightly(sub) -> None:
    p = sub.add_parser("nightly", help="run the default evaluation, report, compare, gate",
                       description="One night: dated run + report under DIR, compared with the "
                       "previous night; exit 0 when the gates hold, 1 when one fails. The run's "
                       "settings are `cassi run`'s, with a night's defaults.")
    p.add_argument("--out", type=Path, required=True,
                   help="the nightly directory (kept across nights)")
    add_run_options(p, C.NIGHTLY)
    p.add_argument("--common-only", action="store_true", dest="common_only",
                   help="when the previous night covered other task files, versions or views, "
                        "gate only what both nights share (default: such a night fails its gate)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress (bars on a terminal, a line per stage every few seconds "
                        "in a log) and no stage times")
    p.set_defaults(func="cassi.harness.actions:cmd_nightly", review=C.NIGHT_REVIEW)


def _add_bench(sub) -> None:
    p = sub.add_parser("bench", help="benchmarks: geometry, rendering, the farm (JSON)",
                       description="Run the registered benchmarks and write one JSON file.")
    p.add_argument("--out", type=Path, default=Path("bench.json"), help="JSON file to write")
    p.add_argument("--quick", action="store_true", help="small sizes (CI smoke test)")
    p.add_argument("--only", default=None, metavar="NAME[,NAME]",
                   help="run only these benchmarks (geometry, render, geometry_memory, "
                        "image_memory, farm_preview, farm, job_cost, incremental_night, full_set: "
                        "cassi.harness.bench.BENCHMARKS); "
                        "e.g. --only render,farm_preview")
    p.set_defaults(func="cassi.harness.actions:cmd_bench")


def _add_gc(sub) -> None:
    p = sub.add_parser("gc", help="remove old nights and what no kept night needs",
                       description="In a nightly directory: keep the newest --keep nights (runs "
                       "and reports), remove the older ones and every object of the shared "
                       "store that no kept night links. Given a store (cassi run --cache DIR), "
                       "remove what no run directory links.")
    p.add_argument("dir", type=Path, help="a nightly directory (cassi nightly --out) or a store")
    p.add_argument("--keep", type=ascii_int, default=KEEP_NIGHTS,
                   help=f"nights to keep (default {KEEP_NIGHTS}: a month)")
    p.set_defaults(func="cassi.harness.actions:cmd_gc")


def _add_sensitivity(sub) -> None:
    p = sub.add_parser("sensitivity", help="each version-level finding of a run with its "
                                           "robustness to the project's own constants",
                       description="Re-derive every version-level finding of a finished run "
                       "(per table, each version against the one before it, by total negatives "
                       "and by the paired comparison) with one constant at a time at each end of "
                       "its declared range: rubric thresholds re-applied to the stored values "
                       "(no render), version constants by animating and checking again (one "
                       "geometry stage each). Writes sensitivity.json and sensitivity.md.")
    p.add_argument("run", type=Path, help="a finished run directory")
    p.add_argument("--out", type=Path, help="where to write (default: the run directory)")
    p.add_argument("--only", choices=("thresholds", "versions"),
                   help="only the rubric thresholds, or only the version constants")
    p.add_argument("--workers", type=ascii_int,
                   help="processes animating the version settings (default: the run's)")
    p.set_defaults(func="cassi.harness.actions:cmd_sensitivity")


def register(sub) -> None:
    """Add ``run``, ``nightly``, ``bench``, ``gc`` and ``sensitivity`` to the ``cassi``
    subcommands."""
    _add_run(sub)
    _add_nightly(sub)
    _add_bench(sub)
    _add_gc(sub)
    _add_sensitivity(sub)


def config_from_args(args: argparse.Namespace, defaults: C.RunConfig = C.RunConfig(), *,
                     need_out: bool = True) -> C.RunConfig:
    """``defaults`` (the command's), the run file (if any) over them, the flags over both."""
    base = defaults
    if getattr(args, "config", None):
        in_file = C.load_config(args.config)
        given = {k: getattr(in_file, k) for k in in_file.where}
        if "video_versions" in given and in_file.video_versions is None:
            given["video_versions"] = C.EVERY_VERSION  # None would read as "not set"
        base = C.merge(defaults, given).replace(where=in_file.where)
    flags = {k: getattr(args, k, None) for k in C.FIELDS}
    for name in ("subjects", "tasks", "versions", "views"):
        # `--subjects JW11,JW45` and `--subjects JW11 JW45` mean the same.
        if flags.get(name):
            flags[name] = [part for item in flags[name] for part in str(item).split(",") if part]
    if flags.get("video_versions") is not None:
        flags["video_versions"] = [v.strip() for v in flags["video_versions"].split(",")
                                   if v.strip()]
    cfg = C.merge(base, flags)
    if need_out and cfg.out is None:
        raise CassiInputError("no output directory: give --out DIR (or out = ... in --config)")
    return cfg
