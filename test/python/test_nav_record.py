"""A recorded navigation run's bag -> `snake_autonomy nav run`'s results folder (runs/nav_record.py),
without a master: a hand-made bag of a run killed before its end, with a contact and a replan that
found no free arc."""
import csv
import json
import math

import numpy as np
import pytest

pytest.importorskip("rosbag")

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from nav_msgs.msg import Path as PathMsg  # noqa: E402
from visualization_msgs.msg import Marker  # noqa: E402

from snake_autonomy.cli import main as cli_main  # noqa: E402
from snake_autonomy.msg import GaitCommand  # noqa: E402
from snake_autonomy.runs.nav_metrics import NavFacts, nav_metrics  # noqa: E402
from snake_autonomy.runs.nav_record import read_nav_run, start_event  # noqa: E402
from snake_autonomy.runs.run_log import RunBag  # noqa: E402
from snake_autonomy.sim.world_file import World  # noqa: E402

from conftest import ROOT  # noqa: E402

WORLD = World(start=(0.0, 0.0, 0.0), goal=(1.0, 0.0), goal_radius_m=0.2, name="hand_made")
IDENTITY = {"robot": "cobra", "perception": "depth", "seed": 3, "world": "hand_made", "flat_belly_fraction": 0.8,
            "gait": "rectilinear", "pose_source": "mocap", "nav_config": "nav.yaml", "on_no_free_arc": "back_off"}
T0 = 11.0          # the loop's first command
SPEED = 0.05       # m/s of the hand-made base_link from T0


def _diag(name, values):
    return DiagnosticArray(status=[DiagnosticStatus(name=name, values=[KeyValue(k, v) for k, v in values.items()])])


def _path(stamp, xs):
    import rospy
    msg = PathMsg()
    msg.header.stamp = rospy.Time.from_sec(stamp)
    for x in xs:
        p = PoseStamped()
        p.pose.position.x, p.pose.orientation.w = x, 1.0
        msg.poses.append(p)
    return msg


@pytest.fixture
def killed_run(tmp_path):
    """A run's bag from 10 s to 20 s, never closed with an end event (the recorder was killed)."""
    log = RunBag(tmp_path / "run", 10.0)
    log.event(start_event(WORLD, IDENTITY, "/", 0.8), 10.0)
    log.write("/gait_command", GaitCommand(gait="hold"), 10.0)           # before the loop: straight hold
    for k in range(19):
        t = T0 + 0.5 * k
        log.write("/gait_command", GaitCommand(gait="rectilinear", curve=True, kappa=0.1), t)
    for k in range(201):
        t = 10.0 + 0.05 * k
        p = PoseStamped()
        p.pose.position.x, p.pose.orientation.w = SPEED * max(0.0, t - T0), 1.0
        log.write("/ground_truth/base_pose", p, t)
    planner = {"state": "following", "follower_mode": "follow", "replans": "2", "stops_no_free_arc": "1",
               "refused_pose": "2", "tick_errors": "0"}
    log.write("/diagnostics", _diag("planner: navigation", planner), 12.0)
    log.write("/nav/path", _path(12.0, [0.05, 0.3, 0.6]), 12.0)
    contact = Marker(text="link_3 touched obstacle_0")
    contact.pose.position.x, contact.pose.position.y = 0.3, 0.1
    log.write("/sim/contacts", contact, 14.5)
    log.write("/diagnostics", _diag("sim: simulated robot", {"obstacle_contacts": "1", "min_clearance_m": "0.000"}),
              15.0)
    log.write("/nav/path", _path(17.0, []), 17.0)                     # no free arc
    log.flush()
    log._bag.close()      # closed with its index but without the end event
    return tmp_path / "run"


