"""The ``cassi corpus`` command group: ``make``, ``check``, ``preprocess``, ``stats``.

Exit codes follow the CLI: 0 success, 2 bad input (a malformed file: ``file:line: reason`` on
stderr), 1 other failures.
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import numpy as np

from cassi.common.errors import CassiInputError

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
    mk.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    mk.add_argument("--alignments", type=Path, default=None,
                    help="directory of SUBJECT/tpNNN.TextGrid alignments to time the gestures")
    mk.set_defaults(func=cmd_make)

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
    ck.set_defaults(func=cmd_check)

    pp = sub.add_parser("preprocess", help="write maxprotru.txt and lipthick.txt (thesis 4.2)",
                        description="Select up to 20 error-free files per subject and write the "
                                    "CASSI 2.x profile tables maxprotru.txt and lipthick.txt, "
                                    "plus selected_files.csv (one row per file used).")
    pp.add_argument("corpus", type=Path, help="corpus directory")
    pp.add_argument("--out", required=True, type=Path, help="output directory")
    pp.add_argument("--subjects", type=_subject_list, default=None,
                    help="comma-separated subjects (default: all)")
    pp.set_defaults(func=cmd_preprocess)

    st = sub.add_parser("stats", help="kinematic statistics of a corpus, subject or task file",
                        description="Per pellet speed percentiles, x/y ranges and second-"
                                    "difference RMS (tracking noise); jaw MNI-MNM distance; lip "
                                    "midpoint height relative to the incisor tip; UL-LL "
                                    "distance. Task files listed in Mis.dat are left out. With "
                                    "--compare, side by side with a second path and the ratios. "
                                    "Exit 2 on a malformed file (file:line: reason).")
    st.add_argument("path", type=Path, help="a corpus directory, a subject directory or one file")
    st.add_argument("--compare", type=Path, default=None, metavar="PATH2",
                    help="a second corpus, subject directory or task file")
    st.add_argument("--tasks", type=_task_list, default=None,
                    help="only these tasks, e.g. 105 or 102-105,13")
    st.add_argument("--json", action="store_true", help="print JSON")
    st.set_defaults(func=cmd_stats)


def _subject_list(text: str) -> list[str]:
    names = [s.strip() for s in text.split(",") if s.strip()]
    bad = [n for n in names if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_-]{0,31}", n)]
    if not names or bad:
        raise argparse.ArgumentTypeError(f"bad subject list {text!r}")
    return names


def _task_list(text: str) -> list[int]:
    out: list[int] = []
    for part in (p.strip() for p in text.split(",")):
        m = re.fullmatch(r"(\d{1,3})(?:-(\d{1,3}))?", part)
        if not m or int(m.group(2) or m.group(1)) < int(m.group(1)):
            raise argparse.ArgumentTypeError(f"bad task list {text!r} (e.g. 105 or 102-105,13)")
        out.extend(range(int(m.group(1)), int(m.group(2) or m.group(1)) + 1))
    return out


# ----------------------------------------------------------------------------- make
def cmd_make(args) -> int:
    from cassi.data.synth.corpus import make_corpus  # lazy: the generator is heavy and optional here

    if args.alignments is not None and not args.alignments.is_dir():
        raise CassiInputError("alignments directory not found", path=args.alignments)
    out = make_corpus(args.out, subjects=args.subjects, seed=args.seed,
                      alignments=args.alignments)
    print(f"synthetic corpus written to {out}")
    return EXIT_OK


# ----------------------------------------------------------------------------- check
def _check_single_file(path: Path) -> tuple[list[dict], list[str]]:
    """Check one file by its kind (task file, PAL/PHA.DAT, Mis.dat, head measures, tables)."""
    from cassi.data.corpus import profile
    from cassi.data.xrmb import alignment, headmeasures, mis
    from cassi.data.xrmb import files as xrmb
    from cassi.data.corpus.disk import Corpus, check_task_file

    name = path.name.lower()
    record = {"path": str(path), "subject": None, "task": None, "rep": None, "frames": None,
              "first_valid_us": None, "usable": None, "problems": [], "warnings": []}
    readers = {"pal.dat": xrmb.read_pal, "pha.dat": xrmb.read_pha, "mis.dat": mis.read_mis,
               headmeasures.HEAD_MEASURES_FILE.lower(): headmeasures.read_head_measures,
               "maxprotru.txt": profile.read_maxprotru, "lipthick.txt": profile.read_lipthick}
    if name.endswith(".txy"):
        subject = None
        try:
            corpus = Corpus(path.parent)
            subject = corpus.subject(corpus.subjects[0]) if corpus.subjects else None
            if subject is not None:
                subject.mistracking  # usability needs Mis.dat; without it, judge the file alone
        except CassiInputError:
            subject = None
        rep = check_task_file(path, subject=subject)
        d = rep.as_dict()
        errors = list(rep.problems) if rep.error else []
        return [d], errors
    if name.endswith(".textgrid"):
        reader = alignment.read_alignment
    elif name in readers:
        reader = readers[name]
    else:
        raise CassiInputError("unknown file kind (expected *.txy, PAL.DAT, PHA.DAT, Mis.dat, "
                              "Headmeasures.txt, maxprotru.txt, lipthick.txt or *.TextGrid)",
                              path=path)
    try:
        reader(path)
        record["usable"] = True
        return [record], []
    except CassiInputError as err:
        record["problems"].append(str(err))
        record["usable"] = False
        return [record], [str(err)]


def cmd_check(args) -> int:
    from cassi.data.corpus.disk import Corpus, check_corpus

    path: Path = args.path
    if not path.exists():
        raise CassiInputError("not found", path=path)
    if path.is_dir():
        corpus = Corpus(path)
        reports, errors = check_corpus(corpus)
        records = [r.as_dict() for r in reports]
        errors = errors + [p for r in reports if r.error for p in r.problems]
        for w in corpus.warnings:
            print(f"warning: {w}", file=sys.stderr)
        for name in corpus.subjects:
            for w in corpus.subject(name).warnings:
                print(f"warning: {w}", file=sys.stderr)
        synthetic = corpus.is_synthetic if not any("corpus.json" in e for e in errors) else False
    else:
        records, errors = _check_single_file(path)
        synthetic = False
    if args.json:
        print(json.dumps(records, indent=1))
    else:
        _print_table(records, synthetic=synthetic)
        # A file's own warnings (implausible coordinates, odd sample intervals) are in the
        # JSON records; the text output states them too.
        for w in dict.fromkeys(w for r in records for w in r.get("warnings") or []):
            print(f"warning: {w}", file=sys.stderr)
    if getattr(args, "strict", False):
        errors = errors + [p for r in records if r.get("task") is not None and not r.get("error")
                           and not r.get("usable") for p in r.get("problems", [])]
    for e in dict.fromkeys(errors):  # once each (a missing Mis.dat concerns every task file)
        print(e, file=sys.stderr)
    return EXIT_BAD_INPUT if errors else EXIT_OK


def _print_table(records: list[dict], *, synthetic: bool) -> None:
    if synthetic:
        print("# synthetic corpus (generated): figures describe the software, not real speakers")
    for r in records:
        if r.get("task") is None and r.get("frames") is None:  # a subject file or a table
            why = "; ".join(r.get("problems") or [])
            print(f"{r['path']}\t" + ("ok" if r.get("usable") else f"MALFORMED\t{why}"))
            continue
        else:
            status = ("error-free" if r.get("error_free") else
                      "usable" if r.get("usable") else "UNUSABLE")
        first = "-" if r.get("first_valid_us") is None else f"{r['first_valid_us']} us"
        frames = "-" if r.get("frames") is None else r["frames"]
        why = "; ".join(r.get("problems") or [])
        print(f"{r['path']}\t{frames} frames\tfirst valid {first}\t{status}"
              + (f"\t{why}" if why else ""))
    if all(r.get("task") is None and r.get("frames") is None for r in records):
        return
    n_ok = sum(1 for r in records if r.get("error_free"))
    n_use = sum(1 for r in records if r.get("usable"))
    print(f"# {len(records)} file(s): {n_use} usable, {n_ok} error-free")


# ----------------------------------------------------------------------------- preprocess
def cmd_preprocess(args) -> int:
    from cassi.common.atomic import atomic_open
    from cassi.data.corpus.disk import Corpus
    from cassi.data.corpus.profile import preprocess, write_lipthick, write_maxprotru

    corpus = Corpus(args.corpus)
    if not corpus.subjects:
        raise CassiInputError("no subject directories in the corpus", path=args.corpus)
    skipped: list[str] = []
    profiles = preprocess(corpus, args.subjects, skipped=skipped)
    for msg in skipped:
        print(f"warning: {msg}", file=sys.stderr)
    if not profiles:
        raise CassiInputError("no subject could be preprocessed", path=args.corpus)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    write_maxprotru(out / "maxprotru.txt", profiles)
    write_lipthick(out / "lipthick.txt", profiles)
    with atomic_open(out / "selected_files.csv", "w", newline="") as fh:
        fh.write("subject,task,rep,jaw_length_mm,rest_ul,rest_ll,max_ul,max_ll,min_ul,min_ll,"
                 "lipthick\n")
        for name, prof in profiles.items():
            for row in prof.per_file.itertuples(index=False):
                fh.write(f"{name},{row.task},{row.rep},{row.jaw_length_mm:.4f},{row.rest_ul:.6f},"
                         f"{row.rest_ll:.6f},{row.max_ul:.6f},{row.max_ll:.6f},{row.min_ul:.6f},"
                         f"{row.min_ll:.6f},{row.lipthick:.6f}\n")
    if corpus.is_synthetic:
        print("note: synthetic corpus: these profiles describe the software, not real speakers")
    for name, prof in profiles.items():
        print(f"{name}: {len(prof.selected)} file(s), jaw {prof.jaw_length_mm:.2f} mm, "
              f"REST UL {prof.rest_ul:.6f}, MAX UL {prof.max_ul:.6f}, lipthick {prof.lipthick:.6f}")
    print(f"wrote {out / 'maxprotru.txt'}, {out / 'lipthick.txt'}, {out / 'selected_files.csv'}")
    return EXIT_OK


# ----------------------------------------------------------------------------- stats
def _fmt(v: float) -> str:
    if v is None or not np.isfinite(v):
        return "-"
    return f"{v:.3g}" if abs(v) < 100 else f"{v:.0f}"


def cmd_stats(args) -> int:
    from cassi.data.corpus.disk import Corpus
    from cassi.data.corpus.stats import PELLET_COLUMNS, SCALARS, UNITS, compare, corpus_stats

    a = corpus_stats(args.path, tasks=args.tasks)
    b = None if args.compare is None else corpus_stats(args.compare, tasks=args.tasks)
    if args.json:
        doc = {"a": a.as_dict()}
        if b is not None:
            df = compare(a, b)
            doc["b"] = b.as_dict()
            doc["ratio"] = [{"pellet": r.pellet or None, "figure": r.figure,
                             "ratio": None if not np.isfinite(r.ratio) else round(r.ratio, 6)}
                            for r in df.itertuples(index=False)]
        print(json.dumps(doc, indent=1))
        return EXIT_OK
    for label, s in (("A", a), ("B", b)):
        if s is None:
            continue
        synth = s.label and Path(s.label).is_dir() and Corpus(s.label).is_synthetic
        print(f"# {label}: {s.label} ({s.n_files} task file(s))"
              + (" - synthetic: figures describe the software, not real speakers" if synth
                 else ""))
    head = [f"{c} ({UNITS[c]})" for c in PELLET_COLUMNS]
    print("pellet\t" + "\t".join(head))
    # one cell per figure: A alone, or "A | B | xA/B" from compare()
    rows = compare(a, b if b is not None else a).itertuples(index=False)
    cell = {(r.pellet, r.figure): (_fmt(r.a) if b is None else
                                   f"{_fmt(r.a)} | {_fmt(r.b)} | x{_fmt(r.ratio)}")
            for r in rows}
    for p in a.pellets.index:
        print(p + "\t" + "\t".join(cell[(p, c)] for c in PELLET_COLUMNS))
    for k in SCALARS:
        print(f"{k} ({UNITS[k]})\t{cell[('', k)]}")
    if b is not None:
        print("# cells: A | B | A/B")
    return EXIT_OK


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
        return int(args.func(args) or EXIT_OK)
    except CassiInputError as err:
        print(f"cassi: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as err:  # noqa: BLE001 - CLI boundary, as in cassi.harness.cli
        print(f"cassi: failed: {type(err).__name__}: {err}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
