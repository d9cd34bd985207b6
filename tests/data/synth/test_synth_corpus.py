"""The generated corpus as a whole: determinism, calibration, artifacts, alignments, cache.

Calibration targets are thesis Figures 4.16 and 4.25 (tests/fixtures/profiles, see SOURCES.md).
The default suite generates two subjects (JW45, and JW32 whose molar pellet came off, thesis
3.2.5); the full 15-subject checks are marked slow.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cassi.data.corpus.disk import Corpus
from cassi.common.errors import CassiInputError
from cassi.data.corpus.profile import preprocess, read_lipthick, read_maxprotru
from cassi.data.synth.corpus import (GENERATOR_VERSION, JW32_MNM_LOST_FROM_TASK, PROTECTED_TASKS,
                              TABLE_5_1_TASKS, default_corpus, generate_task, make_corpus)
from cassi.data.corpus.stats import corpus_stats, recording_stats
from cassi.data.synth.motion import (KINEMATIC_TARGETS, REAL_FRAME_TARGETS, REAL_FRAMES_TOLERANCE,
                                     REAL_RECORDING_TARGETS)
from cassi.data.synth.subjects import SUBJECTS
from cassi.data.xrmb.files import PELLETS, read_head_measures, read_mis

TOL = 0.03          # the calibration tolerance (profile units: divided by jaw length)
TOL_MIN = 0.05      # MIN UL / MIN LL (issue 10)
#: Published MIN UL above 0.1 of the jaw length: reproduced; the others are near-zero values no
#: gesture reaches (cassi.data.synth.subjects' docstring gives the numbers).
MIN_UL_REPRODUCED = ("JW18", "JW19", "JW32", "JW41", "JW502")


def _digest(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("synth") / "c", subjects=["JW45", "JW32", "JW12"],
                       seed=0, workers=2)


@pytest.fixture(scope="module")
def jw11(tmp_path_factory) -> Path:
    return make_corpus(tmp_path_factory.mktemp("synth") / "jw11", subjects=["JW11"], seed=0,
                       workers=1)


@pytest.fixture(scope="module")
def corpus(small) -> Corpus:
    return Corpus(small)


def _check_profiles(profiles, fixtures_dir, names):
    mp = read_maxprotru(fixtures_dir / "profiles" / "maxprotru.txt")
    lt = read_lipthick(fixtures_dir / "profiles" / "lipthick.txt")
    for name in names:
        p, ref = profiles[name], mp[name]
        assert p.rest_ul == pytest.approx(ref.rest_ul, abs=TOL), name
        assert p.max_ul == pytest.approx(ref.max_ul, abs=TOL), name
        assert p.lipthick == pytest.approx(lt[name], abs=TOL), name
        assert p.rest_ll == pytest.approx(ref.rest_ll, abs=TOL), name
        assert p.max_ll == pytest.approx(ref.max_ll, abs=TOL), name
        assert p.min_ll == pytest.approx(ref.min_ll, abs=TOL_MIN), name
        if name in MIN_UL_REPRODUCED:
            assert p.min_ul == pytest.approx(ref.min_ul, abs=TOL_MIN), name
        else:       # a typical 1.5 mm spreading: well above the published near-zero value
            assert ref.min_ul < 0.02 and 0.25 < p.min_ul < ref.rest_ul, name


# ----------------------------------------------------------------------------- layout, metadata
def test_layout_and_metadata_say_synthetic(small, corpus):
    meta = json.loads((small / "corpus.json").read_text())
    assert meta["synthetic"] is True and meta["seed"] == 0
    assert meta["generator_version"] == GENERATOR_VERSION
    assert corpus.is_synthetic and corpus.subjects == ["JW12", "JW32", "JW45"]
    for name in ("JW45", "JW32"):
        d = small / name
        for f in ("PAL.DAT", "PHA.DAT", "Mis.dat"):
            assert (d / f).is_file()
        tasks = {(t, r) for t, r in corpus.subject(name).tasks()}
        assert {(t, 1) for t in range(1, 119)} <= tasks
        assert len([1 for _, r in tasks if r > 1]) == 2          # two repetitions
        assert np.allclose(corpus.subject(name).palate_mm, SUBJECTS[name].palate_outline(),
                           atol=0.001)
    hm = read_head_measures(small / "Headmeasures.txt")
    assert sorted(hm) == ["JW12", "JW32", "JW45"]
    for name, m in hm.items():
        assert np.allclose(m.gonion_mm, SUBJECTS[name].gonion_mm)
        assert np.allclose(m.gnathion_mm, SUBJECTS[name].gnathion_mm)
        # the angle of the jaw behind and above the chin (tests/data/synth/test_synth_model.py has the rest)
        assert 70.0 < m.gnathion_mm[0] - m.gonion_mm[0] < 100.0
        assert m.gonion_mm[1] > m.gnathion_mm[1] + 10.0
        rec = corpus.load(name, 13)
        mni = rec.xy_mm[rec.first_valid_index, PELLETS.index("MNI")]
        assert m.gnathion_mm[1] < mni[1] - 25.0


def test_cache_directory_is_named_by_generator_version(tmp_path, monkeypatch):
    # a corpus cached by an older generator version is never reused
    import cassi.data.synth.corpus as synth
    monkeypatch.setenv("CASSI_CACHE", str(tmp_path))
    stale = tmp_path / f"corpus-{GENERATOR_VERSION}-0"
    stale.mkdir()
    (stale / "corpus.json").write_text(json.dumps(
        {"synthetic": True, "generator_version": "2", "seed": 0, "subjects": list(SUBJECTS)}))
    assert not synth._complete(stale, 0)
    current = {"synthetic": True, "generator_version": GENERATOR_VERSION, "seed": 0,
               "subjects": list(SUBJECTS), "generator_digest": synth.generator_digest()}
    (stale / "corpus.json").write_text(json.dumps(current))
    assert synth._complete(stale, 0)
    assert GENERATOR_VERSION != "2"
    # the generator's code changed without a bump of its version: not reused either
    (stale / "corpus.json").write_text(json.dumps({**current, "generator_digest": "0" * 64}))
    assert not synth._complete(stale, 0)


def test_the_generator_digest_follows_the_subjects_table(tmp_path, monkeypatch):
    import cassi.data.synth.corpus as synth
    pkg = tmp_path / "synth"
    pkg.mkdir()
    (pkg / "subjects.py").write_text("JAW = 31.1\n")
    monkeypatch.setattr(synth, "__file__", str(pkg / "corpus.py"))
    synth.generator_digest.cache_clear()
    try:
        first = synth.generator_digest()
        (pkg / "subjects.py").write_text("JAW = 40.9\n")
        synth.generator_digest.cache_clear()
        assert synth.generator_digest() != first
    finally:
        synth.generator_digest.cache_clear()


def test_task_files_are_xrmb_shaped(small):
    first = (small / "JW45" / "tp013.txy").read_text().splitlines()
    cols = [row.split("\t") for row in first[:10]]
    assert all(len(c) == 17 for c in cols)
    assert cols[0][1:] == ["1000000"] * 16                   # tracking not started yet
    times = [int(c[0]) for c in cols]
    assert times == [6866 * i for i in range(10)]
    rec = Corpus(small).load("JW45", 13)
    assert 2 <= rec.first_valid_index <= 8
    assert rec.first_valid_time_us == 6866 * rec.first_valid_index


# ----------------------------------------------------------------------------- determinism
def test_same_seed_same_bytes_independent_of_the_subject_set(small, tmp_path):
    one = make_corpus(tmp_path / "one", subjects="JW45", seed=0, workers=1)
    a, b = _digest(small / "JW45"), _digest(one / "JW45")
    assert a == b and len(a) == 123
    other = make_corpus(tmp_path / "other", subjects=["JW45"], seed=1, workers=1)
    da, do = _digest(one / "JW45"), _digest(other / "JW45")
    assert sum(da[k] != do.get(k) for k in da) > 100
    # regenerating over a corpus made with another seed leaves no stale file behind
    make_corpus(other, subjects=["JW45"], seed=0, workers=1)
    assert _digest(other / "JW45") == da


# ----------------------------------------------------------------------------- calibration
def test_preprocessing_reproduces_the_thesis_profiles(corpus, fixtures_dir):
    profiles = preprocess(corpus)
    _check_profiles(profiles, fixtures_dir, ["JW45", "JW32", "JW12"])
    assert len(profiles["JW45"].selected) == 20 and (118, 1) in profiles["JW45"].selected
    assert len(profiles["JW32"].selected) == 4                 # thesis: four usable files
    assert profiles["JW45"].jaw_length_mm == pytest.approx(SUBJECTS["JW45"].jaw_length_mm,
                                                           abs=0.3)


# ----------------------------------------------------------------------------- artifacts
def test_error_free_files_per_subject(corpus):
    jw45 = corpus.subject("JW45")
    ok = {t for t, r in jw45.error_free_tasks() if r == 1}
    assert len(ok) >= 80 and set(PROTECTED_TASKS) <= ok
    jw32 = corpus.subject("JW32")
    ok32 = sorted(t for t, r in jw32.error_free_tasks())
    assert len(ok32) == 4 and max(ok32) < JW32_MNM_LOST_FROM_TASK
    later = [t for t in range(JW32_MNM_LOST_FROM_TASK + 1, 119) if t not in jw32.mistracked_tasks]
    assert len(later) > 80 and {106, 118} <= set(later)
    for task in later[:3] + [106, 118]:
        rec = jw32.load(task, require_valid=False)
        assert not rec.valid[:, PELLETS.index("MNM")].any()   # pellet removed, not logged
        assert not jw32.usability(task).usable
    part = jw32.load(JW32_MNM_LOST_FROM_TASK, require_valid=False)
    mnm = part.valid[:, PELLETS.index("MNM")]
    assert mnm[part.first_valid_index] and not mnm[-1]      # came off part-way through


def test_mistracking_is_logged_and_only_logged_files_deviate(small, corpus):
    meta = json.loads((small / "corpus.json").read_text())["artifacts"]["JW45"]
    subj = corpus.subject("JW45")
    entries = read_mis(small / "JW45" / "Mis.dat")
    assert len(entries) >= 10
    listed = {e.task for e in entries}
    assert listed == set(meta["logged_tasks"])
    assert any(e.note for e in entries) and any(e.offset_ms == -1 for e in entries)
    fig = SUBJECTS["JW45"]
    checked = 0
    for e in entries:
        if e.xrmb_pellet is None:                              # MAX G: reference pellet
            continue
        rec = subj.load(e.task, require_valid=False)
        _, clean = generate_task(fig, e.task, seed=0)
        p = PELLETS.index(e.xrmb_pellet)
        f0 = int(e.onset_ms / 6.866)
        f1 = rec.n_frames if e.offset_ms == -1 else int(e.offset_ms / 6.866) + 1
        seg_valid = rec.valid[f0:f1, p]
        dev = np.abs(rec.xy_mm[f0:f1, p] - clean[f0:f1, p])
        assert (~seg_valid).any() or np.nanmax(dev) > 0.3, e
        checked += 1
    assert checked >= 5
    # an error-free file is exactly the clean tracks (to the micrometre) after the leading rows
    for task in (13, 106, 118):
        rec = subj.load(task)
        _, clean = generate_task(fig, task, seed=0)
        i = rec.first_valid_index
        assert rec.valid[i:].all()
        assert np.abs(rec.xy_mm[i:] - clean[i:]).max() <= 0.0005 + 1e-9


def test_jw12_has_its_published_mistracking_log_and_table_5_1_tasks_are_error_free(
        small, corpus, fixtures_dir):
    key = lambda e: (e.task, e.pellet, e.onset_ms, e.offset_ms, e.note)   # noqa: E731
    real = sorted(map(key, read_mis(fixtures_dir / "xrmb" / "JW12" / "Mis.dat")))
    made = sorted(map(key, read_mis(small / "JW12" / "Mis.dat")))
    assert made == real
    jw12 = corpus.subject("JW12")
    rec = jw12.load(106, require_valid=False)                  # "106 LL 0 -1": lower lip lost
    assert not rec.valid[:, PELLETS.index("LL")].any()
    rec = jw12.load(11, require_valid=False)                   # "011 TD 2330 -1 k;j": raster hop
    t4, t3 = rec.pellet("T4"), rec.pellet("T3")
    k = int(round(3000 / 6.866))
    assert np.linalg.norm(t4[k:] - t3[k:], axis=1).max() < 2.0
    for name, tasks in TABLE_5_1_TASKS.items():
        if name in corpus.subjects:
            for task in tasks:
                assert corpus.subject(name).usability(task).error_free, (name, task)


def test_mis_dat_lines_look_like_jw12s(small):
    pattern = re.compile(r"\d{3} (TT|TB1|TB2|TD|UL|LL|MAN I|MAN M|MAX G) \d+ (-1|\d+)( [a-z];[a-z])?")
    lines = (small / "JW45" / "Mis.dat").read_text().splitlines()
    assert lines and all(pattern.fullmatch(line) for line in lines), lines


def test_error_free_files_stay_in_physiological_ranges(corpus):
    """Pellet speeds, jaw opening and lip order over JW45's error-free files."""
    subj = corpus.subject("JW45")
    keys = subj.error_free_tasks()[::3]
    assert len(keys) >= 25
    peaks = []
    for task, rep in keys:
        rec = subj.load(task, rep)
        xy = rec.xy_mm[rec.first_valid_index:]
        v = np.linalg.norm(np.diff(xy, axis=0), axis=2) / 6866e-6        # mm/s
        peaks.append(v.max(axis=0))
        opening = xy[0, 6, 1] - xy[:, 6, 1].min()
        assert opening < (32.0 if task == 114 else 25.0), task
        assert (xy[:, 0, 1] > xy[:, 1, 1]).all(), task                    # UL above LL
        d = np.linalg.norm(xy[:, 6] - xy[:, 7], axis=1)
        assert d.max() - d.min() < 2.0, task                              # rigid jaw
    peaks = np.array(peaks)
    assert peaks.max() < 600.0
    med = np.median(peaks, axis=0)
    # typical per-file peak speeds, mm/s: the upper lip almost still, the tongue tip fastest
    assert 2.0 < med[0] < 40.0 and 80.0 < med[1] < 300.0 and 120.0 < med[2] < 350.0
    assert 40.0 < med[6] < 160.0 and med[7] < med[6]


