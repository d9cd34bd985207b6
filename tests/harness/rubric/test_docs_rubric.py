"""docs/rubric.md's check reference is the registry's: regenerated, never edited by hand."""
from __future__ import annotations

import dataclasses

import pytest

from testpaths import REPO
from cassi.common.errors import CassiInputError
from cassi.harness.rubric.manual import BEGIN, END, REGENERATE, main, rubric_reference, with_reference
from cassi.harness.rubric.model import TABLES
from cassi.harness.rubric.registry import CHECKS

PAGE = REPO / "docs" / "rubric.md"


def test_the_rubric_page_is_what_the_registry_gives():
    page = PAGE.read_text(encoding="utf-8")
    assert page == with_reference(page, str(PAGE)), (
        f"{PAGE.name}'s check reference differs from the check registry: regenerate it with "
        f"`{REGENERATE}` (and commit the page)")


def test_the_reference_names_every_check_with_its_fields():
    text = rubric_reference()
    for table in {c.table for c in CHECKS.values()}:
        assert f"### Table {table}:" in text
    for check in CHECKS.values():
        section = text.split(f"#### `{check.name}`\n", 1)[1].split("\n#### ", 1)[0]
        for field in (check.reason, check.frames, check.description, check.text,
                      f"**view** {check.view}", f"**unit** {check.unit}"):
            assert field in section, (check.name, field)
        for threshold, negatives in zip(check.thresholds, check.negatives):
            assert f"{threshold:g} {check.unit}: {negatives}" in section, check.name
    assert list(TABLES)[0] == "A" and text.index("### Table A:") < text.index("### Table G:")
    assert rubric_reference() == text  # deterministic


def test_a_changed_threshold_makes_the_page_stale():
    page = PAGE.read_text(encoding="utf-8")
    changed = dict(CHECKS)
    check = changed["lips_never_touch"]
    changed["lips_never_touch"] = dataclasses.replace(check, thresholds=(1.25, 4.0))
    assert with_reference(page, checks=changed) != page
    assert "> 1.25 mm: 1" in with_reference(page, checks=changed)


def test_only_the_generated_block_is_rewritten(tmp_path):
    page = f"# Rubric\n\nhand-written\n\n{BEGIN}\nstale\n{END}\n\nmore prose\n"
    new = with_reference(page)
    assert new.startswith("# Rubric\n\nhand-written\n\n" + BEGIN)
    assert new.endswith(f"{END}\n\nmore prose\n") and "stale" not in new
    for bad in ("no markers\n", f"{END}\n{BEGIN}\n", f"{BEGIN}\n{BEGIN}\n{END}\n"):
        with pytest.raises(CassiInputError, match="rubric.md"):
            with_reference(bad)


def test_write_updates_the_page_in_place(tmp_path, capsys):
    path = tmp_path / "rubric.md"
    path.write_text(f"prose\n{BEGIN}\n{END}\n", encoding="utf-8")
    assert main(["--write", str(path)]) == 0
    assert path.read_text(encoding="utf-8") == with_reference(f"prose\n{BEGIN}\n{END}\n")
    assert main(["--write", str(path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1].endswith("up to date")
    assert main(["--write", str(tmp_path / "absent.md")]) == 2
    assert "absent.md" in capsys.readouterr().err
