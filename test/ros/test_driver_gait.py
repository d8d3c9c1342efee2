#!/usr/bin/env python3
"""rostest: driver_node on the mocked servo bus: joint_states flow, a commanded gait reaches the
mock's goal positions, a refused command leaves the gait running, a stale pose holds locomotion
and fresh poses resume it, driver/hold freezes the goals, and when the commanding process is
killed the driver holds within its command lifetime (command_timeout_s)."""
import math
import os
import signal
import subprocess
import time

import rostest

from driver_test_helpers import LOCO, DriverTestCase, wait_for

# One sidewinding cycle (config/gaits.yaml: 0.35 Hz, 2.86 s) and a little more: a window this long sees
# the wave's whole swing whatever its phase. A shorter one can sit on a crest: over 1.5 s a 512-tick
# swing can span only 552 ticks, over 0.5 s a wave still decaying can span under 20.
CYCLE_S = 3.0


class DriverGait(DriverTestCase):
    NODE_NAME = "test_driver_gait"

    def test_1_gait_reaches_the_mock(self):
        h = self.h
        names = wait_for(lambda: h.joint_states and list(h.joint_states.name), 5.0, "joint_states")
        self.assertEqual(names, [f"joint_{i}" for i in range(1, 12)])
        # The mock's servos start with the factory Return Delay Time (500 us); the driver wrote 0
        # over Protocol 2.0 before enabling torque.
        self.assertEqual({s["return_delay_us"] for s in h.mock_state().values()}, {0})
        h.command("sidewind")
        h.wait_diag(LOCO, lambda s: s.message == "running", 5.0, "running")
        # Yaw joint 2 swings about +-45 deg = +-512 ticks once the amplitude has grown.
        h.wait_moving(2, 600, 12.0)
        # The mock's servos follow their goals: joint_states report the motion, in radians.
        positions = []
        wait_for(lambda: positions.append(h.joint_states.position[1]) or
                 (max(positions) - min(positions) > math.radians(40)), 5.0, "joint_2 to move in joint_states")
        self.assertEqual(h.value(LOCO, "gait"), "sidewind")

    def test_2_refused_command_leaves_the_gait_running(self):
        h = self.h
        refused = int(h.value(LOCO, "commands_refused"))
        h.command("sidewind", heartbeat=False, amplitude=[0.1, 0.2, 0.3])
        h.command("no_such_gait", heartbeat=False)
        h.command("sidewind", heartbeat=False, omega=[float("nan")] * 11)
        s = h.wait_diag(LOCO, lambda s: int(h.value(LOCO, "commands_refused")) >= refused + 3, 5.0,
                        "three refusals in the diagnostics")
        self.assertIn("omega[0] (joint_1): nan", h.value(LOCO, "last_refusal"))
        self.assertEqual(s.message, "running")
        self.assertEqual(h.value(LOCO, "gait"), "sidewind")
        self.assertGreater(h.goal_span(2, CYCLE_S), 600)

    def test_3_stale_pose_holds_and_fresh_poses_resume(self):
        h = self.h
        h.pose_on = False
        self.addCleanup(setattr, h, "pose_on", True)  # a failure here must not starve the later tests of poses
        h.wait_diag(LOCO, lambda s: s.message == "base pose stale: locomotion held", 5.0, "the stale-pose hold")
        # The waves decay (critically damped, gamma 2/s: about 3 s from the full swing to 20 ticks) and the
        # goals come to rest; no com_pose meanwhile. Whole-cycle windows: the decay never overshoots, so once
        # one cycle spans <= 20 ticks every later one does.
        wait_for(lambda: h.goal_span(2, CYCLE_S) <= 20, 20.0, "the goals to come to rest")
        count = h.com_count
        self.assertLessEqual(h.goal_span(2, CYCLE_S), 20)
        self.assertEqual(h.com_count, count, "com_pose published from a stale pose")
        h.pose_on = True
        h.wait_diag(LOCO, lambda s: s.message == "running", 5.0, "running again")
        wait_for(lambda: h.com_count > count, 5.0, "com_pose again")
        h.wait_moving(2, 600, 12.0)

    def test_4_hold_service_freezes_the_goals(self):
        h = self.h
        h.stop_heartbeat()  # the next command would resume locomotion
        r = h.hold()
        self.assertTrue(r.success, r.message)
        h.wait_diag(LOCO, lambda s: s.message == "holding", 5.0, "holding")
        self.assertLessEqual(h.goal_span(2, 1.0), 0)

    def test_5_killed_commander_holds_within_the_command_timeout(self):
        """SIGKILL the node that commands the gait; the driver stops and holds
        within command_timeout_s (+ one command period + a diagnostics period), says why, and the
        mock's goals stop changing; the next command resumes."""
        h = self.h
        h.stop_heartbeat()
        timeout_s = float(h.value(LOCO, "command_timeout_s"))
        commander = subprocess.Popen(["rostopic", "pub", "-r", "1", "gait_command", "snake_autonomy/GaitCommand",
                                      "{gait: sidewind}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            h.wait_diag(LOCO, lambda s: s.message == "running", 10.0, "running on the commander's commands")
            h.wait_moving(2, 600, 12.0)
            # Running past the lifetime: the commander's repeats keep it alive.
            self.assertGreater(h.goal_span(2, timeout_s + 0.5), 600)
            self.assertEqual(h.state(), "running")
        finally:
            os.kill(commander.pid, signal.SIGKILL)
            commander.wait()
        killed = time.monotonic()
        s = h.wait_diag(LOCO, lambda s: s.message.startswith("holding: no gait command"), timeout_s + 3.0,
                        "the hold after the command lifetime")
        elapsed = time.monotonic() - killed
        self.assertLessEqual(elapsed, timeout_s + 1.0 + 0.5 + 0.5)  # lifetime + command period + diag period
        self.assertIn("command_timeout_s", s.message)
        self.assertEqual(h.value(LOCO, "state"), "holding")
        self.assertLessEqual(h.goal_span(2, 1.0), 0)
        h.command("sidewind")
        h.wait_diag(LOCO, lambda s: s.message == "running", 5.0, "running again on the next command")
        h.wait_moving(2, 600, 12.0)


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "driver_gait", DriverGait)
