"""Shared helpers of the driver rostests: the mocked bus's control socket, the driver's topics and
diagnostics, waiting on conditions with timeouts (never fixed sleeps)."""
import threading
import time
import unittest

import rospy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from sensor_msgs.msg import JointState
from std_srvs.srv import SetBool, Trigger

from snake_autonomy.msg import GaitCommand
from snake_autonomy.sim.mock_servo_bus import MockBusClient
from snake_autonomy.srv import RebootServo


def diagnostic_values(msg, name_suffix):
    """key -> value of the first status of a DiagnosticArray whose name ends with name_suffix (None if
    the message has no such status)."""
    return next(({kv.key: kv.value for kv in st.values} for st in msg.status if st.name.endswith(name_suffix)),
                None)


def wait_for(cond, timeout, what):
    deadline = time.monotonic() + timeout
    while True:
        value = cond()
        if value:
            return value
        if time.monotonic() > deadline or rospy.is_shutdown():
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.02)


class DriverHarness:
    """Publishes base poses (50 Hz while `pose_on`), re-sends the last gait command every second as
    the mission node does (the driver's command lifetime, command_timeout_s; stop_heartbeat() ends
    it), listens to joint_states, com_pose and /diagnostics, and talks to the mocked bus through its
    control socket."""
    HEARTBEAT_PERIOD_S = 1.0

    def __init__(self, port):
        self.lock = threading.Lock()
        self.diag = {}            # status name -> DiagnosticStatus (latest)
        self.joint_states = None
        self.joint_count = 0
        self.com_count = 0
        self.pose_on = True
        self._beat = None         # the command re-sent every HEARTBEAT_PERIOD_S
        self.mock = wait_for(lambda: self._connect(port + ".ctl"), 20.0, "the mocked bus's control socket")
        self.gait_pub = rospy.Publisher("gait_command", GaitCommand, queue_size=10)
        self.pose_pub = rospy.Publisher("base_pose", PoseWithCovarianceStamped, queue_size=10)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self._on_diag)
        rospy.Subscriber("joint_states", JointState, self._on_joints)
        rospy.Subscriber("com_pose", PoseStamped, self._on_com)
        threading.Thread(target=self._pose_loop, daemon=True).start()
        rospy.wait_for_service("driver/enable_torque", 20.0)
        self.enable = rospy.ServiceProxy("driver/enable_torque", SetBool)
        self.hold = rospy.ServiceProxy("driver/hold", Trigger)
        self.reboot = rospy.ServiceProxy("driver/reboot_servo", RebootServo)
        wait_for(lambda: self.gait_pub.get_num_connections() > 0, 10.0, "the driver to subscribe gait_command")

    @staticmethod
    def _connect(path):
        try:
            return MockBusClient(path)
        except OSError:
            return None

    def _on_diag(self, msg):
        with self.lock:
            for s in msg.status:
                self.diag[s.name] = s

    def _on_joints(self, msg):
        with self.lock:
            self.joint_states = msg
            self.joint_count += 1

    def _on_com(self, _msg):
        with self.lock:
            self.com_count += 1

    def _pose_loop(self):
        rate = rospy.Rate(50)
        next_beat = time.monotonic()
        while not rospy.is_shutdown():
            try:
                beat = self._beat
                if beat is not None and time.monotonic() >= next_beat:
                    beat.header.stamp = rospy.Time.now()
                    self.gait_pub.publish(beat)
                    next_beat = time.monotonic() + self.HEARTBEAT_PERIOD_S
                if self.pose_on:
                    p = PoseWithCovarianceStamped()
                    p.header.stamp = rospy.Time.now()
                    p.header.frame_id = "odom"
                    p.pose.pose.position.x = 1.0
                    p.pose.pose.orientation.w = 1.0
                    self.pose_pub.publish(p)
            except rospy.ROSException:  # the test is shutting down: topics closed
                return
            rate.sleep()

    # --- diagnostics ---
    def status(self, name):
        with self.lock:
            return self.diag.get(name)

    def value(self, name, key):
        s = self.status(name)
        if s is None:
            return None
        for kv in s.values:
            if kv.key == key:
                return kv.value
        return None

    def wait_diag(self, name, pred, timeout, what):
        """Waits until a fresh status `name` satisfies pred(status); returns it."""
        return wait_for(lambda: (lambda s: s if s is not None and pred(s) else None)(self.status(name)),
                        timeout, what)

    def locomotion(self):
        return self.status("snake_driver: locomotion")

    def state(self):
        return self.value("snake_driver: locomotion", "state")

    # --- commands ---
    def command(self, gait="", heartbeat=True, **vectors):
        """Publishes a gait command; heartbeat: re-send it every second from now on (a command the
        driver refuses should pass heartbeat=False)."""
        msg = GaitCommand()
        msg.header.stamp = rospy.Time.now()
        msg.gait = gait
        for key, value in vectors.items():
            setattr(msg, key, value)
        self.gait_pub.publish(msg)
        if heartbeat:
            self._beat = msg

    def stop_heartbeat(self):
        self._beat = None

    # --- the mock ---
    def goals(self):
        return {int(k): v["goal_ticks"] for k, v in self.mock.call("state").items()}

    def mock_state(self):
        return {int(k): v for k, v in self.mock.call("state").items()}

    def goal_span(self, servo_id, duration_s):
        """max - min of a servo's goal ticks in the mock over duration_s (polled at 50 Hz)."""
        lo, hi = 1 << 30, -(1 << 30)
        end = time.monotonic() + duration_s
        while time.monotonic() < end:
            g = self.goals()[servo_id]
            lo, hi = min(lo, g), max(hi, g)
            time.sleep(0.02)
        return hi - lo

    def wait_frozen(self, servo_id, timeout, window_s=1.0):
        """Waits (up to timeout) until a servo's goals stay put for a whole window_s."""
        return wait_for(lambda: self.goal_span(servo_id, window_s) <= 0, timeout,
                        f"servo {servo_id}'s goals to stay frozen for {window_s} s")

    def wait_moving(self, servo_id, min_span, timeout, window_s=1.5):
        return wait_for(lambda: self.goal_span(servo_id, window_s) >= min_span, timeout,
                        f"servo {servo_id}'s goals to swing over {min_span} ticks")


LOCO = "snake_driver: locomotion"


class DriverTestCase(unittest.TestCase):
    """A rostest case against one driver_node: a harness on the mock's port (param ~port), created
    once the driver holds its posture after start. Subclasses set NODE_NAME."""
    NODE_NAME = "test_driver"
    h = None

    @classmethod
    def setUpClass(cls):
        rospy.init_node(cls.NODE_NAME)
        cls.h = DriverHarness(rospy.get_param("~port"))
        wait_for(lambda: cls.h.state() == "holding", 20.0, "the driver to hold its posture after start")
