"""The navigation experiment in batch, ROS-free: a world file, the plant with its
obstacles, the head camera, traversability (depth or the monocular classifier), the perception-space
planner and the receding-horizon follower, closed through the rectilinear gait's Python reference.

    run = NavRun(NavRunSpec(world=load_world(FILE), robot="cobra", perception="depth", seed=0))
    result = run.run()
    result.write(out_dir)      # metrics.json (the issue's contract), topview.png, frames/*.png,
                               # contacts.csv (each contact episode: when, which link, where, and
                               # what the follower was doing), replans.csv (each replan: the pose,
                               # every candidate arc's free length, the choice or the stop and why)

metrics.json adds to the contract: `closest_to_goal_m` (how near base_link came to the goal's disc),
`outcome` (success, reached_with_contact, rolled_over,
circling_goal, stopped, time_limit: NavRun._outcome) and contacts_follow / _turn_in_place / _back_off /
_idle (the contact episodes by the follower's mode when they began).

Pose source: the plant's ground truth of base_link (the head's front, where the camera looks and
the arcs start; the simulated VIO's place, not wired here yet). The head's yaw answers a change of
kappa at once (the lateral joints bend the body behind it: about L/2 = 0.75 rad per 1/m on COBRA),
so the heading feedback gain must stay well below 1 / (L/2) in kappa per rad: with the paper-like
0.5 1/s (38 /m per rad) the follower oscillated bang-bang and rolled COBRA over within 3 s
(config/nav.yaml k_heading). The body's average axis (chord) is no better a heading for planning:
at kappa 1/m it points up to 43 deg away from the camera's 27.5 deg half field of view.
The camera's pose in the planning frame is the true one at the frame (the head bobs with the gait).
kappa is updated every command_period_s and slewed at kappa_slew_per_m_s (the body reshapes over a
gait cycle; an instant 0.5 rad jump of every lateral joint whips the body).
Joint targets (NavRunSpec.gait_source): "driver" (default) commands config/gaits.yaml's rectilinear
gait with curve + kappa through the C++ driver on the plant (runs/gait_driver.py: LockStepDriver, the
DriverController driver_node runs; its CPG ramps the wave in from the hold posture); "reference"
writes the Python reference's gait.joint_angles(t, kappa) (config/nav.yaml gait:) straight to the
plant every control period, ramped in over ramp_s. The driver's gaits are the nav config's `gaits:`
(forward, reverse); without a nav config named, the robot's own (config.nav_config_path: config/
nav_chang_rectilinear.yaml names rectilinear_chang, derived for its 0.07 m links) or nav.yaml's.
With the nav config's gaits.steering follow_the_leader kappa is laid along the head's path as
it crawls (planning/rectilinear/follow_the_leader.py, the crawl measured on base_link's ground truth)
and each yaw joint gets its own curvature: through the driver as explicit per-joint biases of the gait
command (GaitCommand bias, every command_period_s), with the reference as its yaw angles.
"""
import collections
import csv
import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, Optional

import numpy as np

from snake_autonomy import _core
from snake_autonomy.paths import config_path, robot_yaml
from snake_autonomy.perception.block_classifier import BlockClassifier, truth_traversable
from snake_autonomy.perception.depth_traversability import DepthTraversability
from snake_autonomy.planning.rectilinear.body_model import BodyGeometry
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera, head_width_m, nav_config_path
from snake_autonomy.planning.rectilinear.follow_the_leader import FollowTheLeader
from snake_autonomy.planning.rectilinear.follower import BACK_OFF, MODES, RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.overlay import overlay
from snake_autonomy.planning.rectilinear.planner import NavPlanner, T_world_ground, ground_frame
from snake_autonomy.planning.rectilinear.route import grid_shape
from snake_autonomy.runs.gait_driver import PlantGaitDriver
from snake_autonomy.runs.results import PathLength
from snake_autonomy.sim.camera import HeadCamera
from snake_autonomy.sim.collisions import CollisionMonitor
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.scales import ScaledPlant
from snake_autonomy.sim.scene import build_scene
from snake_autonomy.sim.world_file import World


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
    control_period_s: float = 0.01
    ramp_s: float = 2.0
    command_period_s: float = 0.5
    kappa_slew_per_m_s: float = 1.0
    keep_frames: bool = True
    flat_belly_fraction: Optional[float] = None   # None: nav.yaml plant.flat_belly_fraction
    gait_source: str = "driver"           # driver (C++ gait, config/gaits.yaml) | reference (gait.py)
    gait_name: Optional[str] = None       # the driver's gait (steering: curvature); None: nav config gaits.forward
    reverse_gait_name: Optional[str] = None   # backing off (follower back_off); None: gaits.reverse


