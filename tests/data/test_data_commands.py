"""The ``cassi corpus`` commands: check, preprocess, make (exit codes 0 / 2 / 1)."""
from __future__ import annotations

import importlib
import json
import shutil

import pytest
from data_helpers import FIXTURES, JW45_EXCERPT, recording, write_metadata, write_subject

from cassi.data.commands import main
from cassi.data.corpus.profile import read_lipthick, read_maxprotru


@pytest.fixture
def corpus_dir(tmp_path):
    root = tmp_path / "corpus"
    write_subject(root, "JW11", {(t, 1): recording(task=t) for t in (1, 2, 3)}, mis=[(3, "TD")])
    write_subject(root, "JW12", {(1, 1): recording(task=1), (118, 1): recording(task=118)})
    return root


def test_check_corpus_json(corpus_dir, capsys):
    assert main(["check", str(corpus_dir), "--json"]) == 0
    records = json.loads(capsys.readouterr().out)
    assert len(records) == 5
    for r in records:
        assert {"path", "subject", "task", "frames", "first_valid_us", "usable",
                "problems"} <= r.keys()
    r3 = next(r for r in records if r["subject"] == "JW11" and r["task"] == 3)
    assert r3["usable"] and not r3["error_free"] and "Mis.dat" in r3["problems"][0]
    r1 = next(r for r in records if r["subject"] == "JW12" and r["task"] == 118)
    assert r1["frames"] == 40 and r1["first_valid_us"] == 3 * 6866 and r1["problems"] == []


def test_check_single_task_file(capsys):
    assert main(["check", str(JW45_EXCERPT)]) == 0
    out = capsys.readouterr().out
    assert "16 frames" in out and "first valid 27464 us" in out


