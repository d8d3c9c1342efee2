#!/usr/bin/env python3
"""rostest: a mission whose legs alternate between the waypoint tracker and the planner, through ROS
(sim.launch world:=... mission:=...: mission node and planner_node side by side, the simulated COBRA).

Checks: the mission ends done with every waypoint reached; its navigate_to leg went to planner_node as
one move_base goal that SUCCEEDED; every gait_command is attributed to its publisher (the connection
header's callerid): while the goal is active only planner_node's reach the driver, and among them the
rectilinear gait; before the goal and after its end (plus one planner tick: the stop it sends when the
goal ends) only the mission node's, which sidewinds both before and after the leg; the simulated
robot never rolls over (sim_node's diagnostics: the hand-overs settle in the hold, nodes/mission_nav_leg.py).
"""
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from move_base_msgs.msg import MoveBaseActionGoal, MoveBaseActionResult
from snake_autonomy.msg import GaitCommand
from std_msgs.msg import String

from mission_test_helpers import wait_for

MISSION_S = 120.0        # measured 58 s: tracker 5 s, settle 4 s, the leg 25 s, settle 4 s, tracker 20 s
PLANNER_TICK_S = 0.5     # planner_node's ~rate_hz 2: its stop on the goal's end may arrive this late
SETTLE_MARGIN_S = 0.3    # the mission node's last settle hold and its goal travel on two connections


def sim_node_values(timeout_s: float = 10.0) -> dict:
    """The values of sim_node's next status on /diagnostics ("... simulated robot"); {} if none came."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not rospy.is_shutdown():
        array = rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=timeout_s)
        ours = [st for st in array.status if st.name.endswith("simulated robot")]
        if ours:
            return {kv.key: kv.value for kv in ours[0].values}
    return {}


class SimMissionNavTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_mission_nav_test")
        cls.lock = threading.Lock()
        cls.commands = []                      # (receive time, callerid, gait)
        cls.goals, cls.results = [], []        # (receive time, message)
        cls.state = ""
        rospy.Subscriber("gait_command", GaitCommand, cls.on_cmd, queue_size=50)
        rospy.Subscriber("move_base/goal", MoveBaseActionGoal, cls.on_goal, queue_size=5)
        rospy.Subscriber("move_base/result", MoveBaseActionResult, cls.on_result, queue_size=5)
        rospy.Subscriber("mission/state", String, cls.on_state, queue_size=5)

    @classmethod
    def on_cmd(cls, msg):
        with cls.lock:
            cls.commands.append((time.monotonic(), msg._connection_header["callerid"], msg.gait))

    @classmethod
    def on_goal(cls, msg):
        with cls.lock:
            cls.goals.append((time.monotonic(), msg))

    @classmethod
    def on_result(cls, msg):
        with cls.lock:
            cls.results.append((time.monotonic(), msg))

    @classmethod
    def on_state(cls, msg):
        with cls.lock:
            cls.state = msg.data

    def test_the_legs_alternate_and_one_node_commands_at_a_time(self):
        wait_for(lambda: self.state.startswith("running"), 90, "the mission running")
        t0 = time.monotonic()
        wait_for(lambda: not self.state.startswith("running"), MISSION_S, "the mission's end")
        rospy.loginfo(f"sim_mission_nav: mission ran {time.monotonic() - t0:.0f} s: {self.state}")
        time.sleep(1.0)
        self.assertTrue(self.state.startswith("done"), self.state)
        self.assertIn("every waypoint reached", self.state)
        with self.lock:
            commands, goals, results = list(self.commands), list(self.goals), list(self.results)
        self.assertEqual(len(goals), 1, "one move_base goal: the navigate_to leg")
        self.assertEqual(len(results), 1, "one move_base result")
        (t_goal, goal), (t_end, result) = goals[0], results[0]
        self.assertEqual(result.status.status, result.status.SUCCEEDED, result.status.text)
        p = goal.goal.target_pose.pose.position
        self.assertEqual((p.x, p.y, goal.goal.target_pose.header.frame_id), (0.25, 0.6, "map"))
        publishers = {who for _, who, _ in commands}
        self.assertEqual(publishers, {"/mission", "/planner"}, "gait_command's publishers")
        before = [(who, g) for t, who, g in commands if t < t_goal - SETTLE_MARGIN_S]
        during = [(who, g) for t, who, g in commands if t_goal + SETTLE_MARGIN_S < t < t_end]
        after = [(who, g) for t, who, g in commands if t > t_end + PLANNER_TICK_S]
        rospy.loginfo(f"sim_mission_nav: commands before the leg {len(before)}, during {len(during)}, "
                      f"after {len(after)}; the leg {t_end - t_goal:.0f} s")
        self.assertEqual({who for who, _ in during}, {"/planner"}, "only planner_node commands during the leg")
        self.assertGreaterEqual(sum(g == "rectilinear" for _, g in during), 5, "the planner drove")
        self.assertEqual({who for who, _ in before}, {"/mission"}, "only the mission node before the leg")
        self.assertEqual({who for who, _ in after}, {"/mission"}, "only the mission node after the leg")
        self.assertIn("sidewind", {g for _, g in before})
        self.assertIn("sidewind", {g for _, g in after})
        sim = sim_node_values()
        rospy.loginfo(f"sim_mission_nav: largest tilt {sim.get('max_tilt_deg')} deg")
        self.assertEqual(sim.get("rolled_over"), "False", f"sim_node: {sim}")
        last = [g for _, who, g in commands if who == "/planner"][-1]
        self.assertIn(last, ("hold", "hold_curve"), "the planner's last command: the stop as its goal ended")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_mission_nav", SimMissionNavTest)
