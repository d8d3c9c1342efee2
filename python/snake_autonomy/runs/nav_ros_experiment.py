"""Navigation through ROS over several worlds, each compared with its batch run: for every world
file and seed, `roslaunch snake_autonomy sim.launch world:=FILE seed:=S` in real time (sim_node,
driver_node, planner_node), watched until the planner's goal is reached and the robot rests, or the
time limit; then the batch run (runs/nav_batch.py, the same NavLoop) of the same world and seed.

    rows = run_experiment([(world, "/abs/world.yaml")], seeds=[0], out="/tmp/ros_exp",
                          time_limits_s=[200.0])
    print(comparison_table(rows))

Each ROS run has a master of its own (roslaunch -p PORT on a free port, ROS_MASTER_URI to match), a
servo bus pty of its own and a process group of its own: SIGINT to the group at the end (Ctrl+C),
SIGKILL after SHUTDOWN_S to the group and to every process below roslaunch by its pid (roslaunch
starts each node in a session of its own), and the next run starts only when none of them is left. The
watcher (runs/nav_ros_watch.py) is a child process: rospy initialises once per process.

OUT/runs/WORLD_sSEED/: metrics.json (the ROS run: world, seed, goal_reached, loop_reached, time_s,
final_distance_m, collisions, wall_s, end, the log paths), commands.csv and trajectory.csv (the ROS
run's gait commands and base_link), roslaunch.log (the launch's output), log/ (ROS_LOG_DIR: every
node's log), batch.json (the batch run's metrics), batch/ (its files: nav_batch.NavResult.write). OUT/table.md and
OUT/summary.json: one row per world and seed (comparison_table).
"""
import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
from snake_autonomy.runs.results import write_json_atomic
from snake_autonomy.sim.world_file import World

SETTLE_S = 10.0         # goal_reached this long before the end (nav_batch.NavRunSpec.settle_s)
STARTUP_S = 300.0       # launch to the first command that moves (MuJoCo builds its model, the camera starts)
SHUTDOWN_S = 30.0       # SIGINT to SIGKILL
MARGIN_S = 120.0        # beyond startup + limit + settle: the watcher is hung, stop it
SUPPORTED_ROBOTS = ("cobra", "chang_rectilinear")   # the robots sim.launch robot:= simulates with a nav config


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def check_robot(robot: str) -> None:
    """ValueError unless sim.launch simulates the robot."""
    if robot not in SUPPORTED_ROBOTS:
        raise ValueError(f"--robot {robot}: sim.launch simulates {', '.join(SUPPORTED_ROBOTS)} only "
                         "(the batch experiment, `snake_autonomy nav experiment`, runs the other robots)")


def moving_time_s(commands, reached_t: Optional[float], end_t: float, stop_gaits: Sequence[str]) -> Optional[float]:
    """A batch run's time as the ROS run counts it: from its first command that moves (a gait not in
    stop_gaits) to the loop's goal_reached (else to end_t); commands: (t, gait, kappa, state)."""
    first = next((c[0] for c in commands if c[1] not in stop_gaits), None)
    if first is None:
        return None
    return round((reached_t if reached_t is not None else end_t) - first, 1)


def success(metrics: Dict) -> bool:
    """Reached with no contact (the batch experiment's success)."""
    return bool(metrics.get("goal_reached")) and metrics.get("collisions") == 0


def same_outcome(ros: Dict, batch: Dict) -> bool:
    """Both successes or both not."""
    return success(ros) == success(batch)


# ROS runs ended by the launch or the watcher, not by the robot: no outcome to compare
CUT_SHORT = ("launch_stopped", "launch_ended", "watcher_stopped", "watcher_failed")


def cut_short(ros: Dict) -> bool:
    return str(ros.get("end", "")).startswith(CUT_SHORT)


def comparison_row(world: str, seed: int, ros: Dict, batch: Dict) -> Dict:
    return {"world": world, "seed": int(seed),
            "ros_reached": bool(ros.get("goal_reached")), "ros_contacts": ros.get("collisions"),
            "ros_time_s": ros.get("time_s"), "ros_end": ros.get("end"),
            "batch_reached": bool(batch.get("goal_reached")), "batch_contacts": batch.get("collisions"),
            "batch_time_s": batch.get("time_from_move_s"), "batch_outcome": batch.get("outcome"),
            "same_outcome": None if cut_short(ros) else same_outcome(ros, batch)}


