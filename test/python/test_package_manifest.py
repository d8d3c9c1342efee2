"""package.xml, CMakeLists.txt and requirements.txt: catkin_lint clean, every Python import declared.

The declared dependencies are checked against what the code imports: each third-party module that
python/, scripts/, test/ or bench/ imports has a rosdep key in package.xml or a pin in
requirements.txt (PyPI-only), and each pin is imported somewhere (or listed in PLANNED), or is a
command-line tool a script runs (TOOLS). What python/snake_autonomy imports at run time also has its
rosdep key among package.xml's exec_depend/depend (a ROS user's `rosdep install`), unless rosdistro has
no key installing a Debian package for it (NO_ROSDEP, pinned in requirements.txt).
"""
import ast
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# Module imported -> how it is declared: ("rosdep", key) in package.xml or ("pypi", name) in requirements.txt.
THIRD_PARTY = {
    "numpy": ("rosdep", "python3-numpy"), "scipy": ("rosdep", "python3-scipy"), "yaml": ("rosdep", "python3-yaml"),
    "matplotlib": ("rosdep", "python3-matplotlib"), "tqdm": ("rosdep", "python3-tqdm"),
    "rospkg": ("rosdep", "python3-rospkg"), "pytest": ("rosdep", "python3-pytest"),
    "rospy": ("rosdep", "rospy"), "rosbag": ("rosdep", "rosbag"), "rostest": ("rosdep", "rostest"),
    "genpy": ("rosdep", "rospy"), "tf2_msgs": ("rosdep", "tf2_msgs"), "tf2_ros": ("rosdep", "tf2_ros"),
    "std_msgs": ("rosdep", "std_msgs"), "std_srvs": ("rosdep", "std_srvs"),
    "geometry_msgs": ("rosdep", "geometry_msgs"),
    "sensor_msgs": ("rosdep", "sensor_msgs"), "nav_msgs": ("rosdep", "nav_msgs"),
    "diagnostic_msgs": ("rosdep", "diagnostic_msgs"), "visualization_msgs": ("rosdep", "visualization_msgs"),
    "rosgraph_msgs": ("rosdep", "rosgraph_msgs"), "catkin_pkg": ("rosdep", "catkin"),
    "diagnostic_updater": ("rosdep", "diagnostic_updater"), "trajectory_msgs": ("rosdep", "trajectory_msgs"),
    "actionlib": ("rosdep", "actionlib"), "actionlib_msgs": ("rosdep", "actionlib_msgs"),
    "move_base_msgs": ("rosdep", "move_base_msgs"),
    "cv_bridge": ("rosdep", "cv_bridge"), "image_geometry": ("rosdep", "image_geometry"),
    "dynamic_reconfigure": ("rosdep", "dynamic_reconfigure"),
    "mujoco": ("pypi", "mujoco"), "evo": ("pypi", "evo"), "rosbags": ("pypi", "rosbags"),
    "dynamixel_sdk": ("pypi", "dynamixel-sdk"), "shapely": ("pypi", "shapely"),
    "cv2": ("pypi", "opencv-python-headless"), "sklearn": ("pypi", "scikit-learn"), "joblib": ("pypi", "joblib"),
    "rosgraph": ("rosdep", "rosgraph"), "rosnode": ("rosdep", "rosnode"),
    "threadpoolctl": ("pypi", "threadpoolctl"),
    "distributed": ("pypi", "distributed"),
    "importlinter": ("pypi", "import-linter"),
    "gtsam": ("pypi", "gtsam"),
    "ompl": ("pypi", "ompl"),
}
# PyPI-pinned modules the package itself (python/snake_autonomy) imports at run time also need their rosdep key in
# package.xml, for ROS users who install with rosdep rather than the venv (official keys: rosdistro rosdep/python.yaml).
ROSDEP_OF_PYPI = {"cv2": "python3-opencv", "sklearn": "python3-sklearn", "joblib": "python3-joblib",
                  "shapely": "python3-shapely"}
# ... unless rosdistro has no key for them that installs a Debian package (package.xml says so too).
NO_ROSDEP = {
    "mujoco": "only a pip key (python3-mujoco-pip): rosdep would pip-install system-wide, refused on Debian 12",
    "rosbags": "only a pip key (python3-rosbags-pip), as mujoco",
    "evo": "no key", "dynamixel_sdk": "no Debian package (a ROS package of ROBOTIS)",
    "threadpoolctl": "no key (Debian has python3-threadpoolctl, rosdistro no entry)",
    "distributed": "no key (Debian has python3-distributed, rosdistro no entry)",
    "gtsam": "no Debian package (Debian 12 ships no GTSAM): the PyPI wheel",
}
# Pinned before their first import, for work under way (none now: shapely is imported by planning/fbsr).
PLANNED = set()
# Pinned command-line tools, run rather than imported: each counts as used when the script named runs it.
TOOLS = {"ruff": "scripts/check_style", "clang-format": "scripts/check_style"}


