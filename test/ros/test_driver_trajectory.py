#!/usr/bin/env python3
"""rostest: driver_node on the mocked servo bus executes driver/joint_trajectory: a valid
trajectory reaches its final posture in joint_states and driver/trajectory_status says done (the
driver then holds it: HoldReason trajectory done); a refused one leaves the posture where it was,
and every reason is on the status topic and in /diagnostics; a planned FBSR raise sent by the mission's
TopicTrajectoryExecutor is followed to its end through the status topic; 50 trajectories sent back to
back each get exactly one final status; one longer than max_trajectory_duration_s is refused.

Tolerance on the final posture: 2 servo ticks (2 x 0.088 deg = 0.0031 rad). The goal is rounded
to a whole tick (<= 0.5 tick), the mock's shafts converge on their goals exponentially (a first-order
lag, no steady-state error), and joint_states carry the present position rounded to a tick (<= 0.5
tick): at most 1 tick once settled, doubled for margin. The test waits for it with a timeout."""
import math
import threading

import rospy
import rostest
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from driver_test_helpers import LOCO, DriverTestCase, wait_for
from snake_autonomy.msg import TrajectoryStatus
from snake_autonomy.nodes.scout_trajectory import TopicTrajectoryExecutor
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.trajectory import driver_velocity_limit, lead_in_s, plan_points
from snake_autonomy.sim.config import servo_torque_limit_nm

TRAJ = "snake_driver: trajectory"
TICK_RAD = 2 * math.pi / 4096
N = 11
B2B = 50           # trajectories sent back to back
# rospy keeps ONE connection per topic and process, shared by every Publisher of the topic; its queue is
# the queue_size in force when the driver connected, and a later Publisher's queue_size does not resize
# it. So driver/joint_trajectory has one Publisher here, made first and sized for the back-to-back
# burst (the driver's own subscriber queue, TrajectoryTopics::kQueueSize): with a queue of 2, a loaded
# machine dropped 8 of 20 messages in the test's process, before the driver.
PUB_QUEUE = 100


def trajectory(frame_id, final_rad, duration_s, names=None):
    msg = JointTrajectory()
    msg.header.frame_id = frame_id
    msg.joint_names = names or [f"joint_{j + 1}" for j in range(N)]
    for fraction in (0.5, 1.0):
        p = JointTrajectoryPoint()
        p.positions = [fraction * q for q in final_rad]
        p.time_from_start = rospy.Duration.from_sec(fraction * duration_s)
        msg.points.append(p)
    return msg