def test_kinematics_land_in_their_calibrated_ranges(small):
    """Every figure of KINEMATIC_TARGETS (real-data ranges, sources in synth_motion), measured by
    `cassi corpus stats` on JW45, JW32 and JW12 (synthetic: describes the generator)."""
    measured = {}
    for figure, pellet, tasks, low, high in KINEMATIC_TARGETS:
        if tasks not in measured:
            measured[tasks] = corpus_stats(small, tasks=tasks)
        st = measured[tasks]
        value = st.scalars[figure] if pellet is None else st.pellets.at[pellet, figure]
        assert low <= value <= high, (figure, pellet, tasks[:3], value)
    every = corpus_stats(small)
    d2 = every.pellets["d2_rms_um"]
    # tracking noise differs by pellet: tongue pellets noisiest, the upper lip stillest
    assert d2[["T1", "T2", "T3", "T4"]].min() > d2[["UL", "MNI", "MNM"]].max()
    assert d2["UL"] == d2.min()
    # the lips rest at and below the incisor tip and go lower while speaking
    assert -3.0 < every.scalars["lip_mid_first"] < 1.5
    assert every.scalars["lip_mid_p05"] < every.scalars["lip_mid_first"] - 3.0


def test_jw45_at_rest_is_like_the_real_excerpt(small, fixtures_dir):
    """Real-data check: thesis Figure 3.9 prints the first 13 valid rows of the real JW45 task 13
    (at rest). The same rows of the synthetic JW45 task 13 have the same lips and jaw within
    tenths of a millimetre and tracking noise (second differences) within a factor of 3."""
    from cassi.data.corpus.stats import summarise
    from cassi.data.xrmb.files import read_txy

    real = read_txy(fixtures_dir / "xrmb" / "JW45" / "JW45_013.TXY")
    syn = Corpus(small).load("JW45", 13)
    i, j = real.first_valid_index, syn.first_valid_index
    n = real.n_frames - i
    a = summarise(syn.time_us[j:j + n], syn.xy_mm[j:j + n], syn.valid[j:j + n])
    b = summarise(real.time_us[i:], real.xy_mm[i:], real.valid[i:])
    ratio = a.pellets["d2_rms_um"] / b.pellets["d2_rms_um"]
    assert ratio.between(1 / 3, 3).all(), ratio
    assert a.scalars["lip_mid_first"] == pytest.approx(b.scalars["lip_mid_first"], abs=0.3)
    assert a.scalars["ul_ll_first"] == pytest.approx(b.scalars["ul_ll_first"], abs=1.0)
    assert a.scalars["jaw_distance_mean"] == pytest.approx(b.scalars["jaw_distance_mean"], abs=0.3)


