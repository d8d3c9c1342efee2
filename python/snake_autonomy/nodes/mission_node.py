"""mission_node: runs missions with the 1 Hz waypoint tracker and the planner's move_base (navigate_to legs),
logs every run. Wiring only: the logic is missions.runner.MissionRunner, the log runs.run_log.RunLog.

Subscribes  com_pose (geometry_msgs/PoseStamped, the driver's CoM + virtual-chassis orientation), /diagnostics:
            the pose remapper's status ~pose_status_name (default "<ns>/pose_remapper: base pose", optional;
            not OK holds the robot), and for the bag: base_pose, odom, bound_state, joint_states and the
            standard topics (runs.recorded_topics: /tf, /tf_static, /diagnostics; the static transforms seen
            before a run are written at its start, so each bag replays in rviz on its own).
Publishes   gait_command (snake_autonomy/GaitCommand, every control step while a mission runs: the
            repeat is the driver's heartbeat, its command_timeout_s holds the robot when it stops; none
            during a leg's move_base goal: the planner drives; the hold around it), tracking_status,
            mission/waypoints (geometry_msgs/PoseArray, latched), mission/state (std_msgs/String, latched: a
            tool that joins late, and a run started by ~auto_start that no action client owns, see the state).
Action      mission/run (snake_autonomy/RunMission): goal = a mission (name or file, YAML text, or inline
            waypoints in frame_id: nodes/mission_goal_frame.py), feedback = every decision (tracker or
            leg), result = outcome and per-waypoint metrics, cancel = abort (hold). A new goal while an
            action's mission runs preempts it; one while a service- or auto-started mission runs is rejected.
Client      move_base (move_base_msgs/MoveBaseAction): a goal per navigate_to leg (nodes/mission_nav_leg.py).
Services    mission/load (snake_autonomy/LoadMission), mission/start, mission/abort, mission/resume
            (std_srvs/Trigger; resume goes on after a pause for a driver fault), kept beside the action:
            ~auto_start and `rosservice call` (the one-line stop of any run) need no action client.
Diagnostics /diagnostics (diagnostic_updater): "mission" (state, mission, waypoint, distance, last
            scout stop; WARN while holding for a stale pose, ERROR when a run aborted) and
            "tracking_status topic status" (the tracker's rate against ~rate_hz), "tracker gains".
Reconfigure ~tracker (dynamic_reconfigure, cfg/Tracker.cfg): kp, delta0_deg, delta_lim_deg at run time, for the
            running mission and every later one (nodes/gain_tuning.py); start values from ~tracker_config.
Time        with use_sim_time the node waits for the first /clock before it loads or starts anything.
Params      ~mission (file or provided name: loaded at start-up), ~auto_start (false), ~tracker_config
            (config/tracker.yaml), ~tracker_overrides (a YAML file whose `tracker:` section is merged
            over tracker_config, e.g. config/sim.yaml for the simulated robot; empty: none),
            ~gaits_config (config/gaits.yaml), ~rate_hz, ~pose_timeout_s, ~yaw_filter_window,
            ~heading_offset_deg (defaults from tracker_config + overrides), ~results_dir, ~record (true),
            ~world_frame (odom), ~nav_server_timeout_s, ~nav_settle_s (nodes/mission_nav_leg.py), ~pose_status_name,
            ~robot (cobra) and ~scout_config (empty: config/scout.yaml) for the scout stops of a mission,
            ~scout_accept_timeout_s (3), ~scout_result_margin_s (5): nodes/scout_trajectory.py,
            ~driver_status_name (the driver's locomotion status, default "snake_driver: locomotion"),
            ~on_driver_fault: abort (default: the mission ends, hold sent, results written, the action
            aborted with the fault) or pause (hold until mission/resume; the driver's own recovery never
            restarts it). A mission does not start while the driver reports a fault.
"""
import math
import os
import re
import signal
import threading
import time
from pathlib import Path

import actionlib
import diagnostic_updater
import rospy
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Pose, PoseArray, PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Trigger, TriggerResponse

from snake_autonomy.missions import MissionError, gait_library_names, load_defaults, load_mission, read_overrides
from snake_autonomy.missions.runner import DONE, MissionRunner
from snake_autonomy.missions.scout import fbsr_scout_planner
from snake_autonomy.msg import (BoundState, GaitCommand, RunMissionAction, RunMissionFeedback, RunMissionResult,
                                TrackingStatus, WaypointResult)
