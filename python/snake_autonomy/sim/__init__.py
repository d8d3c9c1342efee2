"""snake_autonomy.sim"""
import os

# MuJoCo picks its offscreen GL backend when first imported (every import of mujoco in the project
# goes through this package): headless EGL unless the caller chose one (sim/camera.py renders).
os.environ.setdefault("MUJOCO_GL", "egl")