class DriverTrajectory(DriverTestCase):
    NODE_NAME = "test_driver_trajectory"

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        cls.statuses = []
        cls.status_lock = threading.Lock()
        rospy.Subscriber("driver/trajectory_status", TrajectoryStatus, cls._on_status)
        cls.pub = rospy.Publisher("driver/joint_trajectory", JointTrajectory, queue_size=PUB_QUEUE)
        wait_for(lambda: cls.pub.get_num_connections() > 0, 10.0, "the driver to subscribe driver/joint_trajectory")

    @classmethod
    def _on_status(cls, msg):
        with cls.status_lock:
            cls.statuses.append(msg)

    def status_of(self, trajectory_id, phase, timeout):
        def find():
            with self.status_lock:
                return next((s for s in reversed(self.statuses) if s.id == trajectory_id and s.phase == phase), None)
        return wait_for(find, timeout, f"driver/trajectory_status '{trajectory_id}' {phase}")

    def positions(self):
        return list(self.h.joint_states.position)

    def test_1_valid_trajectory_reaches_its_final_posture_and_holds(self):
        h = self.h
        final = [math.radians(20.0 * (-1) ** j) * (j + 1) / N for j in range(N)]
        self.pub.publish(trajectory("lift", final, 2.0))
        self.status_of("lift", "running", 5.0)
        done = self.status_of("lift", "done", 10.0)
        self.assertEqual(done.point_reached, 1)
        self.assertEqual(done.num_points, 2)
        self.assertAlmostEqual(done.duration_s, 2.0)
        wait_for(lambda: max(abs(a - b) for a, b in zip(self.positions(), final)) <= 2 * TICK_RAD, 5.0,
                 "joint_states within 2 ticks of the final posture")
        h.wait_diag(LOCO, lambda s: s.message == "holding" and "trajectory done" in h.value(LOCO, "hold_reason"),
                    5.0, "holding the last point (hold_reason: trajectory done)")
        h.wait_diag(TRAJ, lambda s: h.value(TRAJ, "phase") == "done" and h.value(TRAJ, "id") == "lift", 5.0,
                    "the trajectory diagnostics to say done")

    def test_2_refused_trajectory_leaves_the_posture_and_says_why(self):
        h = self.h
        before_goals = h.goals()
        before = self.positions()
        names = [f"joint_{j + 1}" for j in range(N)]
        names[3] = "joint_99"
        bad = trajectory("bad", [math.radians(120.0)] * N, 2.0, names)
        bad.points[0].positions[5] = float("nan")
        self.pub.publish(bad)
        refused = self.status_of("bad", "refused", 5.0)
        for part in ("joint_names[3]: 'joint_99' is not a joint of this robot", "joint_names: joint_4 is missing",
                     "points[0].positions[5] (joint_6): nan is not finite",
                     "points[1].positions[0] (joint_1): 2.0944 rad outside the joint limits"):
            self.assertIn(part, refused.reason)
        h.wait_diag(TRAJ, lambda s: "joint_99" in (h.value(TRAJ, "last_refusal") or ""), 5.0,
                    "the refusal in the trajectory diagnostics")
        self.assertEqual(h.goal_span(2, 1.0), 0)
        self.assertEqual(h.goals(), before_goals)
        self.assertLessEqual(max(abs(a - b) for a, b in zip(self.positions(), before)), TICK_RAD)
        self.assertEqual(h.value(LOCO, "state"), "holding")

    def test_3_planned_raise_through_the_mission_executor(self):
        planner = build_planner("cobra", torque_limit_nm=servo_torque_limit_nm())[0]
        plan = planner.plan(max_active=2, seed=0)
        now = self.positions()
        traj = plan_points(plan, 0.05, lead_in_s(now, planner.chain.q_lying, driver_velocity_limit()))
        executor = TopicTrajectoryExecutor()
        wait_for(lambda: executor.pub.get_num_connections() > 0, 10.0, "the executor's publisher to connect")
        self.assertEqual(executor.execute(traj, rospy.get_time()), "")
        self.assertFalse(executor.finished(rospy.get_time()))
        wait_for(lambda: executor.finished(rospy.get_time()), traj.duration_s + 10.0, "the raise to finish")
        self.assertEqual(executor.aborted, "")
        final = traj.final_positions_rad
        wait_for(lambda: max(abs(a - b) for a, b in zip(self.positions(), final)) <= 2 * TICK_RAD, 5.0,
                 "joint_states within 2 ticks of the plan's last posture")
        # A refused one ends at once, with the driver's reasons.
        traj.points[0] = traj.points[0].__class__(-1.0, traj.points[0].positions_rad, traj.points[0].velocities_rad_s)
        self.assertEqual(executor.execute(traj, rospy.get_time()), "")
        wait_for(lambda: executor.finished(rospy.get_time()), 5.0, "the refusal")
        self.assertIn("refused", executor.aborted)
        self.assertIn("points[0].time_from_start: -1 s, must be > 0", executor.aborted)

    def test_4_back_to_back_trajectories_each_end_exactly_once(self):
        """B2B trajectories sent back to back: every one gets exactly one final status:
        the last is done, each earlier one is superseded and names a later one that replaced it; none is
        lost on the way (the driver's queue, its diagnostics say 0 lost)."""
        h = self.h
        now = self.positions()
        ids = [f"b2b-{k}" for k in range(B2B)]
        for k, trajectory_id in enumerate(ids):  # small moves from the present posture, 2 s each
            msg = JointTrajectory()
            msg.header.frame_id = trajectory_id
            msg.joint_names = [f"joint_{j + 1}" for j in range(N)]
            for t in (1.0, 2.0):
                p = JointTrajectoryPoint()
                p.positions = [q - math.copysign(0.002 * (k + 1) * t, q) for q in now]  # towards 0: inside the limits
                p.time_from_start = rospy.Duration.from_sec(t)
                msg.points.append(p)
            self.pub.publish(msg)
        ended = ("done", "aborted", "refused")

        def finals():
            with self.status_lock:
                return [s for s in self.statuses if s.id in ids and s.phase in ended]
        try:
            # the statuses come within about 2.5 s (the last runs 2 s); the bound is generous for a loaded machine
            wait_for(lambda: {s.id for s in finals()} == set(ids), 45.0, f"a final status for each of the {B2B}")
        except AssertionError as e:     # say which ended and which did not, every status seen of them, and
            with self.status_lock:      # how many messages never reached the driver (header.seq gaps)
                seen = [(s.id, s.phase, s.abort) for s in self.statuses if s.id in ids]
            missing = sorted(set(ids) - {s.id for s in finals()})
            raise AssertionError(f"{e}: no final status for {missing}; statuses seen: {seen}; messages lost "
                                 f"before the driver: {h.value(TRAJ, 'lost_before_driver')}") from None
        rospy.sleep(1.0)  # a duplicate would come within the next publisher cycles
        got = finals()
        self.assertEqual(sorted(s.id for s in got), sorted(ids), "exactly one final status each")
        by_id = {s.id: s for s in got}
        self.assertEqual(by_id[ids[-1]].phase, "done")
        for k, trajectory_id in enumerate(ids[:-1]):
            s = by_id[trajectory_id]
            self.assertEqual((s.phase, s.abort), ("aborted", "superseded"), s)
            self.assertIn(s.superseded_by, ids[k + 1:], s)
            self.assertGreater(s.superseded_by_sequence, s.sequence, s)
            self.assertIn(f"superseded by '{s.superseded_by}'", s.reason)
        self.assertEqual(len({s.sequence for s in got}), B2B, "one sequence number each")
        h.wait_diag(TRAJ, lambda s: h.value(TRAJ, "lost_before_driver") == "0"
                    and h.value(TRAJ, "final_statuses_dropped") == "0", 5.0, "nothing lost, in the diagnostics")

    def test_5_a_trajectory_longer_than_the_maximum_duration_is_refused(self):
        """A point at 2^31 s used to be accepted and "run 68 years": refused, with the rule."""
        msg = trajectory("forever", self.positions(), 2.0)
        msg.points[-1].time_from_start = rospy.Duration(2 ** 31 - 1)  # the largest a Duration carries
        self.pub.publish(msg)
        refused = self.status_of("forever", "refused", 5.0)
        self.assertIn("longer than max_trajectory_duration_s 600 s", refused.reason)


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "driver_trajectory", DriverTrajectory)
