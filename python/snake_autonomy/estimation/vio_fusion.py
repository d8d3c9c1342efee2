"""Visual-inertial odometry: the visual odometry's poses fused with IMU preintegration in a
fixed-lag smoother (GTSAM), ROS-free.

    vio = VioFusion(K, T_imu_camera, vo_params, load_fusion_params(path), initial_imu_pose=T_world_imu)
    vio.add_imu(t_s, gyro_rad_s, accel_m_s2)          # every IMU sample, in time order
    result = vio.add_frame(image, depth_m, stamp_s)    # every camera frame (after its IMU samples)
    result.T_world_camera, result.covariance (what to publish: LOST_COVARIANCE when lost),
    result.marginal_covariance (the smoother's, always), result.state, result.reason, result.vo,
    result.smoother_restarted

One state per camera frame: the IMU's pose X(k) in a gravity-aligned world frame (z up), its
velocity V(k) and the IMU biases B(k). Consecutive states are tied by a CombinedImuFactor (the
preintegrated gyro and accelerometer samples between the frames, with the bias random walk). A
frame the visual odometry tracked adds a between factor to X(k) from the state of the frame its
keyframe was taken at (vo_from_keyframe; that frame's visual pose taken, its state in the window):
the PnP fit's motion from the keyframe, with that fit's covariance, so that the frames measured
against one keyframe share its error instead of adding up their own; else from the last tracked
frame's state (within half the smoother's window), the two PnP fits' covariances summed (the
keyframe's own error drops out). The odometry's frame never enters the world: a drifted or
restarted odometry frame moves nothing. The first tracked frame after a gap only anchors the next
one (it is reported lost). On the simulated star mission (sidewinding) this kept the estimate within
metres where the odometry's poses taken as absolute priors ran away (a study; docs/estimation.md).

The gyro's zero-rate offset is measured at rest before the first frame (rest_calibration.py: the
mean rate over the last rest_calibration_s of IMU samples before it, the robot held still), and the
first state's gyro bias prior is centred there; a window that moved, or too short, leaves the prior
zero-mean and wide (uncalibrated_gyro_bias_sigma_rad_s). The outcome is recorded, not logged
(self.calibration): its owner says it once (vio_node's log, the batch run's vo summary).

The robot's motion model (motion_model.py: velocity_prior_sigma_m_s, height_prior_sigma_m, and
standing still while lost: still_*) adds priors on every state.

The visual odometry is given the camera's pose the IMU predicts (its last good pose moved by the
fused motion since): it matches a keyframe point only near where that pose projects it
(VoParams.guided_radius_px), which keeps the fast turns of sidewinding from mismatching.

The IMU gate: the visual pose (relative: the anchor state's estimate moved by the measured motion)
is refused when it is further from the pose the IMU predicts from the last estimate than gate_m /
gate_deg plus gate_sigmas times the prediction's std (so that the
gate widens while dead-reckoning and a diverged state takes the visual pose again). Should the
smoother fail (an indeterminate system), a new one starts from the visual pose or the prediction.

Tracking is lost when the visual odometry is lost or the gate refuses it: the state is then
dead-reckoned on the IMU alone, its marginal covariance grows, and the published covariance is
LOST_COVARIANCE. After vo_reset_after_lost consecutive lost frames the visual odometry restarts from
the fused pose (a new keyframe), so that tracking resumes where the keyframe's scene is out of view.

Frames: the IMU frame is the body of the preintegration (sim/imu.py: camera_link, x forward,
y left, z up); T_imu_camera is the camera's optical frame in it. Covariances are 6x6 in
geometry_msgs order: x, y, z, then small rotations about the world's x, y, z axes.
"""
import math
from dataclasses import dataclass, fields
from typing import List, Optional

import gtsam
import numpy as np
from gtsam.symbol_shorthand import B, V, X

from .config_section import load_section
from .motion_model import GRAVITY_M_S2, MotionModel
from .pose_remap import base_covariance
from .rest_calibration import GyroCalibration, RestSettings, calibrate_gyro_at_rest
from .visual_odometry import LOST, LOST_COVARIANCE, OK, VisualOdometry, VoParams, VoResult, rotation_angle_deg


