"""The watcher of one navigation run through ROS (runs/nav_ros_experiment.py): a child process, one
rospy node per master (rospy cannot initialise twice in one process), that listens to a running
`sim.launch world:=FILE` and writes what it saw as JSON.

    ROS_MASTER_URI=http://127.0.0.1:PORT python3 -m snake_autonomy.runs.nav_ros_watch \\
        --world FILE --seed S --time-limit 300 --out RUN/watch.json

Listens to  ground_truth/base_pose (base_link by ground truth), gait_command (the first command
            that moves: not the stop gait), /diagnostics ("planner: navigation": state, distance to
            the goal, replans, stops; "sim: simulated robot": obstacle_contacts, min_clearance_m).
Ends        when the planner's state has been goal_reached for settle_s (the robot at rest; then
            base_link's final position decides "reached", as the batch run), at time_limit_s after
            the first command that moves (the settle cut at the limit, as the batch run), when a
            node of the launch dies (NodeCheck: its pid gone, its URI silent, roslaunch saw it die),
            when the launch stops (roslaunch killed its nodes on exit) or the master goes, or when
            nothing moves within startup_s.
Times       wall clock (the launch runs on it: use_sim_time false); time_s from the first command
            that moves to the first goal_reached status (diagnostics every 1 s: +-1 s).
Writes      the JSON (Watch.result) every second while it runs and once at the end: a killed
            watcher leaves its latest state; at the end, beside it, commands.csv and trajectory.csv.
"""
import argparse
import math
import os
import sys
import threading
import time
from pathlib import Path
from typing import Callable, Dict, List, Optional, Set, Tuple
from xmlrpc.client import ServerProxy

from snake_autonomy.planning.rectilinear.config import NavConfig, nav_config_path
from snake_autonomy.runs.results import write_json_atomic
from snake_autonomy.sim.world_file import load_world

PLANNER_STATUS = "planner: navigation"
SIM_STATUS = "sim: simulated robot"
STOP_GAITS = ("hold",)          # and the nav config's gaits.stop (Watch(stop_gait=...))
PROGRESS_PERIOD_S = 30.0
NODE_CHECK_PERIOD_S = 5.0


