"""The EMA readers and the coil map refuse bad input with file:line (or byte) and keep missing
samples missing."""
from __future__ import annotations

import numpy as np
import pytest

from ema_writers import write_est, write_pos, write_table
from cassi.common.errors import CassiInputError
from cassi.data.corpus.disk import Corpus
from cassi.data.ema.coilmap import read_coil_map
from cassi.data.ema.est import read_est
from cassi.data.ema.pos import read_pos
from cassi.data.ema.table import read_table

T = np.arange(5) / 500.0
V = np.arange(10, dtype=float).reshape(5, 2)


@pytest.mark.parametrize("binary,order", [(False, "01"), (True, "01"), (True, "10")])
def test_est_variants_read_alike(tmp_path, binary, order):
    tr = read_est(write_est(tmp_path / "a.ema", ["ul_x", "ul_y"], T, V, binary=binary,
                            order=order, breaks=np.array([1, 1, 0, 1, 1])))
    assert tr.channels == ("ul_x", "ul_y") and tr.rate_hz == pytest.approx(500)
    np.testing.assert_allclose(tr.values, V)
    assert tr.valid.tolist() == [True, True, False, True, True]  # an EST break


def test_est_truncated_binary_names_the_byte(tmp_path):
    path = write_est(tmp_path / "a.ema", ["x", "y"], T, V, binary=True, frames=6)
    with pytest.raises(CassiInputError, match=r"truncated: NumFrames 6 .* ends at byte"):
        read_est(path)


def test_est_ascii_bad_row_names_the_line(tmp_path):
    path = write_est(tmp_path / "a.ema", ["x", "y"], T, V)
    lines = path.read_text().splitlines()
    lines[-2] = "0.006 oops 7"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(CassiInputError, match=rf"a.ema:{len(lines) - 1}: column 2"):
        read_est(path)
    path.write_text("\n".join(lines[:-2]) + "\n")
    with pytest.raises(CassiInputError, match="truncated: 3 frames of NumFrames 5"):
        read_est(path)


def test_est_not_a_track(tmp_path):
    (tmp_path / "a.ema").write_bytes(b"hello\n")
    with pytest.raises(CassiInputError, match="a.ema:1: not an EST track"):
        read_est(tmp_path / "a.ema")


def test_pos_with_and_without_header_and_nan(tmp_path):
    coils = np.arange(4 * 2 * 3, dtype=float).reshape(4, 2, 3)
    coils[2, 1, 0] = np.nan
    plain = read_pos(write_pos(tmp_path / "a.pos", coils), channels=2, rate_hz=200)
    head = read_pos(write_pos(tmp_path / "b.pos", coils, rate_hz=250))
    assert head.rate_hz == 250 and plain.rate_hz == 200
    np.testing.assert_array_equal(plain.values, head.values)
    assert np.isnan(head.column("2_x")[2]) and head.column("1_z")[1] == 8.0


def test_pos_truncated_and_undeclared(tmp_path):
    coils = np.zeros((4, 2, 3))
    path = write_pos(tmp_path / "a.pos", coils, rate_hz=250)
    path.write_bytes(path.read_bytes()[:-5])
    with pytest.raises(CassiInputError, match="truncated or wrong channel count.*byte"):
        read_pos(path)
    plain = write_pos(tmp_path / "b.pos", coils)
    with pytest.raises(CassiInputError, match="must declare 'channels' and 'rate_hz'"):
        read_pos(plain)
    with pytest.raises(CassiInputError, match="declares channels 3, the file's header 2"):
        read_pos(path, channels=3)


@pytest.mark.parametrize("sep,suffix", [("\t", "tsv"), (",", "csv")])
def test_table_missing_cells_stay_missing(tmp_path, sep, suffix):
    v = V.copy()
    v[1, 0] = np.nan
    path = write_table(tmp_path / f"a.{suffix}", {"ul": v}, T * 1000, sep=sep)
    tr = read_table(path, time_unit="ms")
    np.testing.assert_allclose(tr.time_s, T)
    assert np.isnan(tr.column("ul_x")[1]) and tr.column("ul_y")[1] == 3.0
    path.write_text(path.read_text().replace(f"{sep}9\n", f"{sep}x9\n"))
    with pytest.raises(CassiInputError, match=rf"a.{suffix}:6: column 'ul_y'"):
        read_table(path, time_unit="ms")


MAP = """\
format: est
pellets: {UL: ul, LL: ll, T1: t1, T2: t2, T3: t3, T4: t4, MNI: mni, MNM: mnm}
references: {upper_incisor: ui, nose_bridge: nb}
head_frame: {forward: +x, up: +y}
"""


def test_map_without_references_is_refused(tmp_path):
    path = tmp_path / "ema.yaml"
    path.write_text(MAP.replace("references: {upper_incisor: ui, nose_bridge: nb}\n", ""))
    with pytest.raises(CassiInputError, match="ema.yaml: no reference coils"):
        read_coil_map(path)
    path.write_text(MAP.replace("MNM: mnm", "MNX: mnm"))
    with pytest.raises(CassiInputError, match="ema.yaml:2: 'MNX' is not an XRMB pellet"):
        read_coil_map(path)
    path.write_text("preset: mocha\n")
    with pytest.raises(CassiInputError, match="ema.yaml:1: unknown preset 'mocha'"):
        read_coil_map(path)


def test_unknown_coil_names_the_map_line(tmp_path):
    d = tmp_path / "spk1"
    d.mkdir()
    coils = ["ul", "ll", "t1", "t2", "t3", "t4", "mni", "mnm", "ui", "nb"]
    names = [f"{c}_{a}" for c in coils for a in "xy"]
    vals = np.random.default_rng(0).normal(size=(5, len(names)))
    write_est(d / "spk1_001.ema", names, T, vals)
    (d / "ema.yaml").write_text(MAP.replace("T4: t4", "T4: tongue4"))
    subj = Corpus(tmp_path).subject("spk1")
    with pytest.raises(CassiInputError, match=r"ema.yaml:2: coil 'tongue4': no channel"):
        subj.load(1001)


def test_nan_and_broken_frames_are_invalid_pellets(tmp_path):
    d = tmp_path / "spk1"
    d.mkdir()
    rest = {"ul": (15, 11), "ll": (12, -10), "t1": (-8, 5), "t2": (-27, 11), "t3": (-43, 9),
            "t4": (-54, 1), "mni": (-1, -7), "mnm": (-35, -10), "ui": (0, 0), "nb": (8, 45)}
    names = [f"{c}_{a}" for c in rest for a in "xy"]
    vals = np.tile(np.ravel(list(rest.values())).astype(float), (5, 1))
    vals[1, names.index("t2_x")] = np.nan       # a missing coil sample
    vals[3, names.index("nb_y")] = np.nan       # a missing reference: the whole frame
    write_est(d / "spk1_001.ema", names, T, vals, breaks=np.array([1, 1, 0, 1, 1]))
    (d / "ema.yaml").write_text(MAP)
    rec = Corpus(tmp_path).subject("spk1").load(1001)
    assert rec.valid.all(axis=1).tolist() == [True, False, False, False, True]
    assert rec.valid[1].sum() == 7 and np.isnan(rec.pellet("T2")[1]).all()
    np.testing.assert_allclose(rec.pellet("UL")[0], (15, 11))
