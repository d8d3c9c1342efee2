#!/usr/bin/env python3
"""rostest: driver_node with ~realtime_priority 50. Where the process is permitted
(root, CAP_SYS_NICE + CAP_IPC_LOCK, or rtprio/memlock limits high enough) its loop thread runs
SCHED_FIFO at priority 50 and its memory is locked: checked from outside in /proc (a thread with
policy SCHED_FIFO and rt_priority 50, VmLck > 0), and the "loop" diagnostics report that mode. Where
it is not, the diagnostics say what was refused and the loop runs on (the refusal itself is tested
in test/cpp/test_realtime.cpp)."""
import os
import resource
import xmlrpc.client

import rosgraph
import rosnode
import rostest

from driver_test_helpers import DriverTestCase

LOOP = "snake_driver: loop"
PRIORITY = 50
SCHED_FIFO = 1


def permitted():
    """Whether this user may ask for SCHED_FIFO 50 and lock its memory (the node runs as this user)."""
    if os.geteuid() == 0:
        return True
    rtprio = resource.getrlimit(resource.RLIMIT_RTPRIO)[0]
    memlock = resource.getrlimit(resource.RLIMIT_MEMLOCK)[0]
    return (rtprio == resource.RLIM_INFINITY or rtprio >= PRIORITY) and memlock == resource.RLIM_INFINITY


def driver_pid():
    uri = rosnode.get_api_uri(rosgraph.Master("/test_driver_realtime"), "/driver")
    code, _msg, pid = xmlrpc.client.ServerProxy(uri).getPid("/test_driver_realtime")
    assert code == 1, "the driver did not give its pid"
    return pid


def fifo_threads(pid):
    """(tid, rt_priority) of the process's threads scheduled SCHED_FIFO (/proc/PID/task/TID/stat)."""
    out = []
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{tid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        # After "pid (comm)": field 3 is fields[0]; rt_priority is field 40, policy field 41.
        rt_priority, policy = int(fields[37]), int(fields[38])
        if policy == SCHED_FIFO:
            out.append((int(tid), rt_priority))
    return out


def locked_kb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmLck:"):
                return int(line.split()[1])
    return 0


class DriverRealtime(DriverTestCase):
    NODE_NAME = "test_driver_realtime"

    def test_loop_thread_runs_sched_fifo_with_memory_locked(self):
        h = self.h
        s = h.wait_diag(LOOP, lambda s: h.value(LOOP, "realtime") not in (None, "starting"), 10.0,
                        "the loop diagnostics to report the real-time mode")
        mode = h.value(LOOP, "realtime")
        self.assertEqual(h.value(LOOP, "realtime_priority"), str(PRIORITY))
        if not permitted():
            self.assertIn("refused", mode)
            self.assertIn("real-time mode refused", s.message)
            return
        self.assertEqual(mode, f"SCHED_FIFO priority {PRIORITY}, memory locked")
        self.assertEqual(h.value(LOOP, "memory_locked"), "true")
        pid = driver_pid()
        self.assertEqual([p for _tid, p in fifo_threads(pid)], [PRIORITY], "one SCHED_FIFO thread: the loop")
        self.assertGreater(locked_kb(pid), 0, "VmLck: the driver's memory is locked")
        # And it keeps its rate.
        h.wait_diag(LOOP, lambda s: abs(float(h.value(LOOP, "rate_hz")) - 100.0) <= 10.0, 10.0, "100 Hz +-10 %")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "driver_realtime", DriverRealtime)
