"""One run from a configuration: check everything, then plan and run the batch.

Order matters: every name and setting is checked (and the output directory proven writable and
locked) before the first job starts, so bad input never leaves a half-done batch behind.
"""
from __future__ import annotations

import json
import sys
import time

from cassi.common.atomic import atomic_write_text
from cassi.common.cores import usable_cores
from cassi.common.errors import CassiInputError, first_few

from cassi.harness.evaluation import config as C
from cassi.harness.evaluation.evalset import default_tasks, explicit_tasks, full_tasks
from cassi.harness.farm.executors import make_executor, require_ray
from cassi.harness.evaluation.inputs import check_inputs
from cassi.harness.farm.jobs import GEOMETRY_VIEW, StageContext
from cassi.harness.evaluation.provenance import code_provenance, shared_provenance
from cassi.harness.farm.runner import Pipeline, RunResult, run_batch
from cassi.harness.farm.store import OutputStore
from cassi.harness.farm.workers import worker_env
from cassi.harness.evaluation.caches import get_corpus, get_profile
from cassi.harness.evaluation.frames import judged_views, masks_only, render_budget
from cassi.harness.evaluation.stages import MASKS_FORMAT, cassi_pipeline, catalog
from cassi.renderer.variant import choose_variant


def plan(cfg: C.RunConfig):
    """Resolve a configuration against the corpus and registries.

    Returns
    -------
    (corpus, tasks, versions, views)
        ``tasks`` a list of :class:`~cassi.harness.farm.plan.TaskSpec` (unusable ones included,
        with reasons), ``views`` the render views (empty for a geometry-only run).

    Raises
    ------
    CassiInputError
        Unknown names (with the valid ones), unreadable corpus.
    """
    corpus = get_corpus(cfg.corpus)
    cat = catalog(corpus)
    try:
        C.check_names(cfg, cat)
    except CassiInputError as err:
        # A name the corpus lacks because its file or directory was refused (a link out of
        # the corpus): the refusal is the answer, not "did you mean".
        refused = list(corpus.problems) + [p for s in (cfg.subjects or cat.subjects)
                                           if s in cat.subjects
                                           for p in corpus.subject(s).problems]
        if refused:
            raise CassiInputError("\n".join([*dict.fromkeys(refused), str(err)])) from None
        raise
    subjects = list(cfg.subjects) if cfg.subjects else list(cat.subjects)
    if cfg.tasks:
        tasks = explicit_tasks(corpus, subjects, cfg.tasks)
    elif cfg.set == "full":
        tasks = full_tasks(corpus, subjects)
    else:
        tasks = default_tasks(corpus, subjects)
    versions = list(cfg.versions) if cfg.versions else list(cat.versions)
    views = [v for v in (cfg.views or cat.views) if v != GEOMETRY_VIEW]
    return corpus, tasks, versions, views


def worker_count(requested: int, jobs: int, *, cpus: int | None = None) -> tuple[int, str]:
    """Workers to start: at most one per job (a worker with nothing to do only costs a start),
    with a warning when more are asked for than there are cores."""
    cpus = cpus or usable_cores()
    n = max(1, min(int(requested), int(jobs)))
    warning = ""
    if n > cpus:
        warning = (f"{n} workers on {cpus} CPU cores: workers will wait for each other "
                   f"(one worker per core is the fastest)")
    return n, warning


def _warn(lines: list[str], *, limit: int = 10) -> None:
    for line in lines[:limit]:
        print(f"warning: {line}", file=sys.stderr)
    if len(lines) > limit:
        print(f"warning: ... and {len(lines) - limit} more (see `cassi corpus check`)",
              file=sys.stderr)


