"""The navigation loop, ROS-free: camera frames and base poses in, gait commands and what to show
out. planner_node (nodes/planner_node.py) only converts messages and calls this; the batch run
(runs/nav_batch.py) feeds it the simulated robot's poses and frames as the node gets them.

    loop = NavLoop(NavConfig.from_yaml(), head_width_m=0.09, perception=DepthTraversability(...),
                   goal_xy=(1.4, 0.0), goal_radius_m=0.15)
    loop.on_pose(t, T_world_base)             # base_pose (4x4 of base_link in the world)
    loop.on_frame(t, depth_m)                 # the latest camera frame (depth in m, or colour for mono)
    loop.on_joints(t, q)                      # joint_states (with body=BodyChain(robot): the body as it lies)
    out = loop.tick(t)                        # at the follower's rate: NavTick

Every replan_period_s (config/nav.yaml follower.replan_period_s) the latest frame with the pose
nearest its stamp (of the last POSE_HISTORY poses) becomes a replan (perception -> perception-space
arcs -> the follower); between replans the follower turns the pose into kappa. The camera's pose
in the replan's ground frame is base_link's pose (the one the driver uses, base_pose) times the
mount of config/nav.yaml camera: (the head bobs with the gait: the mount is the camera's mean pose).

Inputs are checked where they enter (on_pose, on_frame return the reason of a refusal, counted in
`refused`): a pose must be finite, a rotation, inside POSE_WORKSPACE_M and not older than the last one;
a frame must be the camera's size (cfg.intrinsics) with a finite stamp not older than the last one;
joints must be finite, one per joint of the chain, stamps in order. A replan places the body by the
joints nearest its frame's stamp; with none within pose_timeout_s of it, by the curvature commanded
(counted in replans_without_joints).
A pose older than pose_timeout_s or a frame older than frame_timeout_s (or either stamped more than
FUTURE_TOLERANCE_S ahead of the clock) holds the robot (state STALE) until fresh ones arrive; the
first fresh frame after that is replanned at once. tick() never raises: an exception inside it
(perception, planner) is counted in `errors`, kept in `last_error`, and the tick holds (state ERROR).

No free arc: `on_no_free_arc` "hold" (default) stops until a replan finds a free arc; "turn" turns
in place with the follower's kappa_turn_per_m; "back_off" backs off tail first along the track (the
reverse gait, NavTick.backwards; planner_node and the batch run choose it when follower.back_off).
Goal reached (base_link within the goal radius less follower.goal_margin_m, the move the stop itself
makes: stop_radius_m): hold for good, until set_goal gives a new goal.
No goal (goal_xy None at construction, or clear_goal()): hold (state NO_GOAL) until set_goal.
Every hold keeps the body's curvature (NavTick.kappa_per_m is the last kappa commanded, for the nav
config's gaits.stop, hold_curve): straightening a bent body swings its head sideways.
"""
import bisect
import dataclasses
import math
from collections import Counter, deque
from dataclasses import dataclass
from typing import Callable, Optional, Tuple

import numpy as np

from ...perception.ground_region import Traversability
from .body_chain import BodyChain, BodyState
from .follower import BACK_OFF, RecedingHorizonFollower
from .layered_planner import LayeredPlanner
from .planner import NavPlanner, Replan, T_world_ground, ground_frame

FOLLOWING, WAITING, NO_FREE_ARC, GOAL_REACHED = "following", "waiting", "no_free_arc", "goal_reached"
STALE, ERROR = "stale", "error"    # holding: an input too old / an exception inside the tick
NO_GOAL = "no_goal"                # holding: no goal given (or it was cleared)
NO_FREE_ARC_ACTIONS = ("hold", "turn", "back_off")
POSE_HISTORY = 500                 # base poses kept to match a frame's stamp (5 s of 100 Hz)
POSE_WORKSPACE_M = 1000.0          # |x|, |y|, |z| of a pose beyond this is an estimator's blunder
ROTATION_TOLERANCE = 1e-3          # max |R^T R - I| of a pose's rotation
CLOCK_TOLERANCE_S = 1e-6          # a replan due at t is due at a tick stamped a rounding error before t
FUTURE_TOLERANCE_S = 0.5           # a stamp this far ahead of the loop's clock is a clock error, not latency


