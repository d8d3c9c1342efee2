"""nav_record_node: records a navigation run (planner_node's) into a results folder, as mission_node
records a mission run. Wiring only: what is recorded and how the folder is rebuilt from the bag is
runs/nav_record.py; when the run ends is runs/nav_ros_watch.Watch (the ROS experiment's rule).

Records   into ~results_dir/<date>-<time>_nav_<world>/run.bag, from its start: runs/nav_record.NAV_TOPICS,
          /tf, /tf_static, /diagnostics, and the colour camera (camera/color/image_raw + camera_info)
          at most once every ~camera_period_s.
Ends      when the planner's state has been goal_reached for ~settle_s (the robot at rest), at
          ~time_limit_s after the first command that moves, or at shutdown (Ctrl+C): then the bag is
          closed and the folder written from it (metrics.json with `snake_autonomy nav run`'s contract,
          trajectory.csv, commands.csv, contacts.csv, replans.csv, frames/, topview.png); the node stays
          up, recording nothing more. `snake_autonomy report DIR` rebuilds the folder from the bag
          (a killed recorder leaves a bag without an index: it is reindexed).
Params    ~results_dir (empty: paths.default_results_dir), ~world (the world file, as sim_node's and
          planner_node's; empty: the goal comes from nav/goal), ~robot, ~perception, ~seed,
          ~pose_source (mocap | vio | the robot's source), ~nav_config (the planner's),
          ~camera_period_s (5), ~settle_s (10), ~time_limit_s (1200).
"""
import math
import re
import threading
import time
from pathlib import Path

import rospy

from snake_autonomy.paths import config_path, default_results_dir, resolve_world_path
from snake_autonomy.planning.rectilinear.config import NavConfig
from snake_autonomy.runs.nav_record import (CAMERA_TOPICS, NAV_TOPICS, PLANNER_STATUS, SIM_STATUS, report_nav_bag,
                                            run_identity, start_event)
from snake_autonomy.runs.nav_ros_watch import Watch
from snake_autonomy.runs.recorded_topics import STANDARD_TOPICS, message_class
from snake_autonomy.runs.run_log import RunBag
from snake_autonomy.sim.world_file import World, load_world

FLUSH_PERIOD_S = 1.0


