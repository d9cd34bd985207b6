"""The manual's rubric page (``docs/rubric.md``): its check reference is generated from the registry.

The page is hand-written prose around one generated block, between :data:`BEGIN` and :data:`END`;
the block lists every table and every check with its view, unit, frames, thresholds, negatives
and reason, as :data:`~cassi.harness.rubric.registry.CHECKS` declares them, so the manual cannot
drift from the thresholds a run applies (a test compares the two). Regenerate the block with

    python -m cassi.harness.rubric.manual --write docs/rubric.md
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.harness.rubric.model import RATINGS, TABLES, Check, table_title
from cassi.harness.rubric.registry import CHECKS

__all__ = ["BEGIN", "END", "REGENERATE", "rubric_reference", "with_reference", "main"]

REGENERATE = "python -m cassi.harness.rubric.manual --write docs/rubric.md"
BEGIN = f"<!-- BEGIN generated from the check registry by `{REGENERATE}`; do not edit -->"
END = "<!-- END generated -->"


def _number(x: float) -> str:
    return f"{x:g}"


def _cell(text: str) -> str:
    """A table cell: a pipe would end it."""
    return str(text).replace("|", "\\|")


def _tasks(check: Check) -> str:
    if check.tasks is not None:
        return "task " + ", ".join(str(t) for t in check.tasks)
    if check.skip_tasks:
        return "every task but " + ", ".join(str(t) for t in check.skip_tasks)
    return "every task"


def _grades(check: Check) -> str:
    """``> 1.5 mm: 1, > 4 mm: 2`` -- which side of each threshold is a fault, and its negatives."""
    sign = ">" if check.direction == "higher" else "<"
    unit = f" {check.unit}" if check.unit else ""
    return ", ".join(f"{sign} {_number(t)}{unit}: {n}"
                     for t, n in zip(check.thresholds, check.negatives))


def _ranges(check: Check) -> str:
    """``1.4-2 mm (1.5), fixed (4)``: each threshold's declared range, or fixed."""
    unit = f" {check.unit}" if check.unit else ""
    return ", ".join(f"{_number(r[0])}-{_number(r[1])}{unit} ({_number(t)})" if r is not None
                     else f"fixed ({_number(t)})" for t, r in zip(check.thresholds, check.ranges))


def _check_section(check: Check) -> list[str]:
    notes = []
    if not check.counted:
        notes.append("measured, not counted (its rows carry 0 negatives)")
    if check.charged_with:
        notes.append(f"charged with `{check.charged_with}` (earns nothing where that one fires)")
    if check.at_rest:
        notes.append(f"a measure of the face at rest: {check.at_rest}")
    if check.gate_tolerance:
        notes.append(f"gate tolerance {check.gate_tolerance}")
    lines = [f"#### `{check.name}`", "",
             f"- **negative**: \"{check.text}\"",
             f"- **measures**: {check.description}",
             f"- **component** {check.component}; **kind** {check.kind}; **view** {check.view}; "
             f"**unit** {check.unit}",
             f"- **frames**: {check.frames}; **tasks**: {_tasks(check)}",
             f"- **negatives**: {_grades(check)}",
             f"- **reason**: {check.reason}"]
    if check.ranges:
        lines.append(f"- **plausible range** (`cassi sensitivity`): {_ranges(check)}; "
                     f"{check.range_reason}")
    if notes:
        lines.append(f"- **note**: {'; '.join(notes)}")
    return lines + [""]


def rubric_reference(checks: dict[str, Check] | None = None) -> str:
    """The generated block's Markdown (between the markers, without them): the rating scale, then
    one section per table with a summary of its checks and each check in full. Deterministic:
    tables in registry order, checks in rubric order."""
    checks = CHECKS if checks is None else checks
    out = ["### The rating scale (thesis Table 5.2)", "",
           "| negatives | rating |", "|---|---|"]
    out += [f"| {i}{'+' if i == len(RATINGS) - 1 else ''} | {word} |" for i, word in enumerate(RATINGS)]
    out.append("")
    for table in TABLES:
        members = [c for c in checks.values() if c.table == table]
        if not members:
            continue
        out += [f"### Table {table}: {table_title(table)}", "",
                "| check | component | view | unit | negatives |", "|---|---|---|---|---|"]
        out += [f"| `{c.name}` | {_cell(c.component)} | {_cell(c.view)} | {_cell(c.unit)} | "
                f"{_cell(_grades(c)) if c.counted else 'not counted'} |" for c in members]
        out.append("")
        for c in members:
            out += _check_section(c)
    return "\n".join(out).rstrip("\n") + "\n"


def with_reference(page: str, source: str = "docs/rubric.md",
                   checks: dict[str, Check] | None = None) -> str:
    """``page`` with its generated block replaced by :func:`rubric_reference`; the hand-written
    text around it is kept as it is. A page without exactly one pair of markers is refused."""
    if page.count(BEGIN) != 1 or page.count(END) != 1 or page.index(BEGIN) > page.index(END):
        raise CassiInputError(f"{source}: needs one line '{BEGIN}' and, after it, one line "
                              f"'{END}' around the generated check reference")
    head, rest = page.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    return f"{head}{BEGIN}\n\n{rubric_reference(checks)}\n{END}{tail}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m cassi.harness.rubric.manual",
                                 description="regenerate the check reference in the manual's "
                                             "rubric page from the check registry")
    ap.add_argument("--write", type=Path, metavar="PAGE", required=True,
                    help="the page to update in place (docs/rubric.md)")
    args = ap.parse_args(argv)
    try:
        try:
            page = args.write.read_text(encoding="utf-8")
        except OSError as err:
            raise CassiInputError(f"{args.write}: cannot read: {err.strerror}") from None
        new = with_reference(page, str(args.write))
    except CassiInputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    if new != page:
        atomic_write_text(args.write, new)
    print(f"{args.write}: {'updated' if new != page else 'up to date'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