@dataclass
class FusionParams:
    """The fusion: section of config/estimation.yaml. The IMU's noise figures are sim/imu.py's
    BMI055-like model (ImuConfig's defaults) in GTSAM's continuous-time units, but for the
    accelerometer's white noise: 10 times the datasheet's. The simulated head's contact spikes,
    sampled at 200 Hz, alias into the accelerometer's samples: on a simulated rectilinear crawl the
    fused pose was up to 41 mm off with the datasheet's figure (the visual odometry alone: 10 mm),
    8 mm with 10 times it."""
    gyro_noise_density_rad_s_per_sqrt_hz: float = 2.443e-4     # 0.014 deg/s/sqrt(Hz)
    accel_noise_density_m_s2_per_sqrt_hz: float = 1.471e-2     # 10 x 150 ug/sqrt(Hz)
    gyro_bias_walk_rad_s_per_sqrt_s: float = 2.0e-5
    accel_bias_walk_m_s2_per_sqrt_s: float = 4.0e-4
    integration_sigma: float = 1e-4            # preintegration's integration error (GTSAM's default order)
    lag_s: float = 2.0                         # the smoother's window
    prior_position_sigma_m: float = 1e-3       # the first state's prior: pose given ...
    prior_angle_sigma_deg: float = 0.5
    prior_velocity_sigma_m_s: float = 0.5      # ... velocity unknown (zero, loosely)
    # biases: the gyro's at its zero-rate offset measured at rest (rest_calibration_s, below), within 1e-4
    # rad/s (0.006 deg/s). The heading is unobservable from gravity, so the fused heading drifts by what the
    # gyro bias estimate is off: with 5e-3 rad/s the estimate wandered to 2-9e-3 rad/s on the star mission
    # and the heading 3-16 deg RMS, the raw gyro's 0.4-1.7 deg; with 1e-4 the APE RMSE median 21.1 -> 13.7 cm
    # on held-out seeds 50-59 (docs/vo_error_sources.md)
    prior_gyro_bias_sigma_rad_s: float = 1e-4
    prior_accel_bias_sigma_m_s2: float = 0.1   # the accelerometer's: within a few datasheet offsets
    # the gyro calibrated at rest (rest_calibration.py) on the IMU samples of this long before the first
    # frame (0: not at rest, the prior zero-mean: a gyro calibrated beforehand). The window's mean has a
    # standard error of the noise density / sqrt(2 x window) (1.2e-4 rad/s over 2 s; the prior's std is
    # at least that). At rest: the gyro's std within rest_gyro_std_rad_s on each axis (the BMI055's
    # white noise: 2.4e-3 rad/s at 200 Hz), its mean within rest_gyro_rate_rad_s (the BMI055's offset:
    # +-1 deg/s, 0.017 rad/s, per axis), the specific force within rest_accel_m_s2 of gravity
    rest_calibration_s: float = 2.0
    rest_gyro_std_rad_s: float = 0.01
    rest_gyro_rate_rad_s: float = 0.05
    rest_accel_m_s2: float = 0.3
    # a window that moved (or too short): the gyro bias prior zero-mean within this (a few datasheet offsets)
    uncalibrated_gyro_bias_sigma_rad_s: float = 5e-3
    vo_min_sigma_m: float = 1e-3               # the visual pose's std is at least this ...
    vo_min_sigma_deg: float = 0.5              # ... and this (lower: the fused tilt follows the visual one
                                               # and gravity leaks into the dead-reckoning when tracking is lost)
    # the visual motion is measured from the state of the frame the odometry's keyframe was taken
    # at (its PnP fit's own error only; the keyframe's error shared by the frames against it), else
    # (false, or that state out of the window) from the last tracked frame's
    vo_from_keyframe: bool = True
    gate_m: float = 0.1                        # visual pose further than this from the IMU's prediction ...
    gate_deg: float = 10.0
    gate_sigmas: float = 3.0                   # ... plus this many of the prediction's std: refused
    gate_max_refused: int = 3                  # after this many tracked frames refused in a row the next one is
                                               # taken (a runaway state refuses every visual pose; 0: never)
    vo_reset_after_lost: int = 2               # restart the visual odometry after this many lost frames (0: never)
    # the robot's motion model (0: none): every state's velocity zero within this std (it crawls
    # below 0.6 m/s; dead-reckoning on the IMU alone otherwise runs away while lost) ...
    velocity_prior_sigma_m_s: float = 0.5
    height_prior_sigma_m: float = 0.05         # ... and the IMU's height the first state's within this std
    # standing still while lost (every IMU sample since the last frame within these of rest: the gait
    # turns the head at rad/s, the mission holds the robot while the pose is lost; a constant velocity
    # without rotation reads the same): the velocity zero within still_sigma_m_s
    still_gyro_rad_s: float = 0.05             # (0: never taken as still)
    still_accel_m_s2: float = 0.3              # the specific force's norm within this of gravity
    still_sigma_m_s: float = 0.01

    def problems(self, prefix: str = "fusion") -> List[str]:
        out = []
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "vo_from_keyframe":
                if not isinstance(v, bool):
                    out.append(f"{prefix}.{f.name}: must be true or false, got {v!r}")
            elif f.name in ("vo_reset_after_lost", "gate_max_refused"):
                if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                    out.append(f"{prefix}.{f.name}: must be an integer >= 0, got {v!r}")
            elif f.name in ("velocity_prior_sigma_m_s", "height_prior_sigma_m", "still_gyro_rad_s",
                            "rest_calibration_s"):
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                    out.append(f"{prefix}.{f.name}: must be a finite number >= 0, got {v!r}")
            elif isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                out.append(f"{prefix}.{f.name}: must be a finite number > 0, got {v!r}")
        return out


