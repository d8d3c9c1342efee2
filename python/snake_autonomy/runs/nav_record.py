"""A navigation run recorded through ROS (`sim.launch world:=FILE`, or the robot): what goes into its
bag (the recorder, nodes/nav_record_node.py, writes it) and the results folder rebuilt from that bag
with the batch run's contract and files: metrics.json (runs/nav_metrics.py, plus end,
trajectory_source and bag), trajectory.csv, commands.csv, contacts.csv, replans.csv, frames/ and
topview.png (nav_batch.NavResult.write). `snake_autonomy report DIR` runs the same code.

The bag: the run's events on bag_io.RUN_TOPIC (start: {"event": "start", "kind": "navigation", the
world, the run's identity, the node's namespace}; end: why the recording ended), NAV_TOPICS, the
standard topics (/tf, /tf_static, /diagnostics) and CAMERA_TOPICS at a low rate; each message
stamped with its time of receipt.

Read back (times from the planner's first loop command, a gait_command with curve: the batch run's
clock starts half a command period earlier):
- trajectory: ground_truth/base_pose (the simulator) at 10 Hz, else base_pose (the robot's estimate:
  trajectory_source says which); the run's end pose is its last sample.
- commands: every gait_command, with the planner's state of its latest diagnostics.
- replans: each nav/path (empty: no free arc) with the nav/route of the same stamp; the candidate
  arcs stay in the bag (nav/arcs): replans.csv has no arcs column values.
- the loop's goal_reached, replans, stops, refusals and errors: the planner's diagnostics (1 Hz: the
  time of goal_reached is known to about 1 s).
- contacts: sim/contacts (one Marker per contact episode, text "LINK touched OBSTACLE"), each with
  the follower's mode of the planner's latest diagnostics; collisions, min_clearance_m and rolled_over
  from the simulator's diagnostics (none on the robot).
- the goal: the latest nav/goal marker (a goal from rviz or the action), else the world's.
"""
import bisect
import dataclasses
import json
import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from snake_autonomy.planning.rectilinear.config import NavConfig
from snake_autonomy.planning.rectilinear.planner import Replan
from snake_autonomy.planning.rectilinear.sampler import Selection
from snake_autonomy.runs.bag_io import RUN_TOPIC, INTERRUPTED, RunBagError, open_bag
from snake_autonomy.runs.nav_batch import NavResult
from snake_autonomy.runs.nav_metrics import NavFacts, nav_metrics
from snake_autonomy.runs.recorded_topics import CONTACT_TEXT
from snake_autonomy.runs.results import PathLength
from snake_autonomy.sim.collisions import ContactEpisode
from snake_autonomy.sim.world_file import World
from snake_autonomy.transforms import yaw_of_quat

KIND = "navigation"                 # the start event's kind (a mission's start event has none)
PLANNER_STATUS = "planner: navigation"
SIM_STATUS = "sim: simulated robot"
SAMPLE_PERIOD_S = 0.1               # the trajectory's rate, as the batch run's

#: topic (relative to the recorder's namespace) -> message type, recorded whole
NAV_TOPICS = {
    "gait_command": "snake_autonomy/GaitCommand",
    "base_pose": "geometry_msgs/PoseWithCovarianceStamped",
    "com_pose": "geometry_msgs/PoseStamped",
    "odom": "nav_msgs/Odometry",
    "joint_states": "sensor_msgs/JointState",
    "ground_truth/base_pose": "geometry_msgs/PoseStamped",
    "ground_truth/com_pose": "geometry_msgs/PoseStamped",
    "nav/path": "nav_msgs/Path",
    "nav/route": "nav_msgs/Path",
    "nav/arcs": "visualization_msgs/MarkerArray",
    "nav/goal": "visualization_msgs/Marker",
    "nav/map": "nav_msgs/OccupancyGrid",
    "nav/traversability": "sensor_msgs/Image",
    "nav/traversability_mask": "sensor_msgs/Image",
    "move_base_simple/goal": "geometry_msgs/PoseStamped",
    "sim/world_markers": "visualization_msgs/MarkerArray",
    "sim/contacts": "visualization_msgs/Marker",
}
#: recorded at most once every camera period (the recorder's ~camera_period_s)
CAMERA_TOPICS = {
    "camera/color/image_raw": "sensor_msgs/Image",
    "camera/color/camera_info": "sensor_msgs/CameraInfo",
}


def start_event(world: World, identity: Dict[str, Any], namespace: str, min_radius_m: float,
                extra: Optional[Dict[str, Any]] = None) -> Dict[str, Any]:
    """The run's start event: what the report needs besides the recorded topics."""
    return {"event": "start", "kind": KIND, "world": world.to_dict(), "world_source": world.source,
            "identity": dict(identity), "namespace": namespace, "min_radius_m": float(min_radius_m),
            **(extra or {})}


