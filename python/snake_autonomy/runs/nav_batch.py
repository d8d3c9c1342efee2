"""The navigation experiment in batch, ROS-free: a world file, the plant with its obstacles, the
head camera, traversability (depth or the monocular classifier) and the robot's own navigation loop
(planning/rectilinear/nav_loop.NavLoop, the one planner_node runs), closed through the C++ driver.

    run = NavRun(NavRunSpec(world=load_world(FILE), robot="cobra", perception="depth", seed=0))
    result = run.run()
    result.write(out_dir)      # metrics.json, topview.png, frames/*.png, commands.csv (every gait
                               # command the loop sent), contacts.csv (each contact episode: when,
                               # which link, where, what the follower was doing), replans.csv (each
                               # replan: the pose, every candidate arc's free length, the choice or why none)

This file has no navigation logic: it feeds NavLoop what planner_node gets, and sends what it
returns to the driver as driver_node would get it.
- Poses: the run's pose source at its rate (sim/nav_pose_source.py), stamped when sampled and
  delivered pose_latency_s later (default: the source's): `mocap` (default, as sim.launch
  feedback:=mocap: base_link at 100 Hz with config/sim.yaml's mocap noise), `vio` (the simulated
  RTAB-Map through the tracking gate and pose remapper; while tracking is lost no pose comes and the
  loop holds on its stale pose), `vo` (the visual-inertial odometry vio_node runs, on its own
  10 Hz camera at camera_link and the head's 200 Hz IMU, through the same gate and remapper: only on
  a world with a textured floor) or `truth` (the plant's base_link, no noise: a diagnostic).
- Camera frames at camera_rate_hz (sim.launch's 0.5 Hz), stamped at capture and delivered
  frame_latency_s later (sim_node renders in a child process: 0.07-0.17 s). Depth through the
  D435i-like model of config/sim.yaml depth_noise: (sim/depth_noise.py) unless depth_model is
  "perfect" (or depth_noise.enabled is false and depth_model is not "noisy"). A frame is rendered
  when the loop first reads it, from a copy of the plant's state at its stamp: the same image as a
  render at the stamp, and a frame the loop drops unread costs nothing.
- Joint angles: the driver's measured positions (what driver_node publishes on joint_states) every
  control period, undelayed (the layered planner's body sweep places the body by them).
- Commands: NavLoop.tick every command_period_s (planner_node's ~rate_hz 2) -> hold, or the nav
  config's forward / reverse gait with curve + kappa, through the driver (runs/gait_driver.py: the
  DriverController driver_node runs, whose CPG ramps the wave in from the hold posture).
- The end: "reached" means the robot comes to rest with base_link inside the goal's disc by
  ground truth: when the loop says the goal is reached it holds, the run goes on settle_s more
  and base_link's final position decides. Otherwise the run ends at time_limit_s or on roll-over.

metrics.json: goal_reached (by that rule), loop_reached (the loop said so), final_distance_m
(base_link to the goal's centre at the end), closest_to_goal_m (how near base_link came to the
goal's disc), outcome (nav_metrics.nav_outcome), contacts_follow / _turn_in_place / _back_off /
_idle (the contact episodes by the follower's mode when they began), the loop's refusals and errors:
runs/nav_metrics.py, the contract shared with a run recorded through ROS. The batch run adds the
pose source's error against the truth and the time tracking was lost (NavPoseSource.metrics),
pose_latency_s, depth_model and ticks_stale (command ticks holding on a stale pose or frame).
"""
import copy
import csv
import dataclasses
import json
import math
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, List, Optional

import numpy as np

