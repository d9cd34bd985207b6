"""The version registry: names, lazy entries, did-you-mean, freezing, the CLI listing."""
from __future__ import annotations

import pytest

from cassi.common.errors import CassiInputError
from cassi.versions import registry as R
from cassi.versions.protocol import Version


def test_builtin_names():
    assert {"parke-1974", "cassi-1.0", "cassi-2.0", "cassi-2.1"} <= set(R.available_versions())


def test_the_thesis_order_is_the_registry_s_own():
    """The rubric's version order (Table C compares each version with the previous one) is the
    registry's built-ins in their order, and each built-in's class carries its registered name."""
    from cassi.harness.rubric.model import PARKE_VERSION, VERSION_ORDER
    assert VERSION_ORDER == tuple(R.BUILT_IN_VERSIONS) == ("parke-1974", "cassi-1.0", "cassi-2.0", "cassi-2.1")
    assert PARKE_VERSION == "parke-1974"
    assert [R.get_version(n).name for n in VERSION_ORDER] == list(VERSION_ORDER)


@pytest.mark.parametrize("name", ["parke-1974", "cassi-1.0"])
def test_get_version_returns_a_protocol_instance(name):
    v = R.get_version(name)
    assert isinstance(v, Version) and v.name == name


def test_did_you_mean():
    with pytest.raises(CassiInputError) as err:
        R.get_version("cassi-1.O")
    msg = str(err.value)
    assert "Did you mean 'cassi-1.0'" in msg and "parke-1974" in msg and "Known:" in msg


def test_unknown_without_close_match_lists_names():
    with pytest.raises(CassiInputError) as err:
        R.get_version("zzzzzz")
    assert "Did you mean" not in str(err.value) and "cassi-2.1" in str(err.value)


def test_generic_registry_lazy_and_freeze():
    reg = R.Registry("thing")
    reg.register("json-dumps", lazy="json:dumps")
    import json
    assert reg.get("json-dumps") is json.dumps
    with pytest.raises(ValueError):
        reg.register("json-dumps", 1)
    reg.register("json-dumps", 2, replace=True)
    assert reg.get("json-dumps") == 2

    @reg.register("deco")
    def f():
        return 3
    assert reg.get("deco") is f
    reg.freeze()
    with pytest.raises(RuntimeError):
        reg.register("late", 4)
    assert reg.names() == ["deco", "json-dumps"]


def test_lazy_target_that_cannot_load_names_it():
    reg = R.Registry("thing")
    reg.register("broken", lazy="cassi.versions.no_such_module:X")
    with pytest.raises(CassiInputError, match="no_such_module"):
        reg.get("broken")


def test_bad_lazy_string():
    with pytest.raises(ValueError):
        R.Registry("thing").register("x", lazy="no-colon")


def test_entry_points_are_read(monkeypatch):
    from importlib.metadata import EntryPoint

    eps = [EntryPoint(name="third-party", value="cassi.versions.cassi10:Cassi10",
                      group="cassi.versions"),
           EntryPoint(name="cassi-1.0", value="json:dumps", group="cassi.versions")]
    monkeypatch.setattr(R, "entry_points", lambda group: [e for e in eps if e.group == group])
    reg = R.Registry("version", entry_point_group="cassi.versions")
    reg.register("cassi-1.0", lazy="cassi.versions.cassi10:Cassi10")
    assert reg.names() == ["cassi-1.0", "third-party"]
    from cassi.versions.cassi10 import Cassi10
    assert reg.get("third-party") is Cassi10
    assert reg.get("cassi-1.0") is Cassi10      # an entry point never replaces a built-in


def test_cli_lists_names(capsys):
    import argparse

    from cassi.versions.commands import register
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    register(sub)
    args = parser.parse_args(["versions"])
    assert args.func(args) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == sorted(lines) and "cassi-1.0" in lines and "parke-1974" in lines
