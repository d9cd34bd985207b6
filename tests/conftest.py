"""Shared fixtures. Third-party data in ../shared is read in place, never copied; tests that
need it skip cleanly when it is absent."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("CASSI_SHARED", REPO.parent / "shared"))
FIXTURES = Path(__file__).resolve().parent / "fixtures"
# The suites live in folders that mirror the packages (tests/harness/rubric/ ...); the shared
# helpers (data_helpers, reports_fixtures, testpaths ...) stay here, importable from any of them.
sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    if not SHARED.is_dir():
        pytest.skip(f"../shared not present at {SHARED}")
    return SHARED


@pytest.fixture(scope="session")
def annotations_dir(shared_dir) -> Path:
    path = shared_dir / "xrmb-annotations"
    if not path.is_dir():
        pytest.skip(f"no xrmb-annotations in {shared_dir}")
    return path


@pytest.fixture(scope="session")
def fixtures_dir() -> Path:
    return FIXTURES
