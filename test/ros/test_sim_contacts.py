#!/usr/bin/env python3
"""rostest: a contact of the simulated robot with an obstacle reaches rviz. sim_node alone in
test/ros/worlds/contact.yaml (two cylinders against the lying robot's side): sim/contact_markers
(MarkerArray, latched) holds a sphere per contact episode, in the world frame, at the touching link
beside its cylinder, its text naming link and obstacle; a subscriber that comes after the contact
still gets it (latched); "obstacle_contacts" on /diagnostics counts it."""
import math
import threading
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from visualization_msgs.msg import Marker, MarkerArray

from snake_autonomy.runs.recorded_topics import CONTACT_TEXT

from driver_test_helpers import wait_for

OBSTACLES = {"obstacle_0": (-0.15, 0.08), "obstacle_1": (0.15, 0.08)}     # test/ros/worlds/contact.yaml
NEAR_M = 0.05 + 0.10                 # a link's centre beside its cylinder: radius + about a link's half length


class SimContactsTest(unittest.TestCase):
    def test_a_contact_appears_as_a_marker_and_in_the_diagnostics(self):
        rospy.init_node("sim_contacts_test")
        lock, got = threading.Lock(), {}

        def keep(key):
            def on(msg):
                with lock:
                    got[key] = msg
            return on

        rospy.Subscriber("sim/contact_markers", MarkerArray, keep("first"), queue_size=1)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag(lock, got), queue_size=10)
        # MuJoCo's model takes up to a minute on a loaded machine; the contact comes with the first steps
        array = wait_for(lambda: got.get("first"), 120.0, "a first sim/contact_markers")
        self.assertGreaterEqual(len(array.markers), 1)
        for i, m in enumerate(array.markers):
            self.assertEqual((m.type, m.action, m.id, m.ns), (Marker.SPHERE, Marker.ADD, i, "contacts"))
            self.assertEqual(m.header.frame_id, rospy.get_param("/sim/world_frame"))
            link, _, obstacle = m.text.partition(CONTACT_TEXT)
            self.assertIn(obstacle, OBSTACLES, m.text)
            self.assertTrue(link.startswith(("link_", "base_link")), m.text)
            ox, oy = OBSTACLES[obstacle]
            d = math.hypot(m.pose.position.x - ox, m.pose.position.y - oy)
            self.assertLess(d, NEAR_M, (m.text, m.pose.position))
            self.assertGreater(m.color.a, 0.0)

        # latched: a subscriber that comes now gets every episode so far
        rospy.Subscriber("sim/contact_markers", MarkerArray, keep("late"), queue_size=1)
        late = wait_for(lambda: got.get("late"), 10.0, "the latched sim/contact_markers")
        self.assertGreaterEqual(len(late.markers), len(array.markers))
        counted = wait_for(lambda: got.get("contacts"), 30.0, "obstacle_contacts on /diagnostics")
        self.assertGreaterEqual(counted, len(array.markers))

    @staticmethod
    def on_diag(lock, got):
        def on(msg):
            for s in msg.status:
                for kv in s.values:
                    if kv.key == "obstacle_contacts" and int(kv.value) > 0:
                        with lock:
                            got["contacts"] = int(kv.value)
        return on


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_contacts", SimContactsTest)