def load_fusion_params(path) -> FusionParams:
    """The fusion: section of an estimation config (absent: defaults); ValueError naming the file,
    the field and the value."""
    return load_section(path, "fusion", FusionParams)


@dataclass
class FusedResult:
    stamp: float
    T_world_camera: np.ndarray         # 4x4, the camera's optical frame in the world
    T_world_imu: np.ndarray
    velocity_m_s: np.ndarray           # (3,) the IMU's, in the world
    covariance: np.ndarray             # 6x6 to publish: the marginal one, LOST_COVARIANCE diagonal when lost
    marginal_covariance: np.ndarray    # 6x6 of the camera pose, from the smoother (also while lost)
    state: str                         # OK or LOST
    reason: str
    vo: VoResult
    smoother_restarted: bool = False   # the smoother failed on this frame and a new one started
    #: the visual motion this frame measured (gated or not), None without one: (the stamp of the frame
    #: it is measured from, the IMU's motion 4x4, its 6x6 covariance in GTSAM's tangent: rotation, translation)
    measured_motion: Optional[tuple] = None

    @property
    def ok(self) -> bool:
        return self.state == OK


def level_pose(accel_m_s2) -> np.ndarray:
    """The IMU's pose at rest from one specific-force reading: roll and pitch that put it along the
    world's +z, zero yaw and position."""
    a = np.asarray(accel_m_s2, float)
    up = a / np.linalg.norm(a)                      # the world's z in the IMU frame
    x = np.array([1.0, 0.0, 0.0]) - up[0] * up      # the IMU's x projected on the level plane
    if np.linalg.norm(x) < 1e-6:
        x = np.array([0.0, 1.0, 0.0]) - up[1] * up
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.vstack([x, np.cross(up, x), up])   # rows: world axes in the IMU frame
    return T


def ros_to_local(cov: np.ndarray, R: np.ndarray) -> np.ndarray:
    """6x6 covariance in geometry_msgs order (world position, world rotations) -> GTSAM Pose3's
    tangent (body rotation, body translation): T = T_hat . Exp(xi)."""
    J = np.zeros((6, 6))
    J[:3, 3:] = R.T                                  # body rotation from the world's
    J[3:, :3] = R.T                                  # body translation from the world position
    return J @ cov @ J.T


def local_to_ros(cov: np.ndarray, R: np.ndarray) -> np.ndarray:
    """The inverse of ros_to_local."""
    J = np.zeros((6, 6))
    J[:3, 3:] = R
    J[3:, :3] = R
    return J @ cov @ J.T


