"""estimation/vio_stream.py: colour and depth paired by stamp, the IMU samples up to a frame fed before
it, a frame waiting for its IMU sample at most imu_wait_s, a newer pair replacing an unprocessed one,
an exception inside the fusion counted (failed) and published as lost at the last pose, lost
intervals opened and closed, the first frame held until the IMU spans the rest window. The fusion is a
stand-in that records its calls; but for the rest window's test, the rest window is off
(fusion.rest_calibration_s 0)."""
import numpy as np
import pytest

from snake_autonomy.estimation.rest_calibration import GyroCalibration
from snake_autonomy.estimation.vio_fusion import FusedResult, FusionParams
from snake_autonomy.estimation.visual_odometry import LOST, LOST_COVARIANCE, OK
from snake_autonomy.estimation.vio_stream import VioStream, lost_cause


class FakeFusion:
    def __init__(self):
        self.calls, self.fail_at, self.lost_at, self.restart_at = [], set(), set(), set()
        self.calibration = None

    def add_imu(self, t, g, a):
        self.calls.append(("imu", t))

    def add_frame(self, rgb, depth, stamp):
        self.calls.append(("frame", stamp))
        if stamp in self.fail_at:
            raise RuntimeError("indeterminate system")
        T = np.eye(4)
        T[0, 3] = stamp
        lost = stamp in self.lost_at
        cov = np.eye(6) * (LOST_COVARIANCE if lost else 1e-4)
        reason = "IMU gate: the visual pose is 0.2 m, 3.0 deg from the IMU's prediction" if lost else ""
        return FusedResult(stamp, T, T, np.zeros(3), cov, cov, LOST if lost else OK, reason, None,
                           smoother_restarted=stamp in self.restart_at)


class Clock:
    t = 0.0

    def __call__(self):
        return self.t


@pytest.fixture
def stream():
    return make_stream(0.0)


def make_stream(rest_s):
    clock = Clock()
    s = VioStream(np.diag([300.0, 300.0, 1.0]), np.eye(4), fusion_params=FusionParams(rest_calibration_s=rest_s),
                  imu_wait_s=0.1, clock=clock)
    s.fusion = FakeFusion()
    return s, clock


def frame(s, t):
    s.add_colour(t, np.zeros((4, 4, 3), np.uint8))
    s.add_depth(t, np.zeros((4, 4), np.float32))


def test_a_frame_waits_for_its_imu_then_takes_the_samples_up_to_it(stream):
    s, clock = stream
    for k in range(5):
        s.add_imu(0.005 * k, np.zeros(3), np.zeros(3))
    frame(s, 0.03)
    assert s.step() is None                      # the IMU has not reached 0.03 yet
    s.add_imu(0.03, np.zeros(3), np.zeros(3))
    s.add_imu(0.035, np.zeros(3), np.zeros(3))
    out = s.step()
    assert out.ok and out.stamp == 0.03 and out.T_world_link[0, 3] == 0.03
    assert s.fusion.calls == [("imu", 0.005 * k) for k in range(5)] + [("imu", 0.03), ("frame", 0.03)]
    frame(s, 0.1)
    clock.t = 0.05
    assert s.step() is None
    clock.t = 0.2                                # waited imu_wait_s: processed with what there is
    assert s.step().stamp == 0.1 and s.fusion.calls[-2:] == [("imu", 0.035), ("frame", 0.1)]


def test_pairs_by_stamp_and_a_newer_pair_replaces_an_unprocessed_one(stream):
    s, clock = stream
    s.add_imu(0.0, np.zeros(3), np.zeros(3))
    s.add_imu(10.0, np.zeros(3), np.zeros(3))
    s.add_colour(1.0, np.zeros((4, 4, 3), np.uint8))
    s.add_depth(1.1, np.zeros((4, 4), np.float32))     # not the colour's stamp: no frame
    assert s.step() is None
    frame(s, 1.2)
    frame(s, 1.3)
    assert s.step().stamp == 1.3 and s.stats.dropped == 1 and s.step() is None


