"""``cassi report``, ``cassi rate``, ``cassi agree``, ``cassi gate`` and ``cassi golden`` (``cassi nightly``'s
parser is the harness's: it starts a run)."""
from __future__ import annotations

from pathlib import Path

from cassi.common.cliargs import ascii_int, seed_int


def register(sub) -> None:
    p = sub.add_parser("report", help="write an HTML report (and CSV/Markdown tables) of a run",
                       description="Write DIR/index.html and the thesis-style tables of RUN.")
    p.add_argument("run", type=Path, help="a run directory (cassi run --out)")
    p.add_argument("--compare", type=Path, help="a previous run to compare with")
    p.add_argument("--out", type=Path, required=True, help="report directory")
    p.add_argument("--ratings", type=Path, help="ratings people gave (CSV, see `cassi agree`): "
                   "adds the agreement section")
    p.add_argument("--media-cache", type=Path, dest="media_cache",
                   help="where videos, pictures and pages made before are kept by what they are "
                   "made of (a nightly's DIR/store/media): linked instead of made again")
    p.set_defaults(func="cassi.reports.actions:cmd_report")

    p = sub.add_parser("rate", help="write a blinded rating session for people",
                       description="Write DIR/session/ (open index.html from disk: each cell "
                       "plays a task file's face in the viewer under a code, in shuffled order; "
                       "the rater rates it on the thesis's scale, ticks faults and exports a "
                       "ratings CSV) and DIR/key.json (code -> version, the seed), which stays "
                       "with you: cassi agree --key un-blinds the exports.")
    p.add_argument("run", type=Path, help="a run directory (cassi run --out)")
    p.add_argument("--out", type=Path, required=True, help="session directory (new)")
    p.add_argument("--tables", help="the rubric's tables to rate, e.g. A,C,E (default: the "
                   "thesis's tables)")
    p.add_argument("--sample", type=ascii_int, help="rate only the first N cells of the shuffled order")
    p.add_argument("--seed", type=seed_int, help="the shuffle's and the codes' seed (default: drawn "
                   "at random and kept in the key)")
    p.set_defaults(func="cassi.reports.actions:cmd_rate")

    p = sub.add_parser("agree", help="compare a run's ratings with ratings people gave",
                       description="Compare RUN's ratings with FILE.csv (columns subject,task,"
                       "version,table,component,rating[,rater,faults,note,session]; a blank task: "
                       "the subject's rating, a blank component: the whole table). With several "
                       "raters also the agreement between them (Krippendorff's alpha), the run "
                       "against each and their consensus, and each check against the faults "
                       "they ticked. Writes agreement.json, agreement.md and agreement.csv (the "
                       "disagreements) into DIR; exit 2 on a bad line.")
    p.add_argument("run", type=Path, help="a run directory (cassi run --out)")
    p.add_argument("--ratings", type=Path, nargs="+", required=True,
                   help="the ratings file(s) (CSV; a rating session's exports, one per rater)")
    p.add_argument("--key", type=Path, help="the rating session's key.json: un-blinds its codes")
    p.add_argument("--out", type=Path, help="output directory (default: RUN)")
    p.set_defaults(func="cassi.reports.actions:cmd_agree")

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
