"""planner_node: navigation among obstacles with the rectilinear gait (Chang et al.).
Wiring only: the logic is planning.rectilinear.nav_loop.NavLoop (perception -> perception-space
arcs -> receding-horizon follower), the same classes the batch run (runs/nav_batch.py) uses.

Subscribes  base_pose (geometry_msgs/PoseWithCovarianceStamped): base_link's pose, what the driver
            steers with (motion capture, or pose_remap_node's from the VIO). Not com_pose: the arcs
            start at base_link (the head, where the camera is) and the camera's pose is base_link's
            times the mount; com_pose is the body's centre of mass and virtual-chassis heading.
            camera/color/image_raw + camera/color/camera_info (sensor_msgs; the intrinsics come from
            the first camera_info), camera/depth/image_rect_raw (32FC1 m or 16UC1 mm; ~perception depth),
            joint_states (sensor_msgs/JointState, the driver's: the body sweep starts from the body as
            its joints lie, body_chain.py; without them, from the shape of the curvature commanded).
Publishes   gait_command (snake_autonomy/GaitCommand at ~rate_hz: ~gait with curve=true and kappa;
            ~stop_gait keeping the last kappa while waiting for an input, with no free arc and once
            the goal is reached or while there is none; the straight hold before camera_info arrives),
            nav/path (nav_msgs/Path: the chosen arc's free prefix, latched), nav/route (nav_msgs/Path:
            the route on the obstacle map the goal bias steers by, latched; nav config map.route), nav/arcs
            (visualization_msgs/MarkerArray: every candidate, chosen green, free parts yellow,
            blocked red), nav/traversability (sensor_msgs/Image rgb8: the frame with non-ground tinted
            red and the arcs drawn), nav/traversability_mask (sensor_msgs/Image mono8, same stamp and frame:
            255 ground, 0 not), nav/map (nav_msgs/OccupancyGrid, latched, after each replan when map.source
            is not none: the obstacle map on map.cell_m cells, planner_display.occupancy; with planner.kind
            layered its local map with unknown cells, planner_display.local_grid),
            /diagnostics ("planner: navigation": WARN with no free arc, OK otherwise; replans, stops,
            distance to the goal, the follower's mode, the goal and its source, goals refused),
            nav/goal (visualization_msgs/Marker, latched: the goal's disc; planner_goals.py).
Reconfigure ~follower (dynamic_reconfigure, cfg/Follower.cfg): the follower's k_heading, lookahead_m and
            kappa_rate_per_m_s at run time, applied at the next tick (nodes/gain_tuning.py); start values from
            ~nav_config's follower:; "planner: follower gains" on /diagnostics shows the ones in use.
Goals       optional at start: ~world (a world file: its goal and goal radius) or ~goal ("x,y", the world
            frame) + ~goal_radius_m; without either the robot holds (state no_goal) until a goal comes:
            move_base_simple/goal (geometry_msgs/PoseStamped: rviz's "2D Nav Goal") or the action below,
            in any frame tf2 can transform into the world frame. A new goal replaces the current one
            (also one reached); the reached goal holds the robot as before.
Actions     move_base (move_base_msgs/MoveBaseAction, move_base's conventions): feedback every tick
            (base_position), succeeded inside the goal's disc, aborted with the reason (the goal unusable,
            or not following for ~abort_after_s), preempted by a new goal or a cancel (the robot holds).
Params      ~world or ~goal (above), ~goal_radius_m (0.2: ~goal's and every goal that arrives), ~abort_after_s
            (60: an action goal's loop not following this long aborts it); ~nav_config
            (config/nav.yaml), ~robot_config (config/robots/cobra.yaml: head width, link radius),
            ~perception (depth|mono), ~classifier (model file, mono), ~rate_hz (2: the follower's
            command rate), ~gait, ~reverse_gait, ~stop_gait (default: ~nav_config's gaits:),
            ~on_no_free_arc (hold|turn|back_off; default back_off when the nav config's
            follower.back_off, else hold), ~world_frame (frame of
            the path and markers; default base_pose's frame_id), ~pose_timeout_s (1.0),
            ~frame_timeout_s (5.0: the oldest camera frame the robot moves on; give it at least
            two camera periods), ~command_without_goal (hold|none, below).
Commands    with a goal being driven to, gait_command goes out every tick. Without one (none yet, reached,
            cancelled, aborted): ~command_without_goal hold (default) keeps sending the hold, the driver's
            heartbeat (a navigation-only run); none sends the stop gait on the tick the goal ends and then
            nothing, so another node (the mission node's tracker, between its navigate_to legs) is the
            only one commanding the driver.
Inputs      every message is checked before it is used: camera_info (size, fx, fy > 0, finite),
            images (encoding, size equal to camera_info's, bytes), poses (finite, unit quaternion,
            stamps in order). A bad one is dropped, counted and named on /diagnostics (a throttled
            warning too); a pose or frame older than its timeout holds the robot. Nothing that
            arrives, and no bug in a tick, can end the command loop: a tick that fails sends hold.
"""
import dataclasses
import math
from collections import Counter

