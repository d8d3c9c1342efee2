"""The snake as FBSR sees it: the core's forward kinematics with the world fixed at the tail.

Frames are the kinematics binding's (`_core.Kinematics.compute`): index 0 `base_link` (the front end
of the head module), 1 `head_link` (joint 1), 1 + i `link_i` (joint i + 1; the last one is the tail
end). Joint j turns at frame j. Module 0 is the head (frames 0-1), module i is link_i (frames i to
i + 1). With m *active* modules (the head and the m - 1 links behind it) the active joints are
1..m: joint m, at frame m, hinges the active portion on the first base module, whose frames m..N+1
do not move. The model's root is the head, so the paper's "base frame fixed to the world at the
tail end" is obtained by placing the root so that the tail frame keeps the pose it has in the lying
posture: T_world_root = T_world_tail . inv(T_root_tail(q)).

Ground contacts (paper III.B, fig. 2). The paper offsets the base joints slightly so that the robot
rests on every other module, at known points. `lying_posture` does this with pitch_offset_rad = e:
the pitch joints bend +e, -2e, +2e, ..., so seen from the side the body is a zigzag of zero mean
slope resting on its troughs. The world is levelled on the face of the convex hull of the frames
that the body rests on (nearly downward, holding the CoG's projection; capsules are frames swept by
a ball, so the capsule body rests on the same face), and the contacts are the frames in that face
(within CONTACT_TOL_M). With pitch and yaw joints alternating, the slope changes only at pitch
joints: the troughs come every 4 links and a 5-module base rests on 2 of them, on a line, which
spans no polygon; the yaw curl also tilts the zigzag so that a rigid body of many frames rests on 3.
So config/scout.yaml sets e = 0: the base lies flat, every frame of it is a contact (the capsules
lie along the floor), and the yaw joints curl the body, more at the tail, so that the contacts of
every base span an area. Base joints never move, so the contacts of a base are the lying posture's
contacts whose frame is in it (index >= m).
"""
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull

from snake_autonomy import _core

from .batch_kinematics import ChainModel, StageKinematics

#: A frame this close to the resting face is a ground contact.
CONTACT_TOL_M = 1e-3


@dataclass
class Pose:
    """World positions of every frame (num_frames, 3), rotations (num_frames, 3, 3), CoG (3,)."""
    positions: np.ndarray
    rotations: np.ndarray
    com: np.ndarray

    @property
    def zmp(self) -> np.ndarray:
        """Quasi-static ZMP (paper III.B): the centre of gravity projected on the ground."""
        return self.com[:2].copy()

    @property
    def head(self) -> np.ndarray:
        """The end effector: frame 0, the front end of the head module."""
        return self.positions[0]


def lying_posture(robot, pitch_offset_rad: float, yaw_body_rad: float, yaw_tail_rad: float,
                  tail_curl_joints: int) -> np.ndarray:
    """Joint angles of the robot lying on the ground (see the module docstring).

    Pitch joints bend by +e, -2e, +2e, ... (e = pitch_offset_rad) from the head, so the slope of
    the body alternates +e, -e: a zigzag of zero mean slope; yaw joints bend by
    yaw_body_rad, except the last tail_curl_joints yaw joints, which bend by yaw_tail_rad."""
    q = np.zeros(robot.num_joints)
    pitch, yaw = list(robot.pitch_joints), list(robot.yaw_joints)
    for k, j in enumerate(pitch):
        bend = pitch_offset_rad if k == 0 else 2.0 * pitch_offset_rad
        q[j] = bend if k % 2 == 0 else -bend
    for k, j in enumerate(yaw):
        q[j] = yaw_tail_rad if k >= len(yaw) - tail_curl_joints else yaw_body_rad
    return q


def module_frame_weights(masses_kg) -> np.ndarray:
    """The robot's mass model as weights on the frames: the robot YAML's masses per frame (base,
    head, link_1..link_N) placed as the MJCF and the URDF place them, each module's at its centre
    (the head module carries base + head, module i = link_i carries link_i's), and each module's
    mass split half and half onto its two end frames (the centre of a segment is the mean of its
    ends, so the CoG and the gravity torques about any joint are the same)."""
    m = np.asarray(masses_kg, float)
    modules = np.concatenate([[m[0] + m[1]], m[2:]])     # module 0 = frames 0-1, i = frames i, i+1
    w = np.zeros(len(m))
    w[:-1] += 0.5 * modules
    w[1:] += 0.5 * modules
    return w


