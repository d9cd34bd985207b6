"""A synthetic XRMB task written as EMA (3-D, a known head motion and sensor rotation per frame)
in every format, read back through a coil map: the pellets within 0.1 mm."""
from __future__ import annotations

import numpy as np
import pytest

from ema_writers import (PELLET_COILS, coil_table, head_motion_2d, head_motion_3d, write_est,
                         write_pos, write_table)
from cassi.data.corpus.disk import Corpus
from cassi.data.synth.corpus import generate_task
from cassi.data.synth.subjects import SUBJECTS
from cassi.data.xrmb.files import PELLETS

N = 240
MAP_3D = """\
format: {fmt}
{extra}pellets: {{UL: ul, LL: ll, T1: t1, T2: t2, T3: t3, T4: t4, MNI: mni, MNM: mnm}}
references: {{upper_incisor: ui, nose_bridge: nb, mastoid_left: ml, mastoid_right: mr}}
head_frame: {{occlusal: {{front: bf, back: bb{bite}}}}}
"""
ORDER = PELLET_COILS + ("ui", "nb", "ml", "mr", "bf", "bb")


@pytest.fixture(scope="module")
def task():
    t_us, xy = generate_task(SUBJECTS["JW11"], 5)
    return t_us[:N] / 1e6, xy[:N]


def _read(tmp_path, name):
    corpus = Corpus(tmp_path)
    subj = corpus.subject("ema01")
    assert subj.ema is not None
    (key,) = subj.tasks()
    return subj.load(*key)


@pytest.mark.parametrize("variant", ["est-ascii", "est-binary-01", "est-binary-10",
                                     "pos-header", "pos-plain", "tsv-ms", "csv-s"])
def test_round_trip_3d(tmp_path, task, variant):
    time_s, xy = task
    coils = head_motion_3d(xy)
    d = tmp_path / "ema01"
    d.mkdir()
    fmt, bite, extra = variant.split("-")[0], "", ""
    if fmt == "est":
        names, values = coil_table(coils, ORDER)
        write_est(d / "ema01_007.ema", names, time_s, values, binary="binary" in variant,
                  order=variant[-2:])
    elif fmt == "pos":
        stack = np.stack([coils[c] for c in ORDER], axis=1)
        extra = "coils: {" + ", ".join(f"{c}: {k + 1}" for k, c in enumerate(ORDER)) + "}\n"
        if variant == "pos-header":
            write_pos(d / "0007.pos", stack, rate_hz=250)
            # the bite plane: a recording of its own, the head held elsewhere
            bite_stack = np.stack([head_motion_3d(xy[:20], seed=7)[c] for c in ORDER], axis=1)
            write_pos(d / "bite.pos", bite_stack, rate_hz=250)
            bite = ", file: bite.pos"
        else:
            write_pos(d / "0007.pos", stack)
            extra += "channels: 14\nrate_hz: 250\n"
    else:
        sep = "\t" if fmt == "tsv" else ","
        scale = 1000.0 if variant.endswith("ms") else 1.0
        write_table(d / f"take_007.{fmt}", {c: coils[c] for c in ORDER}, time_s * scale, sep=sep)
        extra = "time_unit: ms\n" if scale != 1.0 else ""
    (d / "ema.yaml").write_text(MAP_3D.format(fmt=fmt, extra=extra, bite=bite))
    rec = _read(tmp_path, "ema01")
    assert rec.task == 1007 and rec.derived == ()
    assert rec.valid.all()
    err = np.abs(rec.xy_mm - xy).max()
    assert err < 0.1, f"{variant}: {err:.4f} mm"
    if fmt != "pos":
        np.testing.assert_array_equal(rec.time_us, np.rint(time_s * 1e6).astype(np.int64))


def test_round_trip_mocha_preset(tmp_path, task):
    """2-D, MOCHA-TIMIT's channel names and 0.01 mm units, +x backward: ``preset: mocha-timit``
    alone reads it; T4 and MNM are derived and flagged, the six measured pellets come back."""
    time_s, xy = task
    coils = head_motion_2d(xy)
    mocha = {"ul": "ul", "ll": "ll", "t1": "tt", "t2": "tb", "t3": "td", "mni": "li",
             "ui": "ui", "nb": "bn"}
    renamed = {mocha[c]: v / 0.01 for c, v in coils.items() if c in mocha}
    names, values = coil_table(renamed, list(renamed))
    d = tmp_path / "fsew0"
    d.mkdir()
    rate_time = np.arange(len(time_s)) / 500.0
    write_est(d / "fsew0_012.ema", names, rate_time, values, binary=True,
              breaks=np.ones(len(time_s)))
    (tmp_path / "ema.yaml").write_text("preset: mocha-timit\n")
    subj = Corpus(tmp_path).subject("fsew0")
    rec = subj.load(1012)
    assert rec.derived == ("T4", "MNM")
    assert rec.time_us[1] - rec.time_us[0] == 2000  # the file's 500 Hz, not XRMB's 6866 us
    measured = [PELLETS.index(p) for p in ("UL", "LL", "T1", "T2", "T3", "MNI")]
    assert np.abs(rec.xy_mm[:, measured] - xy[:, measured]).max() < 0.1
    mnm = rec.pellet("MNM")
    jaw = np.hypot(*(mnm - rec.pellet("MNI")).T)
    np.testing.assert_allclose(jaw, 42.6, atol=1e-6)  # the one JW11 jaw length
