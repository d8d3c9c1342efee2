"""Forward kinematics of many postures at once, in the tail-fixed world, for the planner's cost.

The core's FK (`_core.Kinematics.compute`, one posture per call) is the reference; this is the same
chain evaluated with numpy on a batch: the cost of a stage needs the frames at every cost sample
for every finite-difference step of the gradient, (m + 1) x samples postures per gradient.

The chain, read off the core's FK at q = 0 and checked against it (test_fbsr_batch_kinematics.py):
T_root_(i+1) = T_root_i . Rot(a_i, q_i) . D_i, where D_i is the zero-posture transform from frame i
to frame i + 1, a_i the axis of joint i in frame i (i = 1..N; frame 0, base_link, has no joint) and
Rot(a, 0) = I. Walked backwards from the tail: T_i = T_(i+1) . D_i^-1 . Rot(a_i, q_i)^-1, so frame
i's position does not depend on q_i. With m active modules (joints 1..m), the frames m..N+1 stay
where the stage started them: `StageKinematics` computes them once and walks only the m active
frames back from frame m, for every posture of the batch at once.
"""
import numpy as np


def _rotations(axes, angles) -> np.ndarray:
    """(B, 3, 3) rotations by angles (B,) about unit axes (3,) (Rodrigues)."""
    k = np.array([[0.0, -axes[2], axes[1]], [axes[2], 0.0, -axes[0]], [-axes[1], axes[0], 0.0]])
    s, c = np.sin(angles)[:, None, None], np.cos(angles)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


class ChainModel:
    """The chain's constant parts, from the core's FK: D_i^-1 and the joint axes a_i."""

    def __init__(self, relative_fk, num_joints: int, masses):
        """relative_fk(q) -> (positions (F, 3), rotations (F, 3, 3), com) relative to the root."""
        p0, r0, _ = relative_fk(np.zeros(num_joints))
        frames = len(p0)
        t0 = np.tile(np.eye(4), (frames, 1, 1))
        t0[:, :3, :3], t0[:, :3, 3] = r0, p0
        self.d_inv = np.array([np.linalg.inv(np.linalg.inv(t0[i]) @ t0[i + 1]) for i in range(frames - 1)])
        self.axes = np.zeros((num_joints, 3))
        probe = 0.5
        for j in range(num_joints):
            q = np.zeros(num_joints)
            q[j] = probe
            _, r, _ = relative_fk(q)
            a = r0[j + 1].T @ r[j + 2] @ r0[j + 2].T @ r0[j + 1]     # joint j + 1's turn, in frame j + 1
            axis = np.array([a[2, 1] - a[1, 2], a[0, 2] - a[2, 0], a[1, 0] - a[0, 1]])
            self.axes[j] = axis / np.linalg.norm(axis)
        self.num_frames = frames
        self.masses = np.asarray(masses, float)
        self.mass_fraction = self.masses / self.masses.sum()


class StageKinematics:
    """Frame positions in the world for a batch of postures that differ from q_start only in the
    first m joints (the active portion); the base's frames are computed once."""

    def __init__(self, model: ChainModel, positions, rotations, active_modules: int):
        """positions (F, 3), rotations (F, 3, 3): the world pose of q_start (Chain.pose)."""
        self.model = model
        self.m = int(active_modules)
        p, r = np.asarray(positions, float), np.asarray(rotations, float)
        self.base_positions = p[self.m:].copy()
        anchor = np.eye(4)
        anchor[:3, :3], anchor[:3, 3] = r[self.m + 1], p[self.m + 1]
        self.anchor = anchor @ model.d_inv[self.m]          # frame m before joint m turns it
        self.base_moment = (model.mass_fraction[self.m:, None] * self.base_positions).sum(axis=0)

    def positions(self, q_active) -> np.ndarray:
        """(B, F, 3) world positions for active joint angles q_active (B, m)."""
        q = np.atleast_2d(np.asarray(q_active, float))
        b, m, model = len(q), self.m, self.model
        out = np.empty((b, model.num_frames, 3))
        out[:, m:] = self.base_positions
        rot = np.broadcast_to(self.anchor[:3, :3], (b, 3, 3))
        pos = np.broadcast_to(self.anchor[:3, 3], (b, 3))
        for i in range(m, 0, -1):             # frame i: turn by -q_i, step back to frame i - 1
            rot = rot @ _rotations(model.axes[i - 1], -q[:, i - 1])
            d = model.d_inv[i - 1]
            pos = pos + rot @ d[:3, 3]
            rot = rot @ d[:3, :3]
            out[:, i - 1] = pos
        return out

    def positions_com(self, q_active):
        """((B, F, 3) positions, (B, 3) centres of gravity)."""
        p = self.positions(q_active)
        frac = self.model.mass_fraction[:self.m]
        com = np.einsum("f,bfk->bk", frac, p[:, :self.m]) + self.base_moment
        return p, com
