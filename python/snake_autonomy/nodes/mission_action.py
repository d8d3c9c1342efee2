"""The RunMission action of mission_node (actionlib server ``mission/run``), the message side only:
goal -> Mission, tracker decision -> feedback, run metrics -> result. The node does the wiring.

Goal: exactly one of ``mission`` (a .yaml/.yml file, or a provided mission's name: only
config/missions/NAME.yaml), ``mission_yaml`` (a whole mission as YAML text, read by the same bounded
loader as the files: safe_yaml.load_yaml_text) or ``waypoints`` (geometry_msgs/Pose2D, theta in rad;
the defaults for the rest; in the world frame: nodes.mission_goal_frame brings those in ``frame_id`` there
first). Result: the run's outcome and per-waypoint metrics, computed from the decisions of this run
(runs.results.compute_metrics, the same figures as metrics.json). Cancel: aborts the mission
(hold sent); the goal ends preempted with the metrics so far.
"""
import math
from typing import Any, Dict, List, Sequence

from snake_autonomy.runs.results import compute_metrics
from snake_autonomy.missions import MissionError, load_mission
from snake_autonomy.missions.mission import mission_from_text, validate_mission

NAN = float("nan")
DECISION_KEYS = ("t", "waypoint_index", "target_index", "reached", "distance", "yaw_error_abs", "yaw_error_rel",
                 "yaw_error", "pose_stale")


def mission_from_goal(goal, defaults, gait_library):
    """The Mission a RunMission goal asks for; MissionError naming the goal field otherwise."""
    given = [name for name, present in (("mission", bool(goal.mission)), ("mission_yaml", bool(goal.mission_yaml)),
                                        ("waypoints", bool(goal.waypoints))) if present]
    if len(given) != 1:
        raise MissionError("RunMission goal", [f"give exactly one of mission, mission_yaml, waypoints; got "
                                               f"{', '.join(given) or 'none'}"])
    if goal.mission:
        return load_mission(goal.mission, defaults=defaults, gait_library=gait_library)
    if goal.mission_yaml:
        return mission_from_text(goal.mission_yaml, "RunMission goal mission_yaml", defaults, gait_library)
    data = {"name": goal.name or "inline",
            "waypoints": [[p.x, p.y, math.degrees(p.theta)] for p in goal.waypoints]}
    return validate_mission(data, "RunMission goal waypoints", defaults, gait_library)


class DecisionSeries:
    """The decisions of one run, in the arrays compute_metrics reads."""

    def __init__(self):
        self.data: Dict[str, List[Any]] = {k: [] for k in DECISION_KEYS}

    def add(self, t_s: float, status: Dict[str, Any]) -> None:
        reached = bool(status["waypoint_reached"])
        row = dict(t=t_s, waypoint_index=status["waypoint_index"],
                   target_index=status["waypoint_index"] - int(reached), reached=reached,
                   distance=status["distance"], yaw_error_abs=status["yaw_error_abs"],
                   yaw_error_rel=status["yaw_error_rel"], yaw_error=status["yaw_error"],
                   pose_stale=status["pose_stale"])
        for k in DECISION_KEYS:
            self.data[k].append(row[k])

    def metrics(self, waypoints: Sequence[Sequence[float]], outcome: str, t0: float) -> Dict[str, Any]:
        return compute_metrics(waypoints, self.data, None, outcome, t0)


def _num(v) -> float:
    return NAN if v is None else float(v)


def fill_feedback(feedback, status: Dict[str, Any], leg_state: str = ""):
    """A decision's feedback: leg_state non-empty on a navigate_to leg's ticks (Decision.leg_state)."""
    feedback.leg, feedback.leg_state = ("navigate_to" if leg_state else "track"), leg_state
    feedback.waypoint_index = int(status["waypoint_index"])
    feedback.num_waypoints = int(status["num_waypoints"])
    feedback.distance = float(status["distance"])
    feedback.yaw_error = float(status["yaw_error"])
    feedback.mode = int(status["mode"])
    feedback.gait = str(status["gait"])
    feedback.pose_stale = bool(status["pose_stale"])
    return feedback


def fill_result(result, waypoint_class, mission_name: str, state: str, outcome: str,
                metrics: Dict[str, Any], path_length_m: float = NAN, run_dir: str = ""):
    result.mission, result.state, result.outcome = mission_name, state, outcome
    result.waypoints_reached = int(metrics["waypoints_reached"])
    result.duration_s = float(metrics["duration_s"])
    result.path_length_m = float(path_length_m)
    result.run_dir = run_dir
    result.waypoints = [waypoint_class(index=e["index"], x_m=e["x_m"], y_m=e["y_m"], heading_deg=e["heading_deg"],
                                       reached=e["reached"], time_to_reach_s=_num(e["time_to_reach_s"]),
                                       segment_duration_s=_num(e["segment_duration_s"]),
                                       final_distance_m=_num(e["final_distance_m"]),
                                       final_yaw_error_abs_deg=_num(e["final_yaw_error_abs_deg"]),
                                       min_distance_m=_num(e["min_distance_m"]))
                        for e in metrics["waypoints"]]
    return result
