"""Check every corpus file a run reads before any job starts, and digest them.

A malformed file (a task file, PAL.DAT, PHA.DAT, Mis.dat, a head-measures file, corpus.json)
stops the run with ``file:line: reason`` (exit 2), exactly as ``cassi corpus check`` reports
it; a well-formed file that cannot be animated (no row with all eight pellets valid) stays a
skipped job with its reason. Each usable task file gets the digest of everything its jobs
read (:func:`cassi.harness.evaluation.provenance.task_inputs_digest`), and each of those
files its own digest (``TaskSpec.reads``: its name inside the corpus and SHA-256, and the
profile's digest under :data:`PROFILE`).

The task files that preprocessing reads for a subject's profile (thesis 4.2: up to 20 of them,
not only the run's) are checked too: a malformed one exits 2 like any other, because leaving it
out of the profile would change every lip normalisation of the subject without a word.

A worker verifies what it reads against those digests (:func:`read_planned`,
:func:`verify_subject_files`, :func:`verify_profile`, :func:`verify_code`): a file edited after
planning, or a cluster node whose corpus or code is not the driver's, fails the job with the
reason instead of storing outputs under a digest that does not describe them.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import platform
from dataclasses import dataclass, field
from pathlib import Path

from cassi.data.corpus.disk import check_task_file
from cassi.data.xrmb.textlines import read_bytes
from cassi.common.errors import CassiInputError

from cassi.harness.farm.plan import TaskSpec
from cassi.harness.evaluation.provenance import (code_digest, file_digest, profile_digest,
                                                 task_inputs_digest, version_digest)
from cassi.harness.evaluation.config import package_version

#: The name under which ``TaskSpec.reads`` holds the subject profile's digest.
PROFILE = "<profile>"

#: Subject attributes that read (and parse) the subject's own files.
_SUBJECT_READS = ("palate_mm", "pharynx_mm", "mistracking", "head_measures")


@dataclass
class CheckedInputs:
    """The run's task files with their input digests, the warnings the files raised, and each
    file's number of rows (``(subject, task, rep) -> rows``)."""

    tasks: list[TaskSpec]
    warnings: list[str] = field(default_factory=list)
    rows: dict[tuple[str, int, int], int] = field(default_factory=dict)


def check_inputs(corpus, tasks: list[TaskSpec], *, get_profile) -> CheckedInputs:
    """Validate the files behind ``tasks`` and fill in each spec's ``inputs`` digest.

    Parameters
    ----------
    corpus : cassi.data.corpus.disk.Corpus
    tasks : list of TaskSpec
        The run's task files (unusable ones included; they stay as they are).
    get_profile : callable (corpus, subject, *, problems) -> SubjectProfile
        The harness's cached profile (thesis 4.2), so that workers in this process reuse it.

    Raises
    ------
    CassiInputError
        Listing every malformed file, one ``file:line: reason`` per line.
    """
    errors: list[str] = list(corpus.problems)
    warnings: list[str] = list(corpus.warnings)
    try:
        corpus.metadata
        corpus.head_measures_table
    except CassiInputError as err:
        errors.append(str(err))
    subjects = {}
    for spec in tasks:
        if spec.subject not in subjects:
            subj = subjects[spec.subject] = corpus.subject(spec.subject)
            for attr in _SUBJECT_READS:
                try:
                    getattr(subj, attr)
                except CassiInputError as err:
                    errors.append(str(err))
            errors.extend(subj.problems)
    paths, rows = {}, {}
    for spec in tasks:
        subj = subjects[spec.subject]
        if (spec.task, spec.rep) not in subj.task_files():
            continue  # no file: a skipped job that says so
        path = paths[spec] = subj.task_path(spec.task, spec.rep)
        report = check_task_file(path, subject=subj)
        rows[(spec.subject, spec.task, spec.rep)] = report.frames or 0
        if report.error:
            errors.extend(report.problems)
        warnings.extend(report.warnings)
    if errors:
        raise CassiInputError("\n".join(dict.fromkeys(errors)))
    profiles, unprofiled = {}, {}
    for name in subjects:
        try:
            profiles[name] = get_profile(corpus, name, problems=errors)
        except CassiInputError as err:
            unprofiled[name] = f"subject cannot be preprocessed: {err}"
    if errors:  # a malformed file that only preprocessing reads
        raise CassiInputError("\n".join(dict.fromkeys(errors)))
    checked = []
    for spec in tasks:
        if spec.usable and spec.subject in unprofiled:
            spec = dataclasses.replace(spec, usable=False, reason=unprofiled[spec.subject])
        if spec.usable and spec in paths:
            subject_files = subjects[spec.subject].subject_files()
            profile = profiles[spec.subject]
            reads = tuple((input_name(corpus, p), file_digest(p))
                          for p in (paths[spec], *subject_files))
            spec = dataclasses.replace(spec, inputs=task_inputs_digest(
                task_file=paths[spec], subject_files=subject_files, profile=profile),
                reads=reads + ((PROFILE, profile_digest(profile)),))
        checked.append(spec)
    return CheckedInputs(checked, list(dict.fromkeys(warnings)), rows)