def run(cfg: C.RunConfig, *, progress: bool = True, pipeline: Pipeline | None = None) -> RunResult:
    """Run ``cfg`` (see :mod:`cassi.harness.evaluation.config`); writes everything under ``cfg.out``.

    Everything is checked before the first job: names, the render variant, and every corpus
    file the run reads (:func:`cassi.harness.evaluation.inputs.check_inputs`).
    """
    if cfg.executor == "ray":
        require_ray()
    corpus, tasks, versions, views = plan(cfg)
    if not tasks or not versions:
        what = "task files for the chosen subjects and tasks" if not tasks else "versions"
        raise CassiInputError(f"nothing to run: the corpus has no {what}, and a run of 0 jobs "
                              "would prove nothing", path=corpus.root)
    variant = cfg.variant
    if views:
        variant = choose_variant(cfg.variant)  # an unknown or unusable variant fails here
    checked = check_inputs(corpus, tasks, get_profile=get_profile)
    _warn(checked.warnings)
    tasks = checked.tasks
    if not any(t.usable for t in tasks):
        raise CassiInputError("nothing to evaluate: no task file of the run is usable ("
                              + first_few([f"{t.subject}/{t.task:03d}-{t.rep}: {t.reason}"
                                        for t in tasks]) + "), and a run that evaluates nothing "
                              "would prove nothing", path=corpus.root)
    synthetic = bool(getattr(corpus, "is_synthetic", False))
    pipeline = pipeline or cassi_pipeline(render=bool(views))
    provenance = code_provenance(versions)
    workers, warning = worker_count(cfg.workers, max(1, sum(t.usable for t in tasks) * len(versions)))
    if warning:
        _warn([warning])
    if progress:
        n = render_budget(checked.rows, tasks, versions, views, stride=cfg.stride,
                          extremes=cfg.extremes, animate_stride=cfg.animate_stride,
                          video_versions=cfg.video_versions)
        print(f"cassi run: {sum(t.usable for t in tasks)} task file(s) x {len(versions)} "
              f"version(s) x {len(views)} view(s): at most {n} frame(s) to render "
              f"({cfg.preset}, {workers} worker(s))", file=sys.stderr, flush=True)
    # The executor first: an unreachable cluster fails here, before --out holds anything.
    executor = make_executor(cfg.executor, workers=workers, address=cfg.address,
                             retries=cfg.retries, initializer=worker_env,
                             initargs=(cfg.threads,), threads=cfg.threads)
    with executor:
        result = _run(cfg, executor, corpus, tasks, versions, views, variant, synthetic,
                      pipeline, provenance, workers, progress)
    if result.ok and result.results.empty:
        # every job skipped in its worker (the plan thought the files usable): no failure, and
        # nothing to show for it
        raise CassiInputError("the run evaluated nothing: every job was skipped ("
                              + first_few([f"{r.key}: {r.reason}" for r in result.summary.skipped])
                              + "), so its empty tables prove nothing", path=cfg.out)
    return result


def run_options(cfg: C.RunConfig) -> tuple[tuple[str, object], ...]:
    """The stages' run options (:meth:`StageContext.option`), part of every job's digest: the
    frame policy's settings and the stored masks' format (a store of another format
    recomputes)."""
    return (("extremes", cfg.extremes), ("animate_stride", cfg.animate_stride),
            ("video_versions", cfg.video_versions), ("masks_format", MASKS_FORMAT))


def derived_pellets(corpus, subjects) -> dict[str, list[str]]:
    """Subject -> the pellets its EMA coil map derives, one line each (none for XRMB subjects):
    ``run.json`` records them so that every report flags them."""
    out = {}
    for name in subjects:
        ema = corpus.subject(name).ema
        if ema is not None and ema.derived_rules():
            out[name] = ema.derived_rules()
    return out


def _run(cfg, executor, corpus, tasks, versions, views, variant, synthetic, pipeline, provenance,
         workers, progress) -> RunResult:
    """The part of :func:`run` that writes ``cfg.out``, once the executor is up."""
    store = OutputStore(cfg.out, cache=cfg.cache)
    store.prepare()
    ctx = StageContext(out_dir=store.root.resolve(), corpus=corpus.root.resolve(),
                       stride=cfg.stride, chunk_size=cfg.chunk, preset=cfg.preset,
                       variant=variant, synthetic=synthetic,
                       options=run_options(cfg),
                       provenance=json.dumps(shared_provenance(provenance), sort_keys=True),
                       version_provenance=tuple(sorted(provenance["version_digests"].items())),
                       ship=cfg.executor == "ray",
                       cache_dir=None if cfg.cache is None else cfg.cache.resolve())
    meta = C.resolved(cfg, corpus_resolved=str(ctx.corpus), synthetic=synthetic,
                      versions_resolved=versions, views_resolved=views,
                      variant_resolved=variant, workers_resolved=workers,
                      tasks_resolved=[[t.subject, t.task, t.rep, t.usable, t.reason, t.inputs]
                                      for t in tasks],
                      provenance=provenance,
                      started=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    derived = derived_pellets(corpus, dict.fromkeys(t.subject for t in tasks))
    if derived:
        meta["derived_pellets"] = derived
    if synthetic:
        meta["note"] = ("results on the synthetic corpus describe the software, not real "
                        "speakers")
    with store.lock():
        store.remove_partials()
        atomic_write_text(store.root / "run.json", json.dumps(meta, indent=1, default=str))
        result = run_batch(tasks, versions, views, pipeline, ctx, executor,
                           progress=progress, extra_meta={"synthetic": synthetic},
                           masks_only=masks_only(tasks, views),
                           judged=judged_views(tasks, views))
        meta["summary"] = result.summary.to_dict()
        meta["finished"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        atomic_write_text(store.root / "run.json", json.dumps(meta, indent=1, default=str))
    return result
