"""The pipe of the paper's fig. 6 in the MuJoCo world: a vertical pipe hanging with its open mouth
pipe.mouth_m above the floor, up to PIPE_TOP_M; the head raised under it enters the mouth.
Its wall is a ring of vertical capsules (contype 2 / conaffinity 1, like the floor: the links touch
it). The planner knows only the axis and the inner radius (eq. 15)."""
import numpy as np

from .cost import Pipe

PIPE_TOP_M = 0.90
WALL_SEGMENTS = 24


def pipe_mjcf(pipe: Pipe) -> str:
    wall_r = pipe.wall_m / 2
    ring = pipe.radius_m + wall_r
    lines = [f'    <body name="pipe" pos="{pipe.x_m:.6g} {pipe.y_m:.6g} 0">']
    for k in range(WALL_SEGMENTS):
        a = 2 * np.pi * k / WALL_SEGMENTS
        x, y = ring * np.cos(a), ring * np.sin(a)
        lines.append(f'      <geom name="pipe_{k}" type="capsule" size="{wall_r:.6g}" '
                     f'fromto="{x:.6g} {y:.6g} {pipe.mouth_m} {x:.6g} {y:.6g} {PIPE_TOP_M}" '
                     f'contype="2" conaffinity="1" rgba="0.3 0.4 0.8 0.5"/>')
    lines.append("    </body>")
    return "\n".join(lines) + "\n"


def head_in_mouth(head_xyz, pipe: Pipe, module_radius_m: float, depth_m: float = 0.0,
                  clearance_m: float = 0.0) -> bool:
    """The head is more than depth_m past the mouth and within the pipe's bore, at least
    clearance_m from its edge."""
    d = float(np.hypot(head_xyz[0] - pipe.x_m, head_xyz[1] - pipe.y_m))
    return head_xyz[2] > pipe.mouth_m + depth_m and d < pipe.radius_m - module_radius_m - clearance_m