from snake_autonomy import _core
from snake_autonomy.paths import config_path, robot_yaml
from snake_autonomy.perception.block_classifier import BlockClassifier, truth_traversable
from snake_autonomy.perception.depth_traversability import DepthTraversability
from snake_autonomy.planning.rectilinear.body_chain import BodyChain
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera, head_width_m, nav_config_path
from snake_autonomy.planning.rectilinear.nav_loop import GOAL_REACHED, STALE, NavLoop, checked_positive
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.overlay import overlay
from snake_autonomy.planning.rectilinear.planner import ground_frame
from snake_autonomy.planning.rectilinear.route import grid_shape
from snake_autonomy.runs.gait_driver import PlantGaitDriver
from snake_autonomy.runs.nav_metrics import NavFacts, nav_metrics
from snake_autonomy.runs.results import PathLength
from snake_autonomy.sim.camera import HeadCamera
from snake_autonomy.sim.collisions import CollisionMonitor
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.depth_noise import DepthNoise
from snake_autonomy.sim.nav_pose_source import POSE_SOURCES, NavPoseSource, imu_in_head
from snake_autonomy.sim.scales import ScaledPlant
from snake_autonomy.sim.scene import build_scene
from snake_autonomy.sim.sensor_clock import SensorClock
from snake_autonomy.sim.world_file import ODOMETRY_FLOOR_TEXTURES, World

DEPTH_MODELS = ("noisy", "perfect")


@dataclass
class NavRunSpec:
    world: World
    robot: str = "cobra"                  # config/robots/NAME.yaml or a YAML path
    perception: str = "depth"             # depth | mono | truth (segmentation render, classifier's cells)
    seed: int = 0
    time_limit_s: float = 1200.0
    classifier: Optional[str] = None      # model file (mono)
    nav_config: Optional[str] = None      # None: config/nav_<robot>.yaml if it exists, else nav.yaml
    sim_config: Optional[str] = None      # default config/sim.yaml
    control_period_s: float = 0.01        # the driver's 100 Hz
    command_period_s: float = 0.5         # planner_node's ~rate_hz 2
    camera_rate_hz: float = 0.5           # sim.launch camera_rate_hz
    frame_latency_s: float = 0.2          # capture to the planner: sim_node's render (0.07-0.17 s) + transport
    pose_source: str = "mocap"            # mocap | vio | vo | truth (a diagnostic: no noise)
    pose_latency_s: Optional[float] = None   # sample to the planner; None: the source's (sim.yaml vio.latency_s)
    depth_model: Optional[str] = None     # noisy | perfect; None: config/sim.yaml depth_noise.enabled
    pose_timeout_s: float = 1.0           # planner_node's ~pose_timeout_s
    frame_timeout_s: Optional[float] = None   # None: sim.launch's max(5, 3 camera periods)
    settle_s: float = 10.0                # after the loop's goal-reached hold: the robot comes to rest
    keep_frames: bool = True
    flat_belly_fraction: Optional[float] = None   # None: nav.yaml plant.flat_belly_fraction
    gait_name: Optional[str] = None       # the driver's gait (steering: curvature); None: nav config gaits.forward
    reverse_gait_name: Optional[str] = None   # backing off; None: gaits.reverse
    on_no_free_arc: Optional[str] = None  # hold | turn | back_off; None: planner_node's default (follower.back_off)

    def check(self) -> None:
        """ValueError naming the field and value of anything a run cannot use."""
        for key in ("time_limit_s", "control_period_s", "command_period_s", "camera_rate_hz", "pose_timeout_s"):
            checked_positive(key, getattr(self, key))
        for key in ("frame_latency_s", "pose_latency_s", "settle_s"):
            v = getattr(self, key)
            if v is None and key == "pose_latency_s":
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ValueError(f"{key}: must be a finite number >= 0, got {v!r}")
        if self.pose_source not in POSE_SOURCES:
            raise ValueError(f"pose_source: expected one of {', '.join(POSE_SOURCES)}, got {self.pose_source!r}")
        if self.pose_source == "vo" and self.world.floor_texture not in ODOMETRY_FLOOR_TEXTURES:
            raise ValueError(f"pose_source vo: world {self.world.source or self.world.name!r} has floor_texture "
                             f"{self.world.floor_texture!r}, on which the visual odometry loses track (too few "
                             f"features); vo needs floor_texture {' or '.join(ODOMETRY_FLOOR_TEXTURES)}")
        if self.depth_model is not None and self.depth_model not in DEPTH_MODELS:
            raise ValueError(f"depth_model: expected one of {', '.join(DEPTH_MODELS)}, got {self.depth_model!r}")
        if self.perception not in ("depth", "mono", "truth"):
            raise ValueError(f"perception: expected depth, mono or truth, got {self.perception!r}")
        if self.perception == "mono" and not self.classifier:
            raise ValueError("perception mono needs a classifier model (snake_autonomy nav "
                             "train-classifier --out FILE; then --classifier FILE)")