from snake_autonomy.nodes.gain_tuning import TrackerGains
from snake_autonomy.nodes.mission_action import DecisionSeries, fill_feedback, fill_result, mission_from_goal
from snake_autonomy.nodes.mission_goal_frame import GoalFrames
from snake_autonomy.nodes.mission_nav_leg import MoveBaseNavigator
from snake_autonomy.nodes.scout_trajectory import TopicTrajectoryExecutor
from snake_autonomy.paths import default_results_dir
from snake_autonomy.runs.recorded_topics import STATIC_TF_TOPIC, StaticTransforms, standard_topic_types
from snake_autonomy.runs.run_log import RunLog
from snake_autonomy.sim.config import servo_torque_limit_nm
from snake_autonomy.srv import LoadMission, LoadMissionResponse
from snake_autonomy.transforms import yaw_of_quat

RECORDED = {  # topic -> type, recorded into the run's bag besides com_pose and our own outputs
    "base_pose": PoseWithCovarianceStamped,
    # the simulator's ground truth (sim_node); nothing publishes them on the robot
    "ground_truth/base_pose": PoseStamped,
    "ground_truth/camera_pose": PoseStamped,
    "ground_truth/com_pose": PoseStamped,
    "odom": Odometry, "joint_states": JointState, "bound_state": BoundState,
}