def test_generated_files_match_the_real_recordings_figures(small, jw11):
    """Issue 23: UL speed, T3 second difference and lip midpoint of the generated JW11 task 105
    and JW45 task 13, read as the checks read them, within the factor (or mm) of the real
    recordings' figures (REAL_RECORDING_TARGETS, sources in synth_motion)."""
    roots = {"JW11": jw11, "JW45": small}
    for subject, task, figure, pellet, real, kind, tol in REAL_RECORDING_TARGETS:
        rec = Corpus(roots[subject]).subject(subject).load(task, require_valid=False)
        st = recording_stats([rec])
        value = st.scalars[figure] if pellet is None else st.pellets.at[pellet, figure]
        if kind == "factor":
            assert real / tol <= value <= real * tol, (subject, task, figure, pellet, value)
        else:
            assert abs(value - real) <= tol, (subject, task, figure, value)


def test_jw11_moves_like_the_real_jw11_frames(jw11, fixtures_dir):
    """The generated JW11, all its tasks as `cassi corpus stats` measures them: the lips pressed
    together (UL-LL 0.1th and 1st percentiles), the jaw length and the jaw's height (MNI 95th,
    50th, 5th percentiles) within 10 % of the real JW11 frames' (REAL_FRAME_TARGETS, sources in
    synth_motion); its preprocessed profile is still the thesis's, now with the real jaw."""
    st = corpus_stats(jw11 / "JW11")
    assert st.n_files > 90
    for figure, real in REAL_FRAME_TARGETS:
        value = st.scalars[figure]
        assert abs(value / real - 1.0) <= REAL_FRAMES_TOLERANCE, (figure, value, real)
    profiles = preprocess(Corpus(jw11))
    _check_profiles(profiles, fixtures_dir, ["JW11"])
    assert profiles["JW11"].jaw_length_mm == pytest.approx(42.6, abs=0.3)