def _cell(v, fmt="{}") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return fmt.format(v)


def _same_count(rows: List[Dict]) -> Tuple[int, int]:
    """(rows with the same outcome, rows compared)."""
    return sum(r["same_outcome"] is True for r in rows), sum(r["same_outcome"] is not None for r in rows)


def comparison_table(rows: List[Dict]) -> str:
    """world | seed | ROS: reached, contacts, time | batch: reached, contacts, time | same outcome ("-"
    where the ROS run was cut short), and a last line counting the rows with the same outcome."""
    lines = ["| world | seed | ROS: reached | ROS: contacts | ROS: time (s) | batch: reached | batch: contacts "
             "| batch: time (s) | same outcome |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ros_time = _cell(r["ros_time_s"], "{:.0f}") + ("" if r["ros_end"] in ("goal_reached", None)
                                                        else f" ({r['ros_end']})")
        lines.append(f"| {r['world']} | {r['seed']} | {_cell(r['ros_reached'])} | {_cell(r['ros_contacts'])} | "
                     f"{ros_time} | {_cell(r['batch_reached'])} | {_cell(r['batch_contacts'])} | "
                     f"{_cell(r['batch_time_s'], '{:.0f}')} | {_cell(r['same_outcome'])} |")
    same, compared = _same_count(rows)
    cut = len(rows) - compared
    lines.append(f"\nsame outcome (reached with no contact in both, or in neither): {same} of {compared} runs"
                 + (f" ({cut} more cut short by the launch, not compared)" if cut else ""))
    return "\n".join(lines)


# -- one ROS run -------------------------------------------------------------------------------------
def launch_command(world_file: str, seed: int, port: int, bus: str, perception: str = "depth",
                   classifier: Optional[str] = None, nav_config: Optional[str] = None,
                   robot: str = "cobra") -> List[str]:
    """The run's sim.launch; record:=false: the watcher and the batch run write this run's files."""
    cmd = ["roslaunch", "-p", str(port), "snake_autonomy", "sim.launch", f"world:={world_file}", f"seed:={seed}",
           "rviz:=false", f"port:={bus}", f"perception:={perception}", f"robot:={robot}", "record:=false"]
    if classifier:
        cmd.append(f"classifier:={Path(classifier).resolve()}")
    if nav_config:
        cmd.append(f"nav_config:={Path(nav_config).resolve()}")
    return cmd


def _proc_stat(pid: int) -> Optional[Tuple[int, str, int]]:
    """(parent pid, state, start time in clock ticks) of a process from /proc, None when it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()     # after "pid (comm) "
    return int(fields[1]), fields[0], int(fields[19])


def descendants(pid: int) -> Dict[int, int]:
    """Every process below pid (children, theirs...), pid -> start time: roslaunch starts each node
    in a session of its own (os.setsid), out of reach of a signal to roslaunch's group."""
    stats = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            st = _proc_stat(int(d.name))
            if st is not None:
                stats[int(d.name)] = st
    found, todo = {}, [pid]
    while todo:
        parent = todo.pop()
        for child, (ppid, _, started) in stats.items():
            if ppid == parent and child not in found:
                found[child] = started
                todo.append(child)
    return found


def _alive(pid: int, started: int) -> bool:
    """The same process (its start time: a pid may be reused), not yet a zombie."""
    st = _proc_stat(pid)
    return st is not None and st[2] == started and st[1] != "Z"


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
        return True
    except ProcessLookupError:
        return False
    except PermissionError:
        return True