import diagnostic_updater
import numpy as np
import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point, PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Path
from sensor_msgs.msg import CameraInfo, Image, JointState
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from snake_autonomy import _core
from snake_autonomy.msg import GaitCommand
from snake_autonomy.nodes.gain_tuning import FollowerGains
from snake_autonomy.nodes.image_msgs import from_camera_info, from_image, to_image
from snake_autonomy.nodes.planner_display import local_grid, occupancy, traversability_mask
from snake_autonomy.nodes.planner_goals import PARAMETER, Goal, GoalServer
from snake_autonomy.paths import config_path, resolve_world_path
from snake_autonomy.perception.block_classifier import BlockClassifier
from snake_autonomy.perception.depth_traversability import DepthTraversability
from snake_autonomy.planning.rectilinear.body_chain import BodyChain
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera, head_width_m
from snake_autonomy.planning.rectilinear.nav_loop import (ERROR, FOLLOWING, GOAL_REACHED, NO_FREE_ARC, NO_GOAL, STALE,
                                                          WAITING, NavLoop, checked_positive)
from snake_autonomy.planning.rectilinear.overlay import overlay
from snake_autonomy.planning.rectilinear.planner import to_world
from snake_autonomy.sim.world_file import load_world
from snake_autonomy.transforms import pose_to_matrix

QUATERNION_TOLERANCE = 0.01     # | |q| - 1 | beyond this is not an orientation (as the driver's rule)
WARN_PERIOD_S = 5.0             # refusals and errors are logged at most this often (all are counted)

GREEN, YELLOW, RED = ColorRGBA(0.1, 0.9, 0.1, 1.0), ColorRGBA(0.95, 0.85, 0.1, 1.0), ColorRGBA(0.9, 0.1, 0.1, 1.0)