def test_same_seed_same_stats(small, tmp_path):
    again = make_corpus(tmp_path / "again", subjects=["JW45"], seed=0, workers=1)
    a = corpus_stats(small / "JW45", tasks=[13, 105]).as_dict()
    b = corpus_stats(again / "JW45", tasks=[13, 105]).as_dict()
    a.pop("label"), b.pop("label")
    assert a == b


def test_unlogged_lost_pellets_are_caught_by_usability(small, corpus):
    meta = json.loads((small / "corpus.json").read_text())["artifacts"]["JW45"]
    lost = meta["unlogged_lost"]
    assert len(lost) == 2
    subj = corpus.subject("JW45")
    for task, rep, pellet, t_us in lost:
        assert task not in subj.mistracked_tasks
        rec = subj.load(task, rep)
        p = PELLETS.index(pellet)
        k = int(np.searchsorted(rec.time_us, t_us))
        assert 0 < k < rec.n_frames and not rec.valid[k:, p].any() and rec.valid[k - 1, p]
        use = subj.usability(task, rep)
        assert use.usable and not use.error_free
        assert any(pellet in r for r in use.reasons)


# ----------------------------------------------------------------------------- alignments
def test_alignments_time_the_gestures(annotations_dir, tmp_path):
    from praatio import textgrid
    out = make_corpus(tmp_path / "al", subjects=["JW45"], alignments=annotations_dir, workers=1)
    meta = json.loads((out / "corpus.json").read_text())["artifacts"]["JW45"]
    assert len(meta["aligned_tasks"]) >= 90
    tg = textgrid.openTextgrid(str(annotations_dir / "JW45" / "tp013.TextGrid"),
                               includeEmptyIntervals=False)
    words = [e for e in tg.getTier("word").entries if e.label not in ("sp", "")]
    rec = Corpus(out).load("JW45", 13)
    assert rec.time_us[-1] / 1e6 == pytest.approx(tg.maxTimestamp, abs=0.01)
    i = rec.first_valid_index
    t = rec.time_us / 1e6
    moved = np.linalg.norm(rec.xy_mm[:, :6] - rec.xy_mm[i, :6], axis=2).max(axis=1) > 1.5
    onset = t[np.flatnonzero(moved & (t > t[i]))[0]]
    assert words[0].start - 0.25 < onset < words[0].start + 0.15
    # silence between the sVd words: the lips return close to rest
    gap = [e for e in tg.getTier("word").entries if e.label == "sp" and e.end - e.start > 0.5
           and e.start > words[0].start]
    assert gap
    mid = int(np.searchsorted(t, 0.5 * (gap[0].start + gap[0].end) + 0.15))
    assert np.linalg.norm(rec.xy_mm[mid, :2] - rec.xy_mm[i, :2], axis=1).max() < 2.0


