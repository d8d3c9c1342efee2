"""The ROS run's watcher decides a node has died only when its pid is gone, its URI no longer answers
and roslaunch saw it die; a launch stopped from outside (its nodes killed on exit) is not a node death.
The lookups are injected: no ROS master."""
from snake_autonomy.runs.nav_ros_watch import NodeCheck, Watch


class FakeLaunch:
    """Processes by pid, each node's getPid answer (None: its URI silent) and roslaunch's dead list
    (None: roslaunch gone)."""

    def __init__(self, pids):
        self.live = set(pids.values())
        self.answers = dict(pids)
        self.roslaunch_dead = set()

    def check(self, pids):
        return NodeCheck(pids, pid_of=self.answers.get,
                         seen_dead=lambda: None if self.roslaunch_dead is None else set(self.roslaunch_dead),
                         alive=lambda pid: pid in self.live, confirm_s=30.0)


def test_a_live_node_whose_first_pid_is_gone_but_whose_uri_answers_a_live_pid_is_not_dead():
    launch = FakeLaunch({"/driver": 100, "/robot_state_publisher": 200})
    check = launch.check({"/driver": 100, "/robot_state_publisher": 999})   # a pid no process has
    assert check.check(5.0) == (None, None)
    assert check.pids["/robot_state_publisher"] == 200 and not check.suspect
    assert check.check(10.0) == (None, None)


def test_a_node_whose_process_is_gone_and_whose_uri_is_silent_ends_the_run_with_its_name():
    launch = FakeLaunch({"/driver": 100, "/planner": 300})
    check = launch.check(dict(launch.answers))
    launch.live.discard(300)
    launch.answers["/planner"] = None
    launch.roslaunch_dead.add("/planner")
    died, stopped = check.check(5.0)
    assert (died, stopped) == ("/planner", None)
    w = Watch((1.0, 0.0), 0.15, time_limit_s=100.0, t0=0.0)
    assert w.step(5.0, died, stopped) == "node_died: /planner"


def test_nodes_killed_by_a_stopping_roslaunch_end_the_run_as_launch_stopped_not_node_died():
    launch = FakeLaunch({"/driver": 100, "/robot_state_publisher": 200, "/sim": 400})
    check = launch.check(dict(launch.answers))
    launch.live.discard(200)                        # killed on exit first: roslaunch still lists it active
    launch.answers["/robot_state_publisher"] = None
    assert check.check(5.0) == (None, None) and "/robot_state_publisher" in check.suspect
    launch.roslaunch_dead = None                    # roslaunch's server gone with the launch
    died, stopped = check.check(6.0)
    assert died is None and "/robot_state_publisher" in stopped
    w = Watch((1.0, 0.0), 0.15, time_limit_s=100.0, t0=0.0)
    assert w.step(6.0, died, stopped).startswith("launch_stopped: /robot_state_publisher")


def test_a_gone_node_roslaunch_never_reports_dead_is_declared_dead_after_the_confirmation_time():
    launch = FakeLaunch({"/sim": 400})
    check = launch.check(dict(launch.answers))
    launch.live.discard(400)
    launch.answers["/sim"] = None
    assert check.check(5.0) == (None, None)
    assert check.check(34.0) == (None, None)
    assert check.check(35.0) == ("/sim", None)
