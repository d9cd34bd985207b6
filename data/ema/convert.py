"""``cassi corpus convert``: an EMA corpus written as XRMB task files.

Per speaker: ``tpNNNN.txy`` for every readable recording (the EMA file's own sample times; a
derived pellet is written like a measured one, and the map beside says which), ``PAL.DAT``
where the speaker has a palate, the recording's ``.wav`` and ``.TextGrid`` renamed as the task,
and ``ema_map.json``: the coil map as resolved (preset expanded), its derived pellets and the
source file of every task. The output directory is built beside its destination and renamed
into place when complete, so it is never half written.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.data.corpus.disk import Corpus
from cassi.data.xrmb.files import task_file_name, write_pal, write_txy

RESOLVED_MAP = "ema_map.json"


def convert(ema_dir: str | os.PathLike, out: str | os.PathLike) -> tuple[int, list[str]]:
    """Convert ``ema_dir`` into ``out`` (which must not exist or be empty).

    Returns ``(task files written, problems)``: a recording that cannot be read is left out
    and named in ``problems`` (``file:line: reason``).
    """
    corpus = Corpus(ema_dir)
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise CassiInputError("exists and is not an empty directory", path=out)
    subjects = [corpus.subject(s) for s in corpus.subjects]
    if not any(s.ema is not None for s in subjects):
        raise CassiInputError("no speaker directory with a coil map (ema.yaml) and recordings",
                              path=corpus.root)
    out.parent.mkdir(parents=True, exist_ok=True)
    problems: list[str] = list(corpus.problems)
    written = 0
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        for subj in subjects:
            if subj.ema is None:
                continue
            written += _convert_subject(subj, tmp / subj.name, problems)
        (tmp / "corpus.json").write_text(json.dumps(
            {"converted_from": str(corpus.root), "format": "EMA"}, indent=1) + "\n")
        if out.exists():
            out.rmdir()
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return written, problems


def _convert_subject(subj, dest: Path, problems: list[str]) -> int:
    dest.mkdir()
    sources = {}
    for (task, rep), path in subj.task_files().items():
        try:
            rec = subj.load(task, rep, require_valid=False)
        except CassiInputError as err:
            problems.append(str(err))
            continue
        name = task_file_name(task, rep)
        write_txy(dest / name, rec)
        sources[name] = path.name
        for side, suffix in ((subj.audio_path(task, rep), ".wav"),
                             (subj.alignment_path(task, rep), ".TextGrid")):
            if side is not None:
                shutil.copyfile(side, dest / (Path(name).stem + suffix))
    try:
        write_pal(dest / "PAL.DAT", subj.palate_mm)
    except CassiInputError as err:
        problems.append(f"{err} (no PAL.DAT written)")
    resolved = subj.ema.map.resolved()
    resolved["derived_rules"] = subj.ema.derived_rules()
    resolved["tasks"] = sources
    atomic_write_text(dest / RESOLVED_MAP, json.dumps(resolved, indent=1, default=str) + "\n")
    return len(sources)