def checked_positive(key: str, v) -> float:
    """v as a float when it is a finite number > 0, else ValueError naming key and v."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ValueError(f"{key}: must be a finite number > 0, got {v!r}")
    return float(v)


def _nearest(history, t_s: float):
    """The (t_s, value) of a non-empty history (stamps in order) whose stamp is nearest t_s."""
    times = [h[0] for h in history]
    i = bisect.bisect_left(times, t_s)
    return history[min((j for j in (i - 1, i) if 0 <= j < len(times)), key=lambda j: abs(times[j] - t_s))]


def _checked_goal(goal_xy) -> Tuple[float, float]:
    """(x, y) as floats when both are finite, else ValueError naming the value."""
    try:
        x, y = (float(v) for v in goal_xy)
    except (TypeError, ValueError):
        raise ValueError(f"goal_xy: expected two numbers (x, y), got {goal_xy!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"goal_xy: must be finite, got {tuple(goal_xy)!r}")
    return x, y


def make_planner(cfg, head_width_m: float, body):
    """The local planner config/nav.yaml `planner.kind` names, with a follower of cfg.follower."""
    follower = RecedingHorizonFollower(cfg.follower)
    if cfg.planner.kind == "layered":
        return LayeredPlanner(cfg.intrinsics, head_width_m, cfg, follower, body)
    geometry = body.geometry if isinstance(body, BodyChain) else body
    return NavPlanner(cfg.intrinsics, head_width_m, cfg.sampler, follower, geometry, cfg.map)


@dataclass
class NavTick:
    state: str                         # FOLLOWING | WAITING (no frame or pose yet) | NO_FREE_ARC | GOAL_REACHED
                                       # | NO_GOAL (none given or cleared: holding)
                                       # | STALE (an input too old: holding) | ERROR (the tick failed: holding)
    hold: bool                         # stop: the nav config's gaits.stop keeping kappa_per_m (else move)
    kappa_per_m: float = 0.0           # body curvature; while holding, the last one commanded
    backwards: bool = False            # run the gait backwards (backing off with no free arc)
    replan: Optional[Replan] = None    # a replan happened in this tick
    ground: Optional[np.ndarray] = None   # its traversability image
    frame: Optional[np.ndarray] = None    # the frame it used
    T_ground_camera: Optional[np.ndarray] = None
    message: str = ""


class NavLoop:
    def __init__(self, cfg, head_width_m: float, perception: Callable[[np.ndarray], object],
                 goal_xy: Optional[Tuple[float, float]] = None, goal_radius_m: float = 0.1,
                 on_no_free_arc: str = "hold", pose_timeout_s: float = 1.0, body=None,
                 frame_timeout_s: float = 5.0, obstacle_map=None):
        """perception: a frame -> its traversability image (bool) or a ground_region.Traversability
        (with the pixels it did not measure: DepthTraversability.classify).
        body: the robot's BodyChain (body_chain.py: with on_joints, the layered planner's body sweep
        starts from the body as its joints lie) or BodyGeometry (body_model.py: uniform arcs).
        pose_timeout_s, frame_timeout_s: the oldest pose / camera frame the loop still moves on.
        obstacle_map: with map.source truth only, the map given in advance (the simulator's
        diagnostic: ObstacleMap.from_world of the world's obstacles)."""
        if on_no_free_arc not in NO_FREE_ARC_ACTIONS:
            raise ValueError(f"on_no_free_arc: expected hold, turn or back_off, got {on_no_free_arc!r}")
        for key, v in (("goal_radius_m", goal_radius_m), ("pose_timeout_s", pose_timeout_s),
                       ("frame_timeout_s", frame_timeout_s)):
            checked_positive(key, v)
        self.goal_xy = None if goal_xy is None else _checked_goal(goal_xy)
        self.goal_radius_m = float(goal_radius_m)
        self.cfg = cfg
        self.perception = perception
        self.on_no_free_arc = on_no_free_arc
        self.pose_timeout_s = float(pose_timeout_s)
        self.frame_timeout_s = float(frame_timeout_s)
        self.T_base_optical = cfg.mount.T_base_optical()
        follower = dataclasses.replace(cfg.follower, back_off=on_no_free_arc == "back_off")
        if (cfg.map.source == "truth") != (obstacle_map is not None):
            raise ValueError("map.source: truth is the simulator's diagnostic (the world's obstacles, given as "
                             "obstacle_map); a robot's planner maps the faces it sees: use faces or none"
                             if obstacle_map is None else "obstacle_map: given only with map.source truth")
        self.planner = make_planner(dataclasses.replace(cfg, follower=follower), head_width_m, body)
        self.chain = body if isinstance(body, BodyChain) else None
        if obstacle_map is not None:
            self.planner.obstacle_map = obstacle_map
        self.replan_period_s = float(cfg.replan_period_s)
        self._T_wb = None
        self._pose_t = None
        self._history = deque(maxlen=POSE_HISTORY)     # (t_s, T_world_base), in arrival order
        self._frame = None
        self._joints = deque(maxlen=POSE_HISTORY)      # (t_s, q), in arrival order
        self._next_replan = None
        self.state = WAITING if self.goal_xy is not None else NO_GOAL
        self.replans = 0
        self.replans_without_joints = 0    # with a chain: replans on the commanded shape (no fresh joints)
        self.stops_no_free_arc = 0
        self.refused = Counter()           # input kind ("pose", "frame") -> refusals
        self.last_refusal = ""
        self.errors = 0                    # ticks that raised (and held)
        self.last_error = ""
        self._was_stale = False
        self.kappa_per_m = 0.0             # the last kappa commanded while moving (kept by every hold)

    # ---- the goal ----------------------------------------------------------------------------------
    def set_goal(self, goal_xy: Tuple[float, float], goal_radius_m: float) -> None:
        """A new goal (world frame), checked as the constructor's (ValueError naming the value; nothing
        changes then). Ends GOAL_REACHED and NO_GOAL: the loop moves again, replanning at the next tick."""
        xy, radius = _checked_goal(goal_xy), checked_positive("goal_radius_m", goal_radius_m)
        self.goal_xy, self.goal_radius_m = xy, radius
        self.state = WAITING
        self._next_replan = None

    def clear_goal(self) -> None:
        """No goal: every tick holds (state NO_GOAL, the body's curvature kept) until set_goal."""
        self.goal_xy = None
        self.state = NO_GOAL
        self._next_replan = None

    # ---- inputs ------------------------------------------------------------------------------------
    def refuse(self, kind: str, reason: str) -> str:
        """Counts a refused input and keeps its reason as last_refusal; returns the reason."""
        self.refused[kind] += 1
        self.last_refusal = f"{kind}: {reason}"
        return reason

    def on_pose(self, t_s: float, T_world_base: np.ndarray) -> Optional[str]:
        """base_link's pose at t_s. None when taken, else why it was refused (nothing changes then)."""
        T = np.asarray(T_world_base, float)
        if T.shape != (4, 4) or not np.all(np.isfinite(T)):
            return self.refuse("pose", "not finite" if T.shape == (4, 4) else f"shape {T.shape}, expected (4, 4)")
        if not math.isfinite(t_s):
            return self.refuse("pose", f"stamp {t_s!r} not finite")
        if np.max(np.abs(T[:3, 3])) > POSE_WORKSPACE_M:
            return self.refuse("pose", f"position {tuple(np.round(T[:3, 3], 3))} beyond {POSE_WORKSPACE_M:g} m")
        R = T[:3, :3]
        if np.max(np.abs(R.T @ R - np.eye(3))) > ROTATION_TOLERANCE or np.linalg.det(R) < 0:
            return self.refuse("pose", "orientation is not a rotation")
        if self._pose_t is not None and t_s < self._pose_t:
            return self.refuse("pose", f"stamp {t_s:.3f} s older than the last pose's {self._pose_t:.3f} s")
        self._T_wb = T
        self._pose_t = float(t_s)
        self._history.append((self._pose_t, self._T_wb))
        return None

    def pose_at(self, t_s: float) -> np.ndarray:
        """base_link's pose nearest t_s among the recent ones (the latest when the history is empty)."""
        if not self._history:
            return self._T_wb
        return _nearest(self._history, t_s)[1]

    def on_frame(self, t_s: float, image: np.ndarray) -> Optional[str]:
        """The latest camera frame (what the perception reads: depth in m or colour, the size of
        cfg.intrinsics). None when taken, else why it was refused (the last good frame stays)."""
        k = self.cfg.intrinsics
        shape = getattr(image, "shape", None)
        if shape is None or len(shape) not in (2, 3) or tuple(shape[:2]) != (k.height, k.width):
            return self.refuse("frame", f"size {'x'.join(str(v) for v in reversed(shape[:2])) if shape else None}"
                                        f" differs from the camera's {k.width}x{k.height} (camera_info)")
        if not math.isfinite(t_s):
            return self.refuse("frame", f"stamp {t_s!r} not finite")
        if self._frame is not None and t_s < self._frame[0]:
            return self.refuse("frame", f"stamp {t_s:.3f} s older than the last frame's {self._frame[0]:.3f} s")
        self._frame = (float(t_s), image)
        return None

    def on_joints(self, t_s: float, q) -> Optional[str]:
        """The joints' measured angles at t_s (rad, joint_1 .. joint_N: joint_states). None when taken,
        else why it was refused (nothing changes then). Without a BodyChain they are refused."""
        chain = self.chain
        if chain is None:
            return self.refuse("joints", "this loop has no body chain (body: BodyChain) to place them on")
        q = np.asarray(q, float)
        if q.shape != (chain.num_joints,):
            return self.refuse("joints", f"shape {q.shape}, expected ({chain.num_joints},)")
        if not (math.isfinite(t_s) and np.all(np.isfinite(q))):
            return self.refuse("joints", "not finite")
        if self._joints and t_s < self._joints[-1][0]:
            return self.refuse("joints", f"stamp {t_s:.3f} s older than the last joints' {self._joints[-1][0]:.3f} s")
        self._joints.append((float(t_s), q))
        return None

    def body_at(self, t_s: float, T_ground_base: np.ndarray) -> Optional[BodyState]:
        """The body as its joints lay nearest t_s (base_link at T_ground_base in the replan's ground
        frame), None without joints within pose_timeout_s of t_s."""
        if not self._joints:
            return None
        t_joints, q = _nearest(self._joints, t_s)
        return BodyState(q, T_ground_base) if abs(t_joints - t_s) <= self.pose_timeout_s else None

    @property
    def pose(self):
        return None if self._T_wb is None else ground_frame(self._T_wb)

    def distance_to_goal_m(self) -> Optional[float]:
        p = self.pose
        if p is None or self.goal_xy is None:
            return None
        return math.hypot(self.goal_xy[0] - p[0], self.goal_xy[1] - p[1])

    # ---- the tick ----------------------------------------------------------------------------------
    def tick(self, t_s: float) -> NavTick:
        """The command for t_s; never raises (an exception holds: state ERROR, counted in errors)."""
        try:
            out = self._tick(t_s)
        except Exception as exc:      # noqa: BLE001 - the loop must outlive any bug or bad frame
            self.errors += 1
            self.last_error = f"{type(exc).__name__}: {exc}"[:300]
            self._next_replan = None          # replan on the next tick that works
            out = NavTick(ERROR, True, message=f"tick failed ({self.last_error}): holding")
        if out.hold:
            out.kappa_per_m, out.backwards = self.kappa_per_m, False
        else:
            self.kappa_per_m = out.kappa_per_m
        return out

    def stale(self, t_s: float) -> Optional[str]:
        """Why the pose or the frame is too old (or ahead of the clock) to move on, else None."""
        for what, t_in, limit, key in (("base pose", self._pose_t, self.pose_timeout_s, "pose_timeout_s"),
                                       ("camera frame", self._frame[0], self.frame_timeout_s, "frame_timeout_s")):
            age = t_s - t_in
            if age > limit:
                return f"{what} {age:.1f} s old ({key} {limit:g})"
            if age < -FUTURE_TOLERANCE_S:
                return f"{what} stamped {-age:.1f} s ahead of the clock"
        return None

    def stop_radius_m(self) -> float:
        """The loop stops at the goal when base_link is this near its centre: the goal radius less the
        follower's goal_margin_m (the stop's own move), but never less than half the radius."""
        return max(self.goal_radius_m - self.cfg.follower.goal_margin_m, 0.5 * self.goal_radius_m)

    def _tick(self, t_s: float) -> NavTick:
        if self.state == GOAL_REACHED:
            return NavTick(GOAL_REACHED, True, message="goal reached: holding")
        if self.goal_xy is None:
            self.state = NO_GOAL
            return NavTick(NO_GOAL, True, message="no goal: holding")
        d = self.distance_to_goal_m()
        if d is not None and d <= self.stop_radius_m():
            self.state = GOAL_REACHED
            return NavTick(GOAL_REACHED, True, message=f"goal reached: base_link {d:.3f} m from the goal, holding")
        if self._T_wb is None or self._frame is None:
            return NavTick(WAITING, True, message="waiting for " + ("a base pose" if self._T_wb is None else
                                                                      "a camera frame"))
        why = self.stale(t_s)
        if why is not None:
            self._was_stale = True
            return NavTick(STALE, True, message=f"{why}: holding")
        if self._was_stale:                   # moving again: on what the camera shows now
            self._was_stale, self._next_replan = False, None
        pose = self.pose
        out = NavTick(self.state, False)
        if self._next_replan is None or t_s >= self._next_replan - CLOCK_TOLERANCE_S:
            self._next_replan = t_s + self.replan_period_s
            out = self._replan(t_s, pose)
        cmd = self.planner.command(t_s, pose)
        if self.state == NO_FREE_ARC and (self.on_no_free_arc == "hold" or self.planner.holding):
            out.hold = True
        else:
            out.hold, out.kappa_per_m = False, float(cmd.kappa_per_m)
            out.backwards = cmd.mode == BACK_OFF
        out.state = self.state
        if not out.message:
            out.message = cmd.reason or f"{cmd.mode}: kappa {cmd.kappa_per_m:+.2f} /m"
        return out

    def _replan(self, t_s: float, pose) -> NavTick:
        t_frame, image = self._frame
        seen = self.perception(image)
        ground, unknown = (seen.ground, seen.unknown) if isinstance(seen, Traversability) else (seen, None)
        ground = np.asarray(ground, bool)
        T_wb = self.pose_at(t_frame)           # where the camera was when it took the frame
        pose = ground_frame(T_wb)
        T_gb = np.linalg.inv(T_world_ground(pose)) @ T_wb
        T_gc = T_gb @ self.T_base_optical
        body = self.body_at(t_frame, T_gb)
        if body is None and self.chain is not None:
            self.replans_without_joints += 1
        r = self.planner.replan(t_s, ground, T_gc, pose, self.goal_xy, self.goal_radius_m, unknown, body)
        self.replans += 1
        if r.path_world is None:
            self.stops_no_free_arc += 1
            self.state = NO_FREE_ARC
            action = {"hold": "holding", "turn": "turning in place", "back_off": "backing off along the track"}[
                self.on_no_free_arc]
            msg = f"no collision-free arc ({len(r.selection.arcs)} candidates): {action} until a replan finds one"
        else:
            self.state = FOLLOWING
            msg = r.reason
        return NavTick(self.state, False, replan=r, ground=ground, frame=image, T_ground_camera=T_gc, message=msg)
