"""Helper process for test_run_log.py: logs a fake run until it is signalled.

argv: RUN_DIR READY_FILE HANDLE_SIGTERM(0|1). Writes com_pose at 50 poses per decision and one
tracker decision per loop; after 3 decisions touches READY_FILE (waypoint 0 is reached at decision
2). With HANDLE_SIGTERM=1 a SIGTERM closes the log like the mission node's shutdown hook. As in the
node, the logging runs on a worker thread while the main thread only waits (rospy.spin): a handler
that closed the log from inside a locked write on the same thread would deadlock.
"""
import math
import signal
import sys
import threading
import time
from pathlib import Path

from geometry_msgs.msg import PoseStamped

from snake_autonomy.runs.run_log import RunLog
from snake_autonomy.msg import TrackingStatus

run_dir, ready, handle = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3] == "1"
waypoints = [(1.0, 0.0, 0.0), (1.0, 1.0, math.pi / 2)]
log = RunLog(run_dir, "fake", waypoints, t_start_s=100.0, mission_yaml="waypoints: [[1, 0, 0], [1, 1, 90]]\n",
             tracker={"d_th": 0.35, "psi_wp": math.radians(30), "psi_turn": math.radians(40)})
if handle:
    def on_term(signum, frame):
        log.close("aborted: SIGTERM")
        sys.exit(0)
    signal.signal(signal.SIGTERM, on_term)


def log_forever():
    t = 100.0
    index = 0
    for k in range(10_000):
        for _ in range(50):
            t += 0.02
            x = min(1.0, 0.3 * (t - 100.0))
            msg = PoseStamped()
            msg.header.stamp.secs, msg.header.stamp.nsecs = int(t), int((t % 1) * 1e9)
            msg.pose.position.x = x
            msg.pose.orientation.w = 1.0
            log.write("/com_pose", msg, t)
            log.add_pose(t, x, 0.0)
        reached = k == 2
        target = index
        index += int(reached)
        d = max(0.0, 1.0 - min(1.0, 0.3 * (t - 100.0)))
        st = TrackingStatus(waypoint_index=index, num_waypoints=2, waypoint_reached=reached, distance=d,
                            yaw_error_abs=0.1, yaw_error_rel=0.2, yaw_error=0.15, w=0.5, mode=1, gait="sidewind")
        st.header.stamp.secs, st.header.stamp.nsecs = int(t), int((t % 1) * 1e9)
        log.write("/tracking_status", st, t)
        log.add_decision(t, index, target, reached, d, 0.1, 0.2, 0.15)
        if k == 3:
            ready.write_text("ready")
        time.sleep(0.02)


threading.Thread(target=log_forever, daemon=True).start()
while True:
    time.sleep(0.1)
