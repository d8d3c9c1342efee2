"""The MuJoCo model (MJCF text) of a snake robot, generated from its robot YAML.

Geometry, axes, masses and limits come from `_core.RobotModel` only; physics and servo values from
`SimParams`. The body tree follows thesis eq. 3.3-3.4 exactly:

    head_link = base_link . Trans(-H, 0, 0) . Rx(+90 deg)
    link_i    = link_{i-1} . Rz(-q_i) . Trans(-L, 0, 0) . Rx(twist_i)

twist_i is -90 deg after a pitch joint and +90 deg after a yaw joint (COBRA: -90, +90, -90, ...;
after the last joint the alternation continues). Joint i turns about the z axis of the frame
before it; its MuJoCo hinge axis is (0, 0, -1), so MuJoCo's qpos is the thesis's q_i.

Bodies and sites:
- body `base_link` (free joint) carries the head segment: a capsule from the base origin back to
  the head frame (joint 1), with the base and head masses together. Sites `base_link` and
  `head_link` are those kinematic frames.
- body `link_i` has its origin at joint i, oriented as Rz(-q_i) of the previous frame, and carries
  a capsule of length L along its -x axis with link i's mass. Site `link_i` (at the capsule's far
  end, twisted by twist_i) is the kinematic frame link_i of eq. 3.4.
- physics.self_collision: links collide with each other too (contype 1, conaffinity 3), except
  neighbours (a `<contact><exclude>` per joint).
- with imu_in_head (a 4x4 pose in head_link: config/camera.yaml's camera_in_head, the URDF's
  camera_link): site `camera_link` on base_link there, and sensors `imu_gyro` (angular velocity,
  rad/s) and `imu_accel` (specific force, m/s^2, gravity included) at it, in the site's frame
  (sim/imu.py adds the BMI055's errors). Without it the model has no sensors.
- lights: a scene_xml with a <light> of its own is lit by its lights alone; otherwise the model has
  OVERHEAD_LIGHT (straight down, casting shadows).
- actuator `servo_i`: the position servo of joint i. Its internal state (act) is the setpoint,
  integrated from a velocity command bounded by the joint speed limit and clamped to the joint's
  limits; force = kp (setpoint - q) - kv q', saturated at the torque limit.
"""
import re
from typing import Optional
from xml.sax.saxutils import quoteattr

import numpy as np

from ..transforms import make_transform, matrix_to_quat, rot_x
from .config import SimParams

IMU_SITE = "camera_link"
IMU_SENSORS = ("imu_gyro", "imu_accel")
#: the light of a model whose scene brings none: straight down, casting shadows
OVERHEAD_LIGHT = '<light name="overhead_light" pos="0 0 4" dir="0 0 -1" directional="true"/>'
_LIGHT = re.compile(r"<light[\s/>]")


def twists_rad(axes) -> list:
    """The Rx twist after each joint (eq. 3.4): -90 deg going pitch->yaw, +90 deg yaw->pitch."""
    out = []
    for i, axis in enumerate(axes):
        nxt = axes[i + 1] if i + 1 < len(axes) else ("yaw" if axis == "pitch" else "pitch")
        if axis == nxt:
            raise ValueError(f"joints {i + 1} and {i + 2} share axis {axis!r}: eq. 3.4 needs "
                             "alternating pitch/yaw joints")
        out.append(-np.pi / 2 if axis == "pitch" else np.pi / 2)
    return out


def _quat_rx(angle_rad: float) -> str:
    """MuJoCo quaternion (w x y z) of Rx(angle)."""
    return f"{np.cos(angle_rad / 2):.17g} {np.sin(angle_rad / 2):.17g} 0 0"


