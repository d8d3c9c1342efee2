"""A mission on the simulated robot in lock-step, without ROS, faster than real time.

    run = BatchRun(RunSpec(mission="star", seed=3, feedback="vio"))
    result = run.run(progress=True)
    metrics = result.write("results/sim/star_s3")        # metrics.json, CSVs, the thesis's figures

Every 10 ms of simulated time (the driver's 100 Hz):

    world.step_to(t) (sim.world: plant, sensors, disturbances, monitor) -> pose source (mocap 100 Hz |
    simulated RTAB-Map 30 Hz -> gate -> eq. 3.1) -> DriverController.set_base_pose
    -> servo states (MujocoServoBackend: ticks, velocity, current) into a FakeServoBus
    -> DriverController.update (the C++ driver's cycle: gait command, CPG + steering, stale-pose
       gating, slew limit, joint limits, faults, kinematics) -> goal ticks from the bus -> plant
    -> com_pose (fresh base pose only) -> MissionRunner.on_pose

and at the tracker's rate (config/tracker.yaml rate_hz, 1 Hz) MissionRunner.step -> gait command.
The classes are the ROS path's: the mission node wraps MissionRunner, pose_remap_node the gate and
remapper, driver_node the same DriverController (here through _core, over an in-process bus
instead of the mocked one on a pty); the world (plant, sensors, disturbances, roll-over and limit
monitor, ground truth) is the one sim_node steps (sim.realtime). Only the clock (simulated time in
lock-step) and the transport (an in-process bus) differ.

Configuration of the simulated robot: config/sim.yaml (physics, sensors, and its `tracker:`
section merged over config/tracker.yaml). The start pose is the tracker's view: the centre of mass
of a straight body at (x, y), heading (direction of travel) in degrees. A roll-over (SimWorld's
monitor) ends the run.

A mission with navigate_to legs (missions/nav_leg.py) is refused: the obstacle-aware planner drives
those through its move_base action, on the ROS path only; the batch run has no second navigation loop.
"""
import json
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from tqdm import tqdm

from snake_autonomy import _core
from snake_autonomy.control.angles import wrap
from snake_autonomy.evaluation import EvaluationOptions, evaluate, trajectory_from_arrays, write_outputs
from snake_autonomy.missions import MissionError
from snake_autonomy.missions.runner import MissionRunner
from snake_autonomy.missions.scout import fbsr_scout_planner
from snake_autonomy.runs.results import write_json_atomic, write_results
from snake_autonomy.runs.scout_executor import DriverTrajectoryExecutor
from snake_autonomy.sim.config import servo_torque_limit_nm
from snake_autonomy.sim.feedback import make_feedback
from snake_autonomy.sim.mujoco_servo_backend import MujocoServoBackend
from snake_autonomy.sim.plant import Plant
from snake_autonomy.sim.servo_backend import ShaftUnits
from snake_autonomy.sim.scene import vo_room
from snake_autonomy.sim.world import CONFIG, FEEDBACK_SENSORS, SimWorld, WorldSpec

DRIVER_RATE_HZ = 100.0
TRAJECTORY_RATE_HZ = 10.0
SCOUT_PLAN_TIMEOUT_S = 600.0     # wall time a scout plan may take in a batch run
NAV_LEG_REFUSAL = "navigate_to legs need the planner: run through ROS (sim.launch world:=...)"
DEG = 180.0 / math.pi


@dataclass
class RunSpec(WorldSpec):
    """The world (sim.world.WorldSpec: seed, feedback, start, sim_config, robot, tracker_config,
    randomize, scene_xml) plus the mission and the run's own settings."""
    mission: str = "single_waypoint"          # a file or a provided mission's name
    time_limit_s: Optional[float] = None      # None: the mission's
    gaits: str = str(CONFIG / "gaits.yaml")
    driver_config: str = str(CONFIG / "driver.yaml")   # the DriverController's keys of driver_node's file
    settle_s: float = 0.5                     # pose source running before the mission starts
    label: str = ""                           # free text for tables
    scout_config: Optional[str] = None        # the FBSR planner's (None: config/scout.yaml)

    def __post_init__(self):
        if self.sensors is None:              # the pose source's sensors only
            self.sensors = FEEDBACK_SENSORS.get(self.feedback, (self.feedback,))