@dataclass
class NavResult:
    metrics: dict
    trajectory: np.ndarray                            # (N, 3) t, x, y of base_link
    replans: list = field(default_factory=list)       # planner.Replan
    frames: List[np.ndarray] = field(default_factory=list)   # overlays at each replan
    world: Optional[World] = None
    contacts: list = field(default_factory=list)     # (collisions.ContactEpisode, the follower's mode)
    obstacle_map: Any = None                          # the planner's map at the end (shapely; map.source)

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
        if self.frames:
            import cv2  # lazy: OpenCV is heavy and only this path needs it
            (out / "frames").mkdir(exist_ok=True)
            for i, img in enumerate(self.frames):
                cv2.imwrite(str(out / "frames" / f"replan_{i:03d}.png"), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
        self._topview(out / "topview.png")

    def _write_replans(self, path) -> None:
        """One row per replan: base_link's pose, the candidate arcs as curvature:free_m pairs (path
        curvature 1/m, free prefix m), the chosen arc's (empty when none was free) and the planner's
        reason (back off, turn in place, ...): why a run went where it did, without re-running it."""
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["t_s", "x_m", "y_m", "heading_deg", "arcs", "chosen_curvature_per_m", "chosen_free_m",
                        "reason"])
            for r in self.replans:
                arc = r.selection.arc
                w.writerow([f"{r.t_s:.2f}", f"{r.pose[0]:.4f}", f"{r.pose[1]:.4f}", f"{math.degrees(r.pose[2]):.1f}",
                            " ".join(f"{a.curvature_per_m:+.2f}:{a.free_m:.2f}" for a in r.selection.arcs),
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
                                     label="obstacle map at the end (map.source)" if i == 0 else None))
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
        self.spec = spec
        if not (isinstance(spec.time_limit_s, (int, float)) and math.isfinite(spec.time_limit_s)
                and spec.time_limit_s > 0):
            raise ValueError(f"time_limit_s: must be a finite number of seconds > 0, got {spec.time_limit_s!r}")
        self.nav_config = spec.nav_config or str(nav_config_path(spec.robot))
        self.cfg = NavConfig.from_yaml(self.nav_config)
        mp = self.cfg.map
        if mp.route:   # the route's grid over the start-goal box is bounded: refused before the plant is built
            grid_shape(spec.world.start[:2], spec.world.goal, mp.cell_m, mp.pad_m, mp.route_max_cells)
        self.gait_name = spec.gait_name or self.cfg.gaits.forward
        self.reverse_gait_name = spec.reverse_gait_name or self.cfg.gaits.reverse
        ry = robot_yaml(spec.robot)
        self.robot = _core.RobotModel.from_yaml(str(ry))
        sim_cfg = SimConfig.from_yaml(spec.sim_config or str(config_path("sim.yaml")))
        belly = self.cfg.plant.flat_belly_fraction if spec.flat_belly_fraction is None else spec.flat_belly_fraction
        self.params = sim_cfg.with_flat_belly(belly).draw(seed=spec.seed, num_joints=self.robot.num_joints)
        scene = build_scene(spec.world)
        self.plant = ScaledPlant(self.robot, self.params, spec.world.start_rad,
                                 scene_xml=scene.scene_xml, assets_xml=scene.assets_xml)
        self.camera = HeadCamera(self.plant.model, self.cfg.intrinsics, self.cfg.mount)
        self.collisions = CollisionMonitor(self.plant.model)
        self._contact_modes: List[str] = []
        self.planner = NavPlanner(self.cfg.intrinsics, head_width_m(ry), self.cfg.sampler,
                                  RecedingHorizonFollower(self.cfg.follower), BodyGeometry.of_robot(self.robot),
                                  self.cfg.map)
        self.rollover_deg = sim_cfg.monitor.rollover_tilt_deg
        if self.cfg.map.source == "truth":          # the diagnostic: the planner knows every obstacle
            self.planner.obstacle_map = ObstacleMap.from_world(spec.world.obstacles)
        if spec.gait_source not in ("driver", "reference"):
            raise ValueError(f"gait_source: expected driver or reference, got {spec.gait_source!r}")
        self.drive = None
        if spec.gait_source == "driver":
            self.drive = PlantGaitDriver(self.robot, self.plant)
        self.flat_belly_fraction = belly
        if spec.perception == "depth":
            self._depth = DepthTraversability(self.cfg.intrinsics,
                                              T_ground_camera(self.cfg.mount, self.robot.link_radius_m),
                                              self.cfg.depth, seed=spec.seed)
            self.perceive = lambda f: self._depth(f.depth_m)
        elif spec.perception == "mono":
            if not spec.classifier:
                raise ValueError("perception mono needs a classifier model (snake_autonomy nav "
                                 "train-classifier --out FILE; then --classifier FILE)")
            clf = BlockClassifier.load(spec.classifier)
            margin = self.cfg.classifier.ground_margin
            self.perceive = lambda f: clf.traversable(f.rgb, margin)
        elif spec.perception == "truth":
            # a perfect classifier: the segmentation render through the classifier's
            # blocks and cells (nav.yaml classifier: block_px, stride_px): what mono could reach
            c = self.cfg.classifier
            self.perceive = lambda f: truth_traversable(f.ground_truth_ground(), c.block_px, c.stride_px,
                                                        c.ground_fraction)
        else:
            raise ValueError(f"perception: expected depth, mono or truth, got {spec.perception!r}")

    def run(self) -> NavResult:
        spec, plant, gait, world = self.spec, self.plant, self.cfg.gait, self.spec.world
        dt = spec.control_period_s
        t, kappa = 0.0, 0.0
        traj, replans, frames = [], [], []
        next_replan, next_sample = spec.ramp_s, 0.0
        path, reached, rolled = PathLength(min_step_m=0.0), False, False   # ground truth at 10 Hz: every step
        kappa_goal, next_command, backwards = 0.0, spec.ramp_s, False
        # backing off (follower BACK_OFF) with the reference: the same wave travelling to the head
        # (direction negated, as gaits.yaml's reverse gaits negate the lag)
        reverse = dataclasses.replace(gait, direction=-gait.direction)
        ftl, next_bias = None, 0.0
        if self.cfg.gaits.steering == "follow_the_leader":
            ftl = FollowTheLeader.of_robot(self.robot)
        while t < spec.time_limit_s:
            T_wb = plant.frame_transform("base_link")
            pose = ground_frame(T_wb)
            if t >= next_sample:
                next_sample += 0.1
                traj.append((t, pose[0], pose[1]))
                path.add(pose[0], pose[1])
                self._count_contacts(clearance=True)
                if world.goal_reached(pose[0], pose[1]):
                    reached = True
                    break
                if plant.base_tilt_deg() > self.rollover_deg:
                    rolled = True
                    break
            else:
                self._count_contacts(clearance=False)
            if t >= next_replan:
                next_replan += self.cfg.replan_period_s
                frame = self.camera.render(plant.data, T_wb, t, colour=spec.perception == "mono" or spec.keep_frames,
                                           depth=spec.perception == "depth", labels=spec.perception == "truth")
                ground = self.perceive(frame)
                T_gc = np.linalg.inv(T_world_ground(pose)) @ frame.T_world_camera
                r = self.planner.replan(t, ground, T_gc, pose, world.goal, world.goal_radius_m)
                replans.append(r)
                if spec.keep_frames:
                    frames.append(overlay(frame.rgb, ground, r.selection,
                                          PerceptionCollisionChecker(self.cfg.intrinsics, T_gc,
                                                                     self.planner.footprint_width_m)))
            if t >= spec.ramp_s:
                if t >= next_command:
                    next_command += spec.command_period_s
                    cmd = self.planner.command(t, pose)
                    kappa_goal, backwards = cmd.kappa_per_m, cmd.mode == BACK_OFF
                step = spec.kappa_slew_per_m_s * dt
                kappa += max(-step, min(step, kappa_goal - kappa))
            if ftl is not None and t >= spec.ramp_s:
                ftl.crawl(pose, kappa)
            if self.drive is not None:
                name = self.reverse_gait_name if backwards else self.gait_name
                if ftl is not None:
                    if t >= next_bias or self.drive.gait != name:
                        next_bias = t + spec.command_period_s
                        self.drive.command(name, bias_rad=ftl.biases())
                elif self.drive.kappa_per_m != kappa or self.drive.gait != name:
                    self.drive.command(name, kappa_per_m=kappa)
                self.drive.step(t, dt)
            elif t >= spec.ramp_s:
                g = reverse if backwards else gait
                yaw_kappas = None if ftl is None else ftl.joint_kappas()
                plant.set_joint_targets(g.joint_angles(self.robot, t - spec.ramp_s, kappa, yaw_kappas))
            else:
                plant.set_joint_targets(gait.joint_angles(self.robot, 0.0, 0.0) * (t / spec.ramp_s))
            t += dt
            plant.step_to(t)
        self.camera.close()
        clearance = self.collisions.min_clearance_m
        by_mode = collections.Counter(self._contact_modes)
        traj = np.array(traj)
        metrics = {"goal_reached": bool(reached), "time_s": round(float(t), 3),
                   "collisions": int(self.collisions.collisions),
                   "min_clearance_m": float(clearance) if math.isfinite(clearance) else None,
                   "path_length_m": round(path.length_m, 4), "replans": len(replans),
                   "stops_no_free_arc": sum(1 for r in replans if r.path_world is None),
                   "rolled_over": rolled, "robot": self.robot.name, "perception": spec.perception,
                   "seed": spec.seed, "world": world.source or world.name,
                   "flat_belly_fraction": self.flat_belly_fraction, "gait_source": spec.gait_source,
                   "gait": self.gait_name if self.drive is not None else "reference",
                   "steering": self.cfg.gaits.steering,
                   "nav_config": Path(self.nav_config).name,
                   "closest_to_goal_m": round(self._closest_to_goal(traj), 4),
                   "outcome": self._outcome(reached, rolled, replans, pose),
                   **{f"contacts_{m}": by_mode.get(m, 0) for m in MODES}}
        contacts = [(e, m) for e, m in zip(self.collisions.episodes, self._contact_modes)]
        omap = self.planner.obstacle_map
        return NavResult(metrics, traj, replans, frames, world, contacts,
                         None if omap is None else omap.geometry())

    def _count_contacts(self, clearance: bool) -> None:
        """New contact episodes, each tagged with what the follower was doing (FOLLOW,
        TURN_IN_PLACE, BACK_OFF, IDLE)."""
        new = self.collisions.update(self.plant.data, clearance=clearance)
        self._contact_modes += [self.planner.follower.mode] * new

    def _closest_to_goal(self, traj: np.ndarray) -> float:
        """How near base_link came to the goal's disc (0: reached), over the 10 Hz samples (t, x, y)."""
        w = self.spec.world
        if not len(traj):
            return math.nan
        xy = traj[:, 1:3]
        d = np.hypot(xy[:, 0] - w.goal[0], xy[:, 1] - w.goal[1]).min() - w.goal_radius_m
        return float(max(0.0, d))

    def _outcome(self, reached: bool, rolled: bool, replans, pose) -> str:
        """success | reached_with_contact | rolled_over | circling_goal (at the time limit the goal lies
        inside the tightest circle the follower drives, within its radius: the arcs circle it) |
        stopped (3 of the last 5 replans found no free arc) | time_limit."""
        if reached:
            return "success" if self.collisions.collisions == 0 else "reached_with_contact"
        if rolled:
            return "rolled_over"
        goal = self.spec.world.goal
        r = self.cfg.follower.min_radius_m
        x, y, th = pose
        dx, dy = goal[0] - x, goal[1] - y
        gx, gy = math.cos(th) * dx + math.sin(th) * dy, -math.sin(th) * dx + math.cos(th) * dy
        if math.hypot(gx, gy) < r and gx * gx + (abs(gy) - r) ** 2 < r * r:
            return "circling_goal"
        if sum(1 for rp in replans[-5:] if rp.path_world is None) >= 3:
            return "stopped"
        return "time_limit"
