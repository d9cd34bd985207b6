"""`cassi export --format gltf` end to end on a one-subject synthetic corpus.

The .glb is read back here with its own small decoder (GLB chunks, dense and sparse accessors,
the root node's transform) and with trimesh, never with the writer's code.
"""
from __future__ import annotations

import importlib

import numpy as np
import pytest
import trimesh
from gltf_helpers import accessor as _accessor, chunks as _chunks

from cassi.data.face.topology import render_topology
from cassi.harness.actions import task_positions
from cassi.harness.cli import main

PERIOD_S = 6866e-6


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    importlib.import_module("cassi.data.face.model")
    from cassi.data.synth.corpus import make_corpus

    return make_corpus(tmp_path_factory.mktemp("corpus"), subjects=["JW45"])


@pytest.fixture(scope="module")
def task(corpus):
    from cassi.data.corpus.disk import Corpus

    return Corpus(corpus).subject("JW45").tasks()[0][0]


@pytest.fixture(scope="module")
def animated(corpus, task):
    return task_positions(str(corpus), "JW45", task, 1, "cassi-2.1")


@pytest.fixture(scope="module")
def m_per_unit(corpus, animated):
    """Metres a Parke unit in the export: the subject's own size, d / p (thesis 4.1.1), from its
    profile's jaw length and the face's jaw sites."""
    from cassi.harness.evaluation.caches import get_corpus, get_profile
    from cassi.versions.mapping import XrmbToParke
    profile = get_profile(get_corpus(str(corpus)), "JW45")
    return 1e-3 / XrmbToParke.from_face(animated[0].vertices, profile.jaw_length_mm).scale


def _export(corpus, task, out, *extra) -> int:
    return main(["export", "--corpus", str(corpus), "--subject", "JW45", "--task", str(task),
                 "--version", "cassi-2.1", "--format", "gltf", "--out", str(out), *extra])


def _root(gltf):
    return gltf["nodes"][gltf["scenes"][gltf["scene"]]["nodes"][0]]


def _to_parke(gltf, local: np.ndarray, m_per_unit: float) -> np.ndarray:
    """Mesh-local positions -> Parke units on Parke axes (undo the root's TRS, metres, axes)."""
    root = _root(gltf)
    assert "rotation" not in root and "matrix" not in root
    world = local * np.asarray(root.get("scale", [1, 1, 1])) + root.get("translation", [0, 0, 0])
    return (world / m_per_unit)[:, [2, 0, 1]]  # glTF (x, y, z) = Parke (y, z, x)


def _frame(gltf, binary, k: int, m_per_unit: float) -> np.ndarray:
    """Frame k decoded: the animated mesh's base plus its target k (what weight 1 shows)."""
    prim = gltf["meshes"][0]["primitives"][0]
    base = _accessor(gltf, binary, prim["attributes"]["POSITION"]).astype(np.float64)
    delta = _accessor(gltf, binary, prim["targets"][k]["POSITION"]).astype(np.float64)
    return _to_parke(gltf, base + delta, m_per_unit)