@dataclass
class RunResult:
    spec: RunSpec
    waypoints: List[Tuple[float, float, float]]
    trajectory: Dict[str, np.ndarray]
    decisions: Dict[str, list]
    outcome: str
    meta: Dict[str, Any]
    extra: Dict[str, Any]
    tracker: Dict[str, float]
    vio_samples: list = field(default_factory=list)

    def write(self, out_dir, plots: bool = True, evaluate_vio: bool = True) -> Dict[str, Any]:
        """The results folder (experiments.write_results) plus, after a vio or vo run, the evaluation of
        the camera odometry against the plant's camera pose in out_dir/evaluation. Returns the metrics."""

        out = Path(out_dir)
        p = self.tracker
        write_results(out, self.waypoints, self.trajectory, self.decisions, self.outcome, self.meta,
                      plots=plots, d_th=p["d_th"], psi_wp=p["psi_wp"], psi_turn=p["psi_turn"],
                      title=f"{self.meta['mission']} seed {self.spec.seed} {self.spec.feedback}")
        metrics = json.loads((out / "metrics.json").read_text())
        metrics.update(self.extra)
        if evaluate_vio and self.vio_samples:
            try:
                vo = self.spec.feedback == "vo"      # vo starts at the truth: no alignment (as its replays)
                metrics["vio_evaluation"] = evaluate_vio_samples(
                    self.vio_samples, out / "evaluation", plots=plots,
                    name="visual-inertial odometry" if vo else "simulated RTAB-Map", align="none" if vo else "yaw")
            except Exception as exc:  # noqa: BLE001 - the run's own results must not be lost
                metrics["vio_evaluation"] = {"error": f"{type(exc).__name__}: {exc}"}
        write_json_atomic(out / "metrics.json", metrics)
        return metrics


def evaluate_vio_samples(samples, out_dir, plots: bool = True, name: str = "simulated RTAB-Map",
                         align: str = "yaw") -> Dict[str, Any]:
    """The camera odometry (lost samples flagged) against the plant's camera pose
    (snake_autonomy.evaluation, `align` as evo's): APE and RPE over about 1 s (in frames) of the
    translation, the tracking-loss intervals and their total; APE's figures and stats.json into out_dir."""
    t = np.array([s[0] for s in samples])
    est = trajectory_from_arrays(t, np.array([s[1] for s in samples]), np.array([s[2] for s in samples]),
                                 name=name, lost=np.array([s[3] for s in samples]))
    ref = trajectory_from_arrays(t, np.array([s[4] for s in samples]), np.array([s[5] for s in samples]),
                                 name="ground truth (plant)")
    result = evaluate(ref, est, EvaluationOptions(align=align, t_max_diff_s=0.005))
    write_outputs(result, out_dir, plots=plots, report=plots)
    frames_1s = max(1, int(round(1.0 / float(np.median(np.diff(t)))))) if len(t) > 1 else 1
    rpe = evaluate(ref, est, EvaluationOptions(metric="rpe", align=align, t_max_diff_s=0.005, delta=frames_1s))
    return {"ape_translation_m": {k: float(v) for k, v in result.stats.items()},
            "rpe_translation_m": {k: float(v) for k, v in rpe.stats.items()}, "rpe_delta_frames": frames_1s,
            "alignment": align, "loss_intervals": len(result.loss_intervals),
            "lost_s": float(sum(i.duration_s for i in result.loss_intervals)),
            "loss_interval_list": [i.to_dict() for i in result.loss_intervals], "folder": str(Path(out_dir))}


def load_driver_config(path: str):
    """_core.DriverConfig from driver_node's YAML (config/driver.yaml) by the C++ loader
    (DriverConfig::from_yaml): the controller's keys, the node's own (port, rates, frames) ignored;
    ValueError lists every problem."""
    return _core.DriverConfig.from_yaml(str(path))