class DeferredFrame:
    """A camera frame rendered when first read. The plant's state at the stamp is copied (MjData),
    so the image is the one a render at the stamp gives, and a frame the loop replaces before it
    replans costs no render (frames come every 2 s, replans every 10 s)."""

    def __init__(self, camera, data, T_world_base: np.ndarray, t_s: float, kinds: dict):
        self._camera, self._data, self._T, self.t_s, self._kinds = camera, copy.copy(data), T_world_base, t_s, kinds
        self.shape = (camera.intrinsics.height, camera.intrinsics.width)
        self._frame = None

    def render(self):
        if self._frame is None:
            self._frame = self._camera.render(self._data, self._T, self.t_s, **self._kinds)
            self._data = None
        return self._frame


@dataclass
class NavResult:
    metrics: dict
    trajectory: np.ndarray                            # (N, 3) t, x, y of base_link
    replans: list = field(default_factory=list)       # planner.Replan
    frames: List[np.ndarray] = field(default_factory=list)   # overlays at each replan
    world: Optional[World] = None
    contacts: list = field(default_factory=list)     # (collisions.ContactEpisode, the follower's mode)
    obstacle_map: Any = None                          # the planner's map at the end (shapely; map_geometry)
    commands: list = field(default_factory=list)      # (t_s, gait, kappa_per_m, loop state) each command sent

    def write(self, out_dir) -> None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        (out / "metrics.json").write_text(json.dumps(self.metrics, indent=2) + "\n")
        np.savetxt(out / "trajectory.csv", self.trajectory, delimiter=",", header="t_s,x_m,y_m", comments="")
        with open(out / "contacts.csv", "w") as f:
            f.write("t_s,obstacle,link,x_m,y_m,follower_mode\n")
            for e, mode in self.contacts:
                f.write(f"{e.t_s:.2f},{e.obstacle},{e.link},{e.x_m:.4f},{e.y_m:.4f},{mode}\n")
        self._write_replans(out / "replans.csv")
        with open(out / "commands.csv", "w") as f:
            f.write("t_s,gait,kappa_per_m,state\n")
            for t, gait, kappa, state in self.commands:
                f.write(f"{t:.2f},{gait},{kappa:.4f},{state}\n")
        if self.frames:
            import cv2  # lazy: OpenCV is heavy and only this path needs it
            (out / "frames").mkdir(exist_ok=True)
            for i, img in enumerate(self.frames):
                cv2.imwrite(str(out / "frames" / f"replan_{i:03d}.png"), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
        self._topview(out / "topview.png")

    def _write_replans(self, path) -> None:
        """One row per replan: base_link's pose, the candidate arcs as curvature:free_m pairs (path
        curvature 1/m, free prefix m), what ended each arc's prefix (arc_limits, a letter per arc: o an
        obstacle near the head's path, u the head leaving the floor the views showed, b the body sweep,
        - the horizon or a planner that does not tell), the chosen arc's (empty when none was free) and
        the planner's reason (back off, turn in place, ...): why a run went where it did, without
        re-running it."""
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t_s", "x_m", "y_m", "heading_deg", "arcs", "arc_limits", "chosen_curvature_per_m",
                        "chosen_free_m", "reason"])
            for r in self.replans:
                arc = r.selection.arc
                w.writerow([f"{r.t_s:.2f}", f"{r.pose[0]:.4f}", f"{r.pose[1]:.4f}", f"{math.degrees(r.pose[2]):.1f}",
                            " ".join(f"{a.curvature_per_m:+.2f}:{a.free_m:.2f}" for a in r.selection.arcs),
                            "".join(a.limit[:1] or "-" for a in r.selection.arcs),
                            "" if arc is None else f"{arc.curvature_per_m:+.2f}",
                            "" if arc is None else f"{arc.free_m:.2f}", r.reason])

    def _topview(self, path) -> None:
        import matplotlib  # lazy: matplotlib is heavy and only this path needs it
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.patches import Circle, Polygon
        fig, ax = plt.subplots(figsize=(8, 6))
        w = self.world
        for ob in w.obstacles:
            if ob.kind == "cylinder":
                ax.add_patch(Circle((ob.x_m, ob.y_m), ob.radius_m, color="0.4"))
            else:
                ax.add_patch(Polygon(ob.corners(), color="0.4"))
        if self.obstacle_map is not None and not self.obstacle_map.is_empty:
            polys = [g for g in getattr(self.obstacle_map, "geoms", [self.obstacle_map]) if g.geom_type == "Polygon"]
            for i, poly in enumerate(polys):
                ax.add_patch(Polygon(np.asarray(poly.exterior.coords), color="r", alpha=0.25, lw=0,
                                     label="the planner's map at the end" if i == 0 else None))
        ax.add_patch(Circle(w.goal, w.goal_radius_m, fill=False, color="g", lw=2))
        ax.plot(self.trajectory[:, 1], self.trajectory[:, 2], "b-", lw=1.5, label="base_link")
        routes = [r.route_world for r in self.replans if r.route_world is not None]
        for i, route in enumerate(routes):
            ax.plot(route[:, 0], route[:, 1], "--", color="g", lw=0.6, alpha=0.35,
                    label="route at each replan (map.route)" if i == 0 else None)
        for r in self.replans:
            ax.plot(r.pose[0], r.pose[1], "k.", ms=4)
            if r.path_world is not None:
                ax.plot(r.path_world[:, 0], r.path_world[:, 1], "-", color="orange", lw=0.8)
            else:
                ax.plot(r.pose[0], r.pose[1], "rx", ms=8)
        if self.contacts:
            xy = np.array([(e.x_m, e.y_m) for e, _ in self.contacts])
            ax.plot(xy[:, 0], xy[:, 1], "o", mfc="none", mec="m", ms=7, label="contact (link centre)")
        m = self.metrics
        ax.set_title(f"goal {'reached' if m['goal_reached'] else 'NOT reached'} in {m['time_s']:.0f} s, "
                     f"{m['collisions']} collision(s), {m['replans']} replans, {m['stops_no_free_arc']} stops")
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.legend(loc="best")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        fig.savefig(path, dpi=110)
        plt.close(fig)


