"""The layering of ARCHITECTURE.md, read from the source's imports (no code is run).

common <- data <- versions <- harness -> renderer (-> data); reports read what the harness
wrote (results, the rubric) and never drive the farm's executors. Function-local imports of
cassi's own modules are the exception, each with its reason on the line.
"""
from __future__ import annotations

import argparse
import ast
from pathlib import Path

import pytest

from cassi.harness.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
LAYERS = ("common", "data", "versions", "renderer", "harness", "reports")
#: What each layer may import, besides itself.
ALLOWED = {
    "common": set(),
    "data": {"common"},
    "versions": {"common", "data"},
    "renderer": {"common", "data"},
    "harness": {"common", "data", "versions", "renderer"},
    "reports": {"common", "data", "versions", "renderer", "harness"},
}
#: Modules reports must never import: they start or schedule a run; reports read what a run
#: wrote (the farm's process pool may encode a report's videos: that is no run).
REPORTS_NEVER = ("cassi.harness.evaluation.run", "cassi.harness.evaluation.nightly",
                 "cassi.harness.farm.runner")
#: Names that start a run or a night, wherever they are defined: never imported by reports.
REPORTS_NEVER_NAMES = {"run", "run_batch", "nightly", "make_executor", "RayExecutor",
                       "cassi_pipeline"}
MAX_LOCAL_CASSI_IMPORTS = 20

if not (ROOT / "harness").is_dir():
    pytest.skip("needs the source tree", allow_module_level=True)


def _imports():
    """(layer, path, line, module, inside a function, source line) for every import."""
    for layer in LAYERS:
        for path in sorted((ROOT / layer).rglob("*.py")):
            text = path.read_text()
            tree = ast.parse(text)
            lines = text.splitlines()
            parts = ["cassi", layer, *path.relative_to(ROOT / layer).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts = parts[:-1]
            else:
                parts = parts[:-1]  # the package a relative import starts from

            def visit(node, in_func):
                for child in ast.iter_child_nodes(node):
                    f = in_func or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef))
                    if isinstance(child, ast.Import):
                        for a in child.names:
                            yield child.lineno, a.name, in_func
                    elif isinstance(child, ast.ImportFrom):
                        if child.level:
                            base = parts[:len(parts) - child.level + 1]
                            name = ".".join(base + ([child.module] if child.module else []))
                        else:
                            name = child.module or ""
                        yield child.lineno, name, in_func
                    yield from visit(child, f)

            for lineno, name, in_func in visit(tree, False):
                yield layer, path, lineno, name, in_func, lines[lineno - 1]


def test_every_layer_imports_only_the_layers_below_it():
    wrong = []
    for layer, path, lineno, name, _, _ in _imports():
        if name.startswith("cassi.") and name.split(".")[1] in LAYERS:
            target = name.split(".")[1]
            if target != layer and target not in ALLOWED[layer]:
                wrong.append(f"{path.relative_to(ROOT)}:{lineno}: {layer} imports {name}")
    assert not wrong, "\n".join(wrong)


def test_reports_never_start_a_run():
    wrong = [f"{p.relative_to(ROOT)}:{n}: {name}" for layer, p, n, name, _, _ in _imports()
             if layer == "reports" and name.startswith(REPORTS_NEVER)]
    for path in sorted((ROOT / "reports").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("cassi.harness"):
                wrong += [f"{path.relative_to(ROOT)}:{node.lineno}: {node.module}.{a.name}"
                          for a in node.names if a.name in REPORTS_NEVER_NAMES]
    assert not wrong, "\n".join(wrong)


def test_the_commands_that_start_a_run_are_the_harness_s_and_share_its_options():
    """`cassi run` and `cassi nightly` are composed in the harness, from one set of run
    options (harness.commands.add_run_options), never in reports."""
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for command in ("run", "nightly"):
        handler = sub.choices[command].get_default("func")
        assert handler.startswith("cassi.harness."), (command, handler)
    reports_cmds = (ROOT / "reports" / "commands.py").read_text()
    assert "add_run_options" not in reports_cmds and '"nightly"' not in reports_cmds


def test_few_function_local_imports_of_cassi_each_with_its_reason():
    local = [(p, n, src) for _, p, n, name, in_func, src in _imports()
             if in_func and name.startswith("cassi")]
    listing = "\n".join(f"{p.relative_to(ROOT)}:{n}: {s.strip()}" for p, n, s in local)
    assert len(local) <= MAX_LOCAL_CASSI_IMPORTS, listing
    unexplained = [f"{p.relative_to(ROOT)}:{n}" for p, n, s in local if " - " not in s.split("#", 1)[-1]
                   or "#" not in s]
    assert not unexplained, "a local import says why on its line (# noqa: PLC0415 - why):\n" + \
        "\n".join(unexplained)
