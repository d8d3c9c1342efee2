"""The visual-inertial odometry on live streams (what nodes/vio_node.py wraps, ROS-free): colour and
depth images paired by their stamps, IMU samples buffered, each frame fed to a VioFusion after the
IMU samples up to its stamp, every failure counted instead of raised, and the figures a diagnostic
reports (frames, lost intervals, time per frame).

    stream = VioStream(K, T_imu_camera, vo_params, fusion_params)
    stream.add_imu(t_s, gyro, accel)              # any thread
    stream.add_colour(t_s, rgb); stream.add_depth(t_s, depth_m)
    out = stream.step(now_s)                      # the worker: a StreamOutput when a frame was processed

A frame waits for the IMU sample at or after its stamp (the fusion integrates up to the frame) at
most `imu_wait_s`; then it is processed with the samples there are. A newer image pair replaces one
not processed yet (counted as dropped): the odometry keeps up with the newest frame. The first frame
waits (counted as waiting) until the IMU samples before it span the fusion's rest window
(FusionParams.rest_calibration_s: the robot held still while the gyro is calibrated, rest_calibration.py).

The pose published is the IMU's frame (camera_link: x forward, z up; RTAB-Map's odometry child
frame), T_world_imu; its covariance (geometry_msgs order, about the world's axes) is the fusion's,
whose origin is the same as the optical frame's (the two differ by a rotation only).
"""
import re
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np

from .vio_fusion import FusedResult, FusionParams, VioFusion
from .visual_odometry import LOST_COVARIANCE

STAMP_TOLERANCE_S = 1e-3      # a colour and a depth image within this of each other are one frame


@dataclass
class StreamOutput:
    stamp: float
    T_world_link: np.ndarray          # 4x4: the IMU's frame (camera_link) in the odometry's world
    velocity_m_s: np.ndarray          # (3,) in the world
    covariance: np.ndarray            # 6x6 to publish (LOST_COVARIANCE on the diagonal while lost)
    ok: bool
    reason: str
    ms: float                         # the frame's processing time (wall clock)
    smoother_restarted: bool = False  # the fusion's smoother restarted on this frame


@dataclass
class StreamStats:
    frames: int = 0                   # processed
    tracked: int = 0
    lost: int = 0
    failed: int = 0                   # raised inside the fusion: counted, the stream goes on
    dropped: int = 0                  # replaced by a newer pair before they were processed
    last_error: str = ""
    lost_intervals: List[Tuple[float, Optional[float]]] = field(default_factory=list)   # (start, end or None)
    ms: List[float] = field(default_factory=list)        # the last 100 frames' times
    lost_causes: Counter = field(default_factory=Counter)   # lost frames by cause (lost_cause)
    restarts: int = 0                 # the fusion's smoother restarted (an indeterminate system)
    waiting: int = 0                  # first frames held until the IMU spanned the rest window
    gyro_calibration: str = ""        # the fusion's calibration at rest (or why there was none)

    def lost_now(self) -> bool:
        return bool(self.lost_intervals) and self.lost_intervals[-1][1] is None

    def summary(self) -> dict:
        ms = np.array(self.ms) if self.ms else np.zeros(1)
        total_lost = sum((end if end is not None else self.lost_intervals[-1][0]) - start
                         for start, end in self.lost_intervals)
        return {"frames": self.frames, "tracked": self.tracked, "lost": self.lost, "failed": self.failed,
                "dropped": self.dropped, "lost_intervals": len(self.lost_intervals),
                "lost_s_total": float(total_lost), "ms_median": float(np.median(ms)),
                "ms_p90": float(np.percentile(ms, 90)), "ms_last": float(ms[-1]), "last_error": self.last_error,
                "restarts": self.restarts, "waiting": self.waiting, "gyro_calibration": self.gyro_calibration,
                "lost_causes": "; ".join(f"{n} {cause}" for cause, n in self.lost_causes.most_common())}


def lost_cause(reason: str) -> str:
    """A lost frame's reason without its figures: the text before the first number ("IMU gate: the
    visual pose is 0.2 m ..." -> "IMU gate: the visual pose is")."""
    return re.split(r"\d", reason, maxsplit=1)[0].rstrip(" :,(") or "lost"