class NavRun:
    def __init__(self, spec: NavRunSpec):
        spec.check()
        self.spec = spec
        self.nav_config = spec.nav_config or str(nav_config_path(spec.robot))
        self.cfg = NavConfig.from_yaml(self.nav_config)
        if self.cfg.gaits.steering != "uniform":
            raise ValueError(f"gaits.steering: {self.cfg.gaits.steering!r} is a prototype of "
                             "bench/nav_follow_the_leader; the navigation loop commands curve + kappa (uniform)")
        mp = self.cfg.map
        if mp.route:   # the route's grid over the start-goal box is bounded: refused before the plant is built
            grid_shape(spec.world.start[:2], spec.world.goal, mp.cell_m, mp.pad_m, mp.route_max_cells)
        self.gaits = dataclasses.replace(self.cfg.gaits, forward=spec.gait_name or self.cfg.gaits.forward,
                                         reverse=spec.reverse_gait_name or self.cfg.gaits.reverse)
        ry = robot_yaml(spec.robot)
        self.robot = _core.RobotModel.from_yaml(str(ry))
        sim_cfg = SimConfig.from_yaml(spec.sim_config or str(config_path("sim.yaml")))
        belly = self.cfg.plant.flat_belly_fraction if spec.flat_belly_fraction is None else spec.flat_belly_fraction
        self.flat_belly_fraction = belly
        self.params = sim_cfg.with_flat_belly(belly).draw(seed=spec.seed, num_joints=self.robot.num_joints)
        scene = build_scene(spec.world)
        self.plant = ScaledPlant(self.robot, self.params, spec.world.start_rad, scene_xml=scene.scene_xml,
                                 assets_xml=scene.assets_xml, imu_in_head=imu_in_head(spec.pose_source, self.params))
        self.depth_model = spec.depth_model or ("noisy" if sim_cfg.depth_noise.enabled else "perfect")
        noise = (DepthNoise(sim_cfg.depth_noise, self.cfg.intrinsics.fx, self.params.rng("depth_noise"))
                 if self.depth_model == "noisy" else None)
        self.camera = HeadCamera(self.plant.model, self.cfg.intrinsics, self.cfg.mount, depth_model=noise)
        self.collisions = CollisionMonitor(self.plant.model)
        self._contact_modes: List[str] = []
        self.rollover_deg = sim_cfg.monitor.rollover_tilt_deg
        self.poses = NavPoseSource(spec.pose_source, self.params, self.robot, plant=self.plant)
        self.pose_latency_s = self.poses.latency_s if spec.pose_latency_s is None else spec.pose_latency_s
        self.drive = PlantGaitDriver(self.robot, self.plant)
        self.render_kinds = {"colour": spec.perception == "mono" or spec.keep_frames,
                             "depth": spec.perception == "depth", "labels": spec.perception == "truth"}
        perceive = self._perception()
        cfg, truth_map = self.cfg, None
        if self.cfg.map.source == "truth":          # the diagnostic: the planner knows every obstacle
            truth_map = ObstacleMap.from_world(spec.world.obstacles)
        on_no_free_arc = spec.on_no_free_arc or ("back_off" if cfg.follower.back_off else "hold")
        frame_timeout = spec.frame_timeout_s or max(5.0, 3.0 / spec.camera_rate_hz)
        self.loop = NavLoop(cfg, head_width_m(ry), lambda f: perceive(f.render()), spec.world.goal,
                            spec.world.goal_radius_m, on_no_free_arc, spec.pose_timeout_s,
                            BodyChain(self.robot), frame_timeout_s=frame_timeout,
                            obstacle_map=truth_map)

    def _perception(self):
        """CameraFrame -> traversability image, by spec.perception."""
        spec = self.spec
        if spec.perception == "depth":
            depth = DepthTraversability(self.cfg.intrinsics, T_ground_camera(self.cfg.mount, self.robot.link_radius_m),
                                        self.cfg.depth, seed=spec.seed)
            return lambda f: depth.classify(f.depth_m)
        if spec.perception == "mono":
            clf, margin = BlockClassifier.load(spec.classifier), self.cfg.classifier.ground_margin
            return lambda f: clf.traversable(f.rgb, margin)
        # a perfect classifier: the segmentation render through the classifier's blocks and cells
        # (nav.yaml classifier: block_px, stride_px): what mono could reach
        c = self.cfg.classifier
        return lambda f: truth_traversable(f.ground_truth_ground(), c.block_px, c.stride_px, c.ground_fraction)

    def run(self, progress: Optional[Callable[[float], None]] = None) -> NavResult:
        """The closed loop to the time limit (or the goal plus settling); progress(t_s), if given,
        is called once per simulated second."""
        spec, plant, loop = self.spec, self.plant, self.loop
        next_progress_s = 1.0
        dt = spec.control_period_s
        t, step = 0.0, 0             # t = step x dt: no rounding drift against the tick and sample grids
        traj, replans, frames, commands = [], [], [], []
        poses, camera_frames = deque(), deque()          # (delivery time, stamp, pose or frame)
        camera_clock = SensorClock(spec.camera_rate_hz)
        next_tick, next_sample, end_t = spec.command_period_s, 0.0, spec.time_limit_s
        path, rolled, loop_reached_t = PathLength(min_step_m=0.0), False, None   # truth at 10 Hz
        sent = None
        while t < end_t:
            T_wb = plant.frame_transform("base_link")
            sample = self.poses.poll(plant)
            if sample is not None:
                poses.append((sample[0] + self.pose_latency_s, *sample))
            if camera_clock.due(t):
                camera_clock.tick(t)
                camera_frames.append((t + spec.frame_latency_s, t,
                                      DeferredFrame(self.camera, plant.data, T_wb, t, self.render_kinds)))
            while poses and poses[0][0] <= t + 1e-9:
                _, stamp, T = poses.popleft()
                loop.on_pose(stamp, T)
            loop.on_joints(t, self.drive.driver.controller.position_rad)     # joint_states: the servos' positions
            while camera_frames and camera_frames[0][0] <= t + 1e-9:
                _, stamp, f = camera_frames.popleft()
                loop.on_frame(stamp, f)
            if t >= next_sample - 1e-9:
                next_sample += 0.1
                x, y, _ = ground_frame(T_wb)
                traj.append((t, x, y))
                path.add(x, y)
                self._count_contacts(clearance=True)
                if plant.base_tilt_deg() > self.rollover_deg:
                    rolled = True
                    break
            else:
                self._count_contacts(clearance=False)
            if t >= next_tick - 1e-9:
                next_tick += spec.command_period_s
                tick = loop.tick(t)
                if tick.replan is not None:
                    replans.append(tick.replan)
                    if spec.keep_frames:
                        frames.append(self._overlay(tick))
                gait = self.gaits.command(tick.hold, tick.backwards)
                kappa = float(tick.kappa_per_m)
                commands.append((t, gait, kappa, tick.state))
                if (gait, kappa) != sent:
                    self.drive.command(gait, kappa_per_m=kappa)
                    sent = (gait, kappa)
                if tick.state == GOAL_REACHED and loop_reached_t is None:
                    loop_reached_t, self._stop_xy = t, ground_frame(T_wb)[:2]
                    end_t = min(end_t, t + spec.settle_s)
            self.drive.step(t, dt)
            step += 1
            t = step * dt
            self.poses.step_to(plant, t)
            if progress is not None and t >= next_progress_s - 1e-9:
                next_progress_s += 1.0
                progress(t)
        self.camera.close()
        self.poses.close()
        return self._result(t, traj, replans, frames, commands, path, rolled, loop_reached_t)

    def _overlay(self, tick) -> np.ndarray:
        checker = PerceptionCollisionChecker(self.cfg.intrinsics, tick.T_ground_camera,
                                             self.loop.planner.footprint_width_m)
        return overlay(tick.frame.render().rgb, tick.ground, tick.replan.selection, checker)

    def _result(self, t, traj, replans, frames, commands, path, rolled, loop_reached_t) -> NavResult:
        spec, world, loop = self.spec, self.spec.world, self.loop
        final = ground_frame(self.plant.frame_transform("base_link"))
        traj = np.array(traj)
        metrics = nav_metrics(NavFacts(
            world=world, trajectory=traj, t_end_s=t, final_pose=tuple(final), loop_reached_t_s=loop_reached_t,
            stop_xy=self._stop_xy if loop_reached_t is not None else None,
            collisions=self.collisions.collisions, min_clearance_m=self.collisions.min_clearance_m,
            path_length_m=path.length_m, replans=replans, stops_no_free_arc=loop.stops_no_free_arc,
            rolled_over=rolled, contact_modes=self._contact_modes, min_radius_m=self.cfg.follower.min_radius_m,
            identity={"robot": self.robot.name, "perception": spec.perception, "seed": spec.seed,
                      "world": world.source or world.name, "flat_belly_fraction": self.flat_belly_fraction,
                      "gait": self.gaits.forward, "pose_source": spec.pose_source,
                      "nav_config": Path(self.nav_config).name, "on_no_free_arc": loop.on_no_free_arc},
            loop_refused=loop.refused, loop_errors=loop.errors, loop_last_error=loop.last_error))
        metrics.update(self.poses.metrics(), pose_latency_s=self.pose_latency_s, depth_model=self.depth_model,
                       ticks_stale=sum(1 for c in commands if c[3] == STALE))
        contacts = [(e, m) for e, m in zip(self.collisions.episodes, self._contact_modes)]
        return NavResult(metrics, traj, replans, frames, world, contacts, loop.planner.map_geometry(), commands)

    def _count_contacts(self, clearance: bool) -> None:
        """New contact episodes, each tagged with what the follower was doing (FOLLOW,
        TURN_IN_PLACE, BACK_OFF, IDLE)."""
        new = self.collisions.update(self.plant.data, clearance=clearance)
        self._contact_modes += [self.loop.planner.follower.mode] * new
