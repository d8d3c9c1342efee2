"""Shared pytest fixtures: paths of the package and of ../shared (optional test data), and nav config
overlays written over config/nav.yaml."""
import os
from pathlib import Path

import pytest

# Before any test module imports mujoco directly (it picks its GL backend at import): headless EGL.
os.environ.setdefault("MUJOCO_GL", "egl")

ROOT = Path(__file__).resolve().parents[2]
# ../shared beside the clone; a git worktree in <clone's parent>/wt/NAME finds it one level higher;
# SNAKE_AUTONOMY_SHARED overrides both.
_SHARED_CANDIDATES = [Path(p) for p in (os.environ.get("SNAKE_AUTONOMY_SHARED"),) if p] + [
    ROOT.parent / "shared", ROOT.parent.parent / "shared"]
SHARED = next((p for p in _SHARED_CANDIDATES if p.is_dir()), ROOT.parent / "shared")


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


@pytest.fixture
def nav_config_over(tmp_path):
    """nav_config_over(name, overrides) writes tmp_path/name: config/nav.yaml as its base with the
    YAML text overrides over it (sections merged key by key), and returns its path as a str."""
    def write(name: str, overrides: str = "") -> str:
        path = tmp_path / name
        path.write_text(f"base: {ROOT / 'config' / 'nav.yaml'}\n{overrides}")
        return str(path)
    return write
