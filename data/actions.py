"""What each ``cassi corpus`` subcommand does (the parsers are in :mod:`cassi.data.commands`).

Exit codes follow the CLI: 0 success, 2 bad input (a malformed file: ``file:line: reason``),
1 any other failure.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from cassi.common.atomic import atomic_open, writable_dir
from cassi.common.errors import CassiInputError
from cassi.data.commands import EXIT_BAD_INPUT, EXIT_OK
from cassi.data.corpus import profile
from cassi.data.corpus.disk import Corpus, check_corpus, check_task_file
from cassi.data.corpus.profile import preprocess, write_lipthick, write_maxprotru
from cassi.data.corpus.stats import PELLET_COLUMNS, SCALARS, UNITS, compare, corpus_stats
from cassi.data.ema.coilmap import MAP_FILE
from cassi.data.ema.convert import convert
from cassi.data.synth.corpus import make_corpus
from cassi.data.xrmb import alignment, headmeasures, mis
from cassi.data.xrmb import files as xrmb


# ----------------------------------------------------------------------------- make
def cmd_make(args) -> int:
    if args.alignments is not None and not args.alignments.is_dir():
        raise CassiInputError("alignments directory not found", path=args.alignments)
    out = make_corpus(args.out, subjects=args.subjects, seed=args.seed,
                      alignments=args.alignments)
    print(f"synthetic corpus written to {out}")
    return EXIT_OK


# ----------------------------------------------------------------------------- check
def _ema_subject_of(path: Path):
    """The speaker whose coil map reads ``path`` as an EMA recording (the map in its directory or
    the one above), else None."""
    for root in (path.parent, path.parent.parent):
        if not (root / MAP_FILE).is_file() and not (path.parent / MAP_FILE).is_file():
            continue
        corpus = Corpus(root)
        name = path.parent.name if root != path.parent else next(iter(corpus.subjects), None)
        if name in corpus.subjects:
            subject = corpus.subject(name)
            if subject.ema is not None and subject.ema.is_recording(path.name):
                return subject
    return None


def _check_single_file(path: Path) -> tuple[list[dict], list[str]]:
    """Check one file by its kind (task file, PAL/PHA.DAT, Mis.dat, head measures, tables)."""
    name = path.name.lower()
    record = {"path": str(path), "subject": None, "task": None, "rep": None, "frames": None,
              "first_valid_us": None, "usable": None, "problems": [], "warnings": []}
    readers = {"pal.dat": xrmb.read_pal, "pha.dat": xrmb.read_pha, "mis.dat": mis.read_mis,
               headmeasures.HEAD_MEASURES_FILE.lower(): headmeasures.read_head_measures,
               "maxprotru.txt": profile.read_maxprotru, "lipthick.txt": profile.read_lipthick}
    ema_subject = _ema_subject_of(path)
    if ema_subject is not None:
        rep = check_task_file(path, subject=ema_subject)
        return [rep.as_dict()], list(rep.problems) if rep.error else []
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
                              "Headmeasures.txt, maxprotru.txt, lipthick.txt, *.TextGrid or "
                              "an EMA recording beside its ema.yaml)",
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
    corpus = Corpus(args.corpus)
    if not corpus.subjects:
        raise CassiInputError("no subject directories in the corpus", path=args.corpus)
    skipped: list[str] = []
    profiles = preprocess(corpus, args.subjects, skipped=skipped)
    for msg in skipped:
        print(f"warning: {msg}", file=sys.stderr)
    if not profiles:
        raise CassiInputError("no subject could be preprocessed", path=args.corpus)
    out: Path = writable_dir(args.out)
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
        what = (f"a frame set of {s.n_frames} frames: distributions only" if s.n_frames
                else f"{s.n_files} task file(s)")
        print(f"# {label}: {s.label} ({what})"
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




def cmd_convert(args) -> int:
    """``cassi corpus convert EMA_DIR --out XRMB_DIR``: every problem on stderr, exit 2 if any."""
    written, problems = convert(args.ema_dir, args.out)
    print(f"{written} task file(s) written to {args.out}")
    for p in problems:
        print(p, file=sys.stderr)
    return EXIT_BAD_INPUT if problems else EXIT_OK