def test_a_killed_recording_gives_the_nav_run_contract_and_files(killed_run, tmp_path):
    result = read_nav_run(killed_run / "run.bag")
    m = result.metrics
    assert m["end"] == "interrupted" and m["trajectory_source"] == "ground_truth/base_pose"
    assert not m["loop_reached"] and not m["goal_reached"] and m["outcome"] == "time_limit"
    # times from the loop's first command (11 s) to the last message (20 s)
    assert m["time_s"] == pytest.approx(9.0, abs=0.01)
    assert result.trajectory[0, 0] == pytest.approx(0.0, abs=0.01)
    assert m["final_distance_m"] == pytest.approx(1.0 - SPEED * 9.0, abs=0.01)
    assert m["path_length_m"] == pytest.approx(SPEED * 9.0, abs=0.01)
    assert m["collisions"] == 1 and m["contacts_follow"] == 1 and m["min_clearance_m"] == 0.0
    assert m["replans"] == 2 and m["stops_no_free_arc"] == 1
    assert m["loop_refused"] == {"pose": 2} and m["seed"] == 3
    assert [r.path_world is None for r in result.replans] == [False, True]
    # the replan with no path is placed where base_link was then (6 s after the first command)
    assert result.replans[1].pose[0] == pytest.approx(SPEED * 6.0, abs=0.01)

    out = tmp_path / "report"
    assert cli_main(["report", str(killed_run), "--out", str(out)]) == 0
    assert json.loads((out / "metrics.json").read_text()) == m
    rows = list(csv.DictReader(open(out / "contacts.csv")))
    assert rows == [{"t_s": "3.50", "obstacle": "obstacle_0", "link": "link_3", "x_m": "0.3000", "y_m": "0.1000",
                     "follower_mode": "follow"}]
    commands = list(csv.DictReader(open(out / "commands.csv")))
    assert len(commands) == 19 and {c["gait"] for c in commands} == {"rectilinear"}
    assert (out / "topview.png").stat().st_size > 0
    assert len(list(csv.DictReader(open(out / "replans.csv")))) == 2


def test_a_goal_from_rviz_replaces_the_worlds(killed_run):
    """nav/goal (planner_goals' marker: a disc of the goal's radius) is the goal the run is judged by."""
    bag = RunBag(killed_run.parent / "goal_run", 10.0)
    bag.event(start_event(WORLD, IDENTITY, "/", 0.8), 10.0)
    goal = Marker(action=Marker.ADD)
    goal.pose.position.x, goal.scale.x = 0.2, 0.3
    bag.write("/nav/goal", goal, 10.5)
    bag.write("/gait_command", GaitCommand(gait="rectilinear", curve=True), 11.0)
    p = PoseStamped()
    p.pose.position.x, p.pose.orientation.w = 0.1, 1.0
    bag.write("/ground_truth/base_pose", p, 11.5)
    bag.write("/diagnostics", _diag("planner: navigation", {"state": "goal_reached"}), 12.0)
    bag.close_bag("goal_reached", 13.0)
    m = read_nav_run(killed_run.parent / "goal_run" / "run.bag").metrics
    assert m["end"] == "goal_reached" and m["loop_reached"] and m["goal_reached"]
    assert m["final_distance_m"] == pytest.approx(0.1) and m["time_s"] == pytest.approx(1.0, abs=0.01)


def test_a_bag_without_a_navigation_run_is_refused(tmp_path):
    from snake_autonomy.runs.bag_io import RunBagError
    log = RunBag(tmp_path / "run", 0.0)
    log.close_bag("ended")
    with pytest.raises(RunBagError, match="no navigation run"):
        read_nav_run(tmp_path / "run" / "run.bag")


def test_the_report_of_a_recorded_run_writes_the_files_and_columns_of_nav_run(killed_run, tmp_path):
    """The same figures as `snake_autonomy nav run` (a 3 s batch run): every file it writes, each CSV
    with the same columns, and metrics.json with every key of nav run's contract."""
    batch = tmp_path / "batch"
    assert cli_main(["nav", "run", "--world", str(ROOT / "config" / "worlds" / "one_obstacle.yaml"),
                     "--time-limit", "3", "--no-progress", "--out", str(batch)]) == 0
    report = tmp_path / "report"
    assert cli_main(["report", str(killed_run), "--out", str(report)]) == 0
    batch_files = {p.name for p in batch.iterdir()}
    assert {"metrics.json", "topview.png", "trajectory.csv", "commands.csv", "contacts.csv",
            "replans.csv"} <= batch_files
    # frames/ holds the camera's frames at replans: the hand-made bag has no camera
    assert batch_files <= {p.name for p in report.iterdir()} | {"frames"}, batch_files
    for name in sorted(n for n in batch_files if n.endswith(".csv")):
        with open(batch / name) as a, open(report / name) as b:
            assert next(csv.reader(a)) == next(csv.reader(b)), name
    contract = set(nav_metrics(NavFacts(
        world=WORLD, trajectory=np.zeros((0, 3)), t_end_s=0.0, final_pose=(0.0, 0.0, 0.0), loop_reached_t_s=None,
        stop_xy=None, collisions=0, min_clearance_m=math.nan, path_length_m=0.0, replans=[], stops_no_free_arc=0,
        rolled_over=False, contact_modes=[], min_radius_m=1.0, identity={})))
    assert contract <= set(json.loads((report / "metrics.json").read_text()))
    assert contract <= set(json.loads((batch / "metrics.json").read_text()))