@pytest.mark.parametrize("positions", ["int16", "float32"])
def test_frame_k_is_task_frame_k(corpus, task, animated, tmp_path, positions, m_per_unit):
    face, frames, pos, _ = animated
    stride = 7
    out = tmp_path / "face.glb"
    assert _export(corpus, task, out, "--stride", str(stride), "--positions", positions) == 0
    gltf, binary = _chunks(out.read_bytes())
    topo = render_topology(face)
    kept = pos[::stride]
    assert len(gltf["meshes"][0]["primitives"][0]["targets"]) == len(kept)
    if positions == "int16":
        assert gltf["extensionsRequired"] == ["KHR_mesh_quantization"]
        assert gltf["extensionsUsed"] == ["KHR_mesh_quantization"]
        tol = 0.5 * _root(gltf)["scale"][0] / m_per_unit + 1e-6
        assert tol < 0.05  # half a step under 0.0125 mm
    else:
        assert "extensionsRequired" not in gltf
        tol = 1e-4
    every = set()
    for k in (0, 1, len(kept) // 2, len(kept) - 1):
        want, _, _ = topo.mesh(kept[k])
        got = _frame(gltf, binary, k, m_per_unit)
        assert got.shape == want.shape
        assert np.abs(got - want).max() <= tol, k
        every.add(k)
    # the frames differ (a test of a still face would pass with any target)
    a, b = topo.mesh(kept[0])[0], topo.mesh(kept[len(kept) // 2])[0]
    assert np.abs(a - b).max() > 10 * tol
    # every primitive of the animated mesh shares the base and the targets
    prims = gltf["meshes"][0]["primitives"]
    assert all(p["targets"] == prims[0]["targets"] for p in prims)
    assert all(p["attributes"] == prims[0]["attributes"] for p in prims)


def test_animation_time_base_and_weights(corpus, task, animated, tmp_path):
    face, frames, pos, _ = animated
    stride = 5
    out = tmp_path / "face.glb"
    assert _export(corpus, task, out, "--stride", str(stride)) == 0
    gltf, binary = _chunks(out.read_bytes())
    (anim,) = gltf["animations"]
    (sampler,) = anim["samplers"]
    (channel,) = anim["channels"]
    assert channel["target"]["path"] == "weights"
    node = gltf["nodes"][channel["target"]["node"]]
    assert gltf["meshes"][node["mesh"]] is gltf["meshes"][0]
    F = len(frames[::stride])
    times = _accessor(gltf, binary, sampler["input"])[:, 0].astype(np.float64)
    assert len(times) == F
    assert np.allclose(np.diff(times), PERIOD_S * stride, atol=1e-6)
    assert times[0] == 0.0
    weights = _accessor(gltf, binary, sampler["output"]).reshape(F, F)
    assert np.array_equal(weights, np.eye(F, dtype=weights.dtype))
    assert sampler["interpolation"] in ("LINEAR", "STEP")


def test_glb_loads_in_trimesh_with_parts_and_materials(corpus, task, animated, tmp_path, m_per_unit):
    face, frames, pos, _ = animated
    out = tmp_path / "face.glb"
    assert _export(corpus, task, out, "--stride", "50") == 0
    scene = trimesh.load(out, force="scene")
    topo = render_topology(face)
    assert len(scene.geometry) == len(topo.parts)
    assert sum(len(g.faces) for g in scene.geometry.values()) == \
        sum(len(p.triangles) for p in topo.parts.values())
    # trimesh applies the root's dequantising transform: the neutral head, in metres, at the
    # subject's size (not the model's nominal 0.25 mm a unit)
    verts, _, _ = topo.mesh(face.vertices)
    want = verts[:, [1, 2, 0]] * m_per_unit
    assert abs(m_per_unit - 0.25e-3) > 1e-6
    lo, hi = scene.bounds
    assert np.allclose(lo, want.min(axis=0), atol=2e-5)
    assert np.allclose(hi, want.max(axis=0), atol=2e-5)
    gltf, _ = _chunks(out.read_bytes())
    names = [m["name"] for m in gltf["materials"]]
    assert names == list(topo.parts)
    skin = gltf["materials"][names.index("skin")]["pbrMetallicRoughness"]["baseColorFactor"]
    assert skin[:3] == pytest.approx([0.62, 0.42, 0.33])


def test_neutral_exports_a_still_face(corpus, task, tmp_path):
    out = tmp_path / "n.glb"
    assert main(["export", "--corpus", str(corpus), "--subject", "JW45", "--task", str(task),
                 "--version", "neutral", "--out", str(out)]) == 0
    gltf, _ = _chunks(out.read_bytes())
    assert "animations" not in gltf
    assert all("targets" not in p for m in gltf["meshes"] for p in m["primitives"])


def _frames_in(path) -> int:
    gltf, _ = _chunks(path.read_bytes())
    return gltf["accessors"][gltf["animations"][0]["samplers"][0]["input"]]["count"]


def test_quantised_is_smaller_per_frame(corpus, task, tmp_path):
    a, b, c = tmp_path / "q2.glb", tmp_path / "q4.glb", tmp_path / "f4.glb"
    assert _export(corpus, task, a, "--stride", "2") == 0
    assert _export(corpus, task, b, "--stride", "4") == 0
    assert _export(corpus, task, c, "--stride", "4", "--positions", "float32") == 0
    # what one more frame adds to the file, JSON included
    per_frame = (a.stat().st_size - b.stat().st_size) / (_frames_in(a) - _frames_in(b))
    assert 0 < per_frame < 0.7 * c.stat().st_size / _frames_in(c)


def test_bad_input_exit_2(corpus, task, tmp_path, capsys):
    def run(*args, out="a.glb"):
        return main(["export", "--corpus", str(corpus), "--out", str(tmp_path / out), *args])

    ok = ["--subject", "JW45", "--task", str(task)]
    assert run(*ok, "--version", "no-such-version") == 2
    assert "unknown version 'no-such-version'" in capsys.readouterr().err
    assert run("--subject", "ZZ99", "--task", str(task), "--version", "cassi-2.1") == 2
    assert run("--subject", "../JW45", "--task", str(task), "--version", "cassi-2.1") == 2
    assert run("--subject", "JW45", "--task", "99999", "--version", "cassi-2.1") == 2
    assert run(*ok, "--version", "cassi-2.1", out="a.gltf") == 2
    assert "--out must end in .glb" in capsys.readouterr().err
    assert run(*ok, "--version", "cassi-2.1", "--stride", "0") == 2
    with pytest.raises(SystemExit) as exc:  # argparse's own check (exits 2 in cassi's parser)
        run(*ok, "--version", "cassi-2.1", "--format", "obj")
    assert exc.value.code == 2
    (tmp_path / "d.glb").mkdir()
    assert run(*ok, "--version", "cassi-2.1", out="d.glb") == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.glb"]
