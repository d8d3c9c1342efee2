"""The robot's motion model as factors on the visual-inertial fusion's states (vio_fusion), ROS-free.

    model = MotionModel(velocity_sigma_m_s=0.5, height_sigma_m=0.05, still_gyro_rad_s=0.05,
                        still_accel_m_s2=0.3, still_sigma_m_s=0.01)
    graph.add(factor) for factor in model.priors(k, predicted_pose, height_m)
    still = all(model.at_rest(gyro, accel) for each IMU sample since the last frame)
    if still and lost: graph.add(model.still_factor(k))

- Crawling (velocity_sigma_m_s, height_sigma_m; 0 turns each off): every state's velocity is zero
  within the first (the robot crawls below 0.6 m/s) and the IMU's height a given height (the first
  state's) within the second (it crawls on the floor). Held still in the dark with an accelerometer
  bias the fusion does not know, the IMU alone ran away by metres in 10 s.
- Standing still (still_gyro_rad_s, still_accel_m_s2; still_gyro_rad_s 0: never): an IMU sample is at
  rest when its angular velocity is within still_gyro_rad_s and its specific force's norm within
  still_accel_m_s2 of gravity (the gait turns the head at rad/s). The fusion takes the velocity as
  zero within still_sigma_m_s only while lost (the mission holds the robot then): a constant
  velocity without rotation reads the same.

States: X(k) the IMU's pose (gtsam.Pose3, world z up), V(k) its velocity in the world.
"""
from typing import List

import gtsam
import numpy as np
from gtsam.symbol_shorthand import V, X

GRAVITY_M_S2 = 9.80665


class MotionModel:
    def __init__(self, velocity_sigma_m_s: float, height_sigma_m: float, still_gyro_rad_s: float,
                 still_accel_m_s2: float, still_sigma_m_s: float):
        self.velocity_sigma_m_s = float(velocity_sigma_m_s)
        self.height_sigma_m = float(height_sigma_m)
        self.still_gyro_rad_s = float(still_gyro_rad_s)
        self.still_accel_m_s2 = float(still_accel_m_s2)
        self.still_sigma_m_s = float(still_sigma_m_s)

    @property
    def detects_rest(self) -> bool:
        return self.still_gyro_rad_s > 0

    def at_rest(self, gyro_rad_s, accel_m_s2) -> bool:
        """One IMU sample at rest (always False when rest detection is off)."""
        return (self.detects_rest and float(np.linalg.norm(gyro_rad_s)) <= self.still_gyro_rad_s and
                abs(float(np.linalg.norm(accel_m_s2)) - GRAVITY_M_S2) <= self.still_accel_m_s2)

    def still_factor(self, k: int):
        """State k's velocity zero within still_sigma_m_s."""
        return gtsam.PriorFactorVector(V(k), np.zeros(3), gtsam.noiseModel.Isotropic.Sigma(3, self.still_sigma_m_s))

    def priors(self, k: int, predicted: gtsam.Pose3, height_m: float) -> List:
        """The crawling priors on state k: the velocity zero; the IMU's height height_m (a pose prior
        informative along the world's z only, about the predicted pose)."""
        out = []
        if self.velocity_sigma_m_s > 0:
            out.append(gtsam.PriorFactorVector(V(k), np.zeros(3),
                                               gtsam.noiseModel.Isotropic.Sigma(3, self.velocity_sigma_m_s)))
        if self.height_sigma_m > 0:
            R = predicted.rotation().matrix()
            up = R.T @ np.array([0.0, 0.0, 1.0])       # the world's z in the IMU frame (the tangent's)
            info = np.eye(6) * 1e-9
            info[3:, 3:] += np.outer(up, up) / self.height_sigma_m ** 2
            t = predicted.translation()
            at = gtsam.Pose3(gtsam.Rot3(R), np.array([t[0], t[1], float(height_m)]))
            out.append(gtsam.PriorFactorPose3(X(k), at, gtsam.noiseModel.Gaussian.Information(info)))
        return out