class LockStepDriver:
    """The C++ DriverController (_core, the one driver_node runs) on the plant, in lock-step.

    Every update: each servo's shaft state (MujocoServoBackend: direction, zero offset, current)
    -> present position / velocity / current of a FakeServoBus (the core's unit conversions) ->
    controller.update -> the goal ticks the controller wrote -> the plant's joint targets (the
    backend again). Nothing of the controller is repeated here."""

    def __init__(self, robot, library, plant: Plant, config, control_table: Optional[str] = None):
        dx = _core.dynamixel
        self.table = dx.ControlTable.from_yaml(control_table or str(CONFIG / "dynamixel" / f"{robot.servo_model}.yaml"))
        self.ids = [int(i) for i in robot.servo_ids]
        self.backend = MujocoServoBackend(plant, table=self.table)
        self.bus = dx.FakeServoBus(self.table, self.ids)
        self.units = ShaftUnits(self.table)   # shaft state <-> raw values, by this servo model's table
        self.bus.set_follow_goal(False)
        self.controller = _core.DriverController(robot, library, self.table, self.bus, config)
        self.lower_rad = np.asarray(robot.joint_lower_rad, float)
        self.upper_rad = np.asarray(robot.joint_upper_rad, float)
        self.cpg_clamped = 0              # CPG outputs beyond a joint limit (the goal was clamped)
        self._write_states()
        self.controller.start(plant.time_s)
        if self.controller.state != "holding":
            raise RuntimeError(f"the driver did not start: {self.controller.state} {self.controller.fault_reason}")

    def command_gait(self, gait: str, steer: bool = False, delta_rad: float = 0.0, curve: bool = False,
                     kappa_per_m: float = 0.0, bias=()) -> str:
        """bias: one per joint (rad), replacing the gait's; empty: the gait's."""
        return self.controller.command_gait(gait=gait, bias=[float(b) for b in bias], steer=steer,
                                            delta_rad=delta_rad, curve=curve, kappa_per_m=kappa_per_m)

    def set_base_pose(self, t_s: float, position, quat_xyzw) -> bool:
        return self.controller.set_base_pose(t_s, position, quat_xyzw)

    def update(self, t_s: float, dt_s: float) -> None:
        c = self.controller
        self._write_states()
        c.update(t_s, dt_s)
        if c.state == "fault":
            raise RuntimeError(f"the driver faulted: {c.fault_reason}")
        if c.state == "running":
            raw = c.cpg.unclamped_output
            self.cpg_clamped += int(np.count_nonzero((raw < self.lower_rad) | (raw > self.upper_rad)))
        get, set_goal, goal_rad = self.bus.servos.get, self.backend.set_goal, self.units.goal_rad
        for sid in self.ids:
            set_goal(sid, goal_rad(get(sid, "goal_position")))

    def com_pose(self) -> Optional[Tuple[float, float, float]]:
        """(x, y, yaw) of the centre of mass and virtual chassis, as com_pose carries it; None while
        the base pose is stale (the driver publishes com_pose only from a fresh one)."""
        c = self.controller
        if not c.pose_fresh:
            return None
        com = c.com
        return float(com[0]), float(com[1]), c.com_yaw

    def _write_states(self) -> None:
        put, state, present = self.bus.servos.set_present, self.backend.state, self.units.present
        for sid in self.ids:
            put(sid, *present(state(sid)))


def refuse_navigation_legs(mission) -> None:
    """MissionError naming every navigate_to leg of the mission, when it has any."""
    if mission.legs:
        raise MissionError(mission.source, [f"{leg.describe(i)}: {NAV_LEG_REFUSAL}"
                                            for i, leg in sorted(mission.legs.items())])