class Chain:
    """Forward kinematics in the tail-fixed world, the masses, the base's ground contacts.

    Masses: `module_frame_weights` (each module's mass at its centre, as in the MJCF and the
    URDF), not the robot YAML's per-frame masses at the frames: the CoG, the ZMP and the torques."""

    def __init__(self, robot, q_lying):
        self.robot = robot
        self.kin = _core.Kinematics(robot)
        self.num_joints = robot.num_joints
        self.num_frames = robot.num_frames
        self.num_modules = robot.num_joints + 1
        self.frame_names = list(robot.frame_names)
        self.joint_names = list(robot.joint_names)
        self.masses = np.asarray(robot.masses_kg, float)      # the robot YAML's, per frame
        self.frame_weights_kg = module_frame_weights(self.masses)
        self._mass_fraction = self.frame_weights_kg / self.frame_weights_kg.sum()
        self.radius_m = float(robot.link_radius_m)
        self.lower = np.asarray(robot.joint_lower_rad, float)
        self.upper = np.asarray(robot.joint_upper_rad, float)
        self.q_lying = np.asarray(q_lying, float).copy()
        self._batch_model = None
        self._tail_world = self._level(self.q_lying)
        lying = self.pose(self.q_lying)
        self.contact_frames = np.flatnonzero(
            lying.positions[:, 2] < self.radius_m + CONTACT_TOL_M)
        self.contacts_xy = lying.positions[self.contact_frames, :2].copy()

    # ---- kinematics ----------------------------------------------------------------------------
    def _relative(self, q):
        s = self.kin.compute([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], q)
        p = np.asarray(s.link_positions, float)
        return p, s.link_rotations, self._mass_fraction @ p

    def pose(self, q) -> Pose:
        """Every frame in the world whose tail frame stays where the lying posture put it."""
        p, rot, com = self._relative(q)
        r_t, p_t = rot[-1], p[-1]
        r_w = self._tail_world[:3, :3] @ r_t.T          # root orientation in the world
        p_w = self._tail_world[:3, 3] - r_w @ p_t        # root position in the world
        return Pose(p @ r_w.T + p_w, np.einsum("ij,fjk->fik", r_w, rot), r_w @ com + p_w)

    def positions_com(self, q):
        """(frame positions (num_frames, 3), CoG (3,)) in the world: pose() without rotations."""
        p, rot, com = self._relative(q)
        r_w = self._tail_world[:3, :3] @ rot[-1].T
        p_w = self._tail_world[:3, 3] - r_w @ p[-1]
        return p @ r_w.T + p_w, r_w @ com + p_w

    def _level(self, q) -> np.ndarray:
        """World pose of the tail frame: the lying robot's lowest hull face on the floor, the
        capsules' axes one radius above it, the tail end at x = y = 0, the body along +x."""
        p, rot, _ = self._relative(q)
        p0, rot0, _ = self._relative(np.zeros(self.num_joints))
        # Orientation of the straight robot (root level) for the tail, then re-level on the face.
        r_nominal = rot0[-1]
        pts = (p - p[-1]) @ rot[-1]           # frames in the tail frame
        pts = pts @ r_nominal.T               # ... rotated as the straight robot's tail
        com = self._mass_fraction @ pts
        fix = _resting_rotation(pts, com)
        r_tail = fix @ r_nominal
        pts = pts @ fix.T
        z0 = pts[:, 2].min()
        t = np.eye(4)
        t[:3, :3] = r_tail
        t[:3, 3] = (0.0, 0.0, self.radius_m - z0)
        return t

    def stage_kinematics(self, q_start, active_modules: int) -> StageKinematics:
        """Batched FK of the postures that move only the first `active_modules` joints from
        q_start (batch_kinematics.py; the same chain as pose(), computed with numpy)."""
        if self._batch_model is None:
            self._batch_model = ChainModel(self._relative, self.num_joints, self.frame_weights_kg)
        pose = self.pose(q_start)
        return StageKinematics(self._batch_model, pose.positions, pose.rotations, active_modules)

    # ---- partition -----------------------------------------------------------------------------
    def base_contacts(self, active_modules: int) -> np.ndarray:
        """(k, 2) ground contacts of the base left by `active_modules` active modules."""
        return self.contacts_xy[self.contact_frames >= active_modules]

    def active_frames(self, active_modules: int) -> np.ndarray:
        """Indices of the frames that move with m active modules (the active modules' frames
        except the hinge frame m, which belongs to the base)."""
        return np.arange(active_modules)

    def gravity_torques(self, pose: Pose, active_modules: int) -> np.ndarray:
        """Quasi-static torque (N m) each active joint holds against the weight of the modules on
        its head side; joint j turns about the z axis of frame j."""
        g = np.array([0.0, 0.0, -9.81])
        p, rot = pose.positions, pose.rotations
        out = np.empty(active_modules)
        weights = self.frame_weights_kg[:, None] * g
        moments = np.cross(p, weights)                   # r x F about the origin, per frame
        cum_m = np.cumsum(moments, axis=0)
        cum_f = np.cumsum(weights, axis=0)
        for j in range(1, active_modules + 1):
            # sum over frames k < j of (p_k - p_j) x F_k
            moment = cum_m[j - 1] - np.cross(p[j], cum_f[j - 1])
            out[j - 1] = moment @ rot[j][:, 2]
        return out


def _resting_rotation(pts, com) -> np.ndarray:
    """The rotation that puts the face of the points' convex hull the body rests on (a nearly
    downward face whose contact polygon holds the CoG's projection) on the floor."""
    if np.ptp(pts[:, 2]) < CONTACT_TOL_M:
        return np.eye(3)      # a flat posture: every frame on the floor
    hull = ConvexHull(pts)
    best, best_z = None, 0.0
    for eq in np.unique(np.round(hull.equations, 9), axis=0):
        normal, offset = eq[:3], eq[3]
        if normal[2] > -0.9:
            continue
        on_face = pts[np.abs(pts @ normal + offset) < CONTACT_TOL_M]
        fix = _rotation_between(normal, np.array([0.0, 0.0, -1.0]))
        face = on_face @ fix.T
        c = fix @ com
        if len(face) >= 3 and _inside_hull_2d(face[:, :2], c[:2]) and normal[2] < best_z:
            best, best_z = fix, normal[2]
    if best is None:
        raise ValueError("the lying posture has no face to rest on that holds its centre of gravity")
    return best


def _inside_hull_2d(points, xy) -> bool:
    try:
        hull = ConvexHull(points)
    except Exception:  # noqa: BLE001 - collinear points: no area
        return False
    return bool(np.all(hull.equations[:, :2] @ xy + hull.equations[:, 2] < 0))


def _rotation_between(a, b) -> np.ndarray:
    """The smallest rotation taking unit vector a onto unit vector b."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    v = np.cross(a, b)
    c = float(a @ b)
    if np.linalg.norm(v) < 1e-12:
        if c > 0:
            return np.eye(3)
        raise ValueError("the lying posture rests upside down")
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx * (1.0 / (1.0 + c))