class NavRecordNode:
    def __init__(self):
        world_file = rospy.get_param("~world", "")
        world = load_world(resolve_world_path(world_file)) if world_file else \
            World(start=(0.0, 0.0, 0.0), goal=(0.0, 0.0), goal_radius_m=0.2, name="goal")
        nav_config = rospy.get_param("~nav_config", "") or str(config_path("nav.yaml"))
        self.camera_period_s = float(rospy.get_param("~camera_period_s", 5.0))
        settle_s = float(rospy.get_param("~settle_s", 10.0))
        time_limit_s = float(rospy.get_param("~time_limit_s", 1200.0))
        for key, v in (("~camera_period_s", self.camera_period_s), ("~settle_s", settle_s),
                       ("~time_limit_s", time_limit_s)):
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{key}: must be a finite number > 0, got {v!r}")
        identity, min_radius_m = run_identity(
            nav_config, rospy.get_param("~robot", "cobra"), rospy.get_param("~perception", "depth"),
            int(rospy.get_param("~seed", 0)), world, rospy.get_param("~pose_source", "mocap"))
        results = Path(rospy.get_param("~results_dir", "") or default_results_dir())
        stamp = time.strftime("%Y%m%d-%H%M%S")
        name = re.sub(r"[^A-Za-z0-9_.-]+", "_", world.name or "world")
        self.run_dir = results / f"{stamp}_nav_{name}"
        n = 1
        while self.run_dir.exists():
            n += 1
            self.run_dir = results / f"{stamp}_nav_{name}_{n}"
        self.lock = threading.Lock()
        self.log = RunBag(self.run_dir, rospy.get_time())
        self.log.event(start_event(world, identity, rospy.get_namespace(), min_radius_m,
                                   {"node": rospy.get_name(), "wall_time_start": time.strftime("%Y-%m-%dT%H:%M:%S%z")}),
                       rospy.get_time())
        stop = NavConfig.from_yaml(nav_config).gaits.stop
        self.watch = Watch(world.goal, world.goal_radius_m, time_limit_s, settle_s, startup_s=math.inf,
                           stop_gait=stop, t0=time.monotonic())
        self.finished = False
        self.truth_seen = False           # the simulator's ground truth: the watch follows it, not the estimate
        self.last_camera = {}
        self.subs = []
        for topic, kind in {**NAV_TOPICS, **STANDARD_TOPICS, **CAMERA_TOPICS}.items():
            self.subs.append(rospy.Subscriber(topic, message_class(kind), self.recorder(topic), queue_size=50,
                                              buff_size=2 ** 24))
        self.timer = rospy.Timer(rospy.Duration(FLUSH_PERIOD_S), self.on_timer)
        rospy.loginfo(f"nav_record: recording to {self.run_dir}")

    def recorder(self, topic):
        resolved = rospy.resolve_name(topic)
        camera = topic in CAMERA_TOPICS
        watched = {"gait_command": self.on_command, "ground_truth/base_pose": self.on_truth,
                   "base_pose": self.on_estimate, "/diagnostics": self.on_diagnostics}.get(topic)

        def cb(msg):
            t = rospy.get_time()
            if camera:
                if t - self.last_camera.get(topic, -math.inf) < self.camera_period_s:
                    return
                self.last_camera[topic] = t
            self.log.write(resolved, msg, t)
            if watched is not None:
                watched(msg)
        return cb

    # -- what decides the end (runs/nav_ros_watch.Watch) ----------------------------------------------
    def on_command(self, msg):
        self.watch.on_command(time.monotonic(), msg.gait, msg.kappa)

    def on_truth(self, msg):
        self.truth_seen = True
        self.watch.on_truth(msg.pose.position.x, msg.pose.position.y)

    def on_estimate(self, msg):
        if not self.truth_seen:
            self.watch.on_truth(msg.pose.pose.position.x, msg.pose.pose.position.y)

    def on_diagnostics(self, msg):
        for st in msg.status:
            if st.name == PLANNER_STATUS:
                self.watch.on_planner(time.monotonic(), {kv.key: kv.value for kv in st.values})
            elif st.name == SIM_STATUS:
                self.watch.on_sim({kv.key: kv.value for kv in st.values})

    def on_timer(self, _event):
        self.log.flush()
        end = self.watch.step(time.monotonic())
        if end is not None:
            self.finish(end)

    def finish(self, end: str):
        """Closes the bag (end event: why) and writes the results folder from it; once."""
        with self.lock:
            if self.finished:
                return
            self.finished = True
        for sub in self.subs:
            sub.unregister()
        self.timer.shutdown()
        self.log.closed = True
        self.log.close_bag(end, rospy.get_time())
        try:
            m = report_nav_bag(self.log.bag_path, self.run_dir)
        except Exception as exc:  # noqa: BLE001 - the bag is safe: `snake_autonomy report DIR` retries
            rospy.logerr(f"nav_record: writing the results of {self.run_dir} failed: {type(exc).__name__}: {exc}")
            return
        rospy.loginfo(f"nav_record: {end}: goal reached {m['goal_reached']}, outcome {m['outcome']}, "
                      f"{m['collisions']} contact(s), {m['time_s']:.0f} s; results in {self.run_dir}")


def main():
    rospy.init_node("nav_record")
    try:
        node = NavRecordNode()
    except (ValueError, OSError, RuntimeError) as exc:
        rospy.logfatal(str(exc))
        return 1
    rospy.on_shutdown(lambda: node.finish("shutdown"))
    rospy.spin()
    return 0
