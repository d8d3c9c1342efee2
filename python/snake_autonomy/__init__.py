"""snake_autonomy: autonomy stack for modular snake robots (COBRA first)."""
import os

# MuJoCo picks its offscreen GL backend when it is first imported, and several subpackages import it
# (sim/, runs/): headless EGL unless the caller chose one (sim/camera.py renders). Set here,
# in the package's root, so that it holds whichever subpackage comes first.
os.environ.setdefault("MUJOCO_GL", "egl")

# Found first on sys.path (a spawned process, e.g. a Dask worker, gets its parent's sys.path with
# the source folder ahead of the devel space): the compiled _core and generated msg modules live in
# the other snake_autonomy folders of sys.path.
__path__ = __import__("pkgutil").extend_path(__path__, __name__)
