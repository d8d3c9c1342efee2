"""Shared by the mission node's rostests: a fake driver (a kinematic CoM that obeys gait_command,
published on com_pose at 50 Hz: sidewind 0.5 m/s along the yaw, turns 30 deg/s, hold stops) and
wait_for (a condition with a timeout)."""
import math
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped

from snake_autonomy.msg import GaitCommand

from driver_test_helpers import wait_for  # noqa: F401 (the one helper)


class FakeDriver:
    def __init__(self):
        self.lock = threading.Lock()
        self.x = self.y = self.yaw = 0.0
        self.gait, self.publishing = "hold", True
        self.commands = []
        self.pub = rospy.Publisher("com_pose", PoseStamped, queue_size=10)
        self.pub_diag = rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=10)
        rospy.Subscriber("gait_command", GaitCommand, self.on_cmd)
        self.stopped = False            # set by rospy's first shutdown hooks, before it closes the topics
        rospy.on_shutdown(self.stop)
        threading.Thread(target=self.loop, daemon=True).start()

    def publish_locomotion(self, level, message, repeats=3):
        """The driver's "snake_driver: locomotion" status (level 2 = ERROR: a fault), as its updater does."""
        for _ in range(repeats):
            msg = DiagnosticArray()
            msg.header.stamp = rospy.Time.now()
            msg.status.append(DiagnosticStatus(level=level, name="snake_driver: locomotion", message=message,
                                               hardware_id="snake driver"))
            self.pub_diag.publish(msg)
            time.sleep(0.2)

    def stop(self):
        self.stopped = True

    def on_cmd(self, msg):
        with self.lock:
            self.gait = msg.gait
            self.commands.append(msg)

    def loop(self):
        dt = 0.02
        while not rospy.is_shutdown() and not self.stopped:
            with self.lock:
                if self.gait == "sidewind":
                    self.x += 0.5 * dt * math.cos(self.yaw)
                    self.y += 0.5 * dt * math.sin(self.yaw)
                elif self.gait.endswith("turn_left"):
                    self.yaw += math.radians(30) * dt
                elif self.gait.endswith("turn_right"):
                    self.yaw -= math.radians(30) * dt
                publishing = self.publishing
                m = PoseStamped()
                m.header.stamp = rospy.Time.now()
                m.header.frame_id = "odom"
                m.pose.position.x, m.pose.position.y = self.x, self.y
                m.pose.orientation.z, m.pose.orientation.w = math.sin(self.yaw / 2), math.cos(self.yaw / 2)
            if publishing:
                try:
                    self.pub.publish(m)
                except (rospy.ROSException, ValueError):
                    # the test process ended between the check above and the publish: rospy closed the
                    # topic at exit ("topic was closed during publish()", a traceback in the log; by then
                    # rospy.is_shutdown() may read a module torn down, so the hook's flag decides)
                    if self.stopped:
                        return
                    raise
            time.sleep(dt)