def test_a_failing_frame_is_counted_and_published_lost_at_the_last_pose(stream):
    s, clock = stream
    s.add_imu(0.0, np.zeros(3), np.zeros(3))
    s.add_imu(10.0, np.zeros(3), np.zeros(3))
    s.fusion.fail_at = {0.2}
    s.fusion.lost_at = {0.3}
    outs = []
    for t in (0.1, 0.2, 0.3, 0.4):
        frame(s, t)
        outs.append(s.step())
    assert [o.ok for o in outs] == [True, False, False, True]
    assert outs[1].T_world_link[0, 3] == 0.1 and np.all(np.diag(outs[1].covariance) == LOST_COVARIANCE)
    assert "RuntimeError: indeterminate system" in outs[1].reason
    st = s.stats
    assert (st.frames, st.tracked, st.lost, st.failed) == (4, 2, 2, 1)
    assert st.lost_intervals == [(0.2, 0.4)] and not st.lost_now()
    summary = st.summary()
    assert summary["lost_intervals"] == 1 and summary["lost_s_total"] == pytest.approx(0.2)
    # lost frames counted by cause (the reason without its figures), a failure as "failed"
    assert st.lost_causes == {"failed": 1, "IMU gate: the visual pose is": 1}
    assert summary["lost_causes"] in ("1 failed; 1 IMU gate: the visual pose is",
                                      "1 IMU gate: the visual pose is; 1 failed")
    assert lost_cause("visual odometry lost: too few inliers: 12 (min_inliers 20)") == \
        "visual odometry lost: too few inliers"


def test_a_failure_before_any_estimate_publishes_nothing(stream):
    s, clock = stream
    s.add_imu(0.0, np.zeros(3), np.zeros(3))
    s.add_imu(10.0, np.zeros(3), np.zeros(3))
    s.fusion.fail_at = {0.1}
    frame(s, 0.1)
    assert s.step() is None and s.stats.failed == 1 and s.stats.lost_now()


def test_a_first_frame_without_imu_samples_before_it_is_dropped_not_failed(stream):
    s, clock = stream
    s.add_imu(1.0, np.zeros(3), np.zeros(3))
    frame(s, 0.5)                               # the IMU started after it: nothing to level on
    assert s.step() is None and s.stats.dropped == 1 and s.stats.failed == 0 and s.fusion.calls == []
    s.add_imu(1.1, np.zeros(3), np.zeros(3))
    frame(s, 1.05)
    assert s.step().ok and s.fusion.calls == [("imu", 1.0), ("frame", 1.05)]


def test_smoother_restarts_are_counted_by_the_results_flag_not_its_reason(stream):
    s, clock = stream
    s.add_imu(0.0, np.zeros(3), np.zeros(3))
    s.add_imu(10.0, np.zeros(3), np.zeros(3))
    s.fusion.restart_at = {0.2, 0.4}
    s.fusion.lost_at = {0.3}                     # lost, its reason not about a restart
    outs = []
    for t in (0.1, 0.2, 0.3, 0.4):
        frame(s, t)
        outs.append(s.step())
    assert [o.smoother_restarted for o in outs] == [False, True, False, True]
    assert s.stats.restarts == 2
    assert s.stats.summary()["restarts"] == 2


def test_the_first_frame_waits_until_the_imu_spans_the_rest_window_then_reports_the_calibration():
    """fusion.rest_calibration_s 1: frames before the IMU samples reach 1 s back are held (waiting, not
    dropped, their samples kept for the fusion); the first frame with the window behind it gets every
    sample of the window, and the fusion's calibration is in the summary."""
    s, clock = make_stream(1.0)
    for k in range(301):                         # 1.5 s of IMU from t = 0
        s.add_imu(0.005 * k, np.zeros(3), np.zeros(3))
    for t in (0.5, 0.9):
        frame(s, t)
        assert s.step() is None
    assert s.stats.waiting == 2 and s.stats.dropped == 0 and s.fusion.calls == []
    s.fusion.calibration = GyroCalibration(np.zeros(3), 1e-4, True, "calibrated at rest: gyro mean ...")
    frame(s, 1.2)
    out = s.step()
    assert out.ok and out.stamp == 1.2 and s.stats.frames == 1
    imu = [t for kind, t in s.fusion.calls if kind == "imu"]
    assert imu[0] <= 0.2 and imu[-1] == pytest.approx(1.2) and s.fusion.calls[-1] == ("frame", 1.2)
    assert s.stats.summary()["gyro_calibration"].startswith("calibrated at rest")
    frame(s, 1.3)                                 # later frames do not wait
    assert s.step().stamp == 1.3 and s.stats.waiting == 2