def input_name(corpus, path: Path) -> str:
    """``path``'s name inside the corpus (``JW12/tp002.txy``): the same on every node that
    mounts the corpus, wherever the driver and the worker see its root."""
    try:
        return Path(path).relative_to(corpus.root).as_posix()
    except ValueError:
        return Path(path).name


def _where() -> str:
    return f"host {platform.node()}"


def _changed(name: str, planned: str, found: str) -> CassiInputError:
    return CassiInputError(
        f"changed since the run was planned (sha256 {planned[:12]} planned, {found[:12]} read on "
        f"{_where()}): the job is not stored; rerun once the corpus no longer changes (on a "
        f"cluster: every node must see the driver's corpus)", path=name)


def read_planned(job, corpus, path: Path) -> bytes:
    """The bytes of ``path`` read once, refused unless they are the ones the job was planned
    with (a job planned without digests reads them as they are)."""
    data = read_bytes(path)
    name = input_name(corpus, path)
    planned = job.planned(name)
    if job.reads and planned != hashlib.sha256(data).hexdigest():
        raise _changed(name, planned or "-" * 12, hashlib.sha256(data).hexdigest())
    return data


def verify_subject_files(job, subject) -> None:
    """The subject's files (PAL.DAT, PHA.DAT, Mis.dat, head measures) are the planned ones."""
    if not job.reads:
        return
    corpus = subject.corpus
    found = {input_name(corpus, p): file_digest(p) for p in subject.subject_files()}
    task = input_name(corpus, subject.task_path(job.task, job.rep))
    planned = {n: d for n, d in job.reads if n not in (PROFILE, task)}
    for name in sorted(set(planned) | set(found)):
        if planned.get(name) != found.get(name):
            raise _changed(name, planned.get(name) or "-" * 12, found.get(name) or "-" * 12)


def verify_profile(job, profile) -> None:
    """The profile this worker computed (from up to 20 task files) is the planned one."""
    planned = job.planned(PROFILE)
    if planned is not None and planned != profile_digest(profile):
        raise CassiInputError(
            f"subject {job.subject}: its profile (thesis 4.2, from {len(profile.selected)} task "
            f"files) differs from the one the run was planned with ({_where()}): a file it is "
            f"computed from changed, or this node sees another corpus; the job is not stored")


_verified_code: set[tuple] = set()


def verify_code(ctx, version: str | None = None) -> None:
    """This process runs the code the driver planned with (same package version and cassi
    files, and ``version``'s own code); a cluster node with other code fails its jobs with the
    reason. The rubric digest is not compared: the registry is built from those same files,
    and a driver may patch it in-process (tests) without the workers seeing it."""
    key = (ctx.provenance, version)
    if not ctx.provenance or key in _verified_code:
        return
    planned = json.loads(ctx.provenance)
    here = {"package_version": package_version(), "code_digest": code_digest()}
    planned_version = dict(ctx.version_provenance).get(version)
    if planned_version is not None:
        planned[f"{version} code"] = planned_version
        here[f"{version} code"] = version_digest(version)
    differ = [k for k, v in here.items() if k in planned and planned[k] != v]
    if differ:
        raise CassiInputError(
            f"this worker ({_where()}) runs other code than the driver: "
            + ", ".join(f"{k} {here[k][:12]} here, {str(planned[k])[:12]} on the driver"
                        for k in differ)
            + "; install the same cassi-farm on every node")
    _verified_code.add(key)
