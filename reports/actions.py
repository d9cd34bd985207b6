"""What ``cassi report``, ``agree``, ``gate`` and ``golden`` do (parsers:
:mod:`cassi.reports.commands`). ``cassi nightly`` is the harness's
(:func:`cassi.harness.actions.cmd_nightly`); its review is :func:`.nightly.review_night`."""
from __future__ import annotations

import argparse
from pathlib import Path

from cassi.common.atomic import writable_dir
from cassi.common.errors import CassiInputError
from cassi.reports.gates import gate, update_golden
from cassi.reports.agree import agreement, write_agreement
from cassi.reports.report import evidence_href, write_report
from cassi.reports.runio import load_run


def cmd_report(args: argparse.Namespace) -> int:
    writable_dir(args.out, "report directory")
    index = write_report(args.run, args.out, compare=args.compare, ratings=args.ratings)
    print(index)
    return 0


def cmd_agree(args: argparse.Namespace) -> int:
    run = load_run(args.run)
    result = agreement(run, args.ratings, evidence_href)
    out = args.out or args.run
    writable_dir(out, "report directory")
    paths = write_agreement(result, out)
    for g in result["groups"]:
        kappa = "undefined" if g["kappa"] != g["kappa"] else (
            f"{g['kappa']:.2f} [{g['kappa_low']:.2f}, {g['kappa_high']:.2f}]")
        print(f"Table {g['table']} {g['version']}: {g['n']} ratings, exact {g['exact']:.2f}, "
              f"within one {g['within_one']:.2f}, kappa {kappa}")
    if result["note"]:
        print(result["note"])
    print(f"{len(result['disagreements'])} disagreement(s): {paths[2]}")
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
