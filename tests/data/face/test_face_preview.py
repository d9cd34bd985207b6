"""The face generator's command line and the matplotlib preview."""
from __future__ import annotations

import numpy as np
import pytest

from cassi.data.face.model import FaceModel, build_face
from cassi.data.face.preview import preview_png
from cassi.versions.face_cli import main
from cassi.versions.mapping import subject_face


def test_generator_writes_parke_files_with_a_subject_palate(tmp_path, capsys):
    pal = tmp_path / "PAL.DAT"
    pal.write_text("-5000 8500\n-20000 19000\n-45000 22000\n")
    out = tmp_path / "face"
    assert main([str(out), "--palate", str(pal), "--jaw-length", "34",
                 "--preview", str(tmp_path / "p.png")]) == 0
    face = FaceModel.read(out / "st1.pts", out / "stt.top", out / "st2.pts")
    want = subject_face(palate_mm=np.array([(-5, 8.5), (-20, 19), (-45, 22)]), jaw_length_mm=34)
    np.testing.assert_array_equal(face.st1, want.st1)
    png = (tmp_path / "p.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    assert main([str(out), "--palate", str(tmp_path / "missing.dat")]) == 2


def test_preview_of_a_moved_face(tmp_path):
    face = build_face()
    moved = face.vertices.copy()
    moved[:, 2] += 5.0
    preview_png(face, tmp_path / "moved.png", positions=moved, dpi=40)
    assert (tmp_path / "moved.png").stat().st_size > 5_000


def test_the_face_cli_refuses_bad_inputs_before_making_anything(tmp_path, capsys):
    out = tmp_path / "face"
    for bad in ("-5", "nan"):                   # argparse refuses them: exit 2, nothing made
        with pytest.raises(SystemExit) as exc:
            main([str(out), "--jaw-length", bad])
        assert exc.value.code == 2
        assert f"{bad!r} is not a positive number" in capsys.readouterr().err
    assert main([str(out), "--palate", str(tmp_path / "missing.dat")]) == 2
    assert not out.exists()                      # nothing made for a bad input
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert main([str(afile)]) == 2
    assert "exists and is not a directory" in capsys.readouterr().err
