"""A run's path indexes are checked path by path: nothing outside the run directory is read,
whether it leaves by ``..``, an absolute path, a linked folder or a linked file."""
import os

import pytest

from cassi.common.errors import CassiInputError
from cassi.reports.runio import _all_inside


def _run(tmp_path):
    run = tmp_path / "run"
    (run / "objects" / "ab").mkdir(parents=True)
    (run / "objects" / "ab" / "ab12.png").write_bytes(b"x")
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "secret.png").write_bytes(b"y")
    return run


def test_paths_inside_resolve_to_the_files(tmp_path):
    run = _run(tmp_path)
    got = _all_inside(run, ["objects/ab/ab12.png", "objects/ab/ab12.png"])
    assert got == [str((run / "objects/ab/ab12.png").resolve())] * 2


@pytest.mark.parametrize("how", ["dotdot", "absolute", "linked file", "linked folder"])
def test_a_path_that_leaves_the_run_is_refused(tmp_path, how):
    run = _run(tmp_path)
    secret = tmp_path / "outside" / "secret.png"
    rel = {"dotdot": "objects/ab/../../../outside/secret.png", "absolute": str(secret)}.get(how)
    if how == "linked file":
        os.symlink(secret, run / "objects" / "ab" / "cd34.png")
        rel = "objects/ab/cd34.png"
    if how == "linked folder":
        os.symlink(tmp_path / "outside", run / "objects" / "ef")
        rel = "objects/ef/secret.png"
    with pytest.raises(CassiInputError, match="escapes the run directory"):
        _all_inside(run, ["objects/ab/ab12.png", rel])
