"""``link_or_copy``: a new name is a hard link made in one step, an existing one is replaced
atomically, a missing folder is made, and a missing source is an error, not a new folder.
``replacing``: a named writer's temporary file becomes the target, or vanishes if it fails."""
from __future__ import annotations

import os

import pytest

from cassi.common.atomic import link_or_copy


def test_a_new_name_is_a_hard_link_in_a_folder_made_for_it(tmp_path):
    src = tmp_path / "a.bin"
    src.write_bytes(b"render")
    dest = tmp_path / "x" / "y" / "b.bin"
    assert link_or_copy(src, dest) == dest
    assert dest.read_bytes() == b"render" and os.path.samefile(src, dest)
    assert sorted(p.name for p in dest.parent.iterdir()) == ["b.bin"]  # no temporary left


def test_an_existing_name_is_replaced(tmp_path):
    src, dest = tmp_path / "a.bin", tmp_path / "b.bin"
    src.write_bytes(b"new")
    dest.write_bytes(b"old")
    link_or_copy(src, dest)
    assert dest.read_bytes() == b"new" and os.path.samefile(src, dest)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin", "b.bin"]


def test_a_missing_source_is_an_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        link_or_copy(tmp_path / "none.bin", tmp_path / "b.bin")
    with pytest.raises(FileNotFoundError):
        link_or_copy(tmp_path / "none.bin", tmp_path / "new" / "b.bin")


def test_replacing_renames_on_success_and_leaves_nothing_when_the_writer_fails(tmp_path):
    from cassi.common.atomic import replacing
    dest = tmp_path / "plot.png"
    dest.write_bytes(b"old")
    with replacing(dest) as tmp:
        assert tmp.parent == tmp_path and tmp != dest
        tmp.write_bytes(b"new")
    assert dest.read_bytes() == b"new"
    with pytest.raises(RuntimeError):
        with replacing(dest) as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("writer failed")
    assert dest.read_bytes() == b"new"                       # the old file intact
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plot.png"]   # no .tmp left


def test_a_copy_across_file_systems_keeps_a_read_only_blob_read_only(tmp_path, monkeypatch):
    import errno

    src, dest = tmp_path / "a.bin", tmp_path / "run" / "b.bin"
    src.write_bytes(b"render")
    src.chmod(0o444)

    def other_file_system(*_):
        raise OSError(errno.EXDEV, "Invalid cross-device link")

    monkeypatch.setattr(os, "link", other_file_system)
    link_or_copy(src, dest)
    assert dest.read_bytes() == b"render" and not os.path.samefile(src, dest)
    assert dest.stat().st_mode & 0o777 == 0o444    # a write into the copy is refused too