def shut_down(proc: subprocess.Popen, timeout_s: float = SHUTDOWN_S) -> Dict:
    """Ends the launch as Ctrl+C does (SIGINT to its process group: roslaunch passes it on to its nodes),
    then SIGKILL after timeout_s to the group and to every process that was below roslaunch (the
    nodes, the master, their children), each by its pid; waits until none of them is left. What it
    took, for metrics.json (survivors: pids still there 10 s after SIGKILL)."""
    pgid, t0, how = proc.pid, time.monotonic(), "sigint"
    below = descendants(proc.pid)
    if proc.poll() is None:
        os.killpg(pgid, signal.SIGINT)
    else:
        how = "exited"

    def left():
        # poll: roslaunch reaped (a zombie still counts in its group)
        return ([pgid] if proc.poll() is None or _group_alive(pgid) else []) + [
            p for p, started in below.items() if _alive(p, started)]

    deadline, killed = time.monotonic() + timeout_s, False
    while left():
        if time.monotonic() >= deadline:
            if killed:
                break
            how, killed = how + "+sigkill", True
            for p, started in below.items():
                if _alive(p, started):
                    os.kill(p, signal.SIGKILL)
            if _group_alive(pgid):
                os.killpg(pgid, signal.SIGKILL)
            deadline = time.monotonic() + 10.0
        time.sleep(0.1)
    return {"shutdown": how, "shutdown_s": round(time.monotonic() - t0, 1), "processes": len(below) + 1,
            "survivors": left(), "launch_exit_code": proc.returncode}


def run_ros(world: World, world_file: str, seed: int, time_limit_s: float, run_dir: Path, robot: str = "cobra",
            perception: str = "depth", classifier: Optional[str] = None, nav_config: Optional[str] = None,
            startup_s: float = STARTUP_S) -> Dict:
    """One world through sim.launch in real time; its metrics (also run_dir/metrics.json)."""
    run_dir.mkdir(parents=True, exist_ok=True)
    port, bus = free_port(), f"/tmp/snake_sim_bus_{os.getpid()}_{run_dir.name}"
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(run_dir),
               ROS_LOG_DIR=str(run_dir / "log"), PYTHONUNBUFFERED="1")
    log = run_dir / "roslaunch.log"
    watch_json = run_dir / "watch.json"
    watch_json.unlink(missing_ok=True)
    t0 = time.monotonic()
    with open(log, "w") as log_file:
        command = launch_command(world_file, seed, port, bus, perception, classifier, nav_config, robot)
        launch = subprocess.Popen(command, env=env, stdout=log_file, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                  start_new_session=True)
    watcher, launch_ended = None, None
    try:
        watcher = subprocess.Popen(
            [sys.executable, "-m", "snake_autonomy.runs.nav_ros_watch", "--world", world_file, "--seed", str(seed),
             "--robot", robot, "--time-limit", str(time_limit_s), "--settle", str(SETTLE_S),
             "--startup", str(startup_s), "--out", str(watch_json)]
            + (["--nav-config", str(nav_config)] if nav_config else []), env=env, stdin=subprocess.DEVNULL)
        deadline = t0 + startup_s + time_limit_s + SETTLE_S + MARGIN_S
        while watcher.poll() is None:
            if launch_ended is None and launch.poll() is not None:
                launch_ended = time.monotonic()
                print(f"[ros] roslaunch exited ({launch.returncode}): see {log}", flush=True)
            if time.monotonic() > deadline or (launch_ended and time.monotonic() - launch_ended > 15.0):
                watcher.terminate()
                watcher.wait(10.0)
                break
            time.sleep(0.5)
    finally:
        if watcher is not None and watcher.poll() is None:
            watcher.kill()
            watcher.wait()
        ended = shut_down(launch)
        Path(bus).unlink(missing_ok=True)
    try:
        watched = json.loads(watch_json.read_text())
    except (OSError, ValueError):
        watched = {"goal_reached": False, "loop_reached": False, "time_s": None, "final_distance_m": None,
                   "collisions": None, "end": "watcher_failed"}
    if watched.get("end") == "running":
        watched["end"] = "launch_ended" if launch_ended is not None else "watcher_stopped"
    metrics = {"world": world.name, "seed": int(seed), **watched, "time_limit_s": time_limit_s,
               "wall_s": round(time.monotonic() - t0, 1), "roslaunch_log": str(log),
               "ros_log_dir": str(run_dir / "log"), **ended}
    write_json_atomic(run_dir / "metrics.json", metrics)
    return metrics