def _flat_belly(length_m: float, r: float, fraction: float, roll_rad: float, indent: str) -> list:
    """A flat-bottomed contact option (physics.flat_belly_fraction > 0, off by default and for the
    thesis experiments): a massless box under a link of frame Rx(roll_rad) in the straight pose,
    its bottom face flush with the capsule's lowest line, fraction x 2r wide, r/4 thick: a round
    link on a floor touches along one line and rolls freely; a flat one resists rolling like a
    robot with a flat belly or skids (Chang et al.'s rectilinear robot has a flat ventral side)."""
    if fraction <= 0:
        return []
    t = 0.125 * r
    d = r - t
    down = (-np.sin(roll_rad), -np.cos(roll_rad))
    return [f'{indent}<geom type="box" size="{_f(length_m / 2)} {_f(fraction * r)} {_f(t)}" '
            f'pos="{_f(-length_m / 2)} {_f(d * down[0])} {_f(d * down[1])}" quat="{_quat_rx(-roll_rad)}" '
            f'mass="0" rgba="0.3 0.3 0.3 1"/>']


def _f(x: float) -> str:
    return f"{float(x):.17g}"


def camera_link_in_base(head_length_m: float, camera_in_head) -> np.ndarray:
    """camera_link's 4x4 pose in base_link: head_link (thesis eq. 3.3, base . Trans(-H, 0, 0) .
    Rx(+90 deg)) . config/camera.yaml's camera_in_head. The one place both the IMU's site and the
    odometry camera's render (sim/camera.LinkMount) take it from."""
    return make_transform(rot_x(np.pi / 2), (-head_length_m, 0.0, 0.0)) @ np.asarray(camera_in_head, float)


def _imu(head_length_m: float, imu_in_head) -> tuple:
    """The IMU's site on base_link (head_link . imu_in_head) and its sensors."""
    T = camera_link_in_base(head_length_m, imu_in_head)
    x, y, z, w = matrix_to_quat(T[:3, :3])
    site = (f'      <site name="{IMU_SITE}" pos="{_f(T[0, 3])} {_f(T[1, 3])} {_f(T[2, 3])}" '
            f'quat="{_f(w)} {_f(x)} {_f(y)} {_f(z)}"/>')
    sensors = ['  <sensor>', f'    <gyro name="{IMU_SENSORS[0]}" site="{IMU_SITE}"/>',
               f'    <accelerometer name="{IMU_SENSORS[1]}" site="{IMU_SITE}"/>', '  </sensor>']
    return [site], sensors


