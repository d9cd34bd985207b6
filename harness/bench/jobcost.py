"""``job_cost`` in :data:`cassi.harness.bench.BENCHMARKS`: what a geometry job costs, split into
the version's own computation, the rubric's work and the rest.

One task file of the default set (JW11 task 19: its Table 5.1 sentences) is evaluated by every
version in geometry jobs on one worker (the farm's own path: ``run_batch`` with a
:class:`~cassi.harness.farm.executors.LocalExecutor`); a job's seconds are what its worker
measured. Then, in this process and with warm caches, the parts of the same work are timed on
the same inputs:

- ``animate_s``: the version's animation (``animate_to_file``), the version's own computation;
- ``leave_one_out_s``: Table G's animations with T2, then T3, withheld (``withheld_sites``);
- ``checks_s``: the geometric checks (``run_geometry_checks``);
- ``rest_s``: the job less those three: process and cache set-up, reading and verifying the
  inputs, choosing frames, the viewer's data, serialising and writing the outputs.

``job_overhead_share`` is ``rest_s`` over the job's seconds, summed over the versions.
"""
from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

from cassi.harness.evaluation.caches import (get_corpus, get_face, get_neutral, get_profile,
                                             get_version_face)
from cassi.harness.evaluation.config import RunConfig
from cassi.harness.evaluation.run import plan
from cassi.harness.evaluation.stages import animate_to_file, cassi_pipeline
from cassi.harness.evaluation.withheld import withheld_sites
from cassi.harness.farm.executors import LocalExecutor
from cassi.harness.farm.jobs import StageContext, State
from cassi.harness.farm.runner import run_batch
from cassi.harness.farm.store import OutputStore
from cassi.harness.farm.workers import thread_env
from cassi.harness.rubric import run_geometry_checks
from cassi.versions.registry import get_version

PARTS = ("animate_s", "leave_one_out_s", "checks_s")


def _parts(corpus, subject: str, task: int, rep: int, version: str, tmp: Path) -> dict:
    """The three parts of one geometry job's work, timed in this process (caches warm); the
    positions file in a folder of its own under ``tmp``, read by the checks."""
    profile = get_profile(corpus, subject)
    rec = corpus.subject(subject).load(task, rep, require_valid=False)
    ver = get_version(version)
    face = get_face(corpus, subject, profile)
    with tempfile.TemporaryDirectory(dir=tmp) as positions:
        t0 = time.perf_counter()
        anim = animate_to_file(ver, profile, face, rec, Path(positions))
        t1 = time.perf_counter()
        withheld = withheld_sites(ver, profile, face, rec)
        t2 = time.perf_counter()
        run_geometry_checks(anim, get_version_face(corpus, subject, profile, ver), profile,
                            task=task, subject=subject, rep=rep, neutral=get_neutral(),
                            recording=rec, withheld=withheld)
        t3 = time.perf_counter()
    return {"animate_s": t1 - t0, "leave_one_out_s": t2 - t1, "checks_s": t3 - t2}


def bench_job_cost(quick: bool = False, *, subject: str = "JW11", task: int = 19) -> dict:
    """Each version's geometry job on one task file, its seconds and their split (above)."""
    cfg = RunConfig(subjects=(subject,), tasks=(task,), views=("geometry",))
    corpus, tasks, versions, _ = plan(cfg)
    tasks = [t for t in tasks if t.usable][:1]
    if not tasks:
        return {"error": f"{subject} task {task} is not usable in the default corpus"}
    if quick:
        versions = versions[:2]
    tmp = Path(tempfile.mkdtemp(prefix="cassi-bench-jobcost-"))
    try:
        ctx = StageContext(out_dir=tmp / "run", corpus=Path(corpus.root), stride=0,
                           chunk_size=RunConfig().chunk, preset="preview", synthetic=True)
        OutputStore(ctx.out_dir).prepare()
        with LocalExecutor(1, env=thread_env(1)) as ex:
            res = run_batch(tasks, versions, (), cassi_pipeline(render=False), ctx, ex,
                            progress=False)
        jobs = {key.split("/")[2]: rec.seconds for key, rec in res.records.items()
                if rec.stage == "geometry" and rec.state is State.DONE}
        if len(jobs) != len(versions):
            return {"error": f"{len(versions) - len(jobs)} geometry job(s) did not finish"}
        spec = tasks[0]
        by_version = {}
        for version in versions:
            _parts(get_corpus(str(corpus.root)), spec.subject, spec.task, spec.rep, version,
                   tmp)                                         # warm this process's caches
            parts = _parts(get_corpus(str(corpus.root)), spec.subject, spec.task, spec.rep,
                           version, tmp)
            rest = jobs[version] - sum(parts.values())
            by_version[version] = {"job_s": round(jobs[version], 3),
                                   **{k: round(v, 3) for k, v in parts.items()},
                                   "rest_s": round(rest, 3)}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    total = sum(v["job_s"] for v in by_version.values())
    summed = {k: round(sum(v[k] for v in by_version.values()), 3)
              for k in ("job_s", *PARTS, "rest_s")}
    return {"subject": subject, "task": task, "rows": int(len(corpus.subject(subject).load(
                task, tasks[0].rep, require_valid=False).time_us)),
            "by_version": by_version, "total": summed,
            "job_overhead_share": round(summed["rest_s"] / total, 3) if total else None}
