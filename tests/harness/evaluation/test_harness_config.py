"""Run configuration: TOML/YAML/flags, validation at load time, names checked before work."""
from __future__ import annotations

import argparse
import json

import pytest

from cassi.common.errors import CassiInputError
from cassi.harness.evaluation import config as C
from cassi.harness.commands import config_from_args, register
from cassi.harness.evaluation.evalset import TABLE_5_1

CATALOG = C.Catalog(subjects=("JW11", "JW12"), tasks={"JW11": (19, 21, 106), "JW12": (2, 5)},
                    versions=("cassi-1.0", "cassi-2.1"), views=("front", "side", "half", "top"),
                    presets=("preview", "final"))


def _parser():
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="command"))
    return p


def test_toml_and_yaml_give_the_same_config(tmp_path):
    (tmp_path / "run.toml").write_text(
        'out = "o"\nsubjects = ["JW11"]\ntasks = [19, 21]\nviews = ["front"]\nworkers = 2\n'
        'executor = "ray"\naddress = "127.0.0.1:6379"\n')
    (tmp_path / "run.yaml").write_text(
        "out: o\nsubjects: [JW11]\ntasks: [19, 21]\nviews: [front]\nworkers: 2\n"
        "executor: ray\naddress: '127.0.0.1:6379'\n")
    a, b = C.load_config(tmp_path / "run.toml"), C.load_config(tmp_path / "run.yaml")
    assert a == b
    assert a.out == tmp_path / "o"  # relative to the config file
    assert a.tasks == (19, 21) and a.workers == 2 and a.stride == C.RunConfig().stride


@pytest.mark.parametrize("text, match, line", [
    ('out = "o"\nworkres = 2\n', r"unknown setting 'workres' \(did you mean 'workers'\?\)", 2),
    ('out = "o"\nworkers = 0\n', "workers: must be at least 1", 2),
    ('out = "o"\nstride = "x"\n', "stride: expected an integer", 2),
    ('tasks = ["a"]\n', "tasks: expected an integer", 1),
    ('subjects = []\n', "subjects: the list is empty", 1),
    ('executor = "slurm"\n', "unknown executor 'slurm'; valid: local, ray", 1),
    ('address = "x:1"\n', "address is only used with executor 'ray'", 1),
    ('out = "o"\nset = "ful"\n', "unknown evaluation set 'ful'; valid: thesis, full .did you mean 'full'", 2),
    ('out = "o"\nworkers = [\n', "not valid TOML", None),
    ('out = "o"\nstride = 99999999999\n', r"stride: out of range \(at most", 2),
    ('stride = ' + "9" * 5000 + "\n", "not valid TOML: .*4300 digits", None),
    ('tasks = ["\u0663"]\n', "tasks: expected an integer", 1),       # ASCII digits only
])
def test_bad_settings_name_file_and_line(tmp_path, text, match, line):
    path = tmp_path / "run.toml"
    path.write_text(text)
    with pytest.raises(CassiInputError, match=match) as err:
        C.load_config(path)
    assert err.value.path == str(path)
    if line is not None:
        assert err.value.line == line


@pytest.mark.parametrize("key", ["1", "true", "null", "yes"])
def test_a_yaml_key_that_is_not_text_is_an_unknown_setting(tmp_path, key):
    path = tmp_path / "run.yaml"
    path.write_text(f"out: o\n{key}: x\n")
    with pytest.raises(CassiInputError, match="unknown setting") as err:
        C.load_config(path)
    assert err.value.path == str(path) and err.value.line == 2


def test_bad_yaml_and_suffix(tmp_path):
    (tmp_path / "r.yaml").write_text("out: [unclosed\n")
    with pytest.raises(CassiInputError, match="not valid YAML"):
        C.load_config(tmp_path / "r.yaml")
    (tmp_path / "r.json").write_text("{}")
    with pytest.raises(CassiInputError, match=".toml, .yaml or .yml"):
        C.load_config(tmp_path / "r.json")


def test_yaml_refuses_a_key_set_twice_and_numbers_it_cannot_read(tmp_path):
    """PyYAML keeps the last of two equal keys; a run file that sets one twice is refused with
    the second's line. A number Python cannot read (over 4300 digits) is an input error too."""
    path = tmp_path / "run.yaml"
    path.write_text("stride: 5\nworkers: 2\nstride: 10\n")
    with pytest.raises(CassiInputError, match=r"'stride' is set twice \(first on line 1\)") as err:
        C.load_config(path)
    assert err.value.path == str(path) and err.value.line == 3
    path.write_text("run:\n  tasks: [19]\n  tasks: [21]\n")
    with pytest.raises(CassiInputError, match="'tasks' is set twice"):
        C.load_config(path)
    path.write_text("stride: " + "9" * 5000 + "\n")
    with pytest.raises(CassiInputError, match="not valid YAML: .*4300 digits"):
        C.load_config(path)
    path.write_text("{stride: 1, stride: 2}\n")                     # twice on one line
    with pytest.raises(CassiInputError, match="'stride' is set twice"):
        C.load_config(path)
    path.write_text("workers: 0x" + "F" * 4000 + "\n")                # hex has no digit limit
    with pytest.raises(CassiInputError, match="workers: out of range"):
        C.load_config(path)
    path.write_text("base: &b {stride: 5}\nrun:\n  <<: *b\n")        # a merge key sets no key
    with pytest.raises(CassiInputError, match="unknown setting 'base'"):
        C.load_config(path)
    path.write_text("subjects: [JW11, JW11]\nstride: 5\n")           # a repeated value is fine
    assert C.load_config(path).subjects == ("JW11",)