class Watch:
    """What one run through ROS did so far, fed by the callbacks; `step(now)` says whether (and why)
    it has ended. ROS-free: times are the caller's (time.monotonic() in the watcher)."""

    def __init__(self, goal_xy, goal_radius_m: float, time_limit_s: float, settle_s: float = 10.0,
                 startup_s: float = 300.0, stop_gait: str = "hold_curve", t0: float = 0.0):
        self.goal_xy, self.goal_radius_m = tuple(goal_xy), float(goal_radius_m)
        self.time_limit_s, self.settle_s, self.startup_s = float(time_limit_s), float(settle_s), float(startup_s)
        self.stop_gaits = set(STOP_GAITS) | {stop_gait}
        self.t0 = t0
        self.lock = threading.Lock()
        self.xy: Optional[tuple] = None
        self.lag_s, self.max_lag_s = math.nan, 0.0
        self.t_move: Optional[float] = None        # the first command that moves
        self.t_reached: Optional[float] = None     # the first goal_reached status
        self.t_reached_now: Optional[float] = None  # since when goal_reached holds (reset when it leaves)
        self.planner: Dict[str, str] = {}
        self.sim: Dict[str, str] = {}
        self.end: Optional[str] = None
        self.t_end: Optional[float] = None
        self.commands: List[Tuple[float, str, float]] = []   # (t, gait, kappa) of every gait_command
        self.track: List[Tuple[float, float, float]] = []    # (t, x, y) of base_link, each step()

    # -- inputs ---------------------------------------------------------------------------------------
    def on_truth(self, x: float, y: float, lag_s: Optional[float] = None) -> None:
        """lag_s: wall time at receipt minus the stamp (the plant's clock, started at the wall time):
        how far the simulation has fallen behind real time (plus transport)."""
        with self.lock:
            self.xy = (float(x), float(y))
            if lag_s is not None:
                self.lag_s = float(lag_s)
                self.max_lag_s = max(self.max_lag_s, self.lag_s)

    def on_command(self, now: float, gait: str, kappa_per_m: float = 0.0) -> None:
        with self.lock:
            self.commands.append((now, gait, float(kappa_per_m)))
            if self.t_move is None and gait not in self.stop_gaits:
                self.t_move = now

    def on_planner(self, now: float, values: Dict[str, str]) -> None:
        with self.lock:
            self.planner = dict(values)
            if values.get("state") == "goal_reached" and self.t_move is not None:
                if self.t_reached is None:
                    self.t_reached = now
                if self.t_reached_now is None:
                    self.t_reached_now = now
            else:
                self.t_reached_now = None

    def on_sim(self, values: Dict[str, str]) -> None:
        with self.lock:
            self.sim = dict(values)

    # -- the end --------------------------------------------------------------------------------------
    def step(self, now: float, dead: Optional[str] = None, stopped: Optional[str] = None) -> Optional[str]:
        """The reason the run ends now (and remembers it), else None. dead: a node that died; stopped:
        why the launch itself stopped (roslaunch stopped from outside killed its nodes on exit)."""
        with self.lock:
            if self.xy is not None:
                self.track.append((now, *self.xy))
            if self.end is None:
                self.end = self._why(now, dead, stopped)
                if self.end is not None:
                    self.t_end = now
            return self.end

    def _why(self, now: float, dead: Optional[str], stopped: Optional[str]) -> Optional[str]:
        if dead:
            return f"node_died: {dead}"
        if stopped:
            return f"launch_stopped: {stopped}"
        if self.t_move is None:
            return "no_start" if now - self.t0 >= self.startup_s else None
        if self.t_reached_now is not None and now - self.t_reached_now >= self.settle_s:
            return "goal_reached"
        if now - self.t_move >= self.time_limit_s:
            return "time_limit"
        return None

    def write_csv(self, folder: Path) -> None:
        """folder/commands.csv (every gait command) and trajectory.csv (base_link by ground truth at
        each step), t_s from the first command that moves, as the batch run's files (t_s from its start)."""
        with self.lock:
            t0 = self.t_move if self.t_move is not None else self.t0
            with open(folder / "commands.csv", "w") as f:
                f.write("t_s,gait,kappa_per_m\n")
                f.writelines(f"{t - t0:.2f},{g},{k:.4f}\n" for t, g, k in self.commands)
            with open(folder / "trajectory.csv", "w") as f:
                f.write("t_s,x_m,y_m\n")
                f.writelines(f"{t - t0:.2f},{x:.4f},{y:.4f}\n" for t, x, y in self.track)

    def distance_m(self) -> Optional[float]:
        if self.xy is None:
            return None
        return math.hypot(self.xy[0] - self.goal_xy[0], self.xy[1] - self.goal_xy[1])

    def result(self, now: float) -> Dict:
        """metrics.json's ROS part: goal_reached (the loop said so and base_link ends inside the goal's
        disc), loop_reached, time_s, final_distance_m, collisions (sim_node's contact episodes), the planner's
        replans and replans_without_joints (None before its first status)."""
        with self.lock:
            d = self.distance_m()
            loop_reached = self.t_reached is not None
            until = self.t_reached if loop_reached else (self.t_end if self.t_end is not None else now)
            return {"goal_reached": bool(loop_reached and d is not None and d <= self.goal_radius_m),
                    "loop_reached": loop_reached,
                    "time_s": None if self.t_move is None else round(until - self.t_move, 1),
                    "final_distance_m": None if d is None else round(d, 4),
                    "collisions": _int(self.sim.get("obstacle_contacts")),
                    "min_clearance_m": _float(self.sim.get("min_clearance_m")),
                    "state": self.planner.get("state", "none"),
                    "replans": _int(self.planner.get("replans")),
                    "stops_no_free_arc": _int(self.planner.get("stops_no_free_arc")),
                    # replans on the commanded shape: no joint_states within the pose timeout
                    "replans_without_joints": _int(self.planner.get("replans_without_joints")),
                    "started_after_s": None if self.t_move is None else round(self.t_move - self.t0, 1),
                    "end": self.end or "running",
                    "watched_s": round(now - self.t0, 1),
                    "truth_lag_s": None if math.isnan(self.lag_s) else round(self.lag_s, 3),
                    "truth_lag_s_max": round(self.max_lag_s, 3), "sim_status": dict(self.sim)}


def _int(v) -> Optional[int]:
    try:
        return int(v)
    except (TypeError, ValueError):
        return None


def _float(v) -> Optional[float]:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) and f >= 0 else None


class NodeCheck:
    """Whether a node of the launch has died, from the pids taken once the robot moves.

    Its pid gone is not enough: when roslaunch is stopped from outside (SIGINT/SIGTERM to roslaunch), it
    kills every node on exit, and the first to go (robot_state_publisher, in C++, within 0.1 s) looked
    like a node that died while the launch ran. A node has died when its pid is gone, its URI no longer
    answers getPid with a live pid, and roslaunch's process monitor lists it among its dead (a node
    roslaunch killed on exit stays among its active ones). While roslaunch still lists it active, the
    verdict waits (`suspect`), up to confirm_s; when roslaunch no longer answers, the launch has stopped.

    pid_of(name): the node's pid by its XML-RPC getPid (URI from the master), None when it does not answer;
    seen_dead(): the nodes roslaunch saw die, None when roslaunch does not answer; alive(pid): a process."""

    def __init__(self, pids: Dict[str, int], pid_of: Callable[[str], Optional[int]],
                 seen_dead: Callable[[], Optional[Set[str]]], alive: Optional[Callable[[int], bool]] = None,
                 confirm_s: float = 30.0):
        self.pids, self.pid_of, self.seen_dead = dict(pids), pid_of, seen_dead
        self.alive = alive or _pid_alive
        self.confirm_s = float(confirm_s)
        self.suspect: Dict[str, float] = {}     # name -> when its pid was first seen gone

    def check(self, now: float) -> Tuple[Optional[str], Optional[str]]:
        """(a node that died, else None; why the launch stopped, else None)."""
        dead, asked = None, False               # roslaunch's dead: asked once a check, when a pid is gone
        for name, pid in self.pids.items():
            if self.alive(pid):
                continue
            again = self.pid_of(name)
            if again is not None and self.alive(again):
                self.pids[name] = again
                self.suspect.pop(name, None)
                continue
            if not asked:
                dead, asked = self.seen_dead(), True
            if dead is None:
                return None, f"{name} gone with roslaunch"
            if name in dead:
                return name, None
            if now - self.suspect.setdefault(name, now) >= self.confirm_s:
                return name, None
        return None, None


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    return True


