"""A synthetic XRMB task written as EMA (3-D, a known head motion and sensor rotation per frame)
in every format, read back through a coil map: the pellets within 0.1 mm."""
from __future__ import annotations

import numpy as np
import pytest

from ema_writers import (MAP_3D, ORDER, PELLET_COILS, coil_table, head_motion_2d, head_motion_3d,
                         write_est, write_pos, write_table)
from cassi.data.corpus.disk import Corpus
from cassi.data.synth.corpus import generate_task
from cassi.data.synth.subjects import SUBJECTS, palate_y
from cassi.data.xrmb.files import PELLETS

N = 240


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


def test_palate_trace_in_the_head_frame(tmp_path, task):
    """``palate: {file, coil}``: a coil run along JW11's palate, with the head moving, comes
    back as the outline (front to back) within 0.1 mm."""
    time_s, xy = task
    fig = SUBJECTS["JW11"]
    xs = np.linspace(fig.palate_outline()[0, 0], fig.palate_outline()[-1, 0], 600)
    trace = xy[:1].repeat(600, axis=0)
    trace[:, 0] = np.column_stack([xs, palate_y(fig.palate, xs)])  # UL's coil traces it
    d = tmp_path / "ema01"
    d.mkdir()
    for name, pellets, t in (("ema01_001.ema", xy, time_s),
                             ("palate.ema", trace, np.arange(600) / 200.0)):
        coils = head_motion_3d(pellets)
        names, values = coil_table(coils, ORDER)
        write_est(d / name, names, t, values, binary=True)
    (d / "ema.yaml").write_text(MAP_3D.format(fmt="est", extra="", bite="")
                                + "palate: {file: palate.ema, coil: ul}\n")
    subj = Corpus(tmp_path).subject("ema01")
    assert [p.name for p in subj.task_files().values()] == ["ema01_001.ema"]
    outline = subj.palate_mm
    assert outline[0, 0] > outline[-1, 0]  # front to back
    np.testing.assert_allclose(outline[:, 1], palate_y(fig.palate, outline[:, 0]), atol=0.1)
    assert any(p.name == "palate.ema" for p in subj.subject_files())  # digested with the map


def test_mngu0_preset_reads_head_corrected_channels(tmp_path, task):
    time_s, xy = task
    coils = {"upperlip": "UL", "lowerlip": "LL", "T1": "T1", "T2": "T2", "T3": "T3",
             "jaw": "MNI"}
    names = [f"{c}_{a}" for c in coils for a in ("px", "py", "pz")]
    values = np.column_stack([col for c, p in coils.items() for col in (
        np.zeros(len(xy)), xy[:, PELLETS.index(p), 0], xy[:, PELLETS.index(p), 1])])
    d = tmp_path / "mngu0"
    d.mkdir()
    write_est(d / "mngu0_s1_0042.ema", names, np.arange(len(xy)) / 200.0, values)
    (d / "ema.yaml").write_text("preset: mngu0\n")
    rec = Corpus(tmp_path).subject("mngu0").load(1042)
    measured = [PELLETS.index(p) for p in coils.values()]
    np.testing.assert_allclose(rec.xy_mm[:, measured], xy[:, measured], atol=1e-4)
    assert rec.derived == ("T4", "MNM") and rec.time_us[1] == 5000