def _imports(package_only=False):
    """Top-level modules imported by the package's Python (files without .py in scripts/ and bench/ too), lazy
    imports inside functions included; package_only: python/snake_autonomy alone (what runs once installed)."""
    files = list((ROOT / "python" / "snake_autonomy").rglob("*.py"))
    if not package_only:
        files = list((ROOT / "python").rglob("*.py")) + list((ROOT / "test").rglob("*.py"))
        for folder in ("scripts", "bench"):
            files += [p for p in (ROOT / folder).iterdir()
                      if p.is_file() and p.read_bytes()[:40].startswith(b"#!/usr/bin/env python3")]
    local = {p.stem for p in (ROOT / "test").rglob("*.py")} | {"snake_autonomy"}
    found = {}
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top not in local:
                    found.setdefault(top, path.relative_to(ROOT))
    return found


def _manifest_keys():
    root = ET.parse(ROOT / "package.xml").getroot()
    return root, {e.text for e in root if e.tag.endswith("depend")}


def _requirements():
    out = {}
    for line in (ROOT / "requirements.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, _, version = line.partition("==")
            out[name.strip()] = version.strip()
    return out


def test_package_xml_is_format_3_without_catch_all_depends_on_test_tools():
    root, keys = _manifest_keys()
    assert root.get("format") == "3"
    depends = {e.text for e in root.findall("depend")}
    assert not depends & {"rostest", "gtest", "python3-pytest", "pybind11-dev", "orocos_kdl"}, depends
    assert "liborocos-kdl-dev" in depends and "orocos_kdl" not in keys   # orocos_kdl is no rosdep key in noetic


def test_every_imported_module_is_declared():
    _, keys = _manifest_keys()
    pins = _requirements()
    problems = []
    for module, where in sorted(_imports().items()):
        if module not in THIRD_PARTY:
            problems.append(f"{module} (imported in {where}): add it to package.xml or requirements.txt and here")
            continue
        kind, name = THIRD_PARTY[module]
        if kind == "rosdep" and name not in keys:
            problems.append(f"{module} (imported in {where}): rosdep key {name} missing from package.xml")
        if kind == "pypi" and name not in pins:
            problems.append(f"{module} (imported in {where}): {name} missing from requirements.txt")
    assert not problems, "\n".join(problems)


def test_every_module_the_package_imports_at_run_time_has_a_rosdep_key():
    """A ROS user's `rosdep install` must bring what python/snake_autonomy imports (stdlib: sys.stdlib_module_names):
    its rosdep key is an exec_depend (or depend) of package.xml, or the module is a NO_ROSDEP one, pinned in
    requirements.txt."""
    root, _ = _manifest_keys()
    run_keys = {e.text for e in root if e.tag in ("exec_depend", "depend")}
    pins = _requirements()
    problems = []
    for module, where in sorted(_imports(package_only=True).items()):
        kind, name = THIRD_PARTY.get(module, (None, None))
        key = name if kind == "rosdep" else ROSDEP_OF_PYPI.get(module)
        if key is None and module in NO_ROSDEP:
            if name not in pins:
                problems.append(f"{module} (imported in {where}): no rosdep key, and {name} not pinned in "
                                "requirements.txt")
        elif key is None:
            problems.append(f"{module} (imported in {where}): no rosdep key known here: add its key (rosdistro "
                            "rosdep/python.yaml) to package.xml's exec_depend and to ROSDEP_OF_PYPI or THIRD_PARTY, "
                            "or to NO_ROSDEP saying why there is none")
        elif key not in run_keys:
            problems.append(f"{module} (imported in {where}): rosdep key {key} missing from package.xml's "
                            "exec_depend/depend")
    assert not problems, "\n".join(problems)
    shapely = [e for e in root if e.text == "python3-shapely"]
    assert [e.get("version_gte", "").split(".")[0] for e in shapely] == ["2"], "the shapely 2 API is used: >= 2.0"


def test_every_requirement_is_imported_and_pinned():
    imported = set(_imports())
    by_name = {name: module for module, (kind, name) in THIRD_PARTY.items()}
    for name, version in _requirements().items():
        assert version, f"requirements.txt: {name} is not pinned (name==version)"
        if name in TOOLS:
            assert name in (ROOT / TOOLS[name]).read_text(), f"requirements.txt: {name} is not run by {TOOLS[name]}"
            continue
        module = by_name.get(name, name)
        assert module in imported or module in PLANNED, f"requirements.txt: {name} is never imported"


def test_catkin_lint_is_clean(tmp_path):
    if shutil.which("catkin_lint") is None:
        pytest.fail("catkin_lint is missing: scripts/bootstrap installs it (catkin-lint)")
    # catkin_lint wants the folder named like the package; a clone or worktree may be named otherwise.
    link = tmp_path / "snake_autonomy"
    link.symlink_to(ROOT)
    env = dict(os.environ, PATH="/usr/bin:/bin")
    r = subprocess.run(["catkin_lint", "-W2", "--strict", str(link)], capture_output=True, text=True, env=env,
                       timeout=120)
    assert r.returncode == 0 and "found 0 problems" in r.stderr + r.stdout, r.stdout + r.stderr


def test_only_paths_py_locates_files_from_its_own_location():
    """Config files are found through snake_autonomy.paths.config_path (source tree or install space);
    a module computing the source tree from __file__ breaks in the install space (lib/python3/...)."""
    offenders = [str(p.relative_to(ROOT)) for p in (ROOT / "python" / "snake_autonomy").rglob("*.py")
                 if p.name != "paths.py" and "__file__" in p.read_text()]
    assert offenders == [], f"use snake_autonomy.paths.config_path instead of __file__ in: {offenders}"
