"""The `cassi` console script: every command has --help; exit codes 0 / 2 / 1."""
from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

from cassi.common.cliargs import positive_number, seed_int
from cassi.harness.cli import build_parser, main


def _commands(parser: argparse.ArgumentParser, prefix=()):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*prefix, name)
                yield from _commands(sub, (*prefix, name))


COMMANDS = list(_commands(build_parser()))


def test_every_package_contributes_its_commands():
    top = {c[0] for c in COMMANDS}
    assert {"corpus", "versions", "render", "animate", "run", "bench", "report", "nightly",
            "gate", "golden"} <= top
    assert {("corpus", "make"), ("corpus", "check"), ("corpus", "preprocess")} <= set(COMMANDS)


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_help_on_every_command(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([*command, "--help"])
    assert exc.value.code == 0
    assert "usage: cassi " + " ".join(command) in capsys.readouterr().out


def _parsers(parser: argparse.ArgumentParser):
    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                yield from _parsers(sub)


def test_numeric_options_take_ascii_digits_only(capsys):
    """int() reads '٣' (Arabic-Indic three) and '1_0': every integer option parses through
    ascii_int instead, so such text is refused (exit 2) before any work; a rate or length
    parses through positive_number (float() reads 'nan' and 'inf')."""
    raw = [(p.prog, a.dest) for p in _parsers(build_parser()) for a in p._actions
           if a.type in (int, float)]
    assert raw == []
    base = ["render", "--subject", "JW11", "--version", "cassi-1.0", "--view", "front",
            "--frame", "9", "--out", "x.png"]
    for bad in ("٣", "1_0", " 3", "3.0"):
        with pytest.raises(SystemExit) as exc:
            main([*base, "--task", bad])
        assert exc.value.code == 2
        assert "argument --task: " in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["corpus", "stats", ".", "--tasks", "١٠٥"])
    assert exc.value.code == 2 and "bad task list" in capsys.readouterr().err
    for bad in ("nan", "inf", "0", "-5", "١.٥", "1e999"):
        with pytest.raises(SystemExit) as exc:
            main(["animate", "--subject", "JW11", "--task", "105", "--version", "cassi-1.0",
                  "--out", "x.gif", "--fps", bad])
        assert exc.value.code == 2 and "not a positive number" in capsys.readouterr().err
    assert positive_number("12.5") == 12.5 and positive_number("1e1") == 10.0
    # a seed takes any size SeedSequence does: a 64-bit one (20 digits) is valid
    assert seed_int(str(2 ** 64 - 1)) == 2 ** 64 - 1 and seed_int("0") == 0
    for bad in ("-1", str(2 ** 128), "1_0", "٣", ""):
        with pytest.raises(argparse.ArgumentTypeError, match="is not a seed"):
            seed_int(bad)


def test_bench_help_names_every_benchmark(capsys):
    """The parser does not import the benchmarks (pandas, the executors): its list is checked
    against theirs here."""
    from cassi.harness.bench import BENCHMARKS

    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    listed = text.split("run only these benchmarks (", 1)[1].split(":", 1)[0]
    assert listed.split(", ") == list(BENCHMARKS)


def test_exit_codes_bad_input_and_unknown_command(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["no-such-command"])
    assert exc.value.code == 2
    assert main(["run", "--out", str(tmp_path / "o"), "--versions", "cassi-9.9"]) == 2
    assert "valid versions" in capsys.readouterr().err


def test_console_script_is_installed():
    out = subprocess.run([sys.executable, "-m", "cassi.harness.cli", "versions"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.split() == sorted(out.stdout.split())
    assert {"parke-1974", "cassi-1.0", "cassi-2.0", "cassi-2.1"} <= set(out.stdout.split())


def test_an_output_that_is_a_file_or_a_bad_night_setting_exits_2(tmp_path, capsys):
    from cassi.common.atomic import writable_dir
    from cassi.common.errors import CassiInputError
    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(CassiInputError, match="exists and is not a directory") as info:
        writable_dir(afile, "golden directory")
    assert info.value.path == str(afile) and "golden directory" in str(info.value)
    assert writable_dir(tmp_path / "a" / "b").is_dir()
    assert main(["report", str(tmp_path), "--out", str(afile)]) == 2
    assert "report directory exists and is not a directory" in capsys.readouterr().err
    assert main(["nightly", "--out", str(tmp_path / "n"), "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert "workers: must be at least 1" in err
    assert not (tmp_path / "n").exists()      # refused before any work
