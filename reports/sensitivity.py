"""The report's robustness section: a run's ``sensitivity.json`` (``cassi sensitivity``), when
it has one, as a table of every version-level finding with the settings it holds in."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

from cassi.common.atomic import atomic_write_text
from cassi.common.errors import CassiInputError
from cassi.harness.rubric.sensitivity import robustness_table
from cassi.reports.tables import markdown_table

__all__ = ["SENSITIVITY_FILE", "sensitivity_section"]

#: What ``cassi sensitivity`` writes into the run directory.
SENSITIVITY_FILE = "sensitivity.json"


def sensitivity_section(run_root: Path, out: Path) -> dict | None:
    """The section's data (rows, counts, the constants moved, links to the full table), or
    None when the run has no sensitivity analysis."""
    path = Path(run_root) / SENSITIVITY_FILE
    if not path.is_file():
        return None
    try:
        doc = json.loads(path.read_text())
        table = robustness_table(doc)
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise CassiInputError(f"cannot read the sensitivity analysis: {err}", path=path) from err
    csv, md = out / "tables" / "sensitivity.csv", out / "tables" / "sensitivity.md"
    atomic_write_text(csv, table.to_csv(index=False, lineterminator="\n"))
    atomic_write_text(md, markdown_table(table.set_index("table")))
    kinds = [c.get("kind") for c in doc.get("constants", [])]
    return {"rows": table.to_dict("records"),
            "flipped": int((table["flipped by"] != "").sum()),
            "thresholds": kinds.count("threshold"), "versions": kinds.count("version"),
            "note": _sentence(doc.get("note", "")), "timing": doc.get("timing", {}),
            "csv": csv.relative_to(out).as_posix(), "md": md.relative_to(out).as_posix()}


def _sentence(text: str) -> str:
    """``text`` as a sentence of its own (the analysis writes it to follow a semicolon)."""
    return text[:1].upper() + text[1:]


#: What an analysis file says of where it was made, which the section does not show: a night
#: that reuses an earlier night's analysis rewrites them (cassi.harness.evaluation.sensitivity).
_PROVENANCE_KEYS = ("run", "reused_from")


def section_digest(run_root: Path) -> str | None:
    """The digest of what :func:`sensitivity_section` shows of a run's analysis (None: no
    analysis), so that a report's page memo reuses the section of a night that took the same
    analysis from the store; a file that is not JSON is digested by its bytes."""
    path = Path(run_root) / SENSITIVITY_FILE
    if not path.is_file():
        return None
    data = path.read_bytes()
    try:
        doc = json.loads(data)
        data = json.dumps({k: v for k, v in doc.items() if k not in _PROVENANCE_KEYS},
                          sort_keys=True).encode()
    except (ValueError, AttributeError):  # not a JSON object: the section refuses it
        pass
    return hashlib.sha256(data).hexdigest()
