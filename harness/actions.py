"""What ``cassi run``, ``cassi nightly``, ``cassi bench``, ``cassi gc``, ``cassi sensitivity``,
``cassi render`` and ``cassi animate`` do in the harness (parsers: :mod:`.commands`, :mod:`.render_commands`)."""
from __future__ import annotations

import argparse
import json
from functools import partial
from pathlib import Path

import numpy as np

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.common.lazy import resolve
from cassi.harness.bench import BENCHMARKS, run_benchmarks
from cassi.harness.commands import config_from_args
from cassi.harness.evaluation.caches import get_corpus, get_face, get_profile, get_version_face
from cassi.harness.evaluation.config import MEDIA_GC, NIGHTLY
from cassi.harness.evaluation.nightly import nightly
from cassi.harness.evaluation.nights import gc
from cassi.harness.evaluation.run import run
from cassi.harness.evaluation.sensitivity import JSON_NAME, MD_NAME, sensitivity
from cassi.harness.farm.store import MEDIA_DIR, collect_garbage, store_lock
from cassi.renderer.commands import NEUTRAL
from cassi.versions.registry import get_version


def cmd_run(args: argparse.Namespace) -> int:
    cfg = config_from_args(args)
    # On a terminal: bars; in a log (cron, CI): a line per stage every few seconds.
    result = run(cfg, progress=not args.no_progress)
    print(result.summary.text())
    print(f"results: {cfg.out / 'results.parquet'} (and .csv); ratings: "
          f"{cfg.out / 'ratings.parquet'}")
    return 0 if result.ok else 1


def cmd_nightly(args: argparse.Namespace) -> int:
    cfg = config_from_args(args, NIGHTLY, need_out=False)
    review = partial(resolve(args.review), common_only=args.common_only)
    passed, index = nightly(args.out, config=cfg, progress=not args.quiet, review=review)
    gate = json.loads((Path(args.out) / "runs" / index.parent.name / "gate.json").read_text())
    word = "BASELINE RECORDED" if passed and gate.get("baseline_recorded") else (
        "PASSED" if passed else "FAILED")
    print(f"{word}: {index}")
    return 0 if passed else 1


def cmd_bench(args: argparse.Namespace) -> int:
    only = None
    if args.only:
        only = [n for n in args.only.split(",") if n]
        unknown = sorted(set(only) - set(BENCHMARKS))
        if unknown:
            raise CassiInputError(f"no benchmark {', '.join(unknown)}; "
                                  f"known: {', '.join(BENCHMARKS)}")
    report = run_benchmarks(quick=args.quick, only=only)
    out = Path(args.out)
    try:
        atomic_write_text(out, json.dumps(report, indent=1, sort_keys=True, default=str) + "\n")
    except OSError as err:
        raise CassiInputError(f"cannot write the benchmark file: {err.strerror}", path=out) from err
    for name, entry in sorted(report["benchmarks"].items()):
        status = f"error: {entry['error']}" if "error" in entry else "ok"
        print(f"{name}: {status}")
    if "farm_speedup_2_workers" in report:
        print(f"farm_speedup_2_workers: {report['farm_speedup_2_workers']}")
    print(f"wrote {out}")
    return 0


def cmd_sensitivity(args: argparse.Namespace) -> int:
    out = args.out or args.run
    doc = sensitivity(args.run, out, only=args.only, workers=args.workers)
    flipped = [f for f in doc["findings"] if f["flips"]]
    print(f"{len(doc['findings'])} findings, {len(flipped)} flipped by some setting; "
          f"timing: {doc['timing']}")
    print(f"wrote {Path(out) / JSON_NAME} and {Path(out) / MD_NAME}")
    return 0


def task_positions(corpus_dir, subject: str, task: int, rep: int, version: str):
    """Face (the one ``version`` animates), recording rows int64 (F,), positions float32
    (F, V, 3) Parke units of ``version`` animating one task file and the rows' times int64 (F,)
    us (the recording's clock, at its own rate); ``neutral``: the subject's neutral face in
    every row."""
    corpus = get_corpus(corpus_dir)
    rec = corpus.subject(subject).load(task, rep)
    ver = None if version == NEUTRAL else get_version(version)  # unknown: did-you-mean error
    profile = get_profile(corpus, subject)
    face = get_face(corpus, subject, profile)
    if ver is None:
        n = len(rec.time_us)
        verts = np.asarray(face.vertices, np.float32)
        return (face, np.arange(n, dtype=np.int64), np.broadcast_to(verts, (n, *verts.shape)),
                np.asarray(rec.time_us, np.int64))
    anim = ver.animate(profile, face, rec)
    face = get_version_face(corpus, subject, profile, ver)  # the face the version animated
    return (face, np.asarray(anim.frames, np.int64), np.asarray(anim.positions, np.float32),
            np.asarray(anim.time_us, np.int64))


def cmd_gc(args: argparse.Namespace) -> int:
    root = Path(args.dir)
    if (root / "runs").is_dir():
        out = gc(root, keep=args.keep)
        print(f"kept {len(out['nights_kept'])} night(s), removed {len(out['nights_removed'])}"
              + (f" ({', '.join(out['nights_removed'])})" if out["nights_removed"] else ""))
    elif (root / "objects").is_dir() and (root / "manifests").is_dir():
        with store_lock(root, exclusive=True):
            c = collect_garbage(root)
            pages = resolve(MEDIA_GC)(root / MEDIA_DIR)
        out = {"blobs_removed": c.blobs, "manifests_removed": c.manifests,
               "bytes_freed": c.bytes + pages}
    else:
        raise CassiInputError("neither a nightly directory (runs/) nor a store (objects/, "
                              "manifests/)", path=root)
    print(f"store: removed {out['blobs_removed']} object(s) and {out['manifests_removed']} "
          f"manifest(s), {out['bytes_freed'] / 1e6:.1f} MB freed")
    return 0