def run_identity(nav_config_file: str, robot: str, perception: str, seed: int, world: World,
                 pose_source: str) -> Tuple[Dict[str, Any], float]:
    """The run's identity (nav_metrics.IDENTITY_KEYS) and the follower's tightest circle, from the nav
    config the planner runs with."""
    cfg = NavConfig.from_yaml(nav_config_file)
    return {"robot": robot, "perception": perception, "seed": int(seed), "world": world.source or world.name,
            "flat_belly_fraction": cfg.plant.flat_belly_fraction, "gait": cfg.gaits.forward,
            "pose_source": pose_source, "nav_config": Path(nav_config_file).name,
            "on_no_free_arc": "back_off" if cfg.follower.back_off else "hold"}, cfg.follower.min_radius_m


class _Series:
    """(t, value) in time order, with the latest value at a time."""

    def __init__(self):
        self.t: List[float] = []
        self.v: List[Any] = []

    def add(self, t: float, v) -> None:
        self.t.append(t)
        self.v.append(v)

    def at(self, t: float, default=None):
        i = bisect.bisect_right(self.t, t) - 1
        return self.v[i] if i >= 0 else default

    def last(self, default=None):
        return self.v[-1] if self.v else default


def _path_poses(msg) -> Optional[np.ndarray]:
    if not msg.poses:
        return None
    return np.array([(p.pose.position.x, p.pose.position.y,
                      yaw_of_quat(p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z,
                                  p.pose.orientation.w)) for p in msg.poses])


def _rgb(msg) -> Optional[np.ndarray]:
    if msg.encoding != "rgb8" or len(msg.data) != msg.height * msg.step:
        return None
    rows = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.step)
    return rows[:, :3 * msg.width].reshape(msg.height, msg.width, 3).copy()


def _float(v, default=math.nan) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return default


def read_nav_run(bag_path) -> NavResult:
    """The NavResult of a recorded navigation run (metrics with the nav run contract). RunBagError when
    the bag holds no navigation run's start event."""
    start, end = None, None
    truth, estimate, commands, contacts, frames = [], [], [], [], []
    planner, sim, goal = _Series(), _Series(), None
    paths: Dict[float, Any] = {}
    routes: Dict[float, np.ndarray] = {}
    with open_bag(bag_path) as (bag, reindexed):
        ns = "/"
        for topic, msg, stamp in bag.read_messages():
            t = stamp.to_sec()
            if topic == RUN_TOPIC:
                event = json.loads(msg.data)
                if event.get("event") == "start" and event.get("kind") == KIND:
                    start, ns = event, event.get("namespace", "/")
                elif event.get("event") == "end":
                    end = (t, event.get("outcome", ""))
                continue
            name = topic[len(ns):] if topic.startswith(ns) else topic.lstrip("/")
            if name == "ground_truth/base_pose":
                truth.append((t, msg.pose))
            elif name == "base_pose":
                estimate.append((t, msg.pose.pose))
            elif name == "gait_command":
                commands.append((t, msg.gait, float(msg.kappa), bool(msg.curve)))
            elif name == "nav/path":
                paths[msg.header.stamp.to_sec()] = (t, _path_poses(msg))
            elif name == "nav/route":
                routes[msg.header.stamp.to_sec()] = _path_poses(msg)
            elif name == "nav/traversability":
                frames.append(_rgb(msg))
            elif name == "nav/goal" and msg.action == msg.ADD:
                goal = ((msg.pose.position.x, msg.pose.position.y), 0.5 * msg.scale.x)
            elif name == "sim/contacts" and CONTACT_TEXT in msg.text:
                link, obstacle = msg.text.split(CONTACT_TEXT, 1)
                contacts.append(ContactEpisode(t, obstacle, link, msg.pose.position.x, msg.pose.position.y))
            elif name.lstrip("/") == "diagnostics":
                for st in msg.status:
                    if st.name == PLANNER_STATUS:
                        planner.add(t, {kv.key: kv.value for kv in st.values})
                    elif st.name == SIM_STATUS:
                        sim.add(t, {kv.key: kv.value for kv in st.values})
    if start is None:
        raise RunBagError(f"no navigation run in it: no start event of kind {KIND!r} on {RUN_TOPIC}"
                          + (" (it had no index: reindexed)" if reindexed else ""))
    return _result(bag_path, start, end, truth or estimate, bool(truth), commands, planner, sim, paths, routes,
                   [f for f in frames if f is not None], contacts, goal)