def test_flags_override_the_file(tmp_path):
    (tmp_path / "run.toml").write_text('out = "o"\nworkers = 2\nversions = ["cassi-1.0"]\n')
    args = _parser().parse_args(["run", "--config", str(tmp_path / "run.toml"),
                                 "--workers", "1", "--tasks", "19", "21", "--stride", "5"])
    cfg = config_from_args(args)
    assert cfg.workers == 1 and cfg.tasks == (19, 21) and cfg.stride == 5
    assert cfg.versions == ("cassi-1.0",) and cfg.out == tmp_path / "o"


def test_extremes_setting_is_validated(tmp_path):
    with pytest.raises(CassiInputError, match="extremes: must be at least 0"):
        config_from_args(_parser().parse_args(["run", "--out", "x", "--extremes", "-1"]))
    cfg = config_from_args(_parser().parse_args(["run", "--out", "x", "--extremes", "3"]))
    assert cfg.extremes == 3 and C.RunConfig().extremes == 4


def test_list_flags_take_commas_or_spaces():
    a = config_from_args(_parser().parse_args(["run", "--out", "o", "--subjects", "JW11,JW12",
                                               "--tasks", "19,21", "106", "--views", "front,half"]))
    b = config_from_args(_parser().parse_args(["run", "--out", "o", "--subjects", "JW11", "JW12",
                                               "--tasks", "19", "21", "106", "--views", "front", "half"]))
    assert a == b and a.subjects == ("JW11", "JW12") and a.tasks == (19, 21, 106)
    assert a.views == ("front", "half")


def test_flags_are_validated_like_the_file():
    with pytest.raises(CassiInputError, match="workers: must be at least 1"):
        config_from_args(_parser().parse_args(["run", "--out", "x", "--workers", "0"]))
    with pytest.raises(CassiInputError, match="no output directory"):
        config_from_args(_parser().parse_args(["run"]))
    with pytest.raises(CassiInputError, match="tasks: expected an integer"):
        config_from_args(_parser().parse_args(["run", "--out", "x", "--tasks", "tp19"]))


@pytest.mark.parametrize("change, match", [
    ({"subjects": ("JW11", "JW99")}, r"unknown subject JW99.*; valid subjects: JW11, JW12"),
    ({"tasks": (19, 7)}, r"unknown task 7; valid tasks: 2, 5, 19, 21, 106"),
    ({"subjects": ("JW12",), "tasks": (19,)}, r"unknown task 19; valid tasks: 2, 5"),
    ({"versions": ("cassi-2.2",)}, r"did you mean 'cassi-2.1'.*valid versions: cassi-1.0, cassi-2.1"),
    ({"views": ("fromt",)}, r"unknown view fromt \(did you mean 'front'\?\); valid views: front, "
                            r"side, half, top, geometry"),
    ({"preset": "ultra"}, "unknown preset ultra; valid presets: preview, final"),
])
def test_unknown_names_list_the_valid_ones(change, match):
    with pytest.raises(CassiInputError, match=match):
        C.check_names(C.RunConfig(**change), CATALOG)


@pytest.mark.parametrize("name", ["run.toml", "run.yaml"])
def test_unknown_names_from_a_run_file_name_its_line(tmp_path, name):
    """A name the corpus lacks is refused at the line of the run file that set it, also after
    flags were applied over the file; a flag's own name has no line."""
    path = tmp_path / name
    sep = " =" if name.endswith(".toml") else ":"
    path.write_text(f'out{sep} "o"\nsubjects{sep} ["JW11"]\n\ntasks{sep} [19, 7]\n')
    args = _parser().parse_args(["run", "--config", str(path), "--versions", "cassi-1.0"])
    cfg = config_from_args(args)
    with pytest.raises(CassiInputError, match=r"unknown task 7; valid tasks: 19, 21, 106") as err:
        C.check_names(cfg, CATALOG)
    assert err.value.path == str(path) and err.value.line == 4
    assert str(err.value).startswith(f"{path}:4: ")
    args = _parser().parse_args(["run", "--config", str(path), "--tasks", "8"])
    with pytest.raises(CassiInputError, match="unknown task 8") as err:
        C.check_names(config_from_args(args), CATALOG)
    assert err.value.path is None
    assert C.resolved(cfg).keys().isdisjoint({"where"}) and cfg == cfg.replace(where={})


