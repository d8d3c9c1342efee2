"""Shared pytest fixtures: paths of the package and of ../shared (optional test data)."""
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared"


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def cobra_yaml() -> str:
    return str(ROOT / "config" / "robots" / "cobra.yaml")


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """../shared beside the clone; tests using it skip with a reason when it is absent."""
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent: this test needs the shared reference data")
    return SHARED
