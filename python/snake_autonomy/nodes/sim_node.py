"""sim_node: the simulated robot in real time. Wiring only: the logic is sim.realtime.RealTimeSim.

Hosts the mocked servo bus on a pty (~port) with the MuJoCo plant behind it: driver_node talks
Protocol 2.0 to the simulated servos exactly as to real ones. Publishes the pose source the
experiment uses and the ground truth:

Publishes   base_pose (geometry_msgs/PoseWithCovarianceStamped, motion capture of base_link, 100 Hz,
            covariance from sim.yaml's mocap noise; feedback mocap)
            odom (nav_msgs/Odometry, the simulated RTAB-Map: camera pose, 30 Hz, null pose with
            covariance 9999 while lost; feedback vio: pose_remap_node turns it into base_pose)
            neither with feedback vo: vio_node estimates odom from the head camera, rendered then
            from the IMU's camera_link in an obstacle-free textured room around the camera's start
            (sim/scene.vo_room_around_camera: the odometry frame's origin, and a mission's) at
            ~vo_camera_rate_hz (10) and ~vo_camera_width x ~vo_camera_height (320x240) on the
            camera/* topics below, with ground_truth/camera_pose (camera_link) per frame
            camera/imu (sensor_msgs/Imu, the head camera's IMU: MuJoCo's gyro and accelerometer at
            camera_link with the BMI055-like errors of sim.yaml imu: (sim/imu.py), at imu.rate_hz (200),
            frame ~imu_frame (camera_link; REP 145: rad/s, m/s^2 with gravity; no orientation:
            orientation_covariance[0] = -1; the white noise's variances on the diagonals)),
            ground_truth/base_pose (PoseStamped, 100 Hz), ground_truth/camera_pose (PoseStamped, with
            every odom message, same stamp), ground_truth/com_pose (PoseStamped, 10 Hz: centre of mass
            and heading from the true base pose),
            /diagnostics (diagnostic_updater, every ~diagnostic_period (1 s): "sim: simulated robot"
            (simulated time, tilt, roll-over, joint goals beyond the limits: ERROR on roll-over or a
            goal beyond a limit); "sim: base_pose topic status" (mocap) or
            "sim: odom topic status" (vio): the pose source's rate within 10 % of sim.yaml's),
            /clock (rosgraph_msgs/Clock, every physics step: the plant's time, starting at the wall
            time the simulation started; /use_sim_time:=true makes every node follow it, and then
            the messages above are stamped with it too).
Subscribes  sim/disturbance (geometry_msgs/WrenchStamped: header.frame_id = the body, base_link or
            link_1..link_11; world-frame force and torque; lasts ~disturbance_duration_s),
            tracking_status (the mission's active waypoint: arms the mission's mid-leg disturbances).
Params      ~feedback (mocap|vio|vo), ~seed, ~start ("x,y,heading_deg" of the centre of mass), ~port,
            ~sim_config, ~robot_config, ~tracker_config, ~mission (for its disturbances), ~world_frame
            (odom), ~camera_frame (camera), ~imu_frame (camera_link), ~rate_hz (physics and sensor poll,
            200), ~disturbance_duration_s.
With a world (~world, a nav world file, a relative path taken against the node's working directory,
paths.resolve_world_path; empty: none, everything above unchanged): the
world's obstacles and floor in the plant, base_link at its start (~start ignored), the plant option
of ~nav_config (config/nav.yaml plant:), and the head camera (nav.yaml camera: intrinsics and
mount) rendered in a child process (sim.camera_process) at ~camera_rate_hz (0.5: a colour + depth
pair took 0.07-0.17 s, median 0.15 s, here: about 7 % of a core) and published as
            camera/color/image_raw (rgb8) + camera/color/camera_info, camera/depth/image_rect_raw
            (32FC1, m along the optical axis, 0 = nothing; ~camera_depth true; ~depth_model d435i: the
            D435i-like noise and holes of sim.yaml depth_noise: on its own seeded stream, as the batch
            nav runs render it; perfect: exact), frame
            ~camera_optical_frame (camera_color_optical_frame), stamped with the snapshot's time.
            sim/world_markers (visualization_msgs/MarkerArray, latched, once at start, frame ~world_frame):
            the world's obstacles and goal disc as the simulation has them (ground truth, not what the
            planner knows: that is nav/map; planner_display.world_markers).
Contacts between the robot and the obstacles are counted per episode as the batch nav run counts
them (sim/collisions.py): "obstacle_contacts" and "min_clearance_m" (sampled at 5 Hz) in the
"sim: simulated robot" diagnostics, a ROS_WARN and a marker on sim/contacts (visualization_msgs/Marker,
a sphere where the link touched, text "LINK touched OBSTACLE"; planner_display.contact_marker) at
each new episode, and sim/contact_markers (visualization_msgs/MarkerArray, latched: every episode so
far, as rviz/nav.rviz shows them).
"""
import dataclasses
import math
import threading
import time