class MissionNode:
    def __init__(self):
        self.lock = threading.RLock()
        defaults_path = rospy.get_param("~tracker_config", "") or None
        overrides_path = rospy.get_param("~tracker_overrides", "") or None
        overrides = read_overrides(overrides_path) if overrides_path else None
        self.defaults = load_defaults(defaults_path, overrides, overrides_source=f"{overrides_path} (tracker:)")
        self.gait_library = gait_library_names(rospy.get_param("~gaits_config", "") or None)
        self.rate_hz = float(rospy.get_param("~rate_hz", self.defaults["rate_hz"]))
        self.pose_timeout_s = float(rospy.get_param("~pose_timeout_s", self.defaults["pose_timeout_s"]))
        self.yaw_window = int(rospy.get_param("~yaw_filter_window", self.defaults["yaw_filter_window"]))
        self.heading_offset_rad = math.radians(float(rospy.get_param("~heading_offset_deg",
                                                                     self.defaults["heading_offset_deg"])))
        self.results_dir = Path(rospy.get_param("~results_dir", default_results_dir()))
        self.record = bool(rospy.get_param("~record", True))
        self.world_frame = rospy.get_param("~world_frame", "odom")
        self.goal_frames = GoalFrames(self.world_frame)
        self.navigator = MoveBaseNavigator.from_params(self.world_frame, self.send_hold)
        # Scout stops (missions/scout.py): the FBSR planner for this robot, trajectories to the driver.
        self.robot = rospy.get_param("~robot", "cobra")
        self.scout_config = rospy.get_param("~scout_config", "") or None
        self._scout_parts = None
        self.pose_status_name = rospy.get_param("~pose_status_name",
                                                rospy.resolve_name("pose_remapper")[1:] + ": base pose")
        self.driver_status_name = rospy.get_param("~driver_status_name", "snake_driver: locomotion")
        self.on_driver_fault = rospy.get_param("~on_driver_fault", "abort")
        if self.on_driver_fault not in ("abort", "pause"):
            raise ValueError(f"~on_driver_fault: expected abort or pause, got {str(self.on_driver_fault)[:40]!r}")
        self.driver_fault = ""           # the driver's fault while it reports one
        if not (self.rate_hz > 0 and self.pose_timeout_s > 0 and self.yaw_window > 0):
            raise ValueError(f"~rate_hz ({self.rate_hz}), ~pose_timeout_s ({self.pose_timeout_s}) and "
                             f"~yaw_filter_window ({self.yaw_window}) must be positive")
        lifetime = rospy.get_param("driver/command_timeout_s", None)
        if lifetime and 1.0 / self.rate_hz >= 0.5 * float(lifetime):
            rospy.logwarn(f"~rate_hz {self.rate_hz}: a command every {1.0 / self.rate_hz:.1f} s is too slow for the "
                          f"driver's command_timeout_s {lifetime} s; it will hold between commands")

        # The process that launched this node (roslaunch): when it is gone (SIGKILL of roslaunch) this
        # node is an orphan nobody can stop with Ctrl+C any more; it ends its mission and exits, and
        # the driver holds when its command lifetime expires.
        self.parent_pid = os.getppid()
        self.mission = None
        self.runner = None
        self.log = None
        self.run_dir = None
        self.source_ok, self.source_detail = True, ""
        self.static_tf = StaticTransforms()
        self.decisions = DecisionSeries()
        self.run_ended = threading.Event()
        self.last_result = None
        self.waypoints_msg = None

        self.pub_cmd = rospy.Publisher("gait_command", GaitCommand, queue_size=10)
        self.pub_status = rospy.Publisher("tracking_status", TrackingStatus, queue_size=10)
        self.pub_wps = rospy.Publisher("mission/waypoints", PoseArray, queue_size=1, latch=True)
        self.pub_state = rospy.Publisher("mission/state", String, queue_size=1, latch=True)
        rospy.Subscriber("com_pose", PoseStamped, self.on_com_pose, queue_size=50)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=20)
        self._rec_subs = []
        if self.record:
            types = dict(RECORDED)
            types.update(standard_topic_types())
            for topic, msg_type in types.items():
                self._rec_subs.append(rospy.Subscriber(topic, msg_type, self._recorder(topic), queue_size=100))
        self.state_text = "idle"
        self.last_status = None
        self.updater = diagnostic_updater.Updater()
        self.updater.setHardwareID("none")
        self.updater.add("mission", self.diagnose)
        self._rate = {"min": 0.9 * self.rate_hz, "max": 1.1 * self.rate_hz}   # the task keeps this dict
        self.status_freq = diagnostic_updater.HeaderlessTopicDiagnostic(
            "tracking_status", self.updater, diagnostic_updater.FrequencyStatusParam(self._rate, 0.0, 10))
        self.gains = TrackerGains(self)   # the ~tracker Server, "tracker gains" on /diagnostics
        # the services and the action last: a call may come the moment they are advertised, and the
        # handlers need every part above (the gains' Server takes a while to start)
        rospy.Service("mission/load", LoadMission, self.srv_load)
        rospy.Service("mission/start", Trigger, self.srv_start)
        rospy.Service("mission/abort", Trigger, self.srv_abort)
        rospy.Service("mission/resume", Trigger, self.srv_resume)
        self.action = actionlib.SimpleActionServer("mission/run", RunMissionAction, execute_cb=self.execute,
                                                   auto_start=False)
        self.action.start()
        rospy.Timer(rospy.Duration(1.0), lambda _e: self.updater.update())
        self.set_state("idle")

        mission_param = rospy.get_param("~mission", "")
        if mission_param:
            ok, message = self.load(mission_param)
            if not ok:
                rospy.logfatal(message)
                raise SystemExit(message)
            if rospy.get_param("~auto_start", False):
                ok, message = self.start()
                if not ok:
                    rospy.logerr(message)
        # Other shutdown paths (rosnode kill, master gone): rospy has closed the publishers by now, so
        # the hold may not go out, but the run is still ended and its results written. SIGINT and
        # SIGTERM are handled in main() before rospy shuts down, so their hold does go out.
        rospy.core.add_preshutdown_hook(lambda reason: self.on_shutdown(f"shutdown: {reason}"))
        self.timer = rospy.Timer(rospy.Duration(1.0 / self.rate_hz), self.on_tick)

    # -- helpers -----------------------------------------------------------------------------------
    def make_runner(self, mission):
        self.scouts_logged = 0   # the new runner's scout_log starts empty
        planner = executor = None
        if mission.scouts:
            planner, executor = self.scout_parts()
        return self.gains.tuned_runner(MissionRunner(
            mission, self.pose_timeout_s, self.yaw_window, heading_offset_rad=self.heading_offset_rad,
            scout_planner=planner, executor=executor, navigator=self.navigator))

    def scout_parts(self):
        """The scout planner (FBSR, ~robot) and the executor that publishes driver/joint_trajectory,
        made once, when the first mission with a scout stop is loaded."""
        if self._scout_parts is None:
            planner = fbsr_scout_planner(self.robot, self.scout_config, torque_limit_nm=servo_torque_limit_nm())
            self._scout_parts = (planner, TopicTrajectoryExecutor.from_params())
        return self._scout_parts

    def set_state(self, text):
        self.state_text = text
        self.pub_state.publish(String(data=text))

    def diagnose(self, stat):
        """The "mission" diagnostics task: what mission/state says, with the tracker's latest status."""
        text, s = self.state_text, self.last_status
        level = DiagnosticStatus.OK
        if text.startswith("aborted"):
            level = DiagnosticStatus.ERROR
        elif text.startswith("paused"):
            level = DiagnosticStatus.WARN
        elif s is not None and s.get("pose_stale") and text.startswith("running"):
            level = DiagnosticStatus.WARN
        stat.summary(level, text if level == DiagnosticStatus.OK or s is None else f"{text}: {s.get('note', '')}")
        stat.add("mission", self.mission.name if self.mission is not None else "")
        if s is not None:
            stat.add("waypoint", f"{s['waypoint_index']}/{s['num_waypoints']}")
            stat.add("distance_m", f"{s['distance']:.3f}")
            stat.add("mode", str(s["mode"]))
            stat.add("gait", str(s["gait"]))
        log = self.runner.scout_log if self.runner is not None else []
        if log:
            stat.add("last_scout", f"waypoint {log[-1].waypoint_index}: {log[-1].outcome}")
        return stat

    def resolved(self, name):
        return rospy.resolve_name(name)

    def _recorder(self, topic):
        resolved = self.resolved(topic)
        static = resolved == STATIC_TF_TOPIC

        def cb(msg):
            if static:
                self.static_tf.keep(msg)
            log = self.log
            if log is not None:
                log.write(resolved, msg, rospy.get_time())
        return cb

    # -- subscriptions -------------------------------------------------------------------------------
    def on_com_pose(self, msg):
        t = rospy.get_time()
        q = msg.pose.orientation
        x, y = msg.pose.position.x, msg.pose.position.y
        try:
            yaw = yaw_of_quat(q.x, q.y, q.z, q.w)
        except (ValueError, ZeroDivisionError):
            yaw = float("nan")
        if abs(q.x) + abs(q.y) + abs(q.z) + abs(q.w) == 0:
            yaw = float("nan")   # zero quaternion: no orientation
        with self.lock:
            if self.runner is not None:
                self.runner.on_pose(t, x, y, yaw)
            if self.log is not None:
                self.log.write(self.resolved("com_pose"), msg, t)
                self.log.add_pose(t, x, y)

    def on_diagnostics(self, msg):
        for status in msg.status:
            if status.name == self.pose_status_name:
                self.on_source_status(status)
            elif status.name == self.driver_status_name:
                self.on_driver_status(status)

    def on_driver_status(self, msg):
        """The driver's locomotion status: a fault (ERROR) aborts or pauses the running mission."""
        fault = msg.message.removeprefix("fault: ") if msg.level == DiagnosticStatus.ERROR else ""
        with self.lock:
            new_fault = fault and not self.driver_fault
            self.driver_fault = fault
            if not new_fault:
                return
            rospy.logerr(f"driver fault: {fault}")
            if self.runner is None or not self.runner.running:
                return
            why = f"driver fault: {fault}"
            if self.on_driver_fault == "pause":
                self.runner.pause(why)
                self.send_hold(why)
                self.set_state(f"paused: {self.mission.name}: {why} (mission/resume to go on)")
                rospy.logerr(f"mission {self.mission.name!r} paused: {why}; call mission/resume after the "
                             "driver's recovery (driver/enable_torque)")
            else:
                self.runner.abort(why)
                self.finish(self.runner.final_decision(rospy.get_time()))

    def on_source_status(self, msg):
        ok = msg.level == DiagnosticStatus.OK
        with self.lock:
            if ok != self.source_ok:
                (rospy.loginfo if ok else rospy.logwarn)(f"pose source: {msg.message}")
            self.source_ok, self.source_detail = ok, msg.message
            if self.runner is not None:
                self.runner.set_source_status(ok, msg.message)

    # -- services ------------------------------------------------------------------------------------
    def load(self, path):
        return self.install(lambda: load_mission(path, defaults=self.defaults, gait_library=self.gait_library),
                            path)

    def install(self, make_mission, what):
        """Loads a mission (make_mission() builds it) unless one is running; (ok, message)."""
        try:
            mission = make_mission()        # parsed outside the lock: mission/abort never waits on it
        except MissionError as exc:
            return False, str(exc)
        except ValueError as exc:
            return False, f"{what}: {exc}"
        with self.lock:
            if self.runner is not None and self.runner.running:
                return False, f"mission {self.mission.name!r} is running: abort it first"
            try:
                runner = self.make_runner(mission)
            except MissionError as exc:
                return False, str(exc)
            except ValueError as exc:
                return False, f"{what}: {exc}"
            self.mission, self.runner = mission, runner
            runner.set_source_status(self.source_ok, self.source_detail)
            self.publish_waypoints()
            self.set_state(f"loaded: {mission.name}")
            rospy.loginfo(mission.summary())
            return True, f"loaded {mission.name!r}: {len(mission.waypoints)} waypoint(s) from {mission.source}"

    def srv_load(self, req):
        ok, message = self.load(req.path)
        (rospy.loginfo if ok else rospy.logerr)(message)
        return LoadMissionResponse(success=ok, message=message)

    def start(self):
        with self.lock:
            if self.mission is None:
                return False, "no mission loaded (mission/load or ~mission)"
            if self.driver_fault:
                return False, (f"the driver reports a fault ({self.driver_fault}): "
                               "recover it first (driver/enable_torque)")
            if self.runner.state != "idle":
                # a finished mission reruns from its first waypoint
                self.runner = self.make_runner(self.mission)
                self.runner.set_source_status(self.source_ok, self.source_detail)
            t = rospy.get_time()
            self.decisions = DecisionSeries()
            self.last_result = None
            self.run_ended.clear()
            if self.record:
                self.open_log(t)
                self.static_tf.replay(self.log, t)
                if self.waypoints_msg is not None:   # latched before the run: its bag gets a copy
                    self.log.write(self.resolved("mission/waypoints"), self.waypoints_msg, t)
            self.runner.start(t)
            self.set_state(f"running: {self.mission.name}")
            msg = f"mission {self.mission.name!r} started" + (f", logging to {self.run_dir}" if self.log else "")
            rospy.loginfo(msg)
        self.on_tick(None)   # first decision now, not one period later
        return True, msg

    def srv_start(self, _req):
        ok, message = self.start()
        return TriggerResponse(success=ok, message=message)

    def srv_abort(self, _req):
        with self.lock:
            if self.runner is None or not self.runner.running:
                self.send_hold("abort requested")
                return TriggerResponse(success=False, message="no mission running (hold sent anyway)")
            self.runner.abort("operator request")
            self.finish(self.runner.final_decision(rospy.get_time()))
            return TriggerResponse(success=True, message=self.runner.outcome)

    def srv_resume(self, _req):
        with self.lock:
            if self.runner is None or self.runner.paused is None:
                return TriggerResponse(success=False, message="no paused mission")
            if self.driver_fault:
                return TriggerResponse(success=False, message=f"the driver still reports a fault ({self.driver_fault})")
            self.runner.resume()
            self.set_state(f"running: {self.mission.name}")
            rospy.loginfo(f"mission {self.mission.name!r} resumed")
            return TriggerResponse(success=True, message=f"mission {self.mission.name!r} resumed")

    # -- the action ---------------------------------------------------------------------------------
    def execute(self, goal):
        """One RunMission goal, in actionlib's thread: load, start, wait for the end or a cancel."""
        ok, message = self.install(lambda: mission_from_goal(self.goal_frames.to_world(goal), self.defaults,
                                                             self.gait_library),
                                   "RunMission goal")
        if ok:
            ok, message = self.start()
        if not ok:
            rospy.logerr(f"RunMission goal refused: {message}")
            self.action.set_aborted(RunMissionResult(outcome=message, state="refused"), message)
            return
        cancelled = False
        while not self.run_ended.wait(0.1):
            if rospy.is_shutdown():
                break
            if self.action.is_preempt_requested() and not cancelled:
                cancelled = True
                with self.lock:
                    if self.runner is not None and self.runner.running:
                        self.runner.abort("RunMission goal cancelled")
                        self.finish(self.runner.final_decision(rospy.get_time()))
        result = self.last_result or RunMissionResult(outcome="node shutting down", state="aborted")
        try:
            if cancelled:
                self.action.set_preempted(result, result.outcome)
            elif result.state == DONE:
                self.action.set_succeeded(result, result.outcome)
            else:
                self.action.set_aborted(result, result.outcome)
        except rospy.ROSException as exc:   # shutting down: the status topic is closed
            rospy.logerr(f"RunMission result not sent: {exc}")

    def result_of_run(self, outcome):
        m = self.runner
        path_m = self.log.path_length_m if self.log is not None else float("nan")
        metrics = self.decisions.metrics(self.mission.waypoints, outcome, m.t_start if m.t_start is not None else 0.0)
        return fill_result(RunMissionResult(), WaypointResult, self.mission.name, m.state, outcome, metrics,
                           path_length_m=path_m, run_dir=str(self.run_dir) if self.log is not None else "")

    # -- the control tick --------------------------------------------------------------------------------
    def on_tick(self, _event):
        if os.getppid() != self.parent_pid:
            why = f"the launching process (pid {self.parent_pid}) is gone"
            rospy.logerr(f"{why}: ending the mission and exiting (the driver holds after its command_timeout_s)")
            self.on_shutdown(why)
            rospy.signal_shutdown(why)
            return
        with self.lock:
            if self.runner is None:
                return
            decision = self.runner.step(rospy.get_time())
            if decision is None:
                return
            self.log_scouts(decision.t_s)
            if decision.status["pose_stale"]:
                rospy.logwarn_throttle(5.0, f"{self.mission.name}: {decision.status['note']}")
            if decision.finished:
                self.finish(decision)
            else:
                self.publish(decision)

    def publish(self, decision):
        now = rospy.Time.from_sec(decision.t_s) if decision.t_s > 0 else rospy.Time.now()
        cmd = GaitCommand(gait=decision.gait, steer=decision.steer, delta=decision.delta_rad)
        cmd.header.stamp = now
        status = TrackingStatus(**decision.status)
        status.header.stamp = now
        status.header.frame_id = self.world_frame
        # While a scout trajectory owns the joints no gait command goes out: one would end it (the driver
        # holds its last point afterwards, a finished mission's hold included); nor while the planner drives.
        sends = not (decision.trajectory_active or decision.navigating)
        if sends:
            self.pub_cmd.publish(cmd)
        self.pub_status.publish(status)
        self.status_freq.tick()
        self.last_status = decision.status
        self.decisions.add(decision.t_s, decision.status)
        if self.action.is_active():
            self.action.publish_feedback(fill_feedback(RunMissionFeedback(), decision.status, decision.leg_state))
        if self.log is not None:
            if sends:
                self.log.write(self.resolved("gait_command"), cmd, decision.t_s)
            self.log.write(self.resolved("tracking_status"), status, decision.t_s)
            s = decision.status
            self.log.add_decision(decision.t_s, s["waypoint_index"], s["waypoint_index"] - int(s["waypoint_reached"]),
                                  s["waypoint_reached"], s["distance"], s["yaw_error_abs"], s["yaw_error_rel"],
                                  s["yaw_error"], s["pose_stale"])

    def log_scouts(self, t_s):
        """Each finished scout stop as a run event (metrics.json `scouts`, as in the batch simulator)."""
        records = self.runner.scout_log
        if self.log is not None:
            for record in records[self.scouts_logged:]:
                self.log.event({"event": "scout", **record.as_dict()}, t_s)
                rospy.loginfo(f"scout at waypoint {record.waypoint_index}: {record.outcome}")
        self.scouts_logged = len(records)

    def send_hold(self, why):
        hold = self.runner.hold_gait if self.runner is not None else self.defaults["gaits"]["stop"]
        cmd = GaitCommand(gait=hold, steer=False, delta=0.0)
        cmd.header.stamp = rospy.Time.now()
        self.pub_cmd.publish(cmd)
        (rospy.loginfo if why else rospy.logdebug)(f"hold sent ({why or 'repeated'})")

    def finish(self, decision):
        """The mission ended: hold, report per waypoint, close the log."""
        try:
            self.publish(decision)
        except rospy.ROSException as exc:   # shutting down: topics already closed
            rospy.logerr(f"could not send the final hold: {exc}")
        outcome = self.runner.outcome or decision.outcome
        self.log_scouts(decision.t_s)
        self.set_state(f"{self.runner.state}: {self.mission.name}: {outcome}")
        rospy.loginfo(f"mission {self.mission.name!r} ended: {outcome}")
        self.last_result = self.result_of_run(outcome)
        if self.log is not None:
            log, self.log = self.log, None
            try:
                log.close(outcome, decision.t_s)
            except Exception as exc:  # noqa: BLE001 - the bag and metrics.json are already safe
                rospy.logerr(f"writing the results of {self.run_dir} failed: {exc}")
            else:
                rospy.loginfo(f"results in {self.run_dir}")
        m = self.runner
        m.close()
        reached = m.tracker.waypoint_index
        rospy.loginfo(f"{reached}/{len(self.mission.waypoints)} waypoint(s) reached")
        self.run_ended.set()

    def open_log(self, t):
        stamp = time.strftime("%Y%m%d-%H%M%S")
        safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", self.mission.name)
        self.run_dir = self.results_dir / f"{stamp}_{safe}"
        n = 1
        while self.run_dir.exists():
            n += 1
            self.run_dir = self.results_dir / f"{stamp}_{safe}_{n}"
        source = Path(self.mission.source)
        text = source.read_text() if source.is_file() else yaml.safe_dump(self.mission.raw)
        self.log = RunLog(self.run_dir, self.mission.name, self.mission.waypoints, t, mission_yaml=text,
                          tracker=dict(vars(self.runner.tracker.params)),   # with gains tuned at run time
                          extra={"rate_hz": self.rate_hz, "pose_timeout_s": self.pose_timeout_s,
                                 "heading_offset_deg": math.degrees(self.heading_offset_rad),
                                 "tracker_config": self.defaults.get("source", ""),
                                 "gaits": self.mission.gaits, "node": rospy.get_name()})

    def publish_waypoints(self):
        msg = PoseArray()
        msg.header.frame_id = self.world_frame
        msg.header.stamp = rospy.Time.now()
        for x, y, h in self.mission.waypoints:
            p = Pose()
            p.position.x, p.position.y = x, y
            p.orientation.z, p.orientation.w = math.sin(h / 2), math.cos(h / 2)
            msg.poses.append(p)
        self.pub_wps.publish(msg)
        self.waypoints_msg = msg

    def on_shutdown(self, reason="node shutdown"):
        """SIGINT/SIGTERM/rosnode kill: hold and write what is known."""
        with self.lock:
            if self.runner is not None and self.runner.running:
                self.runner.abort(reason)
                try:
                    self.finish(self.runner.final_decision(rospy.get_time()))
                except Exception as exc:  # noqa: BLE001
                    rospy.logerr(f"shutdown: {exc}")
            elif self.log is not None:
                self.log.close("shutdown")


def wait_for_clock() -> bool:
    """use_sim_time: rospy's time is zero until the first /clock; a mission started then would take
    the simulator's first stamp for a jump of its whole time limit. False when shut down first."""
    if rospy.get_time() == 0.0:
        rospy.loginfo("waiting for the first /clock (use_sim_time)")
    while rospy.get_time() == 0.0:
        if rospy.is_shutdown():
            return False
        time.sleep(0.01)
    return True


def main():
    # Our own SIGINT/SIGTERM handlers: rospy closes every publisher before any shutdown hook runs, so
    # the final hold must go out (and the results be written) before rospy starts shutting down.
    rospy.init_node("mission", disable_signals=True)
    if not wait_for_clock():
        return 0
    try:
        node = MissionNode()
    except (ValueError, MissionError) as exc:
        rospy.logfatal(str(exc))
        return 1

    def on_signal(signum, _frame):
        name = signal.Signals(signum).name
        node.on_shutdown(f"node stopped by {name}")
        rospy.signal_shutdown(name)

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    rospy.spin()
    return 0