def build_mjcf(robot, params: SimParams, scene_xml: str = "", assets_xml: str = "",
               imu_in_head: Optional[np.ndarray] = None) -> str:
    """MJCF text of `robot` (a _core.RobotModel) with the physics of `params`.

    assets_xml: children of an <asset> element (textures, materials) that scene_xml refers to.

    scene_xml: MJCF elements (bodies, geoms, cameras) placed in the worldbody beside the floor:
    obstacles, pipes, the things a planner's world holds. Their geoms should set contype and
    conaffinity so that the links touch them (links: contype 1, conaffinity 2 or 3). If it has a
    <light>, its lights are the model's only ones; otherwise the model has OVERHEAD_LIGHT.

    imu_in_head: the IMU's 4x4 pose in head_link (the module's docstring); None: no IMU."""
    cfg = params.config
    phys, servo = cfg.physics, cfg.servo
    n = robot.num_joints
    axes = list(robot.axes)
    twists = twists_rad(axes)
    H, L, r = robot.head_length_m, robot.link_length_m, robot.link_radius_m
    masses = list(robot.masses_kg)
    lower, upper = list(robot.joint_lower_rad), list(robot.joint_upper_rad)
    imu_site, imu_sensors = _imu(H, imu_in_head) if imu_in_head is not None else ([], [])
    mu = params.floor_friction
    condim = 6 if phys.rolling_friction_m > 0 else (4 if phys.torsional_friction > 0 else 3)
    friction = f"{_f(mu)} {_f(phys.torsional_friction)} {_f(phys.rolling_friction_m)}"
    # Links collide with the floor only (contype 1 vs conaffinity 2), unless self_collision.
    link_affinity = 3 if phys.self_collision else 2
    geom_defaults = (f'contype="1" conaffinity="{link_affinity}" condim="{condim}" '
                     f'friction="{friction}" '
                     f'solref="{_f(phys.contact_timeconst_s)} {_f(phys.contact_dampratio)}"')

    lines = [
        f'<mujoco model={quoteattr(robot.name)}>',
        '  <compiler angle="radian" autolimits="true"/>',
        f'  <option timestep="{_f(phys.timestep_s)}" integrator="{phys.integrator}" '
        f'cone="{phys.cone}" iterations="{int(phys.solver_iterations)}" gravity="0 0 -9.81"/>',
        '  <size memory="4M"/>',
        *(['  <asset>', assets_xml.rstrip("\n"), '  </asset>'] if assets_xml else []),
        '  <default>',
        f'    <joint armature="{_f(servo.armature_kg_m2)}" '
        f'damping="{_f(servo.damping_nm_s_per_rad)}" '
        f'frictionloss="{_f(servo.frictionloss_nm)}" limited="true"/>',
        f'    <geom type="capsule" size="{_f(r)}" {geom_defaults}/>',
        '    <site size="0.01"/>',
        '  </default>',
        '  <worldbody>',
        f'    <geom name="floor" type="plane" size="0 0 1" contype="2" conaffinity="1" '
        f'condim="{condim}" friction="{friction}"/>',
        *([] if _LIGHT.search(scene_xml) else [f'    {OVERHEAD_LIGHT}']),
        *([scene_xml.rstrip("\n")] if scene_xml else []),
        f'    <body name="base_link" pos="0 0 {_f(r + phys.start_height_m)}">',
        '      <freejoint name="base"/>',
        '      <site name="base_link"/>',
        f'      <site name="head_link" pos="{_f(-H)} 0 0" quat="{_quat_rx(np.pi / 2)}"/>',
        f'      <geom name="head" fromto="0 0 0 {_f(-H)} 0 0" mass="{_f(masses[0] + masses[1])}"/>',
        *imu_site,
        *_flat_belly(H, r, phys.flat_belly_fraction, 0.0, "      "),
    ]
    roll = np.pi / 2
    indent = "      "
    parent_pos, parent_quat = f"{_f(-H)} 0 0", _quat_rx(np.pi / 2)
    for i in range(n):
        name = f"link_{i + 1}"
        lines += [
            f'{indent}<body name="{name}" pos="{parent_pos}" quat="{parent_quat}">',
            f'{indent}  <joint name="{robot.joint_names[i]}" type="hinge" axis="0 0 -1" '
            f'range="{_f(lower[i])} {_f(upper[i])}"/>',
            f'{indent}  <geom name="{name}" fromto="0 0 0 {_f(-L)} 0 0" '
            f'mass="{_f(masses[i + 2])}"/>',
            *_flat_belly(L, r, phys.flat_belly_fraction, roll, indent + "  "),
            f'{indent}  <site name="{name}" pos="{_f(-L)} 0 0" quat="{_quat_rx(twists[i])}"/>',
        ]
        roll += twists[i]
        indent += "  "
        parent_pos, parent_quat = f"{_f(-L)} 0 0", _quat_rx(twists[i])
    for _ in range(n):
        indent = indent[:-2]
        lines.append(f"{indent}</body>")
    lines += ['    </body>', '  </worldbody>']
    if phys.self_collision:
        # Neighbours share a joint and always touch there: excluded explicitly (MuJoCo's parent
        # filter would too); every other pair of links collides.
        bodies = ["base_link"] + [f"link_{i + 1}" for i in range(n)]
        lines += ['  <contact>',
                  *[f'    <exclude body1="{a}" body2="{b}"/>' for a, b in zip(bodies, bodies[1:])],
                  '  </contact>']
    lines += ['  <actuator>']
    for i in range(n):
        kp, kv = params.kp_nm_per_rad[i], params.kv_nm_s_per_rad[i]
        lines.append(
            f'    <general name="servo_{i + 1}" joint="{robot.joint_names[i]}" '
            f'dyntype="integrator" '
            f'gaintype="fixed" gainprm="{_f(kp)}" biastype="affine" '
            f'biasprm="0 {_f(-kp)} {_f(-kv)}" '
            f'ctrlrange="{_f(-servo.speed_limit_rad_s)} {_f(servo.speed_limit_rad_s)}" '
            f'actlimited="true" actrange="{_f(lower[i])} {_f(upper[i])}" '
            f'forcerange="{_f(-servo.torque_limit_nm)} {_f(servo.torque_limit_nm)}"/>')
    lines += ['  </actuator>', *imu_sensors, '</mujoco>']
    return "\n".join(lines) + "\n"