import diagnostic_updater
import rospy
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, WrenchStamped
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, Imu
from visualization_msgs.msg import Marker, MarkerArray

from snake_autonomy.msg import GaitCommand, TrackingStatus, TrajectoryStatus
from snake_autonomy.nodes.image_msgs import to_camera_info, to_image
from snake_autonomy.nodes.planner_display import contact_marker, contact_markers, world_markers
from snake_autonomy.paths import config_path, resolve_world_path
from snake_autonomy.planning.rectilinear.config import NavConfig
from snake_autonomy.perception.camera_model import R_LINK_OPTICAL
from snake_autonomy.sim.camera import LinkMount
from snake_autonomy.sim.camera_process import CameraProcess
from snake_autonomy.sim.collisions import CollisionMonitor
from snake_autonomy.sim.depth_noise import named_depth_model
from snake_autonomy.sim.realtime import RealTimeSim, SimSetup
from snake_autonomy.sim.mjcf import camera_link_in_base
from snake_autonomy.sim.scene import vo_room_around_camera, world_plant_fields
from snake_autonomy.sim.vo_feedback import ODOMETRY_CAMERA, OdometryCameraSettings
from snake_autonomy.sim.world_file import load_world
from snake_autonomy.transforms import matrix_to_quat


def _pose(msg_pose, position, quat):
    msg_pose.position.x, msg_pose.position.y, msg_pose.position.z = (float(v) for v in position)
    o = msg_pose.orientation
    o.x, o.y, o.z, o.w = (float(v) for v in quat)


def _imu(sample, stamp, frame):
    m = Imu()
    m.header.stamp, m.header.frame_id = stamp, frame
    m.orientation_covariance[0] = -1.0                 # no orientation estimate
    v, a = m.angular_velocity, m.linear_acceleration
    v.x, v.y, v.z = (float(x) for x in sample.angular_velocity_rad_s)
    a.x, a.y, a.z = (float(x) for x in sample.linear_acceleration_m_s2)
    m.angular_velocity_covariance = [sample.gyro_std_rad_s ** 2 if i % 4 == 0 else 0.0 for i in range(9)]
    m.linear_acceleration_covariance = [sample.accel_std_m_s2 ** 2 if i % 4 == 0 else 0.0 for i in range(9)]
    return m


