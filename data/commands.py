"""The ``cassi corpus`` command group: ``make``, ``check``, ``preprocess``, ``stats``, ``convert``.

Exit codes follow the CLI: 0 success, 2 bad input (a malformed file: ``file:line: reason`` on
stderr), 1 other failures.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path


from cassi.common.cliargs import seed_int, task_list
from cassi.common.errors import CassiInputError
from cassi.common.lazy import resolve
from cassi.data.subject_name import SUBJECT_NAME_RE

EXIT_OK, EXIT_BAD_INPUT = 0, 2


def register(subparsers) -> None:
    """Add ``corpus`` and its subcommands to the ``cassi`` parser."""
    p = subparsers.add_parser("corpus", help="XRMB corpora: generate, check, preprocess",
                              description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="corpus_command", metavar="SUBCOMMAND")
    sub.required = True

    mk = sub.add_parser("make", help="generate a synthetic XRMB corpus (deterministic)",
                        description="Generate a synthetic corpus in the XRMB formats. Same seed, "
                                    "same bytes. The corpus says it is synthetic (corpus.json).")
    mk.add_argument("--out", required=True, type=Path, help="output directory")
    mk.add_argument("--subjects", type=_subject_list, default=None,
                    help="comma-separated subjects, e.g. JW11,JW45 (default: all 15)")
    mk.add_argument("--seed", type=seed_int, default=0, help="random seed (default 0)")
    mk.add_argument("--alignments", type=Path, default=None,
                    help="directory of SUBJECT/tpNNN.TextGrid alignments to time the gestures")
    mk.set_defaults(func="cassi.data.actions:cmd_make")

    ck = sub.add_parser("check", help="validate a task file, a subject file or a whole corpus",
                        description="Read every file and report frames, first valid row, "
                                    "usability and problems. Exit 2 if a file is malformed "
                                    "(file:line: reason on stderr); a well-formed file without "
                                    "a valid row is reported UNUSABLE (exit 2 only with "
                                    "--strict).")
    ck.add_argument("path", type=Path, help="a corpus directory, a subject directory or one file")
    ck.add_argument("--json", action="store_true", help="print a JSON list of records")
    ck.add_argument("--strict", action="store_true",
                    help="also exit 2 when a task file is unusable (no row with all eight "
                         "pellets valid), not only when a file is malformed")
    ck.set_defaults(func="cassi.data.actions:cmd_check")

    pp = sub.add_parser("preprocess", help="write maxprotru.txt and lipthick.txt (thesis 4.2)",
                        description="Select up to 20 error-free files per subject and write the "
                                    "CASSI 2.x profile tables maxprotru.txt and lipthick.txt, "
                                    "plus selected_files.csv (one row per file used).")
    pp.add_argument("corpus", type=Path, help="corpus directory")
    pp.add_argument("--out", required=True, type=Path, help="output directory")
    pp.add_argument("--subjects", type=_subject_list, default=None,
                    help="comma-separated subjects (default: all)")
    pp.set_defaults(func="cassi.data.actions:cmd_preprocess")

    st = sub.add_parser("stats", help="kinematic statistics of a corpus, subject or task file",
                        description="Per pellet speed percentiles, x/y ranges and second-"
                                    "difference RMS (tracking noise); jaw MNI-MNM distance and "
                                    "MNI height; lip midpoint height relative to the incisor "
                                    "tip; UL-LL distance. Task files listed in Mis.dat are left "
                                    "out. A frame set (.npy or .mat: frames x 16 mm, UL..MNM "
                                    "x, y, no times) gives the distributions only. With "
                                    "--compare, side by side with a second path and the ratios. "
                                    "Exit 2 on a malformed file (file:line: reason).")
    st.add_argument("path", type=Path, help="a corpus directory, a subject directory, one task "
                                            "file or a frame set (.npy, .mat)")
    st.add_argument("--compare", type=Path, default=None, metavar="PATH2",
                    help="a second corpus, subject directory, task file or frame set")
    st.add_argument("--tasks", type=task_list, default=None,
                    help="only these tasks, e.g. 105 or 102-105,13")
    st.add_argument("--json", action="store_true", help="print JSON")
    st.set_defaults(func="cassi.data.actions:cmd_stats")

    cv = sub.add_parser("convert", help="write an EMA corpus as XRMB task files",
                        description="Read an EMA corpus (speaker directories of EST .ema, "
                                    "Carstens .pos or TSV/CSV recordings under a coil map, "
                                    "ema.yaml; see docs/formats.md) and write it as an XRMB "
                                    "corpus: tpNNNN.txy per recording, PAL.DAT, and the map "
                                    "used (ema_map.json) beside them. Exit 2 if a recording or "
                                    "the map is malformed (file:line: reason).")
    cv.add_argument("ema_dir", type=Path, help="the EMA corpus (or one speaker directory)")
    cv.add_argument("--out", required=True, type=Path,
                    help="the XRMB corpus to write (must not exist, or be empty)")
    cv.set_defaults(func="cassi.data.actions:cmd_convert")


def _subject_list(text: str) -> list[str]:
    names = [s.strip() for s in text.split(",") if s.strip()]
    bad = [n for n in names if not SUBJECT_NAME_RE.fullmatch(n)]
    if not names or bad:
        raise argparse.ArgumentTypeError(f"bad subject list {text!r}")
    return names


def main(argv: list[str] | None = None) -> int:
    """Run ``corpus`` subcommands without the full ``cassi`` CLI (``python -m
    cassi.data.commands check DIR``); same exit codes: 0 ok, 2 bad input, 1 failure."""
    parser = argparse.ArgumentParser(prog="cassi")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    register(sub)
    try:
        args = parser.parse_args(["corpus", *(sys.argv[1:] if argv is None else argv)])
    except SystemExit as exit_:  # argparse: 2 for usage errors, 0 for --help
        return int(exit_.code or 0)
    try:
        return int(resolve(args.func)(args) or EXIT_OK)
    except CassiInputError as err:
        print(f"cassi: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as err:  # noqa: BLE001 - CLI boundary, as in cassi.harness.cli
        print(f"cassi: failed: {type(err).__name__}: {err}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