def _result(bag_path, start, end, poses, from_truth, commands, planner, sim, paths, routes, frames, contacts,
            goal) -> NavResult:
    world = World.from_dict(start["world"], source=start.get("world_source") or "world")
    if goal is not None:
        world = dataclasses.replace(world, goal=tuple(goal[0]), goal_radius_m=float(goal[1]))
    loop_cmds = [c for c in commands if c[3]]
    t0 = loop_cmds[0][0] if loop_cmds else (commands[0][0] if commands else (poses[0][0] if poses else 0.0))
    t_end = end[0] if end is not None else max([t0] + [p[0] for p in poses[-1:]] + [c[0] for c in commands[-1:]])
    traj, heads, last_t, final = [], [], -math.inf, (world.start[0], world.start[1], math.radians(world.start[2]))
    path = PathLength(min_step_m=0.0)
    for t, pose in poses:
        if t < t0:
            continue
        final = (pose.position.x, pose.position.y, yaw_of_quat(pose.orientation.x, pose.orientation.y,
                                                               pose.orientation.z, pose.orientation.w))
        if t - last_t >= SAMPLE_PERIOD_S - 1e-6:
            last_t = t
            traj.append((t - t0, final[0], final[1]))
            heads.append(final[2])
            path.add(final[0], final[1])
    traj = np.array(traj) if traj else np.zeros((0, 3))
    reached_t = next((t for t, v in zip(planner.t, planner.v) if t >= t0 and v.get("state") == "goal_reached"), None)
    stop_xy = None
    if reached_t is not None and len(traj):
        i = min(int(np.searchsorted(traj[:, 0], reached_t - t0)), len(traj) - 1)
        stop_xy = (float(traj[i, 1]), float(traj[i, 2]))
    replans = []
    for stamp in sorted(paths):
        t, poses_w = paths[stamp]
        where = poses_w[0] if poses_w is not None else _pose_at(traj, heads, t - t0, final)
        replans.append(Replan(t - t0, tuple(float(v) for v in where), Selection(), poses_w, "",
                              routes.get(stamp)))
    last_planner, last_sim = planner.last({}), sim.last({})
    modes = [planner.at(c.t_s, {}).get("follower_mode", "unknown") for c in contacts]
    contacts = [dataclasses.replace(c, t_s=c.t_s - t0) for c in contacts]
    refused = {k[len("refused_"):]: int(_float(v, 0)) for k, v in last_planner.items()
               if k.startswith("refused_") and _float(v, 0) > 0}
    last_error = last_planner.get("last_error", "none")
    facts = NavFacts(
        world=world, trajectory=traj, t_end_s=t_end - t0, final_pose=final,
        loop_reached_t_s=None if reached_t is None else reached_t - t0, stop_xy=stop_xy,
        collisions=max(len(contacts), int(_float(last_sim.get("obstacle_contacts"), 0))),
        min_clearance_m=_clearance(last_sim.get("min_clearance_m")), path_length_m=path.length_m,
        replans=replans, stops_no_free_arc=int(_float(last_planner.get("stops_no_free_arc"), 0)),
        rolled_over=last_sim.get("rolled_over") == "True", contact_modes=modes,
        min_radius_m=float(start["min_radius_m"]), identity=start["identity"], loop_refused=refused,
        loop_errors=int(_float(last_planner.get("tick_errors"), 0)),
        loop_last_error="" if last_error == "none" else last_error)
    metrics = nav_metrics(facts)
    metrics.update({"end": end[1] if end is not None else INTERRUPTED,
                    "trajectory_source": "ground_truth/base_pose" if from_truth else "base_pose",
                    "bag": str(bag_path)})
    state_at = [(c[0] - t0, c[1], c[2], planner.at(c[0], {}).get("state", "none")) for c in commands if c[0] >= t0]
    return NavResult(metrics, traj, replans, frames, world, list(zip(contacts, modes)), None, state_at)


def _pose_at(traj: np.ndarray, heads: List[float], t: float, default):
    """base_link's (x, y, heading) at the trajectory's first sample from t (a replan with no path)."""
    if not len(traj):
        return default
    i = min(int(np.searchsorted(traj[:, 0], t)), len(traj) - 1)
    return (traj[i, 1], traj[i, 2], heads[i])


def _clearance(v) -> float:
    """sim_node's min_clearance_m (-1: none measured yet)."""
    f = _float(v)
    return f if math.isfinite(f) and f >= 0 else math.nan


def report_nav_bag(bag_path, out_dir) -> Dict[str, Any]:
    """Writes the results folder of a recorded navigation run; its metrics."""
    result = read_nav_run(bag_path)
    result.write(out_dir)
    return result.metrics
