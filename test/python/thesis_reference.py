"""An independent numpy transcription of the thesis equations, written from the text (with
../shared/ERRATA.md), sharing no code with the C++ core. The tests compare the bindings with it;
bench/core_tick times it against the C++ tick.

Eq. 3.3-3.4 as printed for COBRA: head = base · Trans(-H,0,0) · Rx(+90°); then
T_{i+1} = T_i · Rz(-q_i) · Trans(-L,0,0) · Rx(-90°) for odd joints and Rx(+90°) for even ones.
"""
import numpy as np


def rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def trans(x, y=0.0, z=0.0):
    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t


def quat_to_matrix(qx, qy, qz, qw):
    n = np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    qx, qy, qz, qw = qx / n, qy / n, qz / n, qw / n
    return np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
    ])


def forward_kinematics(H, L, q, base_position, base_quaternion_xyzw):
    """Eq. 3.2-3.4: list of 4x4 world transforms, base, head, then one per joint."""
    T = np.eye(4)
    T[:3, :3] = quat_to_matrix(*base_quaternion_xyzw)
    T[:3, 3] = base_position
    frames = [T]
    T = T @ trans(-H) @ rx(np.pi / 2)
    frames.append(T)
    for i, qi in enumerate(q):
        joint_number = i + 1
        twist = -np.pi / 2 if joint_number % 2 == 1 else np.pi / 2
        T = T @ rz(-qi) @ trans(-L) @ rx(twist)
        frames.append(T)
    return frames


def virtual_chassis_mean_axis(rotations):
    """Eq. 3.11-3.14."""
    z = np.array([0.0, 0.0, 1.0])
    x_bar = np.mean([R @ np.array([1.0, 0.0, 0.0]) for R in rotations], axis=0)
    h = x_bar - (x_bar @ z) * z
    x = h / np.linalg.norm(h)
    return np.column_stack([x, np.cross(z, x), z])


def virtual_chassis_svd(positions):
    """Principal axis of the centred positions (first left singular vector), horizontal, tail->head."""
    P = np.asarray(positions)
    centred = (P - P.mean(axis=0)).T
    u, _, _ = np.linalg.svd(centred)
    axis = u[:, 0]
    if axis @ (P[0] - P[-1]) < 0:
        axis = -axis
    z = np.array([0.0, 0.0, 1.0])
    h = axis - (axis @ z) * z
    x = h / np.linalg.norm(h)
    return np.column_stack([x, np.cross(z, x), z])


def centre_of_mass(positions, masses):
    """Eq. 3.15."""
    m = np.asarray(masses)
    return (m[:, None] * np.asarray(positions)).sum(axis=0) / m.sum()


def bounding_box_span(positions, com, R, padding=0.1):
    """Eq. 3.17-3.20."""
    local = (R.T @ (np.asarray(positions) - com).T).T
    delta = 0.5 * (local.max(axis=0) - local.min(axis=0))
    return 2 * delta + padding


def coupling_matrices(n):
    """ERRATA #1: A = -Laplacian of the chain; B (n x n-1), B[i][i] = 1, B[i+1][i] = -1."""
    A = np.zeros((n, n))
    for i in range(n - 1):
        A[i, i] -= 1
        A[i + 1, i + 1] -= 1
        A[i, i + 1] += 1
        A[i + 1, i] += 1
    B = np.zeros((n, n - 1))
    for i in range(n - 1):
        B[i, i] = 1
        B[i + 1, i] = -1
    return A, B


def cpg_derivative(state, A, B, mu, gamma, a_des, omega, dphi):
    """Eq. 3.21 and ERRATA #2 for a batch: state (..., 3n) = [θ, r, ṙ]."""
    n = A.shape[0]
    theta, r, rdot = state[..., :n], state[..., n:2 * n], state[..., 2 * n:]
    dtheta = mu * theta @ A.T - mu * dphi @ B.T + omega
    rddot = gamma ** 2 * (a_des - r) - 2 * gamma * rdot
    return np.concatenate([dtheta, rdot, rddot], axis=-1)


def cpg_rk4(state, dt, steps, A, B, mu, gamma, a_des, omega, dphi):
    """Classical RK4 on the batch."""
    f = lambda s: cpg_derivative(s, A, B, mu, gamma, a_des, omega, dphi)  # noqa: E731
    for _ in range(steps):
        k1 = f(state)
        k2 = f(state + 0.5 * dt * k1)
        k3 = f(state + 0.5 * dt * k2)
        k4 = f(state + dt * k3)
        state = state + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return state


def cpg_output(theta, r, bias, lower, upper):
    """Eq. 3.25, clamped to the joint limits."""
    return np.clip(r * np.sin(theta) + bias, lower, upper)


def modify_amplitudes(a_nominal, delta, weights, yaw_joints, offset, a_min, a_max, delta_limit):
    """Eq. 3.26-3.30 / Algorithm 1 MODIFYAMPLITUDES."""
    a = np.array(a_nominal, dtype=float)
    d = np.clip(delta, -delta_limit, delta_limit)
    for w, j in zip(weights, yaw_joints):
        a[j] = np.clip(a[j] + w * d + offset, a_min, a_max)
    return a