class PlannerNode:
    def __init__(self):
        self.cfg = NavConfig.from_yaml(rospy.get_param("~nav_config", str(config_path("nav.yaml"))))
        self.robot_yaml = rospy.get_param("~robot_config", str(config_path("robots", "cobra.yaml")))
        self.head_width_m = head_width_m(self.robot_yaml)
        self.robot = _core.RobotModel.from_yaml(self.robot_yaml)
        self.joint_index = {name: i for i, name in enumerate(self.robot.joint_names)}
        self.perception = rospy.get_param("~perception", "depth")
        if self.perception not in ("depth", "mono"):
            raise ValueError(f"~perception: expected depth or mono, got {self.perception!r}")
        self.classifier = rospy.get_param("~classifier", "")
        if self.perception == "mono" and not self.classifier:
            raise ValueError("~classifier: perception mono needs a model file (snake_autonomy nav train-classifier)")
        self.goal_radius_m = float(rospy.get_param("~goal_radius_m", 0.2))
        self.abort_after_s = float(rospy.get_param("~abort_after_s", 60.0))
        if self.cfg.gaits.steering != "uniform":
            raise ValueError(f"~nav_config: gaits.steering {self.cfg.gaits.steering!r} is a prototype of "
                             "bench/nav_follow_the_leader; this node commands curve + kappa (uniform)")
        g = self.cfg.gaits
        self.gaits = dataclasses.replace(g, forward=rospy.get_param("~gait", g.forward),
                                         reverse=rospy.get_param("~reverse_gait", g.reverse),
                                         stop=rospy.get_param("~stop_gait", g.stop))
        # the nav config's choice (follower.back_off: back off, else hold) unless the param says
        self.on_no_free_arc = rospy.get_param("~on_no_free_arc", "back_off" if self.cfg.follower.back_off else "hold")
        self.rate_hz = float(rospy.get_param("~rate_hz", 2.0))
        self.pose_timeout_s = float(rospy.get_param("~pose_timeout_s", 1.0))
        self.frame_timeout_s = float(rospy.get_param("~frame_timeout_s", 5.0))
        for key, v in (("~rate_hz", self.rate_hz), ("~pose_timeout_s", self.pose_timeout_s),
                       ("~frame_timeout_s", self.frame_timeout_s), ("~goal_radius_m", self.goal_radius_m),
                       ("~abort_after_s", self.abort_after_s)):
            checked_positive(key, v)
        self.world_frame = rospy.get_param("~world_frame", "")
        self.command_without_goal = rospy.get_param("~command_without_goal", "hold")
        if self.command_without_goal not in ("hold", "none"):
            raise ValueError(f"~command_without_goal: expected hold or none, got {self.command_without_goal!r}")
        self.commanding = False           # the last tick drove to a goal (the next one without sends the stop)
        self.send_now = self.command_without_goal == "hold"   # this tick's command goes out (gate())
        self.loop = None
        self.applied = None               # (loop, goal seq) the loop's goal was last set for
        self.base_pose = None             # the latest base pose taken (PoseStamped: the action's feedback)
        self.rgb = None
        self.last_tick = None
        self.intrinsics = None            # of the camera_info the loop was built with
        self.refused = Counter()          # input kind -> refused by this node (the loop counts its own)
        self.last_refusal = ""
        self.warned = {}                  # input kind -> time of its last warning
        self.node_errors = 0              # exceptions in this node's own code (publishing, overlay)
        self.last_node_error = ""
        self.pub_cmd = rospy.Publisher("gait_command", GaitCommand, queue_size=10)
        self.pub_path = rospy.Publisher("nav/path", Path, queue_size=1, latch=True)
        self.pub_route = rospy.Publisher("nav/route", Path, queue_size=1, latch=True)
        self.pub_arcs = rospy.Publisher("nav/arcs", MarkerArray, queue_size=1, latch=True)
        self.pub_trav = rospy.Publisher("nav/traversability", Image, queue_size=1, latch=True)
        self.pub_mask = rospy.Publisher("nav/traversability_mask", Image, queue_size=1, latch=True)
        self.pub_map = rospy.Publisher("nav/map", OccupancyGrid, queue_size=1, latch=True)
        self.updater = diagnostic_updater.Updater()
        self.updater.setHardwareID("rectilinear_planner")
        self.updater.add("navigation", self.diagnose)
        self.gains = FollowerGains(self)   # the ~follower Server, "follower gains" on /diagnostics
        self.goals = GoalServer(self._goal(), self.goal_radius_m, self.abort_after_s, lambda: self.world_frame)
        g = self.guarded
        rospy.Subscriber("camera/color/camera_info", CameraInfo, g(self.on_info, "camera_info"), queue_size=1)
        rospy.Subscriber("base_pose", PoseWithCovarianceStamped, g(self.on_pose, "base_pose"), queue_size=5)
        rospy.Subscriber("joint_states", JointState, g(self.on_joints, "joint_states"), queue_size=5)
        rospy.Subscriber("camera/color/image_raw", Image, g(self.on_colour, "colour image"), queue_size=1,
                         buff_size=2 ** 24)
        if self.perception == "depth":
            rospy.Subscriber("camera/depth/image_rect_raw", Image, g(self.on_depth, "depth image"), queue_size=1,
                             buff_size=2 ** 24)
        self.timer = rospy.Timer(rospy.Duration(1.0 / self.rate_hz), self.on_timer)
        goal = self.goals.goal
        goal_text = "none (waiting for one)" if goal is None else f"{goal.xy} (radius {goal.radius_m:g} m)"
        rospy.loginfo(f"planner: {self.perception} perception, goal {goal_text}, gait {self.gaits.forward}, "
                      f"replan every {self.cfg.replan_period_s:g} s, commands at {self.rate_hz:g} Hz")

    def _goal(self):
        """The goal at start: ~world's, ~goal's, or None (the robot holds until one arrives)."""
        world = rospy.get_param("~world", "")
        if world:
            w = load_world(resolve_world_path(world))
            return Goal((float(w.goal[0]), float(w.goal[1])), float(w.goal_radius_m), PARAMETER)
        goal = str(rospy.get_param("~goal", ""))
        if not goal:
            return None
        try:
            x, y = (float(v) for v in goal.split(","))
        except ValueError:
            raise ValueError(f"~goal: expected x,y, got {goal!r}") from None
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError(f"~goal: must be finite, got {goal!r}")
        return Goal((x, y), self.goal_radius_m, PARAMETER)

    # -- inputs ---------------------------------------------------------------------------------------
    def refuse(self, kind: str, reason: str) -> None:
        """Counts and reports an input this node dropped (the loop keeps what it had)."""
        self.refused[kind] += 1
        self.report_refusal(kind, reason)

    def report_refusal(self, kind: str, reason: str) -> None:
        """Names a dropped input on /diagnostics and in a throttled warning (counted by whoever dropped it)."""
        self.last_refusal = f"{kind}: {reason}"
        self.warn_throttled(kind, f"planner: {kind} dropped: {reason}")

    def warn_throttled(self, kind: str, text: str) -> None:
        """At most one warning per kind of input every WARN_PERIOD_S (rospy throttles per call site)."""
        now = rospy.get_time()
        if now - self.warned.get(kind, -math.inf) >= WARN_PERIOD_S or now < self.warned.get(kind, 0.0):
            self.warned[kind] = now
            rospy.logwarn(text)

    def guarded(self, callback, what: str):
        """callback(msg), never raising into rospy: a bug costs that message only (counted)."""
        def wrapper(msg):
            try:
                callback(msg)
            except Exception as exc:      # noqa: BLE001 - one bad message must not cost the node
                self.node_error(what, exc)
        return wrapper

    def node_error(self, what: str, exc: Exception) -> None:
        self.node_errors += 1
        self.last_node_error = f"{what}: {type(exc).__name__}: {exc}"[:300]
        rospy.logerr_throttle(WARN_PERIOD_S, f"planner: {self.last_node_error}")

    def on_info(self, msg):
        try:
            intr = from_camera_info(msg)
        except ValueError as exc:
            self.refuse("camera_info", str(exc))
            return
        if self.loop is not None:
            if intr != self.intrinsics:
                self.refuse("camera_info", f"{intr.width}x{intr.height} fx {intr.fx:g} differs from the one in use "
                                           f"({self.intrinsics.width}x{self.intrinsics.height} fx "
                                           f"{self.intrinsics.fx:g}): restart the planner to change cameras")
            return
        cfg = dataclasses.replace(self.cfg, intrinsics=intr)
        robot = self.robot
        if self.perception == "depth":
            perceive = DepthTraversability(intr, T_ground_camera(cfg.mount, robot.link_radius_m), cfg.depth).classify
        else:
            clf, margin = BlockClassifier.load(self.classifier), cfg.classifier.ground_margin
            perceive = lambda rgb: clf.traversable(rgb, margin)
        loop = NavLoop(cfg, self.head_width_m, perceive, None, self.goal_radius_m,   # the tick sets the goal
                       self.on_no_free_arc, self.pose_timeout_s,
                       BodyChain(robot), frame_timeout_s=self.frame_timeout_s)
        self.intrinsics, self.loop = intr, loop
        rospy.loginfo(f"planner: camera {intr.width}x{intr.height}, fx {intr.fx:g} (camera_info)")

    def on_pose(self, msg):
        if not self.world_frame:
            self.world_frame = msg.header.frame_id
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        xyz, xyzw = (p.x, p.y, p.z), (q.x, q.y, q.z, q.w)
        if not all(math.isfinite(v) for v in xyz + xyzw):
            self.refuse("pose", f"not finite: position {xyz}, orientation {xyzw}")
            return
        norm = math.sqrt(sum(v * v for v in xyzw))
        if abs(norm - 1.0) > QUATERNION_TOLERANCE:
            self.refuse("pose", f"quaternion norm {norm:.6g} (tolerance {QUATERNION_TOLERANCE:g})")
            return
        if self.loop is not None:
            why = self.loop.on_pose(msg.header.stamp.to_sec(), pose_to_matrix(xyz, [v / norm for v in xyzw]))
            if why is not None:
                self.report_refusal("pose", why)
                return
        self.base_pose = PoseStamped(header=msg.header, pose=msg.pose.pose)

    def on_joints(self, msg):
        """joint_states: every joint of the robot by name (in any order), else dropped and counted."""
        if len(msg.name) != len(msg.position):
            self.refuse("joints", f"{len(msg.name)} names, {len(msg.position)} positions")
            return
        q = np.zeros(len(self.joint_index))
        given = {n: v for n, v in zip(msg.name, msg.position) if n in self.joint_index}
        for name, v in given.items():
            q[self.joint_index[name]] = v
        missing = [n for n in self.joint_index if n not in given]
        if missing:
            self.refuse("joints", f"no position for {', '.join(missing)}")
            return
        if self.loop is not None:
            why = self.loop.on_joints(msg.header.stamp.to_sec(), q)
            if why is not None:
                self.report_refusal("joints", why)

    def on_image(self, msg, kind: str):
        try:
            image = from_image(msg)
        except ValueError as exc:
            self.refuse(kind, str(exc))
            return None
        if self.loop is not None and (kind == "depth") == (self.perception == "depth"):
            why = self.loop.on_frame(msg.header.stamp.to_sec(), image)
            if why is not None:
                self.report_refusal(kind, why)
        return image

    def on_colour(self, msg):
        rgb = self.on_image(msg, "colour")
        if rgb is not None:
            self.rgb = rgb

    def on_depth(self, msg):
        self.on_image(msg, "depth")

    # -- the tick ------------------------------------------------------------------------------------
    def on_timer(self, _event):
        """The command loop (rospy ends a Timer whose callback raises: nothing may escape here)."""
        try:
            self.tick()
        except Exception as exc:          # noqa: BLE001 - the loop outlives any bug: hold and say why
            self.node_error("tick", exc)
            try:
                self.publish_command(True, self.loop.kappa_per_m if self.loop is not None else 0.0)
            except Exception as exc2:     # noqa: BLE001 - publishing during shutdown
                self.node_error("hold", exc2)
        try:
            self.updater.update()
        except Exception as exc:          # noqa: BLE001
            self.node_error("diagnostics", exc)

    def tick(self):
        now = rospy.Time.now()
        goal, seq = self.goals.poll()            # what arrived since the last tick: the goal now
        loop = self.loop
        self.gains.before_tick(loop)             # gains tuned since the last tick (dynamic_reconfigure)
        if loop is None:
            self.gate(goal is not None)
            self.publish_command(True, 0.0, straight=True)
            self.goals.report(now.to_sec(), WAITING, "waiting for camera_info", self.base_pose)
            return
        if self.applied != (loop, seq):
            if goal is None:
                loop.clear_goal()
            else:
                loop.set_goal(goal.xy, goal.radius_m)
            self.applied = (loop, seq)
        tick = loop.tick(now.to_sec())           # never raises: a failed tick holds (state error)
        previous, self.last_tick = self.last_tick, tick
        if tick.state != (previous.state if previous else None) and tick.state in (STALE, ERROR):
            rospy.logwarn(f"planner: {tick.message}")
        self.gate(goal is not None and tick.state != GOAL_REACHED)
        self.publish_command(tick.hold, tick.kappa_per_m, tick.backwards)
        if tick.replan is not None:
            try:
                self.publish_replan(now, tick)
            except Exception as exc:      # noqa: BLE001 - a display problem never stops the robot
                self.node_error("publishing the replan", exc)
            if tick.replan.path_world is None:
                rospy.logwarn(f"planner: {tick.message}")
            else:
                d = self.loop.distance_to_goal_m()
                rospy.loginfo(f"planner: replan {self.loop.replans}: {tick.message}; goal {d:.2f} m away")
        if tick.state == GOAL_REACHED and (previous is None or previous.state != GOAL_REACHED):
            rospy.loginfo(f"planner: {tick.message}")
        self.goals.report(now.to_sec(), tick.state, tick.message, self.base_pose)

    def gate(self, driving: bool) -> None:
        """Whether this tick's command goes out (~command_without_goal none: only while a goal is driven
        to, and on the tick it ends, whose command is the stop gait)."""
        was, self.commanding = self.commanding, driving
        self.send_now = driving or was or self.command_without_goal == "hold"

    def publish_command(self, hold: bool, kappa_per_m: float, backwards: bool = False, straight: bool = False):
        """hold: the stop gait keeping kappa_per_m (the body as it is); straight: the driver's hold posture
        (before the loop has started: nothing commanded yet). Nothing when gate() said so."""
        if not self.send_now:
            return
        c = GaitCommand()
        c.header.stamp = rospy.Time.now()
        if straight:
            c.gait = "hold"
        else:
            c.gait, c.curve, c.kappa = self.gaits.command(hold, backwards), True, float(kappa_per_m)
        self.pub_cmd.publish(c)

    def publish_replan(self, stamp, tick):
        r = tick.replan
        self.pub_path.publish(self.path_msg(stamp, r.path_world))
        if r.route_world is not None:
            xy = r.route_world
            heading = np.arctan2(np.diff(xy[:, 1], append=xy[-1, 1]), np.diff(xy[:, 0], append=xy[-1, 0]))
            self.pub_route.publish(self.path_msg(stamp, np.column_stack([xy, heading])))
        arcs = MarkerArray()
        clear = Marker()
        clear.action = Marker.DELETEALL
        arcs.markers.append(clear)
        for i, a in enumerate(r.selection.arcs):
            world = to_world(a.poses, r.pose)
            m = Marker()
            m.header.stamp, m.header.frame_id = stamp, self.world_frame
            m.ns, m.id, m.type, m.action = "nav_arcs", i, Marker.LINE_STRIP, Marker.ADD
            m.pose.orientation.w = 1.0
            m.scale.x = 0.01
            for s, (x, y, _) in zip(a.s_m, world):
                m.points.append(Point(float(x), float(y), 0.01))
                free = s <= a.free_m + 1e-9
                m.colors.append(GREEN if (i == r.selection.chosen and free and r.path_world is not None)
                                else YELLOW if free else RED)
            arcs.markers.append(m)
        self.pub_arcs.publish(arcs)
        self.pub_trav.publish(to_image(self.overlay(tick), "rgb8", stamp, "camera_color_optical_frame"))
        self.pub_mask.publish(traversability_mask(tick.ground, stamp, "camera_color_optical_frame"))
        omap = self.loop.planner.obstacle_map
        if self.loop.cfg.planner.kind == "layered":           # its local map: occupied, seen free, unknown
            self.pub_map.publish(local_grid(self.loop.planner.map, stamp, self.world_frame))
        elif omap is not None:                               # the perception-space planner's obstacle map
            mp = self.loop.cfg.map
            self.pub_map.publish(occupancy(omap.geometry(), r.pose[:2], self.loop.goal_xy, mp.cell_m, mp.pad_m,
                                           stamp, self.world_frame))

    def path_msg(self, stamp, poses) -> Path:
        """(N, 3) x, y, heading in the world frame (or None) -> nav_msgs/Path."""
        path = Path()
        path.header.stamp, path.header.frame_id = stamp, self.world_frame
        for x, y, th in (poses if poses is not None else []):
            ps = PoseStamped()
            ps.header = path.header
            ps.pose.position.x, ps.pose.position.y = float(x), float(y)
            ps.pose.orientation.z, ps.pose.orientation.w = math.sin(th / 2), math.cos(th / 2)
            path.poses.append(ps)
        return path

    def overlay(self, tick) -> np.ndarray:
        ground = tick.ground
        rgb = self.rgb
        if rgb is None or rgb.shape[:2] != ground.shape:
            depth = np.asarray(tick.frame, float) if tick.frame is not None and tick.frame.ndim == 2 else None
            grey = np.full(ground.shape, 128, np.uint8) if depth is None else \
                (255 * (1.0 - np.clip(depth / 4.0, 0.0, 1.0))).astype(np.uint8)
            rgb = np.dstack([grey] * 3)
        checker = PerceptionCollisionChecker(self.loop.cfg.intrinsics, tick.T_ground_camera, self.head_width_m)
        return overlay(rgb, ground, tick.replan.selection, checker)

    def diagnose(self, stat):
        t, loop = self.last_tick, self.loop
        refused = self.refused + (loop.refused if loop is not None else Counter())
        for kind in ("camera_info", "pose", "joints", "depth", "colour", "frame"):
            stat.add(f"refused_{kind}", str(refused.get(kind, 0)))
        stat.add("last_refusal", self.last_refusal or "none")
        stat.add("tick_errors", str(loop.errors if loop is not None else 0))
        stat.add("node_errors", str(self.node_errors))
        stat.add("command_without_goal", self.command_without_goal)
        stat.add("commanding", "true" if self.send_now else "false")
        stat.add("last_error", (loop.last_error if loop is not None and loop.last_error else "")
                 or self.last_node_error or "none")
        self.goals.diagnose(stat)
        if t is None or loop is None:
            stat.summary(DiagnosticStatus.WARN, "waiting for camera_info" if loop is None else "starting")
            return stat
        level = {ERROR: DiagnosticStatus.ERROR, STALE: DiagnosticStatus.WARN, NO_FREE_ARC: DiagnosticStatus.WARN,
                 WAITING: DiagnosticStatus.WARN, NO_GOAL: DiagnosticStatus.OK, FOLLOWING: DiagnosticStatus.OK,
                 GOAL_REACHED: DiagnosticStatus.OK}.get(t.state, DiagnosticStatus.WARN)
        stat.summary(level, f"{t.state}: {t.message}")
        d = loop.distance_to_goal_m()
        stat.add("state", t.state)
        stat.add("replans", str(loop.replans))
        stat.add("stops_no_free_arc", str(loop.stops_no_free_arc))
        stat.add("replans_without_joints", str(loop.replans_without_joints))    # on the commanded shape
        stat.add("kappa_per_m", f"{t.kappa_per_m:.3f}")
        stat.add("follower_mode", loop.planner.follower.mode)   # a recorded run's contacts are tagged with it
        stat.add("distance_to_goal_m", "unknown" if d is None else f"{d:.3f}")
        return stat


def main():
    rospy.init_node("planner")
    try:
        PlannerNode()
    except (ValueError, OSError, RuntimeError) as exc:
        rospy.logfatal(str(exc))
        return 1
    rospy.spin()
    return 0