def test_check_malformed_file_exits_2_with_file_line_reason(corpus_dir, capsys):
    bad = corpus_dir / "JW11" / "tp002.txy"
    lines = bad.read_text().splitlines()
    toks = lines[6].split("\t")
    lines[6] = "\t".join([toks[0], "x", *toks[2:]])
    bad.write_text("\n".join(lines) + "\n")
    assert main(["check", str(corpus_dir)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:7: column 2 (ULx): 'x' is not a number" in err


@pytest.mark.parametrize("name, content, line", [
    ("Mis.dat", "003 TD zz\n", 1), ("PAL.DAT", "1 2\n3\n", 2), ("tp001.txy", "", None),
])
def test_check_reports_malformed_subject_files(corpus_dir, capsys, name, content, line):
    (corpus_dir / "JW12" / name).write_text(content)
    assert main(["check", str(corpus_dir)]) == 2
    err = capsys.readouterr().err
    where = f"{corpus_dir / 'JW12' / name}:" + (f"{line}:" if line else "")
    assert where in err


def test_check_single_subject_files(capsys):
    assert main(["check", str(FIXTURES / "xrmb" / "JW12" / "Mis.dat")]) == 0
    assert main(["check", str(FIXTURES / "profiles" / "maxprotru.txt")]) == 0
    assert main(["check", str(FIXTURES / "textgrid" / "tp001.TextGrid")]) == 0
    capsys.readouterr()


def test_check_bad_paths_exit_2(tmp_path, capsys):
    assert main(["check", str(tmp_path / "missing")]) == 2
    (tmp_path / "empty").mkdir()
    assert main(["check", str(tmp_path / "empty")]) == 2
    (tmp_path / "readme.md").write_text("hi")
    assert main(["check", str(tmp_path / "readme.md")]) == 2
    err = capsys.readouterr().err
    assert "unknown file kind" in err and "no subject directories" in err


def test_check_synthetic_corpus_says_so(corpus_dir, capsys):
    write_metadata(corpus_dir, synthetic=True)
    assert main(["check", str(corpus_dir)]) == 0
    assert "synthetic corpus" in capsys.readouterr().out


def test_preprocess_writes_tables(corpus_dir, tmp_path, capsys):
    out = tmp_path / "profiles"
    assert main(["preprocess", str(corpus_dir), "--out", str(out)]) == 0
    mp = read_maxprotru(out / "maxprotru.txt")
    lt = read_lipthick(out / "lipthick.txt")
    assert list(mp) == ["JW11", "JW12"] and list(lt) == ["JW11", "JW12"]
    csv = (out / "selected_files.csv").read_text().splitlines()
    assert len(csv) == 1 + 2 + 2  # JW11: tasks 1, 2 (3 is in Mis.dat); JW12: 1, 118
    assert (out / "maxprotru.txt").read_text().startswith("Subject REST_UL REST_LL MAX_UL")
    assert "JW11: 2 file(s)" in capsys.readouterr().out


def test_preprocess_errors(tmp_path, corpus_dir, capsys):
    assert main(["preprocess", str(tmp_path / "none"), "--out", str(tmp_path / "o")]) == 2
    assert main(["preprocess", str(corpus_dir), "--out", str(tmp_path / "o"),
                 "--subjects", "JW77"]) == 2
    assert main(["preprocess", str(corpus_dir), "--out", str(tmp_path / "o"),
                 "--subjects", "../x"]) == 2
    capsys.readouterr()


def test_help_everywhere(capsys):
    for argv in (["--help"], ["check", "--help"], ["make", "--help"], ["preprocess", "--help"]):
        assert main(argv) == 0
    assert "maxprotru.txt" in capsys.readouterr().out


def test_make_then_check_and_preprocess(tmp_path, capsys):
    importlib.import_module("cassi.data.synth.corpus")
    out = tmp_path / "synth"
    assert main(["make", "--out", str(out), "--subjects", "JW45", "--seed", "1"]) == 0
    assert "written" in capsys.readouterr().out
    assert main(["check", str(out), "--json"]) == 0
    records = json.loads(capsys.readouterr().out)
    assert records and all(r["subject"] == "JW45" for r in records)
    assert main(["preprocess", str(out), "--out", str(tmp_path / "p")]) == 0
    assert "synthetic" in capsys.readouterr().out


def test_copy_of_reference_subject_checks(tmp_path, capsys):
    d = tmp_path / "c" / "JW45"
    d.mkdir(parents=True)
    shutil.copy(JW45_EXCERPT, d / "tp013.txy")
    for f in ("PAL.DAT", "Mis.dat"):
        shutil.copy(FIXTURES / "xrmb" / "JW12" / f, d / f)
    (d / "PHA.DAT").write_text("-60000 -5000\n")
    assert main(["check", str(tmp_path / "c"), "--json"]) == 0
    (r,) = json.loads(capsys.readouterr().out)
    # JW12's Mis.dat lists task 13, so this file is usable but not error-free.
    assert r["usable"] and not r["error_free"] and r["first_valid_us"] == 27464


def test_file_without_valid_row_is_unusable_not_malformed(corpus_dir, capsys):
    """The thesis's JW29/JW32: the MNM pellet removed, so no row has all eight pellets valid.
    The file is well-formed: reported UNUSABLE with the reason; exit 2 only with --strict."""
    from cassi.data.xrmb.files import write_txy

    write_txy(corpus_dir / "JW12" / "tp020.txy", recording(task=20, lost=("MNM", 0)))
    assert main(["check", str(corpus_dir), "--json"]) == 0
    records = json.loads(capsys.readouterr().out)
    r = next(r for r in records if r["task"] == 20)
    assert r["usable"] is False and r["first_valid_us"] is None and r["frames"] == 40
    assert "tp020.txy" in r["problems"][0] and "never valid: MNM" in r["problems"][0]
    assert main(["check", str(corpus_dir), "--strict"]) == 2
    assert "never valid: MNM" in capsys.readouterr().err
    assert main(["check", str(corpus_dir / "JW12" / "tp020.txy")]) == 0
    assert "UNUSABLE" in capsys.readouterr().out


def test_through_the_cassi_console_script(corpus_dir):
    """The installed ``cassi`` entry point reaches these commands (exit 2, file:line: reason)."""
    import subprocess
    import sys

    bad = corpus_dir / "JW11" / "Mis.dat"
    bad.write_text("003 TD 0 -1\n003 QQ 0 5\n")
    proc = subprocess.run([sys.executable, "-m", "cassi.harness.cli", "corpus", "check",
                           str(corpus_dir)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert f"{bad}:2: unknown pellet code 'QQ'" in proc.stderr
