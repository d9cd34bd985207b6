"""Every built-in version animated in chunks of frames equals the version animated at once,
exactly (positions and diagnostics): the ground for a geometry stage whose memory does not grow
with the task. Tasks: a sentence, jaw wagging and maximum lip protrusion of the embedded corpus,
for a subject whose lips are centred low (JW40: CASSI 2.1's thickness rule) and one whose are
not (JW45)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from cassi.harness.evaluation.caches import get_corpus, get_face, get_profile
from cassi.versions.registry import get_version

VERSIONS = ("parke-1974", "cassi-1.0", "cassi-2.0", "cassi-2.1")


@pytest.fixture(scope="module")
def inputs():
    corpus = get_corpus(None)
    out = {}
    for subject, task in (("JW40", 5), ("JW40", 118), ("JW45", 106)):
        profile = get_profile(corpus, subject)
        out[(subject, task)] = (profile, get_face(corpus, subject, profile),
                                corpus.subject(subject).load(task))
    return out


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("frames", [1, 97, 1000])
def test_chunks_equal_the_whole_task(inputs, version, frames):
    v = get_version(version)
    for key, (profile, face, rec) in inputs.items():
        rec_short = rec if frames > 1 else _first_rows(rec, 400)
        whole = v.animate(profile, face, rec_short)
        chunks = list(v.animate_chunks(profile, face, rec_short, frames=frames))
        assert all(len(c.frames) <= frames for c in chunks)
        np.testing.assert_array_equal(np.concatenate([c.frames for c in chunks]), whole.frames)
        np.testing.assert_array_equal(np.concatenate([c.positions for c in chunks]),
                                      whole.positions, err_msg=f"{version} {key}")
        pd.testing.assert_frame_equal(
            pd.concat([c.diagnostics for c in chunks], ignore_index=True), whole.diagnostics)


def _first_rows(rec, n):
    """The recording's first ``n`` rows (one-frame chunks over a whole task would be slow)."""
    return type(rec)(rec.path, rec.subject, rec.task, rec.rep, rec.time_us[:n], rec.xy_mm[:n],
                     rec.valid[:n])


def test_a_chunk_of_no_frames_is_refused(inputs):
    profile, face, rec = inputs[("JW45", 106)]
    with pytest.raises(ValueError, match="at least 1"):
        next(get_version("cassi-1.0").animate_chunks(profile, face, rec, frames=0))


@pytest.mark.parametrize("version", VERSIONS)
def test_the_rubric_on_chunks_from_a_file_equals_the_rubric_on_the_whole_array(
        inputs, version, tmp_path):
    """The geometry stage's path (positions streamed to a file, checks read back a chunk at a
    time, jitter windows and frame steps with their halo) gives the same rows, exactly."""
    from cassi.harness.evaluation.caches import get_neutral
    from cassi.harness.evaluation.stages import animate_to_file
    from cassi.harness.rubric import run_geometry_checks

    v = get_version(version)
    for (subject, task), (profile, face, rec) in inputs.items():
        whole = v.animate(profile, face, rec)
        streamed = animate_to_file(v, profile, face, rec, tmp_path)
        streamed.positions.chunk = 97  # many chunks, each boundary crossed by the halos
        kw = dict(task=task, subject=subject, rep=1, neutral=get_neutral(), recording=rec)
        a = run_geometry_checks(whole, face, profile, **kw)
        b = run_geometry_checks(streamed, face, profile, **kw)
        pd.testing.assert_frame_equal(a, b, check_exact=True, obj=f"{version} {subject} {task}")


def test_series_hold_one_chunk_of_positions_at_a_time(tmp_path):
    """Memory, not time: reading a per-frame series through a positions file keeps one chunk
    (plus its results) alive, never the whole task (tracemalloc counts numpy's buffers)."""
    import tracemalloc

    from cassi.harness.rubric.frames import FileFrames

    store = FileFrames(tmp_path / "p.f32", 10, chunk=1000)
    rng = np.random.default_rng(0)
    for _ in range(50):
        store.append(rng.standard_normal((1000, 10, 3)).astype(np.float32))
    whole_mb = 50_000 * 10 * 3 * 8 / 1e6           # 12 MB in float64
    tracemalloc.start()
    try:
        z = store.series(lambda p: p[:, 3, 2])       # a view of each chunk, as measures make
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert z.shape == (50_000,) and peak / 1e6 < whole_mb / 4
    np.testing.assert_array_equal(z, np.concatenate(
        [store.read(a, a + 1000)[:, 3, 2] for a in range(0, 50_000, 1000)]))


def test_the_checks_read_a_task_of_one_chunk_once(inputs, tmp_path):
    """Every series and single frame the geometric, fidelity and shape checks read of a task
    that fits one chunk comes from one read of the positions file, handed out read-only."""
    from cassi.harness.evaluation.caches import get_neutral
    from cassi.harness.evaluation.stages import animate_to_file
    from cassi.harness.rubric import run_geometry_checks
    from cassi.harness.rubric.frames import LastRead

    (subject, task), (profile, face, rec) = next(iter(inputs.items()))
    streamed = animate_to_file(get_version("cassi-2.1"), profile, face, rec, tmp_path)
    reads, read = [], streamed.positions.read
    streamed.positions.read = lambda a, b: reads.append((a, b)) or read(a, b)
    run_geometry_checks(streamed, face, profile, task=task, subject=subject, rep=1,
                        neutral=get_neutral(), recording=rec)
    assert reads == [(0, streamed.positions.n_frames)]
    shared = LastRead(streamed.positions)
    with pytest.raises(ValueError):
        shared.frame(0)[0, 0] = 1.0


def test_take_reads_the_stored_frames_across_chunks(tmp_path):
    """``FileFrames.take`` gives the float32 frames as stored, in the order asked, from
    several chunks; a frame not in the file is an error."""
    from cassi.harness.rubric.frames import FileFrames

    store = FileFrames(tmp_path / "p.f32", 4, chunk=7)
    data = np.random.default_rng(1).standard_normal((30, 4, 3)).astype(np.float32)
    store.append(data[:11])
    store.append(data[11:])
    idx = [29, 0, 6, 7, 7, 13, 20, 3]
    assert store.take(idx).tobytes() == data[idx].tobytes()
    assert store.take([]).shape == (0, 4, 3)
    with pytest.raises(IndexError):
        store.take([30])