def _node_check(me: str) -> NodeCheck:
    """The check of every node the master knows, but this one and rosout."""
    import rosgraph   # ROS lazily: the runs layer is imported without ROS (the Watch, the tests)
    import rosnode
    master = rosgraph.Master(me)

    def pid_of(name: str) -> Optional[int]:
        try:
            code, _, pid = ServerProxy(master.lookupNode(name)).getPid(me)
        except Exception:   # noqa: BLE001 - not listed by the master, or its URI does not answer
            return None
        return int(pid) if code == 1 else None

    def seen_dead() -> Optional[Set[str]]:
        try:
            dead = set()
            for uri in master.getParam("/roslaunch/uris").values():
                _, _, (_, procs) = ServerProxy(uri).list_processes()
                # process "ns/name-N" of node "/ns/name"
                dead.update("/" + proc.rsplit("-", 1)[0] for proc, _ in procs)
            return dead
        except Exception:   # noqa: BLE001 - roslaunch (or the master) gone
            return None

    pids = {}
    for name in rosnode.get_node_names():
        if name not in (me, "/rosout"):
            pid = pid_of(name)
            if pid is not None:
                pids[name] = pid
    return NodeCheck(pids, pid_of, seen_dead)


def watch(args) -> int:
    import rospy      # ROS lazily, as in _node_check
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseStamped

    from snake_autonomy.msg import GaitCommand

    world = load_world(args.world)
    stop = NavConfig.from_yaml(args.nav_config or nav_config_path(args.robot)).gaits.stop
    w = Watch(world.goal, world.goal_radius_m, args.time_limit, args.settle, args.startup, stop, time.monotonic())
    rospy.init_node("nav_ros_watch", disable_signals=True)
    rospy.Subscriber("ground_truth/base_pose", PoseStamped,
                     lambda m: w.on_truth(m.pose.position.x, m.pose.position.y, time.time() - m.header.stamp.to_sec()),
                     queue_size=5)
    rospy.Subscriber("gait_command", GaitCommand, lambda m: w.on_command(time.monotonic(), m.gait, m.kappa),
                     queue_size=20)

    def on_diagnostics(msg):
        for st in msg.status:
            if st.name == PLANNER_STATUS:
                w.on_planner(time.monotonic(), {kv.key: kv.value for kv in st.values})
            elif st.name == SIM_STATUS:
                w.on_sim({kv.key: kv.value for kv in st.values})
    rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics, queue_size=20)

    nodes, next_check, next_progress, next_write = None, 0.0, 0.0, 0.0
    label = f"{world.name} seed {args.seed}"
    while True:
        now = time.monotonic()
        dead = stopped = None
        if rospy.is_shutdown():
            stopped = "the master gone (rospy shut down)"
        elif w.t_move is not None and (now >= next_check or (nodes is not None and nodes.suspect)):
            next_check = now + NODE_CHECK_PERIOD_S
            try:
                if nodes is None or not nodes.pids:
                    nodes = _node_check(rospy.get_name())
                dead, stopped = nodes.check(now)
            except Exception as exc:   # noqa: BLE001 - the master gone: the launch has ended
                stopped = f"the master gone ({type(exc).__name__}: {exc})"
        end = w.step(now, dead, stopped)
        if now >= next_progress or end:
            next_progress = now + PROGRESS_PERIOD_S
            d = w.distance_m()
            print(f"[ros] {label}: {now - w.t0:.0f} s, state {w.planner.get('state', 'none')}, "
                  f"distance to the goal {'-' if d is None else f'{d:.2f} m'}"
                  + (f", contacts {w.sim.get('obstacle_contacts')}" if w.sim else "")
                  + (f"; end: {end}" if end else ""), flush=True)
        if now >= next_write or end:
            next_write = now + 1.0
            write_json_atomic(args.out, {**w.result(now), "nodes": dict(sorted(nodes.pids.items())) if nodes else {}})
        if end:
            break
        time.sleep(0.5)
    w.write_csv(Path(args.out).parent)
    rospy.signal_shutdown("run over")
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="nav_ros_watch", description=__doc__.split("\n\n")[0])
    p.add_argument("--world", required=True)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--robot", default="cobra")
    p.add_argument("--nav-config", default=None)
    p.add_argument("--time-limit", type=float, required=True, help="s after the first command that moves")
    p.add_argument("--settle", type=float, default=10.0, help="s of goal_reached before the end")
    p.add_argument("--startup", type=float, default=300.0, help="s to the first command that moves")
    p.add_argument("--out", required=True, help="JSON file")
    return watch(p.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
