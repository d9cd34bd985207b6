"""What ``cassi report``, ``rate``, ``agree``, ``gate`` and ``golden`` do (parsers:
:mod:`cassi.reports.commands`). ``cassi nightly`` is the harness's
(:func:`cassi.harness.actions.cmd_nightly`); its review is :func:`.nightly.review_night`."""
from __future__ import annotations

import argparse
from pathlib import Path

from cassi.common.atomic import writable_dir
from cassi.common.errors import CassiInputError
from cassi.reports.gates import gate, update_golden
from cassi.reports.agree import agreement, write_agreement
from cassi.reports.rating_session import DEFAULT_TABLES, write_session
from cassi.reports.report import evidence_href, slug, write_report
from cassi.reports.runio import load_run
from cassi.reports.viewer import viewer_href


def cmd_report(args: argparse.Namespace) -> int:
    writable_dir(args.out, "report directory")
    index = write_report(args.run, args.out, compare=args.compare, ratings=args.ratings,
                         media_cache=args.media_cache)
    print(index)
    return 0


def cmd_rate(args: argparse.Namespace) -> int:
    writable_dir(args.out, "session directory")
    tables = args.tables.split(",") if args.tables else DEFAULT_TABLES
    index, key = write_session(args.run, args.out, tables=tables,
                               sample=args.sample, seed=args.seed)
    print(f"rating session: {index} (give raters the folder {index.parent})")
    print(f"key (code -> version, seed): {key}; keep it from the raters; "
          f"cassi agree {args.run} --ratings EXPORT.csv --key {key}")
    return 0


def _viewer_link(subject: str, file: str, version: str) -> str:
    """A task file's viewer in the run's report, showing ``version``."""
    task, _, rep = file.partition("_")
    return viewer_href(slug(subject), int(task), int(rep or 1), a=version)


def _f(x: float) -> str:
    return "undefined" if x != x else f"{x:.2f}"


def _kappa(g: dict) -> str:
    return "undefined" if g["kappa"] != g["kappa"] else (
        f"{g['kappa']:.2f} [{g['kappa_low']:.2f}, {g['kappa_high']:.2f}]")


def cmd_agree(args: argparse.Namespace) -> int:
    run = load_run(args.run)
    result = agreement(run, args.ratings, evidence_href, key_path=args.key,
                       viewer_link=_viewer_link)
    out = args.out or args.run
    writable_dir(out, "report directory")
    paths = write_agreement(result, out)
    for g in result["groups"]:
        print(f"Table {g['table']} {g['version']}: {g['n']} ratings, exact {g['exact']:.2f}, "
              f"within one {g['within_one']:.2f}, kappa {_kappa(g)}")
    if result["alpha"] is not None:
        a = result["alpha"]
        print(f"Between {len(result['rater_names'])} raters: Krippendorff's alpha (ordinal) "
              f"{_f(a['alpha'])} over {a['units']} units")
        for g in result["raters"]:
            print(f"  the run against {g['rater']}, Table {g['table']}: {g['n']} ratings, "
                  f"exact {g['exact']:.2f}, kappa {_kappa(g)}")
        for g in result["consensus"]:
            print(f"  the run against the consensus, Table {g['table']}: {g['n']} units, "
                  f"exact {g['exact']:.2f}, kappa {_kappa(g)}")
    for c in (c for c in result["checks"] if c["fired"] or c["ticked"]):
        print(f"  {c['check']} (Table {c['table']}): fired {c['fired']}, ticked {c['ticked']}, "
              f"precision {_f(c['precision'])}, recall {_f(c['recall'])}")
    if result["note"]:
        print(result["note"])
    print(f"{len(result['disagreements'])} disagreement(s) with the run: {paths[2]}; "
          f"{len(result['rater_disagreements'])} between raters: {paths[1]}")
    return 0


def cmd_gate(args: argparse.Namespace) -> int:
    passed, results = gate(args.run, args.baseline, common_only=args.common_only)
    fails = [r for r in results if r.status == "fail"]
    for r in fails:
        print(f"FAIL {r.gate} {r.version} {r.subject} {r.item}: {r.reason}")
    skips = sum(r.status == "skip" for r in results)
    print(f"{'PASSED' if passed else 'FAILED'}: {len(results) - len(fails) - skips} passed, "
          f"{len(fails)} failed, {skips} skipped (see {args.run / 'gate.md'})")
    failed_jobs = [r.item for r in fails if r.gate == "jobs"]
    if failed_jobs:
        # an incomplete run is bad input to a gate, not a regression
        raise CassiInputError(f"the run has {len(failed_jobs)} failed job(s), so its gates are "
                              f"incomplete: {', '.join(failed_jobs[:6])}", path=args.run)
    return 0 if passed else 1


def cmd_golden(args: argparse.Namespace) -> int:
    n = update_golden(args.run, args.golden)
    print(f"{n} golden images written to {args.golden}")
    return 0
