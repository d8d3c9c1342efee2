"""One pose measurement as the simulated sensors produce it (ROS-free; a node turns it into a
geometry_msgs/PoseStamped or nav_msgs/Odometry)."""
from dataclasses import dataclass

import numpy as np

# What RTAB-Map publishes when odometry is lost: a null pose (all zeros, quaternion included) with
# this variance on the covariance diagonal.
LOST_VARIANCE = 9999.0


@dataclass
class PoseSample:
    t_s: float                  # simulation time of the measured state
    frame_id: str               # the frame whose pose this is (base_link, camera)
    position_m: np.ndarray      # (3,) in the world (odometry) frame
    quat_xyzw: np.ndarray       # (4,) orientation; all zeros when lost
    covariance: np.ndarray      # (6, 6): x, y, z, rotation about x, y, z (ROS order)
    lost: bool = False

    @classmethod
    def lost_sample(cls, t_s: float, frame_id: str) -> "PoseSample":
        return cls(t_s, frame_id, np.zeros(3), np.zeros(4), np.eye(6) * LOST_VARIANCE, True)

    def covariance_row_major(self) -> list:
        """The 36 numbers of a ROS PoseWithCovariance.covariance."""
        return [float(x) for x in self.covariance.reshape(-1)]


def diagonal_covariance(position_std_m: float, rotation_std_rad: float,
                        floor: float = 1e-9) -> np.ndarray:
    return np.diag([max(position_std_m ** 2, floor)] * 3 + [max(rotation_std_rad ** 2, floor)] * 3)
