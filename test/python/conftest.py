"""Shared pytest fixtures: paths of the package and of ../shared (optional test data), and nav config
overlays written over config/nav.yaml."""
import importlib.machinery
import importlib.util
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
def load_script():
    """load_script(name): scripts/NAME (a Python script without .py) imported as a module, for tests of its
    functions."""
    def load(name: str):
        loader = importlib.machinery.SourceFileLoader(name, str(ROOT / "scripts" / name))
        module = importlib.util.module_from_spec(importlib.util.spec_from_loader(name, loader))
        loader.exec_module(module)
        return module
    return load


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


@pytest.fixture
def sim_config_vio(tmp_path):
    """sim_config_vio(**keys) writes tmp_path/sim.yaml: config/sim.yaml with the given keys of its
    vio: section replaced (the camera calibration made absolute), and returns its path as a str."""
    import yaml

    def write(**vio) -> str:
        raw = yaml.safe_load((ROOT / "config" / "sim.yaml").read_text())
        raw["vio"].update(vio)
        raw["vio"]["calibration"] = str(ROOT / "config" / "camera.yaml")
        path = tmp_path / "sim.yaml"
        path.write_text(yaml.safe_dump(raw))
        return str(path)
    return write


@pytest.fixture
def paper_sampler_params():
    """SamplerParams of the paper's planner (Chang et al. III): the longest free arc, every option
    config/nav.yaml (and so SamplerParams()) turns on off, curvatures within 2 /m. Tests of the
    sampler's own rules start from it (dataclasses.replace) rather than from nav.yaml's values."""
    from snake_autonomy.planning.rectilinear.sampler import SamplerParams
    inf = float("inf")
    return SamplerParams(max_curvature_per_m=2.0, resume_free_m=0.0, margin_m=0.0, goal_tie_m=0.0,
                         lateral_margin_m=0.0, body_clearance_m=0.0, earlier_views=0, obstacle_depth_m=inf,
                         blocked_wins=False, footprint_taper_m=0.0, known_free_m=inf, swing_guard_m=0.0,
                         swing_guard_tail_m=0.0, turn_free_m=0.0, turn_keeps_side=False, goal_disc=False,
                         blocked_wins_depth_m=inf, back_off_check_m=0.0, crawl_guard_m=0.0,
                         crawl_dead_band_per_m=0.0, reshape_keeps_centroid=False, crawl_blocked_backs_off=False,
                         swing_guard_body=False, crawl_forces_toward_arc=False)
