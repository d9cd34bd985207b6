"""``cassi report``, ``cassi nightly``, ``cassi gate`` and ``cassi golden``."""
from __future__ import annotations

from pathlib import Path

from cassi.common.cliargs import ascii_int
from cassi.harness.evaluation.config import (NIGHTLY_ANIMATE_STRIDE, NIGHTLY_EXTREMES,
                                             NIGHTLY_STRIDE, NIGHTLY_VIDEO_VERSIONS)


def register(sub) -> None:
    p = sub.add_parser("report", help="write an HTML report (and CSV/Markdown tables) of a run",
                       description="Write DIR/index.html and the thesis-style tables of RUN.")
    p.add_argument("run", type=Path, help="a run directory (cassi run --out)")
    p.add_argument("--compare", type=Path, help="a previous run to compare with")
    p.add_argument("--out", type=Path, required=True, help="report directory")
    p.add_argument("--ratings", type=Path, help="ratings people gave (CSV, see `cassi agree`): "
                   "adds the agreement section")
    p.set_defaults(func="cassi.reports.actions:cmd_report")

    p = sub.add_parser("agree", help="compare a run's ratings with ratings people gave",
                       description="Compare RUN's ratings with FILE.csv (columns subject,task,"
                       "version,table,component,rating; a blank task: the subject's rating, a "
                       "blank component: the whole table). Writes agreement.json, agreement.md "
                       "and agreement.csv (the disagreements) into DIR; exit 2 on a bad line.")
    p.add_argument("run", type=Path, help="a run directory (cassi run --out)")
    p.add_argument("--ratings", type=Path, required=True, help="the ratings file (CSV)")
    p.add_argument("--out", type=Path, help="output directory (default: RUN)")
    p.set_defaults(func="cassi.reports.actions:cmd_agree")

    p = sub.add_parser("nightly", help="run the default evaluation, report, compare, gate",
                       description="One night: dated run + report under DIR, compared with the "
                       "previous night; exit 0 when the gates hold, 1 when one fails.")
    p.add_argument("--out", type=Path, required=True, help="the nightly directory (kept across nights)")
    p.add_argument("--corpus", type=Path, help="corpus directory (default: the embedded synthetic one)")
    p.add_argument("--workers", type=ascii_int, default=2, help="local worker processes (default 2)")
    p.add_argument("--stride", type=ascii_int, default=NIGHTLY_STRIDE,
                   help="also render every N-th frame (default 0: the first frame and the frames "
                        "the checks point at, which keeps a night under 15 minutes on 2 cores)")
    p.add_argument("--extremes", type=ascii_int, default=NIGHTLY_EXTREMES,
                   help="frames the checks point at to render per task file and version "
                        f"(default {NIGHTLY_EXTREMES})")
    p.add_argument("--animate-stride", type=ascii_int, default=NIGHTLY_ANIMATE_STRIDE,
                   help="row stride of every task file's four-view video, all views "
                        f"(default {NIGHTLY_ANIMATE_STRIDE}; 0: no videos)")
    p.add_argument("--video-versions", dest="video_versions",
                   default=",".join(NIGHTLY_VIDEO_VERSIONS) or "none",
                   help="versions also rendered in the side, half and top views on the video "
                        "grid, for a four-view video of every task file: comma-separated names, "
                        "'all' or 'none' (default none: every version gets the front view, which "
                        "the image checks judge, and the versions' side-by-side video; `cassi "
                        "export --format gltf` gives the other views; cassi-2.1 gives the former nights' set)")
    p.add_argument("--common-only", action="store_true", dest="common_only",
                   help="when the previous night covered other task files, versions or views, "
                        "gate only what both nights share (default: such a night fails its gate)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress (bars on a terminal, a line per stage every few seconds "
                        "in a log) and no stage times")
    p.set_defaults(func="cassi.reports.actions:cmd_nightly")

    p = sub.add_parser("gate", help="apply the regression gates to a run",
                       description="Compare RUN with a baseline run or golden directory; write "
                       "gate.json and gate.md into RUN; exit 0 when all gates hold, 1 otherwise, "
                       "2 when they cannot compare (a side with failed or missing jobs, another "
                       "scope or corpus, nothing compared).")
    p.add_argument("run", type=Path)
    p.add_argument("--baseline", type=Path, required=True, help="a run directory or golden directory")
    p.add_argument("--common-only", action="store_true", dest="common_only",
                   help="compare only the task files, versions and views both runs have, and say "
                        "so in gate.md (default: a baseline of another scope is an error, exit 2)")
    p.set_defaults(func="cassi.reports.actions:cmd_gate")

    p = sub.add_parser("golden", help="make a run's renders the golden images (explicit only)",
                       description="Copy RUN's renders and results into GOLDEN; the only way "
                       "golden images change. A run with failed or missing jobs is refused (exit 2).")
    p.add_argument("run", type=Path)
    p.add_argument("--golden", type=Path, required=True, help="golden directory to (re)write")
    p.set_defaults(func="cassi.reports.actions:cmd_golden")