class SimNode:
    def __init__(self):
        start = str(rospy.get_param("~start", "0,0,0"))
        try:
            start_t = tuple(float(v) for v in start.split(","))
            assert len(start_t) == 3
        except (ValueError, AssertionError):
            raise ValueError(f"~start: expected x,y,heading_deg, got {start!r}") from None
        config = config_path()
        self.world_file = rospy.get_param("~world", "")
        if self.world_file:          # absolute, checked: FileNotFoundError names the path tried
            self.world_file = str(resolve_world_path(self.world_file))
        self.nav_cfg, self.camera = None, None
        extra = {}
        self.world = None
        feedback = rospy.get_param("~feedback", "mocap")
        self.vo = feedback == "vo"      # the visual-inertial odometry (vio_node) estimates from the camera
        if self.vo and self.world_file:
            raise ValueError("~feedback vo with a world: not supported (the planner's camera is nav.yaml's "
                             "mount, the odometry's is the IMU's camera_link, and one render stream serves one)")
        if self.world_file:
            self.nav_cfg = NavConfig.from_yaml(rospy.get_param("~nav_config", str(config / "nav.yaml")))
            self.world = load_world(self.world_file)
            extra = world_plant_fields(self.world, self.nav_cfg.plant.flat_belly_fraction)
        setup_feedback = "mocap" if self.vo else feedback     # vo: motion capture is the ground truth only
        setup = SimSetup(feedback=setup_feedback, seed=int(rospy.get_param("~seed", 0)),
                         sensors=("mocap", setup_feedback, "imu"),
                         start=start_t, port=rospy.get_param("~port", "/tmp/snake_sim_bus"),
                         sim_config=rospy.get_param("~sim_config", str(config / "sim.yaml")),
                         robot=rospy.get_param("~robot_config", str(config / "robots" / "cobra.yaml")),
                         tracker_config=rospy.get_param("~tracker_config", str(config / "tracker.yaml")),
                         mission=rospy.get_param("~mission", ""), **extra)
        if self.vo:     # the room around the odometry frame's origin: the camera's start
            room = vo_room_around_camera(setup)
            setup = dataclasses.replace(setup, scene_xml=room.scene_xml, assets_xml=room.assets_xml)
        self.world_frame = rospy.get_param("~world_frame", "odom")
        self.camera_frame = rospy.get_param("~camera_frame", "camera")
        self.rate_hz = float(rospy.get_param("~rate_hz", 200.0))
        self.duration_s = float(rospy.get_param("~disturbance_duration_s", 0.1))
        self.sim = RealTimeSim(setup)
        # the head camera's depth model (with a world), refused by name before the bus opens
        self.depth_model = str(rospy.get_param("~depth_model", "d435i"))
        self.depth_noise = (named_depth_model(self.depth_model, self.sim.params.config.depth_noise,
                                              self.nav_cfg.intrinsics.fx, self.sim.params.rng("depth_noise"))
                            if self.world_file else None)
        self.feedback = feedback
        # /clock: the plant's time from the wall time of the start. With /use_sim_time this node's own
        # rospy clock comes back from /clock, so it stamps with the value it publishes instead.
        self.use_sim_time = bool(rospy.get_param("/use_sim_time", False))
        self.clock_epoch_s = time.time()
        self.pub_clock = rospy.Publisher("/clock", Clock, queue_size=10)
        self.pub_base = (rospy.Publisher("base_pose", PoseWithCovarianceStamped, queue_size=20)
                         if self.feedback == "mocap" else None)
        p = self.sim.params
        self.mocap_covariance = [0.0] * 36
        for i in range(6):
            std = p.mocap_position_noise_m if i < 3 else p.mocap_rotation_noise_rad
            self.mocap_covariance[7 * i] = std * std
        self.pub_odom = rospy.Publisher("odom", Odometry, queue_size=20) if self.feedback == "vio" else None
        self.imu_frame = rospy.get_param("~imu_frame", "camera_link")
        self.pub_imu = rospy.Publisher("camera/imu", Imu, queue_size=50)
        self.pub_gt_base = rospy.Publisher("ground_truth/base_pose", PoseStamped, queue_size=20)
        self.pub_gt_cam = rospy.Publisher("ground_truth/camera_pose", PoseStamped, queue_size=20)
        self.pub_gt_com = rospy.Publisher("ground_truth/com_pose", PoseStamped, queue_size=10)
        if self.world is not None:   # latched: rviz started later still gets them
            self.pub_contact = rospy.Publisher("sim/contacts", Marker, queue_size=10)
            self.pub_contacts_all = rospy.Publisher("sim/contact_markers", MarkerArray, queue_size=1, latch=True)
            self.pub_world = rospy.Publisher("sim/world_markers", MarkerArray, queue_size=1, latch=True)
            self.pub_world.publish(world_markers(self.world, rospy.Time.now(), self.world_frame))
        self.last_status = None
        self.updater = diagnostic_updater.Updater()
        self.updater.setHardwareID("mujoco")
        self.updater.add("simulated robot", self.diagnose)
        # the pose source's rate: motion capture's, the simulated VIO's, or (vo) the odometry camera's
        if self.vo:
            self.vo_camera_rate_hz = float(rospy.get_param("~vo_camera_rate_hz", ODOMETRY_CAMERA.rate_hz))
            source_rate_hz, source_topic = self.vo_camera_rate_hz, "camera/color/image_raw"
        else:
            source = self.sim.params.config.mocap if self.feedback == "mocap" else self.sim.params.config.vio
            source_rate_hz, source_topic = source.rate_hz, "base_pose" if self.feedback == "mocap" else "odom"
        self._source_rate = {"min": 0.9 * source_rate_hz, "max": 1.1 * source_rate_hz}   # the task keeps this dict
        self.source_freq = diagnostic_updater.HeaderlessTopicDiagnostic(
            source_topic, self.updater,
            diagnostic_updater.FrequencyStatusParam(self._source_rate, 0.0, 10))
        rospy.Subscriber("sim/disturbance", WrenchStamped, self.on_disturbance, queue_size=10)
        rospy.Subscriber("tracking_status", TrackingStatus, self.on_status, queue_size=10)
        # A scout trajectory raises the head on purpose: from the driver taking one until the next gait
        # command (the head is down again), the roll-over check watches the tail.
        rospy.Subscriber("driver/trajectory_status", TrajectoryStatus, self.on_trajectory_status, queue_size=10)
        rospy.Subscriber("gait_command", GaitCommand, self.on_gait_command, queue_size=10)
        # with a world: contact episodes between the robot and the obstacles (sim/collisions.py, as the
        # batch nav run counts them), in the diagnostics and the log
        self.contacts = None
        if self.world_file:
            self.contacts = CollisionMonitor(self.sim.plant.model)
        self.sim.start()
        rospy.loginfo(f"simulated {self.sim.robot.name}: seed {setup.seed}, {self.feedback} feedback, servo bus on "
                      f"{setup.port}, start {start_t}; "
                      f"{self.sim.params.summary()['floor_friction']:.3f} floor friction")
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self.loop, name="sim", daemon=True)
        self._thread.start()
        if self.world_file or self.vo:
            self.start_camera()

    # -- the head camera (with a world) ---------------------------------------------------------------
    def start_camera(self):
        """The navigation camera (with a world: nav.yaml's intrinsics and mount), or with ~feedback vo the
        odometry camera: ~vo_camera_width x ~vo_camera_height (320x240, the D435i's 615 px focal length
        scaled) at ~vo_camera_rate_hz (10), rendered from the IMU's camera_link (sim/camera.LinkMount);
        then ground_truth/camera_pose (camera_link) comes with every frame."""
        if self.vo:
            settings = OdometryCameraSettings(int(rospy.get_param("~vo_camera_width", ODOMETRY_CAMERA.width)),
                                              int(rospy.get_param("~vo_camera_height", ODOMETRY_CAMERA.height)),
                                              self.vo_camera_rate_hz)
            problems = settings.problems()       # each names the setting and its value
            if problems:
                raise ValueError("~vo_camera_*: " + "; ".join(problems))
            self.intrinsics = settings.intrinsics()
            f = self.intrinsics.fx
            mount = LinkMount(camera_link_in_base(self.sim.robot.head_length_m, self.sim.world.camera_in_head))
            self.camera_rate_hz = self.vo_camera_rate_hz
            self.depth_noise = named_depth_model(self.depth_model, self.sim.params.config.depth_noise, f,
                                                 self.sim.params.rng("depth_noise"))
        else:
            self.intrinsics, mount = self.nav_cfg.intrinsics, self.nav_cfg.mount
            self.camera_rate_hz = float(rospy.get_param("~camera_rate_hz", 0.5))
        if not self.camera_rate_hz > 0:
            raise ValueError(f"~camera_rate_hz: must be > 0, got {self.camera_rate_hz}")
        self.camera_depth = bool(rospy.get_param("~camera_depth", True))
        self.optical_frame = rospy.get_param("~camera_optical_frame", "camera_color_optical_frame")
        self.pub_rgb = rospy.Publisher("camera/color/image_raw", Image, queue_size=1)
        self.pub_info = rospy.Publisher("camera/color/camera_info", CameraInfo, queue_size=1)
        self.pub_depth = rospy.Publisher("camera/depth/image_rect_raw", Image, queue_size=1) \
            if self.camera_depth else None
        self.camera = CameraProcess(self.sim.plant.mjcf, self.intrinsics, mount,
                                    colour=True, depth=self.camera_depth, depth_model=self.depth_noise)
        self._camera_thread = threading.Thread(target=self.camera_loop, name="camera", daemon=True)
        self._camera_thread.start()
        rospy.loginfo(f"head camera: {self.intrinsics.width}x{self.intrinsics.height} at "
                      f"{self.camera_rate_hz:g} Hz, {self.depth_model} depth, "
                      f"{'at camera_link, the odometry room' if self.vo else f'world {self.world_file}'}")

    def camera_loop(self):
        period = 1.0 / self.camera_rate_hz
        next_t = time.monotonic()
        wall0 = time.monotonic()
        while not self._stop.is_set() and not rospy.is_shutdown():
            with self.sim.world.lock:
                t_s = self.sim.plant.time_s
                qpos = self.sim.plant.data.qpos.copy()
                T_wb = self.sim.plant.frame_transform("base_link")
            stamp = self.stamp(t_s)            # the snapshot's time: the image shows the state then
            self.camera.request(t_s, qpos, T_wb)
            frame = None
            while frame is None and not self._stop.is_set():
                frame = self.camera.poll(0.2)
            if frame is None:
                break
            try:
                self.pub_info.publish(to_camera_info(self.intrinsics, stamp, self.optical_frame))
                self.pub_rgb.publish(to_image(frame.rgb, "rgb8", stamp, self.optical_frame))
                if self.pub_depth is not None:
                    self.pub_depth.publish(to_image(frame.depth_m, "32FC1", stamp, self.optical_frame))
                if self.vo:
                    self.source_freq.tick()
                    gt = PoseStamped()
                    gt.header.stamp, gt.header.frame_id = stamp, self.world_frame
                    T = frame.T_world_camera.copy()
                    T[:3, :3] = T[:3, :3] @ R_LINK_OPTICAL.T            # optical -> camera_link
                    _pose(gt.pose, T[:3, 3], matrix_to_quat(T[:3, :3]))
                    self.pub_gt_cam.publish(gt)
            except rospy.ROSException:
                break
            st = self.camera.stats
            self.camera_load = st["render_s_total"] / max(1e-9, time.monotonic() - wall0)
            next_t += period
            delay = next_t - time.monotonic()
            if delay < 0:
                next_t = time.monotonic()
            else:
                self._stop.wait(delay)

    # -- subscriptions -------------------------------------------------------------------------------
    def on_disturbance(self, msg):
        f, t = msg.wrench.force, msg.wrench.torque
        force = [f.x, f.y, f.z] if (f.x, f.y, f.z) != (0, 0, 0) else None
        torque = [t.x, t.y, t.z] if (t.x, t.y, t.z) != (0, 0, 0) else None
        try:
            self.sim.plant._body_id(msg.header.frame_id)
        except ValueError as exc:
            rospy.logerr(f"sim/disturbance: {exc}")
            return
        self.sim.disturb(msg.header.frame_id, force, torque, self.duration_s)

    def on_status(self, msg):
        self.sim.set_target(msg.waypoint_index)

    def on_trajectory_status(self, msg):
        if msg.phase == "running":
            self.sim.watch_tail(True)

    def on_gait_command(self, _msg):
        self.sim.watch_tail(False)

    # -- the loop ------------------------------------------------------------------------------------
    def loop(self):
        period = 1.0 / self.rate_hz
        next_t = time.monotonic()
        last_status = 0.0
        k = 0
        while not self._stop.is_set() and not rospy.is_shutdown():
            now = time.monotonic()
            try:
                out = self.sim.step(now)
                self.publish(out, k)
                if self.contacts is not None:
                    self.count_contacts(k)
            except rospy.ROSException:
                break
            k += 1
            if now - last_status >= 1.0:
                last_status = now
                self.refresh_status()
            if k % 20 == 0:
                self.updater.update()   # publishes /diagnostics when its period (1 s) is due
            next_t += period
            delay = next_t - time.monotonic()
            if delay < -0.5:
                next_t = time.monotonic()   # fell far behind (machine busy): do not burst
            elif delay > 0:
                time.sleep(delay)

    def count_contacts(self, k):
        with self.sim.world.lock:
            new = self.contacts.update(self.sim.plant.data, clearance=k % 40 == 0)
        if new:
            for i, e in enumerate(self.contacts.episodes[-new:], len(self.contacts.episodes) - new):
                rospy.logwarn(f"sim: {e.link} touched {e.obstacle} at ({e.x_m:.2f}, {e.y_m:.2f}) m "
                              f"({self.contacts.collisions} contact episode(s) so far)")
                self.pub_contact.publish(contact_marker(e, i, rospy.Time.now(), self.world_frame))
            self.pub_contacts_all.publish(contact_markers(self.contacts.episodes, rospy.Time.now(), self.world_frame))

    def stamp(self, t_s):
        if not self.use_sim_time:
            return rospy.Time.now()
        return rospy.Time.from_sec(self.clock_epoch_s + t_s)

    def publish(self, out, k):
        self.pub_clock.publish(Clock(clock=rospy.Time.from_sec(self.clock_epoch_s + out.t_s)))
        stamp = self.stamp(out.t_s)
        for text in out.fired:
            rospy.logwarn(f"disturbance: {text}")
        if out.mocap is not None:
            gt = PoseStamped()
            gt.header.stamp, gt.header.frame_id = stamp, self.world_frame
            _pose(gt.pose, *out.truth_base)
            self.pub_gt_base.publish(gt)
            if self.pub_base is not None:
                m = PoseWithCovarianceStamped()
                m.header.stamp, m.header.frame_id = stamp, self.world_frame
                _pose(m.pose.pose, out.mocap.position_m, out.mocap.quat_xyzw)
                m.pose.covariance = self.mocap_covariance
                self.pub_base.publish(m)
                self.source_freq.tick()
        if out.imu is not None:
            self.pub_imu.publish(_imu(out.imu, self.stamp(out.imu.t_s), self.imu_frame))
        if out.vio is not None and self.pub_odom is not None:
            o = Odometry()
            o.header.stamp, o.header.frame_id, o.child_frame_id = stamp, self.world_frame, self.camera_frame
            _pose(o.pose.pose, out.vio.position_m, out.vio.quat_xyzw)
            o.pose.covariance = out.vio.covariance_row_major()
            self.pub_odom.publish(o)
            self.source_freq.tick()
            gt = PoseStamped()
            gt.header.stamp, gt.header.frame_id = stamp, self.world_frame
            _pose(gt.pose, *out.truth_camera)
            self.pub_gt_cam.publish(gt)
        if k % max(1, int(round(self.rate_hz / 10.0))) == 0:
            with self.sim.backend.lock:
                x, y, h = self.sim.true_com_pose()
            c = PoseStamped()
            c.header.stamp, c.header.frame_id = stamp, self.world_frame
            _pose(c.pose, (x, y, 0.0), (0.0, 0.0, math.sin(h / 2), math.cos(h / 2)))
            self.pub_gt_com.publish(c)

    def refresh_status(self):
        s = self.sim.status()
        if self.contacts is not None:
            s["obstacle_contacts"] = self.contacts.collisions
            c = self.contacts.min_clearance_m
            s["min_clearance_m"] = float(c) if math.isfinite(c) else -1.0
        if self.camera is not None:
            s["camera_frames"] = self.camera.stats["frames"]
            s["camera_render_s_last"] = self.camera.stats["render_s_last"]
            s["camera_core_fraction"] = getattr(self, "camera_load", 0.0)
        bad = s["rolled_over"] or s["limit_violations"]
        if s["rolled_over"]:
            rospy.logerr_throttle(10.0, f"the simulated robot rolled over (tilt {s['max_tilt_deg']:.0f} deg)")
        status = DiagnosticStatus(
            level=DiagnosticStatus.ERROR if bad else DiagnosticStatus.OK, name="sim", hardware_id="mujoco",
            message=("rolled over" if s["rolled_over"] else
                     f"{s['limit_violations']} joint goals beyond the limits" if s["limit_violations"] else "running"),
            values=[KeyValue(k, f"{v:.3f}" if isinstance(v, float) else str(v)) for k, v in s.items()])
        self.last_status = status

    def diagnose(self, stat):
        s = self.last_status
        if s is None:
            stat.summary(DiagnosticStatus.WARN, "starting")
            return stat
        stat.summary(s.level, s.message)
        for kv in s.values:
            stat.add(kv.key, kv.value)
        return stat

    def shutdown(self):
        self._stop.set()
        self._thread.join(2.0)
        if self.camera is not None:
            self._camera_thread.join(2.0)
            self.camera.close()
        # Ctrl+C of the launch stops every node at once: the driver's shutdown action (its final hold
        # write, or torque off) needs the bus, so the bus is served until the driver stops talking.
        if not self.sim.wait_bus_idle(quiet_s=0.3, timeout_s=5.0):
            print("[sim] the servo bus was still busy 5 s after shutdown began: closing it", flush=True)
        self.sim.stop()


def main():
    rospy.init_node("sim")
    try:
        node = SimNode()
    except (ValueError, OSError, RuntimeError) as exc:
        rospy.logfatal(str(exc))
        return 1
    rospy.on_shutdown(node.shutdown)
    rospy.spin()
    return 0
