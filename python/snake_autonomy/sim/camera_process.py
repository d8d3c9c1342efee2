"""The head camera rendered in a child process (sim_node with a world): MuJoCo's offscreen
render takes 0.1-0.3 s per pass on these machines, and in the simulator's process it would hold
the interpreter while the mocked servo bus must answer the driver within milliseconds. The child
builds its own model from the plant's MJCF, takes a snapshot of the state (qpos and base_link's
pose), runs the kinematics and renders colour and/or depth (sim.camera.HeadCamera, EGL).

    cam = CameraProcess(plant.mjcf, intrinsics, mount, colour=True, depth=True, depth_model=None)
    cam.request(t_s, plant.data.qpos, plant.frame_transform("base_link"))   # when cam.idle
    frame = cam.poll()          # a RenderedFrame once the child answered, else None
    cam.close()

depth_model: applied to every depth render in the child (sim.depth_noise.DepthNoise, whose random
stream travels with it: the child draws the numbers the parent's generator would have); None: exact.
One request at a time (request() while busy is refused: False); rendering statistics in `stats`.
"""
import multiprocessing as mp
import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..perception.camera_model import CameraIntrinsics, CameraMount
from .camera import HeadCamera


@dataclass
class RenderedFrame:
    t_s: float
    rgb: Optional[np.ndarray]            # (H, W, 3) uint8 or None
    depth_m: Optional[np.ndarray]        # (H, W) float32, 0 = nothing, or None
    T_world_camera: np.ndarray           # 4x4 optical frame in the world at the snapshot
    render_s: float                      # the child's time for the render passes


def _child(conn, mjcf: str, intrinsics: CameraIntrinsics, mount: CameraMount, colour: bool, depth: bool,
           depth_model):
    import mujoco  # lazy: MuJoCo is heavy and only this path needs it

    model = mujoco.MjModel.from_xml_string(mjcf)
    data = mujoco.MjData(model)
    cam = HeadCamera(model, intrinsics, mount, depth_model=depth_model)
    conn.send("ready")
    try:
        while True:
            msg = conn.recv()
            if msg is None:
                break
            t_s, qpos, T_wb = msg
            t0 = time.perf_counter()
            data.qpos[:] = qpos
            mujoco.mj_kinematics(model, data)
            f = cam.render(data, T_wb, t_s, colour=colour, depth=depth, labels=False)
            conn.send(RenderedFrame(t_s, f.rgb if colour else None, f.depth_m if depth else None,
                                    f.T_world_camera, time.perf_counter() - t0))
    except (EOFError, KeyboardInterrupt):
        pass
    finally:
        cam.close()


class CameraProcess:
    def __init__(self, mjcf: str, intrinsics: CameraIntrinsics, mount: CameraMount, colour: bool = True,
                 depth: bool = True, start_timeout_s: float = 120.0, depth_model=None):
        ctx = mp.get_context("spawn")          # no fork of a process with threads (ROS, the bus)
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_child, args=(child, mjcf, intrinsics, mount, colour, depth, depth_model),
                                 name="head_camera", daemon=True)
        self._proc.start()
        child.close()
        try:
            ready = self._conn.poll(start_timeout_s) and self._conn.recv() == "ready"
        except EOFError:                       # the child died (its traceback is on stderr)
            ready = False
        if not ready:
            self.close()
            raise RuntimeError(f"the head camera's render process did not start within {start_timeout_s:g} s")
        self._busy = False
        self.stats = {"frames": 0, "render_s_total": 0.0, "render_s_last": 0.0}

    @property
    def idle(self) -> bool:
        return not self._busy

    def request(self, t_s: float, qpos, T_world_base) -> bool:
        if self._busy:
            return False
        self._conn.send((float(t_s), np.array(qpos, float), np.array(T_world_base, float)))
        self._busy = True
        return True

    def poll(self, timeout_s: float = 0.0) -> Optional[RenderedFrame]:
        if not self._busy or not self._conn.poll(timeout_s):
            return None
        f = self._conn.recv()
        self._busy = False
        self.stats["frames"] += 1
        self.stats["render_s_total"] += f.render_s
        self.stats["render_s_last"] = f.render_s
        return f

    def close(self) -> None:
        try:
            self._conn.send(None)
        except (OSError, ValueError):
            pass
        self._proc.join(5.0)
        if self._proc.is_alive():
            self._proc.terminate()
            self._proc.join(2.0)
        self._conn.close()
