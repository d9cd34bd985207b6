"""Writers of small EMA files for the tests (EST track, Carstens .pos, TSV/CSV), and a synthetic
XRMB task moved into an EMA recording's coordinates with a known head motion."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cassi.data.synth.corpus import generate_task
from cassi.data.synth.subjects import SUBJECTS
from cassi.data.xrmb.files import PELLETS, write_pal

#: Coil names of the round trip: the eight pellets, then references and bite-plane coils.
PELLET_COILS = ("ul", "ll", "t1", "t2", "t3", "t4", "mni", "mnm")
#: Reference and bite-plane coils in the XRMB head frame (mm; z lateral, + right).
FIXED = {"ui": (0.0, 0.0, 0.0), "nb": (8.0, 45.0, 0.0), "ml": (-85.0, 5.0, -55.0),
         "mr": (-85.0, 5.0, 55.0), "bf": (-2.0, 0.0, 0.0), "bb": (-32.0, 0.0, 0.0)}


def rotation(a: float, b: float, c: float) -> np.ndarray:
    """Rz(a) Ry(b) Rx(c), radians."""
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return rz @ ry @ rx


def head_motion_3d(xy: np.ndarray, *, seed: int = 1) -> dict[str, np.ndarray]:
    """``{coil: (F, 3)}`` recording coordinates: the head frame turned into a tilted sensor
    frame (30 deg and more), with a per-frame head rotation of up to 4 deg and 6 mm."""
    n = len(xy)
    rng = np.random.default_rng(seed)
    tt = np.linspace(0, 2 * np.pi, n)
    angles = np.stack([np.radians(4) * np.sin(tt + k) for k in range(3)], axis=1)
    shift = np.stack([6 * np.sin(tt * (k + 1)) for k in range(3)], axis=1)
    sensor = rotation(0.5, -0.3, 0.6)
    base = rng.normal(size=3) * 40
    head = {c: np.column_stack([xy[:, p], np.zeros(n)]) for p, c in enumerate(PELLET_COILS)}
    head.update({c: np.repeat(np.array(v)[None], n, axis=0) for c, v in FIXED.items()})
    out = {}
    for c, pts in head.items():
        moved = np.stack([rotation(*angles[f]) @ pts[f] for f in range(n)]) + shift
        out[c] = moved @ sensor.T + base
    return out


def head_motion_2d(xy: np.ndarray) -> dict[str, np.ndarray]:
    """``{coil: (F, 2)}``: MOCHA-like midsagittal coordinates, +x toward the back of the head
    (the sign the reader must find), a head rotation of up to 3 deg and 4 mm from frame 2 on."""
    n = len(xy)
    tt = np.linspace(0, 2 * np.pi, n)
    theta = np.radians(3) * np.sin(tt) * (np.arange(n) > 0)
    shift = np.column_stack([4 * np.sin(2 * tt), 3 * np.sin(tt)]) * (np.arange(n) > 0)[:, None]
    head = {c: xy[:, p] for p, c in enumerate(PELLET_COILS)}
    head.update({c: np.repeat(np.array(FIXED[c][:2])[None], n, axis=0) for c in ("ui", "nb")})
    out = {}
    for c, pts in head.items():
        cs, sn = np.cos(theta), np.sin(theta)
        rot = np.column_stack([cs * pts[:, 0] - sn * pts[:, 1], sn * pts[:, 0] + cs * pts[:, 1]])
        moved = rot + shift
        out[c] = np.column_stack([-moved[:, 0], moved[:, 1]])
    return out


def write_est(path: Path, names: list[str], time_s: np.ndarray, values: np.ndarray, *,
              binary: bool = False, order: str = "01", breaks: np.ndarray | None = None,
              frames: int | None = None) -> Path:
    """An EST track file (``frames``: the NumFrames to declare, default the true count)."""
    n = len(time_s)
    head = ["EST_File Track", f"DataType {'binary' if binary else 'ascii'}"]
    if binary:
        head.append(f"ByteOrder {order}")
    head += [f"NumFrames {n if frames is None else frames}", f"NumChannels {len(names)}",
             "EqualSpace 1", f"BreaksPresent {'true' if breaks is not None else 'false'}",
             "CommentChar ;", ""]
    head += [f"Channel_{k} {name}" for k, name in enumerate(names)]
    head.append("EST_Header_End")
    cols = [time_s] + ([breaks.astype(float)] if breaks is not None else []) + [values.T]
    table = np.column_stack([np.asarray(c).T if np.ndim(c) == 2 else c for c in cols])
    if binary:
        body = table.astype(("<" if order == "01" else ">") + "f4").tobytes()
    else:
        body = "".join(" ".join(f"{v:.9g}" for v in row) + "\n" for row in table).encode()
    path.write_bytes(("\n".join(head) + "\n").encode() + body)
    return path


def write_pos(path: Path, coils: np.ndarray, *, rate_hz: float | None = None) -> Path:
    """A .pos file of ``coils`` (F, C, 3) mm; with an AG50x header when ``rate_hz`` is given."""
    f, c, _ = coils.shape
    data = np.zeros((f, c, 7), dtype="<f4")
    data[:, :, :3] = coils
    data[:, :, 5] = 1.0  # rms
    head = b""
    if rate_hz is not None:
        lines = f"NumberOfChannels={c}\nSamplingFrequencyHz={rate_hz:g}\n".encode()
        size = 15 + 9 + len(lines) + 2
        head = b"AG50xDATA_V003\n" + f"{size:08d}\n".encode() + lines + b"\x00\x1a"
    path.write_bytes(head + data.tobytes())
    return path


def write_table(path: Path, coils: dict[str, np.ndarray], time: np.ndarray, *,
                sep: str = "\t") -> Path:
    """A TSV/CSV export: ``time`` then ``<coil>_x, _y, _z``; NaN written as empty cells."""
    names, cols = ["time"], [time]
    for c, v in coils.items():
        for k in range(v.shape[1]):
            names.append(f"{c}_{'xyz'[k]}")
            cols.append(v[:, k])
    rows = [sep.join(names)]
    for row in np.column_stack(cols):
        rows.append(sep.join("" if np.isnan(v) else f"{v:.9g}" for v in row))
    path.write_text("\n".join(rows) + "\n")
    return path


def coil_table(coils: dict[str, np.ndarray], order) -> tuple[list[str], np.ndarray]:
    """Channel names ``<coil>_x, _y[, _z]`` and the (F, C) values, coils in ``order``."""
    names, cols = [], []
    for c in order:
        for k in range(coils[c].shape[1]):
            names.append(f"{c}_{'xyz'[k]}")
            cols.append(coils[c][:, k])
    return names, np.column_stack(cols)


#: MOCHA-TIMIT's names of the coils :func:`head_motion_2d` moves (it has no T4, MNM coil).
MOCHA_COILS = {"ul": "ul", "ll": "ll", "t1": "tt", "t2": "tb", "t3": "td", "mni": "li",
               "ui": "ui", "nb": "bn"}
#: A TSV speaker's coil map: MOCHA's coils under their own names, T4 and MNM derived.
TSV_MAP = """format: tsv
rate_hz: 500
pellets: {UL: ul, LL: ll, T1: t1, T2: t2, T3: t3, MNI: mni}
derive: {T4: {rule: extrapolate, from: [T2, T3]}, MNM: {rule: jaw-rotation}}
references: {upper_incisor: ui, nose_bridge: nb}
head_frame: {forward: x, up: y}
"""


#: A 3-D recording's coil map: every pellet measured, four reference coils, the occlusal plane
#: from two coils (``{bite}``: ", file: ..." for a bite-plane recording of its own).
MAP_3D = """\
format: {fmt}
{extra}pellets: {{UL: ul, LL: ll, T1: t1, T2: t2, T3: t3, T4: t4, MNI: mni, MNM: mnm}}
references: {{upper_incisor: ui, nose_bridge: nb, mastoid_left: ml, mastoid_right: mr}}
head_frame: {{occlusal: {{front: bf, back: bb{bite}}}}}
"""
ORDER = PELLET_COILS + ("ui", "nb", "ml", "mr", "bf", "bb")


def speaker_map(fmt: str) -> str:
    """The ``ema.yaml`` of a speaker :func:`write_ema_speaker` writes in ``fmt`` "tsv", "csv"
    or "pos" (3-D: :data:`MAP_3D`, the coils by channel number in :data:`ORDER`)."""
    if fmt == "pos":
        coils = "coils: {" + ", ".join(f"{c}: {k + 1}" for k, c in enumerate(ORDER)) + "}\n"
        return MAP_3D.format(fmt="pos", extra=f"channels: {len(ORDER)}\nrate_hz: 500\n{coils}",
                             bite="")
    return TSV_MAP.replace("format: tsv", f"format: {fmt}")


def write_ema_speaker(root: Path, name: str, tasks=(5, 7), *, frames: int = 200,
                      fmt: str = "est") -> Path:
    """A speaker directory of JW11's synthetic tasks moved by :func:`head_motion_2d`, at 500 Hz
    (utterances ``<name>_001`` ...), and JW11's PAL.DAT: ``fmt`` "est" or "est-ascii"
    (MOCHA-TIMIT's files, binary or ASCII, in 0.01 mm, for ``preset: mocha-timit``), or "tsv",
    "csv", "pos" (mm, with :func:`speaker_map` as the speaker's ``ema.yaml``)."""
    d = root / name
    d.mkdir(parents=True)
    time_s = np.arange(frames) / 500.0
    for k, task in enumerate(tasks, start=1):
        _, xy = generate_task(SUBJECTS["JW11"], task)
        coils = {c: v for c, v in head_motion_2d(xy[:frames]).items() if c in MOCHA_COILS}
        if fmt == "pos":   # Carstens AG50x: 3-D, the head moving and turning
            moved = head_motion_3d(xy[:frames])
            write_pos(d / f"{name}_{k:03d}.pos", np.stack([moved[c] for c in ORDER], axis=1))
        elif fmt.startswith("est"):
            names, values = coil_table({MOCHA_COILS[c]: v / 0.01 for c, v in coils.items()},
                                       list(MOCHA_COILS.values()))
            write_est(d / f"{name}_{k:03d}.ema", names, time_s, values, binary=fmt == "est")
        else:
            write_table(d / f"{name}_{k:03d}.{fmt}", coils, time_s,
                        sep="\t" if fmt == "tsv" else ",")
    if not fmt.startswith("est"):
        (d / "ema.yaml").write_text(speaker_map(fmt))
    write_pal(d / "PAL.DAT", SUBJECTS["JW11"].palate_outline())
    return d


assert len(PELLET_COILS) == len(PELLETS)
