"""How smoothly each version moves the tongue, side by side, over the default evaluation set.

Geometry only (no renders): every usable task file of ``default_tasks`` on the corpus is
animated by each version, through the harness's caches, and per task file measured:

- ``step ratio``: the largest frame-to-frame step of any tongue vertex over the largest step of
  a tongue pellet (T1-T4, mapped) in that task. The pellets are the data; a tongue that moves
  more than its fastest pellet does so because of the version.
- ``shake``: the rubric's lip-jitter measure (``excess_jitter``: distance from a 9-frame
  quadratic fit, beyond the largest such shake of the T1-T4 vertices) on the tongue, in mm;
  frames above 1 mm are counted.

Usage (versions are registry names or ``module:Class``, so an older copy of a version can be
measured in the same run)::

    python plugins/cassi30/tools/shake.py cassi-2.1 cassi-3.0 [old_cassi30:Cassi30] [--corpus DIR]
"""
from __future__ import annotations

import argparse
import importlib
import time

import numpy as np

from cassi.common.cliargs import ascii_int
from cassi.data.face import numbering as N
from cassi.harness.evaluation.caches import get_corpus, get_face, get_profile
from cassi.harness.evaluation.evalset import default_tasks
from cassi.harness.rubric import geometry as G
from cassi.harness.rubric.registry import JITTER_ORDER, JITTER_WINDOW
from cassi.versions.protocol import PELLET_INDEX, version_face
from cassi.versions.registry import get_version

#: The excess shake counted as a fault per frame, mm (the task's figure: "more than 1 mm").
SHAKE_LIMIT_MM = 1.0
_PELLETS = [PELLET_INDEX[p] for p in ("T1", "T2", "T3", "T4")]


def load_version(spec: str):
    """A registered version by name, or ``module:Class`` instantiated."""
    if ":" in spec:
        module, cls = spec.split(":", 1)
        return getattr(importlib.import_module(module), cls)()
    return get_version(spec)


def tongue_rows(version, face) -> np.ndarray:
    """0-based rows of the tongue in the face ``version`` animates: Parke's 288-299 and every
    vertex the version adds after the shared face's (3.0's added vertices are all tongue)."""
    own = version_face(version, face)
    n_shared, n_own = len(face.vertices), len(own.vertices)
    return np.concatenate([np.asarray(N.TONGUE) - 1, np.arange(n_shared, n_own)])


def measure_task(version, profile, face, rec) -> dict:
    """The figures of one task file (see the module docstring), subject mm."""
    anim = version.animate(profile, face, rec)
    pos = np.asarray(anim.positions, np.float64)
    rows = tongue_rows(version, face)
    mm = G.mm_per_unit(face.vertices, profile.jaw_length_mm)
    step = np.linalg.norm(np.diff(pos[:, rows], axis=0), axis=-1).max()
    pellets = version.context(profile, face, rec).pellets[:, _PELLETS]
    pellet_step = np.linalg.norm(np.diff(pellets, axis=0), axis=-1).max()
    excess = G.excess_jitter(pos, rows, np.asarray(N.TONGUE_PELLETS) - 1,
                             window=JITTER_WINDOW, order=JITTER_ORDER) * mm
    return {"step_mm": step * mm, "ratio": step / max(pellet_step, 1e-12),
            "shake_mm": float(excess.max(initial=0.0)),
            "frames": int((excess > SHAKE_LIMIT_MM).sum())}


def measure(specs, corpus=None, subjects=None) -> dict[str, list[tuple[str, int, dict]]]:
    """Per version spec, (subject, task, figures) for every usable default task file; every
    version sees the same inputs, task by task."""
    c = get_corpus(corpus)
    versions = {s: load_version(s) for s in specs}
    out: dict[str, list] = {s: [] for s in specs}
    for spec in default_tasks(c, subjects):
        if not spec.usable:
            continue
        profile = get_profile(c, spec.subject)
        face = get_face(c, spec.subject, profile)
        rec = c.subject(spec.subject).load(spec.task, spec.rep)
        for s, v in versions.items():
            out[s].append((spec.subject, spec.task, measure_task(v, profile, face, rec)))
    return out


def summary(rows) -> dict:
    ratio = np.array([r["ratio"] for _, _, r in rows])
    shake = np.array([r["shake_mm"] for _, _, r in rows])
    return {"tasks": len(rows), "ratio_worst": ratio.max(), "ratio_mean": ratio.mean(),
            "shake_worst": shake.max(), "frames_over": sum(r["frames"] for _, _, r in rows)}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("versions", nargs="+")
    ap.add_argument("--corpus", default=None)
    ap.add_argument("--subjects", nargs="*", default=None)
    ap.add_argument("--worst", type=ascii_int, default=5, help="task files listed per version")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    res = measure(a.versions, a.corpus, a.subjects)
    print(f"| version | task files | largest step / pellet step: worst, mean "
          f"| shake: worst mm, frames > {SHAKE_LIMIT_MM:g} mm |")
    print("|---|---|---|---|")
    for s, rows in res.items():
        m = summary(rows)
        print(f"| {s} | {m['tasks']} | {m['ratio_worst']:.2f}, {m['ratio_mean']:.2f} "
              f"| {m['shake_worst']:.2f}, {m['frames_over']} |")
    for s, rows in res.items():
        worst = sorted(rows, key=lambda r: (-r[2]["frames"], -r[2]["shake_mm"]))[:a.worst]
        print(f"{s}: " + "; ".join(f"{sub} {t}: {r['frames']} frames, {r['shake_mm']:.2f} mm, "
                                   f"x{r['ratio']:.2f}" for sub, t, r in worst))
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