class VioStream:
    """See the module's docstring. Thread-safe: the add_* calls from callbacks, step() from one worker."""

    def __init__(self, K, T_imu_camera, vo_params=None, fusion_params=None, imu_wait_s: float = 0.1,
                 clock=time.perf_counter):
        self.fusion = VioFusion(K, T_imu_camera, vo_params, fusion_params)
        self.rest_s = (fusion_params or FusionParams()).rest_calibration_s
        self.imu_wait_s = float(imu_wait_s)
        self.clock = clock
        self.stats = StreamStats()
        self._lock = threading.Lock()
        self._imu: List[tuple] = []
        self._last_imu_t = -np.inf
        self._colour: Optional[tuple] = None
        self._depth: Optional[tuple] = None
        self._pending: Optional[tuple] = None        # (stamp, rgb, depth, the wall time it was paired)
        self._last_frame_t = -np.inf
        self._last: Optional[StreamOutput] = None

    # -- inputs ---------------------------------------------------------------------------------------
    def add_imu(self, t_s: float, gyro_rad_s, accel_m_s2) -> None:
        with self._lock:
            if t_s > self._last_imu_t:               # out of order or repeated samples are dropped
                self._imu.append((float(t_s), gyro_rad_s, accel_m_s2))
                self._last_imu_t = float(t_s)

    def add_colour(self, t_s: float, rgb) -> None:
        with self._lock:
            self._colour = (float(t_s), rgb)
            self._pair()

    def add_depth(self, t_s: float, depth_m) -> None:
        with self._lock:
            self._depth = (float(t_s), depth_m)
            self._pair()

    def _pair(self) -> None:
        if self._colour is None or self._depth is None:
            return
        if abs(self._colour[0] - self._depth[0]) > STAMP_TOLERANCE_S:
            return
        if self._pending is not None:
            self.stats.dropped += 1
        self._pending = (self._colour[0], self._colour[1], self._depth[1], self.clock())
        self._colour = self._depth = None

    # -- the worker -----------------------------------------------------------------------------------
    def step(self) -> Optional[StreamOutput]:
        """Processes the pending frame when its IMU samples are in (or imu_wait_s passed); None when
        there is nothing to do yet."""
        with self._lock:
            if self._pending is None:
                return None
            stamp, rgb, depth, paired = self._pending
            if self._last_imu_t < stamp and self.clock() - paired < self.imu_wait_s:
                return None
            self._pending = None
            if self._last_frame_t == -np.inf and self.rest_s > 0 and self._waits(stamp):
                return None
            samples = [s for s in self._imu if s[0] <= stamp]
            self._imu = [s for s in self._imu if s[0] > stamp]
        if stamp <= self._last_frame_t or (not samples and self._last_frame_t == -np.inf):
            # an old frame (a restarted stream), or a first frame with no IMU sample before it (the
            # fusion levels its first pose on the specific force): not fusable
            self.stats.dropped += 1
            return None
        self._last_frame_t = stamp
        t0 = self.clock()
        try:
            for t, g, a in samples:
                self.fusion.add_imu(t, g, a)
            result = self.fusion.add_frame(rgb, depth, stamp)
        except Exception as exc:                      # noqa: BLE001 - any failure is one lost frame
            self.stats.failed += 1
            self.stats.last_error = f"{type(exc).__name__}: {exc}"
            result = None
        ms = 1000.0 * (self.clock() - t0)
        if self.fusion.calibration is not None:
            self.stats.gyro_calibration = self.fusion.calibration.detail
        return self._account(stamp, result, ms)

    def _waits(self, stamp: float) -> bool:
        """Whether the first frame (at stamp) waits: no IMU sample rest_s or more before it. The samples
        older than the window but the last of them are let go. Called with the lock held."""
        start = stamp - self.rest_s
        older = [s for s in self._imu if s[0] <= start]
        self._imu = older[-1:] + [s for s in self._imu if s[0] > start]
        if older:
            return False
        self.stats.waiting += 1
        return True

    def _account(self, stamp: float, result: Optional[FusedResult], ms: float) -> Optional[StreamOutput]:
        s = self.stats
        s.frames += 1
        s.ms = (s.ms + [ms])[-100:]
        ok = result is not None and result.ok
        if ok:
            s.tracked += 1
            if s.lost_now():
                s.lost_intervals[-1] = (s.lost_intervals[-1][0], stamp)
        else:
            s.lost += 1
            s.lost_causes[lost_cause(result.reason) if result is not None else "failed"] += 1
            if not s.lost_now():
                s.lost_intervals.append((stamp, None))
        if result is not None and result.smoother_restarted:
            s.restarts += 1
        if result is None:              # failed: the last pose, lost (none before the first estimate)
            if self._last is None:
                return None
            out = StreamOutput(stamp, self._last.T_world_link, self._last.velocity_m_s,
                               np.eye(6) * LOST_COVARIANCE, False, "failed: " + s.last_error, ms)
        else:
            out = StreamOutput(stamp, result.T_world_imu, np.asarray(result.velocity_m_s, float),
                               np.asarray(result.covariance, float), ok, result.reason or ("" if ok else "lost"), ms,
                               result.smoother_restarted)
        self._last = out
        return out