# -- the batch run and the experiment ----------------------------------------------------------------
def run_batch(world: World, seed: int, time_limit_s: float, run_dir: Path, robot: str = "cobra",
              perception: str = "depth", classifier: Optional[str] = None, nav_config: Optional[str] = None) -> Dict:
    """The batch run of the same world and seed (runs/nav_batch.py); its metrics with time_from_move_s
    (as the ROS run counts time), also run_dir/batch.json; its files (commands, replans, contacts,
    trajectory, top view) in run_dir/batch/."""
    t0 = time.monotonic()
    run = NavRun(NavRunSpec(world, robot=robot, perception=perception, seed=seed, time_limit_s=time_limit_s,
                            classifier=classifier, nav_config=nav_config, keep_frames=False))
    result, stop = run.run(), run.gaits.stop
    reached_t = next((c[0] for c in result.commands if c[3] == "goal_reached"), None)
    end_t = result.commands[-1][0] if result.commands else 0.0
    metrics = {**result.metrics, "time_from_move_s": moving_time_s(result.commands, reached_t, end_t, ("hold", stop)),
               "wall_s": round(time.monotonic() - t0, 1)}
    result.write(run_dir / "batch")
    write_json_atomic(run_dir / "batch.json", metrics)
    return metrics


def run_experiment(worlds: Sequence[Tuple[World, str]], seeds: Sequence[int], out, time_limits_s: Sequence[float],
                   robot: str = "cobra", perception: str = "depth", classifier: Optional[str] = None,
                   nav_config: Optional[str] = None, on_run: Optional[Callable[[], None]] = None) -> List[Dict]:
    """Every (world, its absolute file) x seed: the ROS run, then the batch run; OUT/table.md and
    OUT/summary.json; the rows (comparison_row); on_run() after each pair (the CLI's progress bar).
    RuntimeError when a launch's process survives."""
    check_robot(robot)
    out = Path(out)
    rows, runs, t0 = [], [], time.monotonic()
    for (world, world_file), limit in zip(worlds, time_limits_s):
        for seed in seeds:
            run_dir = out / "runs" / f"{world.name}_s{seed}"
            print(f"[ros] {world.name} seed {seed}: sim.launch, time limit {limit:.0f} s", flush=True)
            ros = run_ros(world, world_file, seed, limit, run_dir, robot, perception, classifier, nav_config)
            print(f"[ros] {world.name} seed {seed}: {ros['end']}, reached {ros['goal_reached']}, contacts "
                  f"{ros['collisions']}, time {ros['time_s']} s, replans {ros.get('replans')} "
                  f"({ros.get('replans_without_joints')} without joint_states), wall {ros['wall_s']} s, shutdown "
                  f"{ros['shutdown']} ({ros['shutdown_s']} s)", flush=True)
            if ros["survivors"]:
                raise RuntimeError(f"processes {ros['survivors']} of the launch outlived SIGKILL (see "
                                   f"{run_dir / 'metrics.json'}): the next run would not start clean; stopped")
            print(f"[batch] {world.name} seed {seed}", flush=True)
            batch = run_batch(world, seed, limit, run_dir, robot, perception, classifier, nav_config)
            print(f"[batch] {world.name} seed {seed}: {batch['outcome']}, time {batch['time_from_move_s']} s, "
                  f"wall {batch['wall_s']} s", flush=True)
            rows.append(comparison_row(world.name, seed, ros, batch))
            runs.append({"world": world.name, "world_file": world_file, "seed": seed, "time_limit_s": limit,
                         "ros": ros, "batch": batch})
            _write(out, rows, runs, robot, perception, time.monotonic() - t0)
            if on_run is not None:
                on_run()
    return rows


def _write(out: Path, rows, runs, robot, perception, wall_s) -> None:
    """table.md and summary.json, after every run: an interrupted experiment keeps what it did."""
    (out / "table.md").write_text(comparison_table(rows) + "\n")
    same, compared = _same_count(rows)
    write_json_atomic(out / "summary.json", {
        "robot": robot, "perception": perception, "runs": len(rows),
        "same_outcome": same, "compared": compared,
        "ros_successes": sum(success(r["ros"]) for r in runs),
        "batch_successes": sum(success(r["batch"]) for r in runs),
        "wall_s": round(wall_s, 1), "rows": rows, "details": runs})