class VioFusion:
    """Visual odometry + IMU preintegration in an incremental fixed-lag smoother (see the module's
    docstring)."""

    def __init__(self, K, T_imu_camera, vo_params: Optional[VoParams] = None,
                 params: Optional[FusionParams] = None, initial_imu_pose: Optional[np.ndarray] = None):
        self.params = params or FusionParams()
        problems = self.params.problems()
        if problems:
            raise ValueError("fusion: " + "; ".join(problems))
        self.T_imu_camera = np.asarray(T_imu_camera, float)
        self.T_camera_imu = np.linalg.inv(self.T_imu_camera)
        self.vo = VisualOdometry(K, vo_params)
        p = self.params
        pim = gtsam.PreintegrationCombinedParams.MakeSharedU(GRAVITY_M_S2)
        pim.setGyroscopeCovariance(np.eye(3) * p.gyro_noise_density_rad_s_per_sqrt_hz ** 2)
        pim.setAccelerometerCovariance(np.eye(3) * p.accel_noise_density_m_s2_per_sqrt_hz ** 2)
        pim.setBiasOmegaCovariance(np.eye(3) * p.gyro_bias_walk_rad_s_per_sqrt_s ** 2)
        pim.setBiasAccCovariance(np.eye(3) * p.accel_bias_walk_m_s2_per_sqrt_s ** 2)
        pim.setIntegrationCovariance(np.eye(3) * p.integration_sigma ** 2)
        self._pim_params = pim
        self._initial = None if initial_imu_pose is None else np.asarray(initial_imu_pose, float)
        self._smoother = gtsam.IncrementalFixedLagSmoother(p.lag_s)
        self._k = -1                                 # the last state's index
        self._imu: List[tuple] = []                  # samples since the last frame: (t, gyro, accel)
        self._last_imu_t = None
        self._lost_frames = 0
        self._last_vo = None                         # (state index, stamp, T_vo_imu, PnP covariance)
        self._vo_key = 0                             # the state at the odometry's last good pose
        self._refused = 0                            # tracked frames the gate refused in a row
        self._keys = {}                              # frame stamp -> its state's index, within the window
        self._est = None                             # the smoother's estimate, None once it was updated since
        self._motion = MotionModel(p.velocity_prior_sigma_m_s, p.height_prior_sigma_m, p.still_gyro_rad_s,
                                   p.still_accel_m_s2, p.still_sigma_m_s)
        self._rest = RestSettings(p.rest_calibration_s, p.prior_gyro_bias_sigma_rad_s,
                                  p.uncalibrated_gyro_bias_sigma_rad_s, p.rest_gyro_std_rad_s,
                                  p.rest_gyro_rate_rad_s, p.rest_accel_m_s2)
        self.calibration: Optional[GyroCalibration] = None    # the gyro's, at the first frame

    def add_imu(self, t_s: float, gyro_rad_s, accel_m_s2) -> None:
        self._imu.append((float(t_s), np.asarray(gyro_rad_s, float), np.asarray(accel_m_s2, float)))

    # ---------------------------------------------------------------------------------------------
    def add_frame(self, image, depth_m, stamp: float, mask=None) -> FusedResult:
        """One camera frame (VisualOdometry.process's arguments), after the IMU samples up to it."""
        if self._k < 0:
            return self._first_frame(image, depth_m, stamp, mask)
        p, k = self.params, self._k + 1
        pim, still = self._preintegrate(stamp)
        predicted = pim.predict(self._state, self._bias)
        graph, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
        graph.add(gtsam.CombinedImuFactor(X(k - 1), V(k - 1), X(k), V(k), B(k - 1), B(k), pim))
        values.insert(X(k), predicted.pose())
        values.insert(V(k), predicted.velocity())
        values.insert(B(k), self._bias)
        for factor in self._motion.priors(k, predicted.pose(), self._initial[2, 3]):
            graph.add(factor)
        before = self._est if self._est is not None else self._smoother.calculateEstimate()   # the states so far
        vo = self.vo.process(image, depth_m, stamp, mask, self._vo_prediction(before, predicted.pose()))
        if vo.ok:
            self._vo_key = k
        state, reason, T_world_imu, anchoring, motion = OK, "", None, False, None
        if not vo.ok:
            state, reason = LOST, f"visual odometry lost: {vo.reason}"
        else:
            T_vo_imu = vo.T_odom_camera @ self.T_camera_imu
            factor, T_world_imu, relative, motion = self._vo_factor(before, k, vo, T_vo_imu)
            if factor is None:              # tracked again: the next frame's motion is measured from it
                state, anchoring = LOST, True
                reason = "visual odometry: no earlier tracked frame to measure the motion from"
            else:
                reason = self._gate(T_world_imu, predicted.pose().matrix(), pim, stamp - self._t, relative)
                if reason and self._refused >= p.gate_max_refused > 0:
                    reason = ""                 # the camera agreed with itself that long: the IMU's state is off
                self._refused = self._refused + 1 if reason else 0
                if reason:
                    state = LOST
                else:
                    graph.add(factor)
            # the next motion is measured from here, even if refused: a refused pose may be in the
            # odometry's keyframe, and so in every pose after it
            self._last_vo = (k, stamp, T_vo_imu, vo.relative_covariance)
        if still and state == LOST:     # standing still while lost (the mission holds the robot)
            graph.add(self._motion.still_factor(k))
        stamps = gtsam.FixedLagSmootherKeyTimestampMap()
        for key in (X(k), V(k), B(k)):
            stamps.insert((key, stamp))
        try:
            self._est = None
            self._smoother.update(graph, values, stamps)
            self._k, self._t = k, stamp
            result = self._estimate(stamp, state, reason, vo)
        except RuntimeError as exc:              # GTSAM's IndeterminateLinearSystemException
            # a new smoother from the visual pose when there is one, else from the IMU's prediction;
            # its first state X(k), the velocity zero within the prior's sigma (not a prediction
            # that may have run away)
            start = T_world_imu if state == OK else predicted.pose().matrix()
            self._k = k - 1
            self._start(start, np.zeros(3), self._bias, stamp)
            if self._last_vo is not None and self._last_vo[0] != k:
                self._last_vo = None
            reason = (reason + "; " if reason else "") + f"smoother restarted: {str(exc).strip().splitlines()[0]}"
            result = self._estimate(stamp, state, reason, vo)
            result.smoother_restarted = True
        result.measured_motion = motion
        self._remember(stamp, state == OK or anchoring)
        self._lost_frames = 0 if state == OK or anchoring else self._lost_frames + 1
        if p.vo_reset_after_lost and self._lost_frames >= p.vo_reset_after_lost:
            self.vo.reset(result.T_world_camera, result.marginal_covariance)
            self._lost_frames, self._last_vo, self._vo_key = 0, None, self._k
        return result

    # ---------------------------------------------------------------------------------------------
    def _preintegrate(self, stamp: float):
        """The IMU samples since the last frame up to stamp (each held over the interval it ends;
        the last one held up to stamp), consumed; and whether every one of them is at rest
        (still_gyro_rad_s, still_accel_m_s2)."""
        pim = gtsam.PreintegratedCombinedMeasurements(self._pim_params, self._bias)
        t, n, still = self._t, 0, True
        for t_s, gyro, accel in self._imu:
            if t_s > stamp:
                break
            if t_s > t:
                pim.integrateMeasurement(accel, gyro, t_s - t)
                t, n = t_s, n + 1
                still = still and self._motion.at_rest(gyro, accel)
        if stamp > t and self._imu:
            pim.integrateMeasurement(self._imu[-1][2], self._imu[-1][1], stamp - t)
        self._imu = [s for s in self._imu if s[0] > stamp]
        return pim, still and n > 0

    def _gate(self, T_world_imu, T_pred, pim, dt: float, relative: bool = False) -> str:
        """Why the visual pose is refused ("" when it is not): further from the IMU's prediction than
        gate_m / gate_deg plus gate_sigmas times the prediction's std (the last marginal covariance,
        its velocity's over dt, and the preintegration's: the gate widens while dead-reckoning).
        relative: the visual pose is the last state's estimate moved by the measured motion, so the
        last state's own pose covariance drops out."""
        p = self.params
        pos_var, rot_var, vel_var = self._variances
        if relative:
            pos_var = rot_var = 0.0
        cov = np.asarray(pim.preintMeasCov())
        sigma_m = math.sqrt(pos_var + vel_var * dt * dt + float(np.trace(cov[3:6, 3:6])))
        sigma_deg = math.degrees(math.sqrt(rot_var + float(np.trace(cov[0:3, 0:3]))))
        allowed_m, allowed_deg = p.gate_m + p.gate_sigmas * sigma_m, p.gate_deg + p.gate_sigmas * sigma_deg
        off_m = float(np.linalg.norm(T_world_imu[:3, 3] - T_pred[:3, 3]))
        off_deg = rotation_angle_deg(T_pred[:3, :3].T @ T_world_imu[:3, :3])
        if off_m > allowed_m or off_deg > allowed_deg:
            return (f"IMU gate: the visual pose is {off_m:.3f} m, {off_deg:.1f} deg from the IMU's prediction "
                    f"(allowed {allowed_m:.3f} m, {allowed_deg:.1f} deg)")
        return ""

    def _first_frame(self, image, depth_m, stamp: float, mask) -> FusedResult:
        """The first state: the given pose (or levelled on the mean specific force of the rest window,
        or of every sample so far without one), velocity loosely zero, the gyro bias calibrated at rest
        (rest_calibration_s) and the accelerometer's loosely zero; the visual odometry's frame is set
        to the world."""
        before = [s for s in self._imu if s[0] <= stamp]
        window = self.params.rest_calibration_s
        rest = [s for s in before if s[0] >= stamp - window] if window > 0 else before
        span = stamp - before[0][0] if before else 0.0
        self.calibration = calibrate_gyro_at_rest([s[1] for s in rest], [s[2] for s in rest], span, self._rest)
        if self._initial is None:
            if not rest:
                raise ValueError("the first frame needs an initial IMU pose or IMU samples before it (levelling)")
            self._initial = level_pose(np.mean([s[2] for s in rest], axis=0))
        bias = gtsam.imuBias.ConstantBias(np.zeros(3), self.calibration.bias_rad_s)
        self._start(self._initial, np.zeros(3), bias, stamp)
        self._imu = [s for s in self._imu if s[0] > stamp]
        self.vo.reset(self._initial @ self.T_imu_camera)
        vo = self.vo.process(image, depth_m, stamp, mask)
        state, reason = (OK, "") if vo.ok else (LOST, f"visual odometry lost: {vo.reason}")
        if vo.ok:
            self._last_vo = (self._k, stamp, vo.T_odom_camera @ self.T_camera_imu, vo.relative_covariance)
        self._remember(stamp, vo.ok)
        return self._estimate(stamp, state, reason, vo)

    def _remember(self, stamp: float, taken: bool) -> None:
        """The frame's state index by its stamp, when its visual pose was taken (a keyframe's state,
        for the motions measured from it): a refused pose the odometry made its keyframe would
        carry its error into every motion measured from it, so those are measured frame to frame."""
        self._keys = {t: k for t, k in self._keys.items() if t >= stamp - self.params.lag_s}
        if taken:
            self._keys[stamp] = self._k

    def _start(self, T_world_imu: np.ndarray, velocity, bias, stamp: float) -> None:
        """A new smoother whose first state is this pose, velocity and bias, with the prior_ sigmas."""
        p = self.params
        self._smoother = gtsam.IncrementalFixedLagSmoother(p.lag_s)
        self._k = self._k + 1
        k = self._k
        pose = gtsam.Pose3(np.asarray(T_world_imu, float))
        graph, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
        sigmas = np.r_[[math.radians(p.prior_angle_sigma_deg)] * 3, [p.prior_position_sigma_m] * 3]
        graph.add(gtsam.PriorFactorPose3(X(k), pose, gtsam.noiseModel.Diagonal.Sigmas(sigmas)))
        graph.add(gtsam.PriorFactorVector(V(k), np.asarray(velocity, float),
                                          gtsam.noiseModel.Isotropic.Sigma(3, p.prior_velocity_sigma_m_s)))
        gyro_sigma = self.calibration.sigma_rad_s if self.calibration is not None else p.prior_gyro_bias_sigma_rad_s
        bias_sigmas = np.r_[[p.prior_accel_bias_sigma_m_s2] * 3, [gyro_sigma] * 3]
        graph.add(gtsam.PriorFactorConstantBias(B(k), bias, gtsam.noiseModel.Diagonal.Sigmas(bias_sigmas)))
        values.insert(X(k), pose)
        values.insert(V(k), np.asarray(velocity, float))
        values.insert(B(k), bias)
        stamps = gtsam.FixedLagSmootherKeyTimestampMap()
        for key in (X(k), V(k), B(k)):
            stamps.insert((key, stamp))
        self._est = None
        self._smoother.update(graph, values, stamps)
        self._t = stamp

    def _vo_prediction(self, estimate, predicted) -> Optional[np.ndarray]:
        """The camera's pose the IMU predicts now, in the odometry's frame: its last good pose moved
        by the fused motion since that state (None when the state has left the window)."""
        if not estimate.exists(X(self._vo_key)):
            return None
        T_world_then = estimate.atPose3(X(self._vo_key)).matrix() @ self.T_imu_camera
        return self.vo.pose @ np.linalg.inv(T_world_then) @ predicted.matrix() @ self.T_imu_camera

    def _vo_factor(self, estimate, k: int, vo: VoResult, T_vo_imu: np.ndarray):
        """(factor, the IMU's pose it puts state k at, whether it is relative to state k - 1, the
        measured motion: FusedResult.measured_motion) for a tracked frame: the motion from its
        keyframe's state (vo_from_keyframe, when that state is in the window) with the PnP fit's
        covariance, else from the last tracked frame's state (within half the window) with the two
        frames' PnP covariances (the keyframe's own error drops out of the motion); all None (and
        False) when no earlier tracked frame is in the window."""
        p = self.params
        j = self._keys.get(vo.keyframe_stamp) if p.vo_from_keyframe else None
        if j is not None and j < k and estimate.exists(X(j)):
            since = vo.keyframe_stamp
            T_rel = np.linalg.inv(vo.T_odom_keyframe @ self.T_camera_imu) @ T_vo_imu
            cov = self._vo_covariance(vo.relative_covariance, vo.T_odom_camera, T_vo_imu)
        else:
            last = self._last_vo
            if last is None or vo.stamp - last[1] > 0.5 * p.lag_s or not estimate.exists(X(last[0])):
                return None, None, False, None
            j, since, T_vo_last, rel_last = last
            T_rel = np.linalg.inv(T_vo_last) @ T_vo_imu
            cov = self._vo_covariance(vo.relative_covariance + rel_last, vo.T_odom_camera, T_vo_imu)
        T_world_imu = estimate.atPose3(X(j)).matrix() @ T_rel
        factor = gtsam.BetweenFactorPose3(X(j), X(k), gtsam.Pose3(T_rel), gtsam.noiseModel.Gaussian.Covariance(cov))
        return factor, T_world_imu, j == k - 1, (since, T_rel, cov)

    def _vo_covariance(self, covariance, T_odom_camera, T_vo_imu) -> np.ndarray:
        """The odometry's camera covariance (its frame's axes) at the IMU, with the floors, in the
        tangent of the IMU's pose (GTSAM's: rotation, translation)."""
        p = self.params
        floor = np.diag([p.vo_min_sigma_m ** 2] * 3 + [math.radians(p.vo_min_sigma_deg) ** 2] * 3)
        cov_imu = base_covariance(covariance, T_odom_camera, self.T_camera_imu) + floor
        return ros_to_local(cov_imu, T_vo_imu[:3, :3])

    def _estimate(self, stamp, state, reason, vo) -> FusedResult:
        k = self._k
        est = self._est = self._smoother.calculateEstimate()     # kept: the next frame's states so far
        pose = est.atPose3(X(k))
        self._bias = est.atConstantBias(B(k))
        velocity = np.asarray(est.atVector(V(k)), float)
        self._state = gtsam.NavState(pose, velocity)
        T_world_imu = pose.matrix()
        cov_imu = local_to_ros(np.asarray(self._smoother.marginalCovariance(X(k))), T_world_imu[:3, :3])
        vel_cov = np.asarray(self._smoother.marginalCovariance(V(k)))
        self._variances = (float(np.trace(cov_imu[:3, :3])), float(np.trace(cov_imu[3:, 3:])), float(np.trace(vel_cov)))
        T_world_camera = T_world_imu @ self.T_imu_camera
        marginal = base_covariance(cov_imu, T_world_imu, self.T_imu_camera)
        published = marginal if state == OK else np.eye(6) * LOST_COVARIANCE
        return FusedResult(stamp, T_world_camera, T_world_imu, velocity, published, marginal, state, reason, vo)