def test_a_malformed_alignment_falls_back_and_is_recorded(fixtures_dir, tmp_path):
    al = tmp_path / "al" / "JW45"
    al.mkdir(parents=True)
    (al / "tp001.TextGrid").write_bytes((fixtures_dir / "textgrid" / "tp001.TextGrid").read_bytes())
    (al / "tp002.TextGrid").write_text("not a TextGrid\n")
    out = make_corpus(tmp_path / "c", subjects=["JW45"], alignments=tmp_path / "al", workers=1)
    meta = json.loads((out / "corpus.json").read_text())["artifacts"]["JW45"]
    assert meta["aligned_tasks"] == [1]
    assert len(meta["alignment_errors"]) == 1 and "JW45/tp002.TextGrid" in meta["alignment_errors"][0]
    assert Corpus(out).subject("JW45").usability(2).usable           # built-in timing instead


def test_bad_arguments_are_input_errors(tmp_path):
    with pytest.raises(CassiInputError, match="unknown subject"):
        make_corpus(tmp_path / "x", subjects=["JW29"])
    with pytest.raises(CassiInputError, match="seed"):
        make_corpus(tmp_path / "x", subjects=["JW45"], seed=-1)
    with pytest.raises(CassiInputError, match="alignments"):
        make_corpus(tmp_path / "x", subjects=["JW45"], alignments=tmp_path / "none")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep me")
    with pytest.raises(CassiInputError, match="not empty"):
        make_corpus(tmp_path / "mine", subjects=["JW45"])
    (tmp_path / "file").write_text("")
    with pytest.raises(CassiInputError, match="not a directory"):
        make_corpus(tmp_path / "file", subjects=["JW45"])
    with pytest.raises(CassiInputError, match="workers"):
        make_corpus(tmp_path / "x", subjects=["JW45"], workers=0)


