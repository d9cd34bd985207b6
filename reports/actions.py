"""What ``cassi report``, ``nightly``, ``gate`` and ``golden`` do (parsers:
:mod:`cassi.reports.commands`). ``cassi nightly`` is the harness's night
(:func:`cassi.harness.evaluation.nightly.nightly`) reviewed by :func:`.nightly.review_night`."""
from __future__ import annotations

import argparse
from functools import partial

from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.nightly import nightly
from cassi.reports.gates import gate, update_golden
from cassi.reports.nightly import review_night
from cassi.reports.report import write_report


def cmd_report(args: argparse.Namespace) -> int:
    index = write_report(args.run, args.out, compare=args.compare)
    print(index)
    return 0


def cmd_nightly(args: argparse.Namespace) -> int:
    video = tuple(v.strip() for v in args.video_versions.split(",") if v.strip())
    cfg = RunConfig(workers=args.workers, stride=args.stride, extremes=args.extremes,
                    animate_stride=args.animate_stride, video_versions=video or None)
    passed, index = nightly(args.out, corpus=args.corpus, config=cfg, progress=not args.quiet,
                            review=partial(review_night, common_only=args.common_only))
    print(f"{'PASSED' if passed else 'FAILED'}: {index}")
    return 0 if passed else 1


def cmd_gate(args: argparse.Namespace) -> int:
    passed, results = gate(args.run, args.baseline, common_only=args.common_only)
    fails = [r for r in results if r.status == "fail"]
    for r in fails:
        print(f"FAIL {r.gate} {r.version} {r.subject} {r.item}: {r.reason}")
    skips = sum(r.status == "skip" for r in results)
    print(f"{'PASSED' if passed else 'FAILED'}: {len(results) - len(fails) - skips} passed, "
          f"{len(fails)} failed, {skips} skipped (see {args.run / 'gate.md'})")
    return 0 if passed else 1


def cmd_golden(args: argparse.Namespace) -> int:
    n = update_golden(args.run, args.golden)
    print(f"{n} golden images written to {args.golden}")
    return 0
