#!/usr/bin/env python3
"""rostest: ~on_driver_fault pause. A driver fault pauses the running mission (hold, state "paused"),
the driver's recovery does not restart it, mission/resume is refused while the fault lasts and goes
on from the same waypoint after it."""
import time
import unittest

import rospy
import rostest
from std_msgs.msg import String
from std_srvs.srv import Trigger

from snake_autonomy.msg import TrackingStatus
from snake_autonomy.srv import LoadMission

from mission_test_helpers import FakeDriver, wait_for


class MissionPauseTest(unittest.TestCase):
    def test_a_driver_fault_pauses_until_resume(self):
        rospy.init_node("mission_pause_test")
        statuses, state = [], [""]
        rospy.Subscriber("tracking_status", TrackingStatus, statuses.append)
        rospy.Subscriber("mission/state", String, lambda m: state.__setitem__(0, m.data))
        driver = FakeDriver()
        for s in ("mission/load", "mission/start", "mission/resume"):
            rospy.wait_for_service(s, 20)
        resume = rospy.ServiceProxy("mission/resume", Trigger)
        with driver.lock:
            driver.x = -3.0
        self.assertTrue(rospy.ServiceProxy("mission/load", LoadMission)(rospy.get_param("~mission_file")).success)
        self.assertFalse(resume().success)                       # nothing paused
        self.assertTrue(rospy.ServiceProxy("mission/start", Trigger)().success)
        wait_for(lambda: driver.gait == "sidewind", 10, "sidewinding")
        driver.publish_locomotion(2, "fault: servo 3 (joint_3) stopped answering")
        wait_for(lambda: driver.gait == "hold", 3, "hold after the fault")
        wait_for(lambda: state[0].startswith("paused: straight: driver fault"), 3, "state paused")
        r = resume()
        self.assertFalse(r.success)
        self.assertIn("still reports a fault", r.message)
        driver.publish_locomotion(0, "holding")                  # recovered: the mission stays paused
        time.sleep(1.5)
        self.assertEqual(driver.gait, "hold")
        self.assertTrue(statuses[-1].note.startswith("paused: driver fault"), statuses[-1].note)
        self.assertTrue(resume().success)
        wait_for(lambda: driver.gait == "sidewind", 10, "sidewinding after the resume")
        self.assertTrue(state[0].startswith("running"))
        self.assertEqual(statuses[-1].waypoint_index, 0)


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "mission_pause", MissionPauseTest)