class BatchRun:
    def __init__(self, spec: RunSpec, robot=None, library=None):
        if spec.feedback == "vo" and not spec.scene_xml:
            # the odometry needs texture wherever the head turns: the odometry room (sim/scene.vo_room)
            # around the start, as bench/vo_replay_record records in
            room = vo_room(tuple(spec.start[:2]))
            spec = replace(spec, scene_xml=room.scene_xml, assets_xml=room.assets_xml)
        self.spec = spec
        self.robot = robot or _core.RobotModel.from_yaml(spec.robot)
        self.library = library or _core.GaitLibrary.from_yaml(spec.gaits)
        self.world = SimWorld(spec, robot=self.robot, gait_names=self.library.names)
        w = self.world
        self.sim_config, self.defaults, self.mission, self.params = w.config, w.defaults, w.mission, w.params
        self.heading_offset_rad, self.plant = w.heading_offset_rad, w.plant
        refuse_navigation_legs(self.mission)
        self.driver = LockStepDriver(self.robot, self.library, self.plant, load_driver_config(spec.driver_config))
        self.feedback = make_feedback(spec.feedback, self.params, self.robot, world=self.world)
        self.scout_executor, scout_planner = None, None
        if self.mission.scouts:     # scout stops: the FBSR planner, trajectories through the driver
            scout_planner = fbsr_scout_planner(spec.robot, spec.scout_config, spec.driver_config,
                                               torque_limit_nm=servo_torque_limit_nm())
            self.scout_executor = DriverTrajectoryExecutor(self.driver.controller)
        self.runner = MissionRunner(self.mission, self.defaults["pose_timeout_s"], self.defaults["yaw_filter_window"],
                                    heading_offset_rad=self.heading_offset_rad, scout_planner=scout_planner,
                                    executor=self.scout_executor)
        self.time_limit_s = spec.time_limit_s if spec.time_limit_s is not None else self.mission.time_limit_s
        if self.time_limit_s is not None:
            self.runner.mission.time_limit_s = float(self.time_limit_s)

    # ---- the run ---------------------------------------------------------------------------------
    def run(self, progress: bool = False) -> RunResult:
        spec, world, driver, runner, fb = self.spec, self.world, self.driver, self.runner, self.feedback
        dt = 1.0 / DRIVER_RATE_HZ
        tick_every = max(1, int(round(DRIVER_RATE_HZ / self.defaults["rate_hz"])))
        traj_every = max(1, int(round(DRIVER_RATE_HZ / TRAJECTORY_RATE_HZ)))
        k_start = int(round(spec.settle_s * DRIVER_RATE_HZ))
        t_start = k_start * dt
        limit = self.time_limit_s if self.time_limit_s is not None else 3600.0
        k_last = k_start + int(math.ceil((limit + 1.5) * DRIVER_RATE_HZ))
        traj = {k: [] for k in ("t", "x", "y", "yaw", "x_true", "y_true", "yaw_true", "tilt_deg")}
        dec: Dict[str, list] = {k: [] for k in (
            "t", "waypoint_index", "target_index", "reached", "distance", "yaw_error_abs", "yaw_error_rel",
            "yaw_error", "mode", "delta", "w", "gait", "pose_stale", "true_distance", "true_yaw_error_abs")}
        source_ok = None
        wall0 = time.perf_counter()
        bar = _progress_bar(progress, limit, f"{self.mission.name} seed {spec.seed} {spec.feedback}")
        last_com = None
        outcome = ""
        world.start_mission(t_start)
        for k in range(1, k_last + 1):
            t = k * dt
            out = world.step_to(t)
            pose = fb.pose(out)
            if pose is not None:
                driver.set_base_pose(t, pose[1], pose[2])
            ok, detail = fb.status(t)
            if ok != source_ok:
                runner.set_source_status(ok, detail)
                source_ok = ok
            driver.update(t, dt)
            if self.scout_executor is not None:
                self._scout_step(t)
            com = driver.com_pose()
            if com is not None:
                runner.on_pose(t, *com)
                last_com = com
            if k % traj_every == 0:
                xt, yt, ht = world.true_com_pose()
                x, y, h = last_com if last_com is not None else (math.nan,) * 3
                for key, v in zip(traj, (t, x, y, wrap(h + self.heading_offset_rad) if last_com else math.nan,
                                         xt, yt, ht, out.tilt_deg)):
                    traj[key].append(v)
            if k == k_start:
                runner.start(t)
            if world.rolled_over:
                runner.abort(f"rolled over: base_link tilted {out.tilt_deg:.0f} deg "
                             f"(limit {world.rollover_tilt_deg:g} deg)")
                self._record(dec, runner.final_decision(t))
                outcome = runner.outcome
                break
            if k >= k_start and (k - k_start) % tick_every == 0:
                if runner.scout is not None and runner.scout.phase == "planning":
                    # lock-step: planning takes no simulated time (its wall time is in the record)
                    runner.scout.wait_planned(SCOUT_PLAN_TIMEOUT_S)
                decision = runner.step(t)
                if decision is None:
                    break
                if decision.trajectory_active:      # a scout trajectory owns the joints
                    self._record(dec, decision)
                    if decision.finished:           # aborted with the head up: it stays held
                        outcome = runner.outcome
                        break
                    continue
                if self.scout_executor is not None and self.scout_executor.active:
                    self.scout_executor.release()
                why = driver.command_gait(decision.gait, decision.steer, decision.delta_rad)
                if why:
                    raise RuntimeError(f"the driver refused the mission's command: {why}")
                self._record(dec, decision)
                world.set_target(runner.tracker.waypoint_index)
                if bar is not None:
                    bar.update(tick_every * dt)
                    bar.set_postfix_str(f"wp {min(world.target_index + 1, len(self.mission.waypoints))}/"
                                        f"{len(self.mission.waypoints)}", refresh=False)
                if decision.finished:
                    outcome = runner.outcome
                    break
        else:
            runner.abort("simulation ended")
            outcome = runner.outcome
        if bar is not None:
            bar.close()
        wall = time.perf_counter() - wall0
        runner.close()
        if spec.feedback == "vo":
            fb.close()
        return self._result(traj, dec, outcome or runner.outcome, t_start, wall)

    def _scout_step(self, t: float) -> None:
        """While a scout trajectory is out, the roll-over check watches the tail; the head's height
        while held raised."""
        self.world.watch_tail(self.scout_executor.active)
        stop = self.runner.scout
        if stop is not None and stop.phase == "holding":
            head_z = float(self.plant.frame_positions()[0, 2])
            rec = stop.record
            rec.measured_head_height_m = head_z if math.isnan(rec.measured_head_height_m) \
                else min(rec.measured_head_height_m, head_z)

    def _record(self, dec, decision) -> None:
        s = decision.status
        cmd = decision.command
        target = cmd.target_index if cmd is not None else min(s["waypoint_index"], len(self.mission.waypoints) - 1)
        xt, yt, ht = self.world.true_com_pose()
        wx, wy, wh = self.mission.waypoints[target]
        for key, v in (("t", decision.t_s), ("waypoint_index", s["waypoint_index"]), ("target_index", target),
                       ("reached", bool(s["waypoint_reached"])), ("distance", s["distance"]),
                       ("yaw_error_abs", s["yaw_error_abs"]), ("yaw_error_rel", s["yaw_error_rel"]),
                       ("yaw_error", s["yaw_error"]), ("mode", s["mode"]), ("delta", s["delta"]), ("w", s["w"]),
                       ("gait", s["gait"]), ("pose_stale", bool(s["pose_stale"])),
                       ("true_distance", math.hypot(wx - xt, wy - yt)), ("true_yaw_error_abs", wrap(wh - ht))):
            dec[key].append(v)

    def _result(self, traj, dec, outcome, t_start, wall) -> RunResult:
        spec, world = self.spec, self.world
        reached_t = {}
        for t, idx, r in zip(dec["t"], dec["target_index"], dec["reached"]):
            if r and idx not in reached_t:
                reached_t[idx] = t
        disturbances = []
        for f in world.fired:
            before, after = f.com_before, f.com_after
            t_reach = reached_t.get(f.target_index)
            entry = {"description": f.description, "t_s": f.mission_t_s, "target_index": f.target_index,
                     "recovered": t_reach is not None and not world.rolled_over,
                     "time_to_recover_s": (t_reach - t_start - f.mission_t_s) if t_reach is not None else None}
            if after is not None:
                entry["com_displacement_2s_m"] = math.hypot(after[0] - before[0], after[1] - before[1])
                entry["heading_change_2s_deg"] = wrap(after[2] - before[2]) * DEG
            disturbances.append(entry)
        sim_time = self.plant.time_s
        extra = {
            "rolled_over": bool(world.rolled_over), "max_tilt_deg": float(world.max_tilt_deg),
            "limit_violations": world.limit_violations, "cpg_outputs_clamped": int(self.driver.cpg_clamped),
            "sim_time_s": sim_time, "mission_time_s": sim_time - t_start, "wall_time_s": wall,
            "real_time_factor": sim_time / wall if wall > 0 else None,
            "disturbances": disturbances,
            "scouts": [r.as_dict() for r in self.runner.scout_log],
            "recovered_all": all(d["recovered"] for d in disturbances),
            "seed": spec.seed, "feedback": spec.feedback, "start": list(spec.start),
        }
        if spec.feedback == "vio":
            samples = self.feedback.samples
            extra["vio"] = {"samples": len(samples), "lost_samples": int(sum(s[3] for s in samples)),
                            "gate_rejected": int(self.feedback.gate.rejected)}
        if spec.feedback == "vo":
            extra["vo"] = self.feedback.summary()
        tracker = self.mission.tracker_params
        meta = {"mission": self.mission.name, "mission_source": self.mission.source, "t_start": t_start,
                "seed": spec.seed, "feedback": spec.feedback, "start": list(spec.start),
                "time_limit_s": self.time_limit_s, "label": spec.label,
                "tracker": {k: (v * DEG if k in ("psi_wp", "psi_turn", "delta0", "delta_lim", "delta_turn",
                                                 "far_blend_max_gap") else v)
                            for k, v in tracker.items()},
                "tracker_config": self.defaults.get("source", ""), "rate_hz": self.defaults["rate_hz"],
                "heading_offset_deg": self.defaults["heading_offset_deg"], "gaits": self.mission.gaits,
                "sim_params": self.params.summary(), "sim_config": spec.sim_config,
                "disturbance_triggers": [t.describe() for t in self.world.triggers]}
        return RunResult(spec, list(self.mission.waypoints), {k: np.asarray(v) for k, v in traj.items()}, dec,
                         outcome, meta, extra, tracker,
                         vio_samples=list(self.feedback.samples) if spec.feedback in ("vio", "vo") else [])


def _progress_bar(enabled: bool, total_s: float, desc: str):
    if not enabled:
        return None
    return tqdm(total=round(total_s), desc=desc, unit="sim s", leave=False, dynamic_ncols=True,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.0f}/{total:.0f} sim s "
                           "[{elapsed}, {rate_fmt}{postfix}]")
