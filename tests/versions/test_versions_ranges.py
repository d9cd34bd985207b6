"""The versions' ranged constants: declared with a reason, inside their range, read when a
version animates (so cassi.versions.ranges can set one for the sensitivity analysis)."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

from cassi.common.errors import CassiInputError
from cassi.versions import constants, lips_constants
from cassi.versions.cassi10 import NoseClearanceStage
from cassi.versions.cassi20 import Cassi20
from cassi.versions.cassi21 import Cassi21
from cassi.versions.lips_ellipse import limit_abc
from cassi.versions.lips_thickness import current_thickness
from cassi.versions.ranges import RANGED_MODULES, constant_set, ranged_constants

VERSIONS_DIR = Path(constants.__file__).parent
PLUGIN_DIR = VERSIONS_DIR.parent / "plugins" / "cassi30" / "cassi30"


def test_every_range_holds_its_value_with_a_reason():
    found = ranged_constants()
    assert "lips_constants.RHO" in found and "constants.NOSE_LIP_MIN_GAP_MM" in found
    for c in found.values():
        assert isinstance(c.value, float) and c.low < c.value < c.high, c
        assert len(c.reason) > 20, c.name


def _import_time_reads(path: Path) -> list[str]:
    """``alias.NAME`` of a ranged constant evaluated when the module is imported: a function's
    default, a class body, the module's top level (a lambda or function body runs later)."""
    tree = ast.parse(path.read_text())
    ranged = {short: set(m.RANGES) for short, m in RANGED_MODULES.items()}
    alias, bad = {}, []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "cassi.versions":
            alias.update({a.asname or a.name: a.name for a in node.names if a.name in ranged})
        if isinstance(node, ast.ImportFrom) and node.module in {f"cassi.versions.{s}" for s in ranged}:
            short = node.module.rsplit(".", 1)[1]
            bad += [f"{path.name}: from-import of {a.name}" for a in node.names if a.name in ranged[short]]

    def reads(expr) -> list[str]:
        return [f"{path.name}:{n.lineno} {n.value.id}.{n.attr}" for n in ast.walk(expr)
                if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name)
                and n.value.id in alias and n.attr in ranged[alias[n.value.id]]
                and not _in_lambda(expr, n)]

    def visit(body):
        for stmt in body:
            if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for d in stmt.args.defaults + [d for d in stmt.args.kw_defaults if d is not None]:
                    bad.extend(reads(d))
                bad.extend(r for dec in stmt.decorator_list for r in reads(dec))
            elif isinstance(stmt, ast.ClassDef):
                visit(stmt.body)
            else:
                bad.extend(reads(stmt))
    visit(tree.body)
    return bad


def _in_lambda(root, target) -> bool:
    return any(isinstance(n, ast.Lambda) and any(m is target for m in ast.walk(n))
               for n in ast.walk(root))


def test_no_version_reads_a_ranged_constant_at_import():
    files = sorted(VERSIONS_DIR.glob("*.py")) + sorted(PLUGIN_DIR.glob("*.py"))
    assert any(f.name == "lips_ellipse.py" for f in files)
    bad = [b for f in files for b in _import_time_reads(f)]
    assert not bad, bad


def test_a_setting_reaches_what_a_version_builds_and_is_undone():
    with constant_set("lips_constants.RHO", 0.2), constant_set("constants.NOSE_LIP_MIN_GAP_MM", 3.0):
        assert Cassi21().params.rho == 0.2 and NoseClearanceStage().min_gap_mm == 3.0
    with constant_set("lips_constants.NEAR_REST_MM", 1.0):
        assert Cassi20().params.near_rest_mm == Cassi21().params.near_rest_mm == 1.0
    with constant_set("lips_constants.THICKEN_GAIN", 0.6):
        assert current_thickness(10.0, [0.0])[0] == pytest.approx(16.0)
    with constant_set("lips_constants.A_MAX", 104.0):
        assert limit_abc([200.0], [0.0])[0][0] == 104.0
    assert Cassi21().params.rho == lips_constants.RHO == 0.1
    assert Cassi20().params.near_rest_mm == lips_constants.NEAR_REST_MM == 0.5
    assert NoseClearanceStage().min_gap_mm == constants.NOSE_LIP_MIN_GAP_MM == 2.0
    assert current_thickness(10.0, [0.0])[0] == pytest.approx(14.0)


def test_an_unknown_constant_is_refused():
    with pytest.raises(CassiInputError, match="no ranged constant"):
        with constant_set("lips_constants.C_REST", 60.0):
            pass
