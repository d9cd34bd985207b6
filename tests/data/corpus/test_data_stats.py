"""Kinematic statistics (cassi.data.corpus.stats) on hand-made trajectories, on the real JW45 excerpt
(thesis Figure 3.9), and the ``cassi corpus stats`` command."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from data_helpers import JW45_EXCERPT

from cassi.data.commands import main
from cassi.common.errors import CassiInputError
from cassi.data.corpus.stats import (SCALARS, compare, corpus_stats, frame_set_stats,
                                     recording_stats, summarise)
from cassi.data.xrmb.files import PELLETS, TaskRecording, format_txy
from cassi.data.xrmb.frames import read_frames

DT_US = 6866
DT = DT_US * 1e-6


def _still(n: int) -> np.ndarray:
    """(n, 8, 2) mm: every pellet at its own fixed place (lips 24 mm apart, jaw 35 mm)."""
    base = np.array([[12.0, 10.0], [10.0, -14.0], [-8.0, 5.0], [-27.0, 11.0], [-43.0, 9.0],
                     [-54.0, 1.0], [-1.0, -8.0], [-36.0, -8.0]])
    return np.repeat(base[None], n, axis=0)


def test_circle_gives_its_speed_range_and_second_difference():
    n, r, w = 400, 5.0, 2 * math.pi * 2.0                   # 5 mm radius, 2 turns per second
    t = np.arange(n) * DT
    xy = _still(n)
    xy[:, 0, 0] += r * np.cos(w * t)
    xy[:, 0, 1] += r * np.sin(w * t)
    s = summarise(np.arange(n) * DT_US, xy)
    chord = 2 * r * math.sin(w * DT / 2) / DT                # mm/s between samples
    for c in ("speed_p50", "speed_p90", "speed_p99"):
        assert s.pellets.at["UL", c] == pytest.approx(chord, rel=1e-9)
    assert s.pellets.at["UL", "x_range"] == pytest.approx(2 * r, abs=0.01)
    assert s.pellets.at["UL", "y_range"] == pytest.approx(2 * r, abs=0.01)
    # |p[t+1] - 2p[t] + p[t-1]| = 4 r sin^2(w dt / 2) on a circle; RMS per coordinate is /sqrt(2)
    d2 = 4 * r * math.sin(w * DT / 2) ** 2 / math.sqrt(2) * 1000.0
    assert s.pellets.at["UL", "d2_rms_um"] == pytest.approx(d2, rel=1e-6)
    assert s.pellets.at["LL", "speed_p99"] == 0.0 and s.pellets.at["LL", "d2_rms_um"] == 0.0


def test_constant_acceleration_has_constant_second_difference():
    n, acc = 100, 2000.0                                    # mm/s^2, y only
    t = np.arange(n) * DT
    xy = _still(n)
    xy[:, 2, 1] += 0.5 * acc * t ** 2
    s = summarise(np.arange(n) * DT_US, xy)
    # only y bends: RMS over both coordinates is a dt^2 / sqrt(2)
    assert s.pellets.at["T1", "d2_rms_um"] == pytest.approx(acc * DT ** 2 / math.sqrt(2) * 1000,
                                                            rel=1e-6)
    assert s.pellets.at["T1", "speed_p99"] == pytest.approx(
        np.percentile(acc * (t[1:] + t[:-1]) / 2, 99), rel=1e-9)


def test_rigid_jaw_lip_midpoint_and_distance():
    n = 200
    xy = _still(n)
    theta = np.radians(np.linspace(0.0, 12.0, n))            # the jaw opens about a condyle
    cond = np.array([-80.0, 15.0])
    for p in (6, 7):
        rel = xy[0, p] - cond
        xy[:, p, 0] = cond[0] + np.cos(theta) * rel[0] + np.sin(theta) * rel[1]
        xy[:, p, 1] = cond[1] - np.sin(theta) * rel[0] + np.cos(theta) * rel[1]
    xy[100:, 1, 1] -= 6.0                                   # the lower lip drops half-way
    s = summarise(np.arange(n) * DT_US, xy).scalars
    assert s["jaw_distance_mean"] == pytest.approx(35.0, abs=1e-9)
    assert s["jaw_distance_sd"] == pytest.approx(0.0, abs=1e-9)
    assert s["lip_mid_first"] == pytest.approx(-2.0)
    assert s["lip_mid_p05"] == pytest.approx(-5.0)
    assert s["ul_ll_first"] == pytest.approx(math.hypot(2.0, 24.0))
    assert s["ul_ll_p01"] == pytest.approx(math.hypot(2.0, 24.0))
    assert s["ul_ll_p001"] == pytest.approx(math.hypot(2.0, 24.0))
    assert s["jaw_distance_median"] == pytest.approx(35.0, abs=1e-9)
    # MNI (-1, -8) turns 0-12 degrees about (-80, 15): the rest at the top, the open jaw below
    mni_y = 15.0 - np.sin(theta) * 79.0 + np.cos(theta) * -23.0
    assert s["mni_y_p95"] == pytest.approx(np.percentile(mni_y, 95))
    assert s["mni_y_median"] == pytest.approx(np.median(mni_y))
    assert s["mni_y_p05"] == pytest.approx(np.percentile(mni_y, 5)) and s["mni_y_p05"] < -20.0


def test_invalid_rows_are_left_out_and_files_are_pooled():
    n = 50
    a = _still(n)
    valid = np.ones((n, 8), bool)
    valid[:3] = False                                       # before tracking starts
    a[:3] = 1000.0                                          # junk there must not count
    valid[20, 0] = False
    a[20, 0] = 500.0                                        # a lost UL sample, not a movement
    b = _still(n)
    b[:, 7, 0] -= 10.0                                      # another file: a 45 mm jaw
    recs = [TaskRecording(None, "S", 1, 1, np.arange(n) * DT_US, a, valid),
            TaskRecording(None, "S", 2, 1, np.arange(n) * DT_US, b, np.ones((n, 8), bool))]
    s = recording_stats(recs)
    assert s.n_files == 2
    assert s.pellets.at["UL", "speed_p99"] == 0.0 and s.pellets.at["UL", "x_range"] == 0.0
    assert s.scalars["jaw_distance_sd"] == pytest.approx(0.0)  # within files: rigid
    assert 35.0 < s.scalars["jaw_distance_mean"] < 45.0


def test_bad_arrays_are_input_errors():
    with pytest.raises(CassiInputError, match="no row"):
        summarise(np.arange(5) * DT_US, np.full((5, 8, 2), np.nan))
    with pytest.raises(CassiInputError, match=r"\(F, 8, 2\)"):
        summarise(np.arange(5), np.zeros((5, 7, 2)))
    with pytest.raises(CassiInputError, match="increase"):
        summarise(np.zeros(5), np.zeros((5, 8, 2)))


def test_real_jw45_excerpt():
    """Thesis Figure 3.9, real XRMB data: JW45 task 13, rows from 27464 us (at rest)."""
    s = corpus_stats(JW45_EXCERPT)
    assert s.n_files == 1
    # first valid row: MNI (-0.699, -7.452), MNM (-34.792, -9.862) mm -> 34.18 mm; the last row
    # 33.91 mm: the real distance wanders by tenths of a millimetre (SD 0.09 mm)
    assert s.scalars["jaw_distance_mean"] == pytest.approx(33.99, abs=0.01)
    assert 0.05 < s.scalars["jaw_distance_sd"] < 0.15
    # UL (15.757, 11.596), LL (12.175, -9.772): midpoint 0.91 mm above the incisor tip
    assert s.scalars["lip_mid_first"] == pytest.approx(0.912, abs=0.001)
    assert s.scalars["ul_ll_first"] == pytest.approx(21.67, abs=0.01)
    d2 = s.pellets["d2_rms_um"]
    assert d2["UL"] < 2.0 and d2["UL"] == d2.min()           # the upper lip is the stillest
    assert (d2[["T1", "T2", "T3", "T4"]] > 3.0).all()


def test_compare_gives_ratios():
    a = corpus_stats(JW45_EXCERPT)
    xy = _still(60)
    b = summarise(np.arange(60) * DT_US, xy)
    df = compare(a, a)
    defined = df.dropna(subset=["ratio"])
    assert len(defined) > 40 and np.allclose(defined["ratio"], 1.0)
    df = compare(a, b)
    row = df[(df.pellet == "") & (df.figure == "jaw_distance_mean")].iloc[0]
    assert row.ratio == pytest.approx(a.scalars["jaw_distance_mean"] / 35.0)
    assert np.isnan(df[(df.pellet == "UL") & (df.figure == "speed_p99")].iloc[0].ratio)  # b = 0


# ----------------------------------------------------------------------------- frame sets
def _frame_set(n: int = 1000) -> np.ndarray:
    """(n, 16) mm, shuffled rows: the lips 24 mm apart, closing to 16 mm in 1 frame of 50."""
    xy = _still(n)
    xy[::50, 1, 1] += 8.0
    xy[:, 6, 1] -= np.linspace(0.0, 10.0, n)                 # the MNI pellet lower and lower
    xy[:, 7, 1] -= np.linspace(0.0, 10.0, n)                 # the jaw drops level: 35 mm
    return np.random.default_rng(0).permutation(xy.reshape(n, 16))


def test_frame_sets_give_distributions_only(tmp_path):
    import scipy.io
    frames = _frame_set()
    np.save(tmp_path / "s.npy", frames)
    scipy.io.savemat(tmp_path / "s.mat", {"frames": frames})
    for name in ("s.npy", "s.mat"):
        xy = read_frames(tmp_path / name)
        assert xy.shape == (1000, 8, 2) and np.array_equal(xy.reshape(1000, 16), frames)
        s = corpus_stats(tmp_path / name)
        assert s.n_frames == 1000 and s.n_files == 0
        assert s.pellets.isna().all().all()          # no times: no speeds, ranges, noise
        sc = s.scalars
        for k in ("jaw_distance_sd", "lip_mid_first", "ul_ll_first"):
            assert math.isnan(sc[k]), k
        assert sc["jaw_distance_mean"] == pytest.approx(35.0)
        assert sc["jaw_distance_median"] == pytest.approx(35.0)
        assert sc["mni_y_median"] == pytest.approx(-13.0, abs=0.01)
        assert sc["mni_y_p95"] == pytest.approx(-8.5, abs=0.01)
        assert sc["mni_y_p05"] == pytest.approx(-17.5, abs=0.01)
        assert sc["ul_ll_median"] == pytest.approx(math.hypot(2.0, 24.0))
        assert sc["ul_ll_p01"] == pytest.approx(math.hypot(2.0, 16.0))   # 20 pressed frames
        assert sc["ul_ll_p001"] == pytest.approx(math.hypot(2.0, 16.0))
        assert sc["lip_mid_mean"] == pytest.approx(-2.0 + 8.0 / 2 / 50)
    # a bad value (NaN) leaves out its frame from the figures of its pellet only
    frames[:500, 12:14] = np.nan                              # MNI lost in half the frames
    s = frame_set_stats(frames.reshape(-1, 8, 2)).scalars
    assert s["ul_ll_median"] == pytest.approx(math.hypot(2.0, 24.0))
    assert s["jaw_distance_median"] == pytest.approx(35.0)
    assert -18.0 < s["mni_y_p05"] and s["mni_y_p95"] < -8.0


def test_the_upper_lip_drawn_back_by_a_wide_jaw():
    """ul_back_wide_jaw: the UL x median over all frames minus its median over the frames with
    the jaw open wider than in 99 % of them (MNI y below its 1st percentile)."""
    n = 1000
    frames = np.zeros((n, 8, 2))
    frames[:, 0, 0] = 15.0
    frames[:, 6, 1] = -8.0 - 0.01 * np.arange(n)    # the jaw opens a little further each frame
    frames[-10:, 0, 0] = 13.8                        # the widest 1 %: the lip 1.2 mm back
    assert frame_set_stats(frames).scalars["ul_back_wide_jaw"] == pytest.approx(1.2)
    frames[:, 0, 0] = 15.0                           # a lip that ignores the jaw
    assert frame_set_stats(frames).scalars["ul_back_wide_jaw"] == pytest.approx(0.0)
    assert math.isnan(frame_set_stats(frames[:50]).scalars["ul_back_wide_jaw"])  # too few


def test_bad_frame_sets_are_input_errors(tmp_path, capsys):
    import scipy.io
    good = _frame_set(200)
    np.save(tmp_path / "cols.npy", good[:, :14])
    np.save(tmp_path / "um.npy", good * 1000.0)
    scipy.io.savemat(tmp_path / "two.mat", {"a": good, "b": good})
    scipy.io.savemat(tmp_path / "none.mat", {"a": good[:, :3]})
    (tmp_path / "junk.npy").write_text("not numpy")
    bad = good.copy()
    bad[7, 0] = 1000000.0                                     # a .txy bad-value marker
    np.save(tmp_path / "marker.npy", bad)
    np.save(tmp_path / "nan.npy", np.full((5, 16), np.nan))
    cases = {"cols.npy": r"frames x 16 numbers.*\(200, 14\)",
             "um.npy": "frame 1: a coordinate beyond 200 mm", "two.mat": "exactly one array",
             "none.mat": r"variables: a \(200, 3\)", "junk.npy": "not a readable .npy",
             "marker.npy": "frame 8: a coordinate beyond", "nan.npy": "no frame has all eight"}
    for name, why in cases.items():
        with pytest.raises(CassiInputError, match=why) as err:
            read_frames(tmp_path / name)
        assert err.value.path == str(tmp_path / name)
    np.save(tmp_path / "good.npy", good)
    with pytest.raises(CassiInputError, match="no task numbers"):
        corpus_stats(tmp_path / "good.npy", tasks=[105])
    assert main(["stats", str(tmp_path / "um.npy")]) == 2
    assert f"{tmp_path / 'um.npy'}: frame 1:" in capsys.readouterr().err
    assert main(["stats", str(tmp_path / "good.npy"), "--tasks", "105"]) == 2


def test_cli_stats_compares_task_files_with_a_frame_set(tmp_path, capsys):
    np.save(tmp_path / "frames.npy", _frame_set())
    assert main(["stats", str(JW45_EXCERPT), "--compare", str(tmp_path / "frames.npy")]) == 0
    out = capsys.readouterr().out
    assert f"# B: {tmp_path / 'frames.npy'} (a frame set of 1000 frames: distributions only)" \
        in out
    assert "jaw_distance_median (mm)\t34 | 35 | x0.97\n" in out
    assert "speed_p99" in out and "- | x-" in out
    assert main(["stats", str(tmp_path / "frames.npy"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)["a"]
    assert doc["n_frames"] == 1000 and set(doc["scalars"]) == set(SCALARS)
    assert doc["scalars"]["ul_ll_first"] is None and doc["pellets"]["UL"]["speed_p99"] is None


# ----------------------------------------------------------------------------- the command
def test_cli_stats_text_json_and_compare(capsys, tmp_path):
    assert main(["stats", str(JW45_EXCERPT)]) == 0
    out = capsys.readouterr().out
    assert "d2_rms_um" in out and "jaw_distance_mean (mm)\t34\n" in out
    assert main(["stats", str(JW45_EXCERPT), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["a"]["pellets"]) == set(PELLETS)
    assert doc["a"]["units"]["speed_p99"] == "mm/s"
    assert main(["stats", str(JW45_EXCERPT), "--compare", str(JW45_EXCERPT), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    ratios = [r["ratio"] for r in doc["ratio"] if r["ratio"] is not None]
    assert ratios and all(r == pytest.approx(1.0) for r in ratios)
    assert main(["stats", str(JW45_EXCERPT), "--compare", str(JW45_EXCERPT)]) == 0
    assert "ul_ll_p01 (mm)\t21.7 | 21.7 | x1\n" in capsys.readouterr().out


def test_cli_stats_bad_input_exits_2_with_file_and_line(capsys, tmp_path):
    good = JW45_EXCERPT.read_text().splitlines()
    bad = tmp_path / "JW45" / "tp013.txy"
    bad.parent.mkdir()
    bad.write_text("\n".join(good[:6] + ["41196\t15763\t11595"] + good[7:]) + "\n")
    (bad.parent / "Mis.dat").write_text("")
    assert main(["stats", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:7:" in err
    assert main(["stats", str(tmp_path / "JW45")]) == 2          # the same through a directory
    assert f"{bad}:7:" in capsys.readouterr().err
    assert main(["stats", str(tmp_path / "missing")]) == 2
    assert "not found" in capsys.readouterr().err
    (tmp_path / "notes.txt").write_text("x")
    assert main(["stats", str(tmp_path / "notes.txt")]) == 2
    assert main(["stats", str(JW45_EXCERPT), "--tasks", "5-2"]) == 2


def test_cli_stats_on_a_generated_subject(tmp_path, capsys):
    from cassi.data.synth.corpus import generate_task
    from cassi.data.synth.subjects import SUBJECTS
    t, xy = generate_task(SUBJECTS["JW45"], 105)
    rec = TaskRecording(None, "JW45", 105, 1, t, xy, np.ones(xy.shape[:2], bool))
    (tmp_path / "JW45").mkdir()
    (tmp_path / "JW45" / "tp105.txy").write_text(format_txy(rec))
    (tmp_path / "JW45" / "Mis.dat").write_text("")
    assert main(["stats", str(tmp_path / "JW45"), "--tasks", "105", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["a"]["n_files"] == 1 and doc["a"]["pellets"]["MNI"]["y_range"] > 10.0
    assert main(["stats", str(tmp_path / "JW45"), "--tasks", "13"]) == 2   # nothing to measure