def test_known_names_pass():
    C.check_names(C.RunConfig(subjects=("JW12",), tasks=(2,), versions=("cassi-1.0",),
                              views=("geometry",)), CATALOG)


def test_resolved_has_provenance(tmp_path):
    doc = C.resolved(C.RunConfig(out=tmp_path, tasks=(1, 2)), extra=1)
    assert doc["out"] == str(tmp_path) and doc["tasks"] == [1, 2] and doc["extra"] == 1
    assert doc["package_version"] == "0.1.0"
    rev = doc["git_revision"]
    assert rev is None or len(rev.split("-")[0]) == 40
    json.dumps(doc)


def test_table_5_1_as_printed():
    # thesis Table 5.1: 15 subjects, two tasks each
    assert len(TABLE_5_1) == 15
    assert TABLE_5_1["JW16"] == (3, 6) and TABLE_5_1["JW502"] == (21, 22)
    assert all(a != b for a, b in TABLE_5_1.values())


def _options(parser: argparse.ArgumentParser, command: str) -> dict[str, argparse.Action]:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {a.dest: a for a in sub.choices[command]._actions}


def test_run_and_nightly_take_the_same_run_settings():
    """One front door: every setting of a run is an option of both commands, parsed alike;
    only the output and the night's own switches differ."""
    run, night = _options(_parser(), "run"), _options(_parser(), "nightly")
    assert set(C.FIELDS) - {"out", "cache"} <= set(run) & set(night)
    for name in set(C.FIELDS) - {"out", "cache"}:
        assert run[name].type is night[name].type and run[name].nargs == night[name].nargs, name
    assert set(night) - set(run) == {"common_only", "quiet"}
    assert set(run) - set(night) == {"cache", "no_progress"}


def test_nightly_reads_a_run_file_over_its_own_defaults(tmp_path):
    """A night's defaults (C.NIGHTLY), then the run file, then the flags."""
    path = tmp_path / "night.yaml"
    path.write_text("subjects: [JW11]\nstride: 50\nvideo_versions: all\n")
    args = _parser().parse_args(["nightly", "--out", "n", "--config", str(path),
                                 "--extremes", "3"])
    cfg = config_from_args(args, C.NIGHTLY, need_out=False)
    assert cfg.subjects == ("JW11",) and cfg.stride == 50 and cfg.video_versions is None
    assert cfg.extremes == 3 and cfg.workers == C.NIGHTLY.workers == 2
    assert cfg.animate_stride == C.NIGHTLY.animate_stride > 0
    plain = config_from_args(_parser().parse_args(["nightly", "--out", "n"]), C.NIGHTLY,
                             need_out=False)
    assert plain.replace(out=None) == C.NIGHTLY
    with pytest.raises(CassiInputError, match="stride: must be at least 0"):
        config_from_args(_parser().parse_args(["nightly", "--out", "n", "--stride", "-1"]),
                         C.NIGHTLY, need_out=False)


def test_task_ranges_work_wherever_tasks_are_taken(tmp_path):
    """`cassi run --tasks 1-118` (refused before as "expected an integer"), a run file's
    "102-105" and corpus stats' --tasks all read ranges by one rule (cliargs.task_range)."""
    cfg = config_from_args(_parser().parse_args(["run", "--out", "o", "--tasks", "1-3", "19,102-104"]))
    assert cfg.tasks == (1, 2, 3, 19, 102, 103, 104)
    (tmp_path / "run.toml").write_text('out = "o"\ntasks = ["102-105", 13]\n')
    assert C.load_config(tmp_path / "run.toml").tasks == (102, 103, 104, 105, 13)
    with pytest.raises(CassiInputError, match=r"tasks: bad task list '5-2'"):
        config_from_args(_parser().parse_args(["run", "--out", "o", "--tasks", "5-2"]))
    with pytest.raises(CassiInputError, match="tasks: expected an integer"):
        config_from_args(_parser().parse_args(["run", "--out", "o", "--tasks", "1-x"]))


def test_the_evaluation_set_from_a_run_file_and_the_flag(tmp_path):
    (tmp_path / "run.yaml").write_text("out: o\nset: full\n")
    assert C.load_config(tmp_path / "run.yaml").set == "full"
    assert C.RunConfig().set == C.NIGHTLY.set == "thesis"
    args = _parser().parse_args(["nightly", "--out", "n", "--config", str(tmp_path / "run.yaml")])
    assert config_from_args(args, C.NIGHTLY).set == "full"
    args = _parser().parse_args(["run", "--out", "o", "--set", "full"])
    assert config_from_args(args).set == "full"
