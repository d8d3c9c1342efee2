"""snake_autonomy: autonomy stack for modular snake robots (COBRA first)."""
import os

# MuJoCo picks its offscreen GL backend when it is first imported, and several subpackages import it
# (sim/, planning/fbsr/): headless EGL unless the caller chose one (sim/camera.py renders). Set here,
# in the package's root, so that it holds whichever subpackage comes first.
os.environ.setdefault("MUJOCO_GL", "egl")
