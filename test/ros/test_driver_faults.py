#!/usr/bin/env python3
"""rostest: driver_node on the mocked servo bus, with faults injected through the mock's control
socket: CRC errors and dropped/truncated replies are counted and the driver carries on; a servo
that stops answering, a hardware error and the pty closing each stop locomotion (hold: goals
frozen, torque stays on), say why in /diagnostics, and recover through the services."""
import rostest

from driver_test_helpers import LOCO, DriverTestCase

BUS = "snake_driver: bus"


def servo(i):
    return f"snake_driver: servo {i} (joint_{i})"


class DriverFaults(DriverTestCase):
    NODE_NAME = "test_driver_faults"

    def run_gait(self):
        self.h.command("sidewind")
        self.h.wait_diag(LOCO, lambda s: s.message == "running", 5.0, "running")

    def recover(self):
        r = self.h.enable(True)
        self.assertTrue(r.success, r.message)
        self.h.wait_diag(LOCO, lambda s: s.level == 0 and s.message in ("holding", "running"), 5.0, "recovered")

    def test_1_crc_errors_are_counted_and_the_loop_goes_on(self):
        h = self.h
        self.run_gait()
        h.mock.call("inject", kind="corrupt_crc", ids=[3], count=5)
        h.wait_diag(servo(3), lambda s: int(h.value(servo(3), "crc_errors")) >= 5, 5.0, "5 CRC errors on servo 3")
        self.assertGreaterEqual(int(h.value(BUS, "crc_errors")), 5)
        self.assertEqual(h.locomotion().message, "running")
        self.assertGreater(h.goal_span(2, 1.0), 100)

    def test_2_dropped_and_truncated_replies_are_counted(self):
        h = self.h
        h.mock.call("inject", kind="drop_reply", ids=[4], count=4)
        h.mock.call("inject", kind="truncate_reply", ids=[8], count=3)
        h.wait_diag(servo(4), lambda s: int(h.value(servo(4), "timeouts")) >= 4, 5.0, "4 timeouts on servo 4")
        h.wait_diag(BUS, lambda s: int(h.value(BUS, "failed_cycles")) >= 7, 5.0, "7 failed cycles")
        self.assertEqual(h.locomotion().message, "running")

    def test_3_dead_servo_stops_locomotion_and_holds(self):
        h = self.h
        self.run_gait()
        h.mock.call("set_silent", id=5, silent=True)
        s = h.wait_diag(LOCO, lambda s: s.level == 2, 5.0, "the fault")
        self.assertIn("servo 5 (joint_5) timeout", s.message)
        self.assertIn("no reply", h.status(servo(5)).message)
        # Hold: goals frozen, torque still on for the others. The hold's own goal write may land on
        # the mock after the fault is on /diagnostics (a loaded machine): frozen within 5 s, for 1 s.
        h.wait_frozen(2, 5.0)
        self.assertTrue(h.mock_state()[2]["torque"])
        r = h.enable(True)
        self.assertFalse(r.success)
        self.assertIn("servo 5 (joint_5) timeout", r.message)
        h.mock.call("set_silent", id=5, silent=False)
        self.recover()

    def test_4_hardware_error_stops_at_once_and_reboot_recovers(self):
        h = self.h
        self.run_gait()
        h.mock.call("set_hardware_error", id=6, bits=["overload"])
        s = h.wait_diag(LOCO, lambda s: s.level == 2, 5.0, "the fault")
        self.assertIn("servo 6 (joint_6): overload", s.message)
        h.wait_diag(servo(6), lambda s: s.level == 2, 5.0, "servo 6 in error")
        self.assertEqual(h.status(servo(6)).message, "hardware error: overload")
        h.wait_frozen(3, 5.0)
        state = h.mock_state()
        self.assertTrue(state[7]["torque"])
        self.assertFalse(state[6]["torque"])
        r = h.enable(True)
        self.assertFalse(r.success)
        self.assertIn("reboot it first", r.message)
        r = h.reboot(6)
        self.assertTrue(r.success, r.message)
        self.recover()
        self.assertTrue(all(v["torque"] for v in h.mock_state().values()))

    def test_5_pty_closing_stops_locomotion_and_reopening_recovers(self):
        h = self.h
        self.run_gait()
        h.mock.call("close_pty")
        s = h.wait_diag(LOCO, lambda s: s.level == 2, 5.0, "the fault")
        self.assertIn("bus", s.message)
        r = h.enable(True)
        self.assertFalse(r.success)
        h.mock.call("reopen_pty")
        self.recover()
        self.run_gait()
        h.wait_moving(2, 300, 10.0)


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "driver_faults", DriverFaults)
