"""``cassi run`` (a batch of subjects x tasks x versions x views) and ``cassi bench``."""
from __future__ import annotations

import argparse
from pathlib import Path

from cassi.common.cliargs import ascii_int
from cassi.common.errors import CassiInputError

from cassi.harness.evaluation import config as C
from cassi.harness.evaluation.config import KEEP_NIGHTS


def _add_run(sub) -> None:
    p = sub.add_parser(
        "run", help="evaluate subjects x tasks x versions x views (resumable batch)",
        description="Run the rubric over a batch: geometry and geometric checks on every frame, "
                    "renders at keyframes and a stride, image checks, ratings. Rerunning into "
                    "the same --out reuses every finished job whose outputs verify.")
    p.add_argument("--config", type=Path, help="a run file (.toml, .yaml); flags override it")
    p.add_argument("--corpus", type=Path, help="corpus directory (default: the embedded synthetic "
                                                "corpus)")
    p.add_argument("--subjects", nargs="+", metavar="NAME", help="default: every subject")
    p.add_argument("--tasks", nargs="+", metavar="N",
                   help="task numbers (default: the thesis's evaluation set, Table 5.1 + 106, 118)")
    p.add_argument("--versions", nargs="+", metavar="NAME", help="default: every version")
    p.add_argument("--views", nargs="+", metavar="NAME",
                   help="front side half top (default: all four); 'geometry' alone: no renders")
    p.add_argument("--stride", help="also render every Nth frame (default 50; 0: first + "
                                    "extremes only)")
    p.add_argument("--extremes", help="render at most N frames the checks point at, per task "
                                      "file and version (default 4)")
    p.add_argument("--animate-stride", dest="animate_stride",
                   help="also render every Nth frame in every view, for each task file's video "
                        "(default 0: off)")
    p.add_argument("--chunk", help="frames per render job (default 16)")
    p.add_argument("--preset", help="render preset (default preview)")
    p.add_argument("--variant", help="Mitsuba variant (default: the renderer's choice)")
    p.add_argument("--executor", choices=C.EXECUTORS, help="local processes (default) or ray")
    p.add_argument("--address", help="Ray cluster address (default: start a local cluster)")
    p.add_argument("--workers", help="worker processes (default: one per usable core)")
    p.add_argument("--threads", help="CPU threads per worker process (default 1)")
    p.add_argument("--retries", help="retries of a job whose worker died (default 1)")
    p.add_argument("--out", type=Path, help="output directory (required here or in --config)")
    p.add_argument("--cache", type=Path, help="a store shared between runs: jobs it holds with "
                                              "the same inputs and code are reused, not run")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func="cassi.harness.actions:cmd_run")


def _add_bench(sub) -> None:
    p = sub.add_parser("bench", help="benchmarks: geometry, rendering, the farm (JSON)",
                       description="Run the registered benchmarks and write one JSON file.")
    p.add_argument("--out", type=Path, default=Path("bench.json"), help="JSON file to write")
    p.add_argument("--quick", action="store_true", help="small sizes (CI smoke test)")
    p.add_argument("--only", default=None, metavar="NAME[,NAME]",
                   help="run only these benchmarks (geometry, render, geometry_memory, "
                        "image_memory, farm_preview, farm, incremental_night: "
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


def register(sub) -> None:
    """Add ``run``, ``bench`` and ``gc`` to the ``cassi`` subcommands."""
    _add_run(sub)
    _add_bench(sub)
    _add_gc(sub)


def config_from_args(args: argparse.Namespace) -> C.RunConfig:
    """The run file (if any) with the command-line flags applied over it."""
    base = C.load_config(args.config) if args.config else C.RunConfig()
    flags = {k: getattr(args, k, None) for k in C.FIELDS}
    for name in ("subjects", "tasks", "versions", "views"):
        # `--subjects JW11,JW45` and `--subjects JW11 JW45` mean the same.
        if flags.get(name):
            flags[name] = [part for item in flags[name] for part in str(item).split(",") if part]
    cfg = C.merge(base, flags)
    if cfg.out is None:
        raise CassiInputError("no output directory: give --out DIR (or out = ... in --config)")
    return cfg