def test_cli_make_writes_the_same_corpus(small, tmp_path):
    exe = Path(sys.executable).with_name("cassi")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "cassi.harness.cli"]
    res = subprocess.run(cmd + ["corpus", "make", "--out", str(tmp_path / "cli"),
                                "--subjects", "JW45", "--seed", "0"],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert _digest(tmp_path / "cli" / "JW45") == _digest(small / "JW45")


# ----------------------------------------------------------------------------- slow: full corpus
@pytest.mark.slow
def test_full_default_corpus_fast_cached_concurrent_and_calibrated(tmp_path, fixtures_dir):
    env = dict(os.environ, CASSI_CACHE=str(tmp_path / "cache"))
    code = ("import sys, time; from cassi.data.synth.corpus import default_corpus; "
            "t = time.perf_counter(); p = default_corpus(); "
            "print(p, time.perf_counter() - t)")
    t0 = time.perf_counter()
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    procs = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE,
                              text=True) for _ in range(3)]
    outs = [p.communicate(timeout=600)[0].split() for p in procs]
    wall = time.perf_counter() - t0
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    assert all(p.returncode == 0 for p in procs)
    paths = {o[0] for o in outs}
    assert len(paths) == 1
    root = Path(paths.pop())
    # one caller builds (the others wait on the lock): its CPU time, spread over 2 cores, is
    # the wall time on an idle 2-core machine (issue 2: under 30 s). Wall time here also pays
    # for whatever else the machine runs, hence the loose bound.
    cpu = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
    assert cpu / 2 < 30.0, cpu
    assert wall < 300.0
    leftovers = [p.name for p in (tmp_path / "cache").iterdir() if p.name.startswith(".corpus")
                 and not p.name.endswith(".lock")]
    assert leftovers == []
    corpus = Corpus(root)
    assert corpus.is_synthetic and len(corpus.subjects) == 15
    _check_profiles(preprocess(corpus), fixtures_dir, list(SUBJECTS))
    for name in SUBJECTS:
        n_ok = len(corpus.subject(name).error_free_tasks())
        assert n_ok >= (4 if name == "JW32" else 20), name
    t1 = time.perf_counter()
    old = os.environ.get("CASSI_CACHE")
    os.environ["CASSI_CACHE"] = str(tmp_path / "cache")
    try:
        assert default_corpus() == root          # cached: no regeneration
    finally:
        if old is None:
            del os.environ["CASSI_CACHE"]
        else:
            os.environ["CASSI_CACHE"] = old
    assert time.perf_counter() - t1 < 1.0
