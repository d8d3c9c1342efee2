"""The navigation experiment over random worlds: random solvable corridors, the closed
loop (runs/nav_batch.py) per world x seed x perception through the sweep runner (Dask by default),
success rate, collisions and time in a table.

    worlds = [random_corridor(k) for k in range(N)]
    tasks = experiment_tasks(worlds, seeds=range(5), perceptions=("depth", "mono"), robot="cobra")
    with open_executor("dask") as ex:
        rows = run_tasks(ex, run_nav_task, tasks)
    print(markdown_table(summarise(rows)))

The world families (sim/nav_worlds.py, each world a pure function of its index): random_corridor(k),
1-3 cylinders between the start and the goal, pairwise gaps >= 2 x the body width, one on the
straight line; barn_world(k), a BARN-like cluttered field with a path for the robot's footprint.
"""
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from snake_autonomy.planning.rectilinear.follower import MODES
from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
from snake_autonomy.sim.nav_worlds import min_gap_m, random_corridor  # noqa: F401 (their home before sim/nav_worlds.py)
from snake_autonomy.sim.world_file import World


TIME_FACTOR = 3.0


def time_limit_s(world: World, speed_m_s: float, factor: float = TIME_FACTOR) -> float:
    """The experiment's time limit for one world: `factor` times the time the
    robot needs, at its follower's speed (the gait map's), to crawl the straight line from its start
    to the goal's disc. The robots differ twice in speed (COBRA 6.35 mm/s, the 12-link 11.2 mm/s):
    a fixed 300 s gave COBRA 1.6 times its straight-line time and the 12-link 2.8 times, and most of
    COBRA's runs that ended at 300 s reached the goal by 420 s."""
    if not speed_m_s > 0 or not factor > 0:
        raise ValueError(f"time limit: speed_m_s and factor must be > 0, got {speed_m_s}, {factor}")
    straight = max(0.0, math.hypot(world.goal[0] - world.start[0], world.goal[1] - world.start[1])
                   - world.goal_radius_m)
    return round(factor * straight / speed_m_s, 1)


@dataclass(frozen=True)
class NavTask:
    world: dict                   # World.to_dict() (picklable, engine independent)
    robot: str = "cobra"
    perception: str = "depth"
    seed: int = 0
    time_limit_s: float = 300.0
    classifier: Optional[str] = None
    nav_config: Optional[str] = None
    pose_source: str = "mocap"     # NavRunSpec.pose_source
    depth_model: Optional[str] = None   # NavRunSpec.depth_model (None: config/sim.yaml's)
    out_dir: Optional[str] = None  # per-run figures and metrics (None: metrics only)


def experiment_tasks(worlds: Sequence[World], seeds: Sequence[int], perceptions: Sequence[str],
                     robot: str = "cobra", time_limits_s: Optional[Sequence[float]] = None, **kw) -> List[NavTask]:
    """Every world x seed x perception; time_limits_s: one per world (time_limit_s), else NavTask's."""
    limits = [{} for _ in worlds] if time_limits_s is None else [{"time_limit_s": t} for t in time_limits_s]
    if len(limits) != len(worlds):
        raise ValueError(f"time_limits_s: one per world expected ({len(worlds)}), got {len(limits)}")
    return [NavTask(w.to_dict(), robot, p, int(s), **lim, **kw)
            for w, lim in zip(worlds, limits) for s in seeds for p in perceptions]


def run_nav_task(task: NavTask) -> Dict:
    """One closed-loop run; its metrics (module-level: process-based engines import it)."""
    world = World.from_dict(task.world, task.world.get("name", "world"))
    t0 = time.perf_counter()
    spec = NavRunSpec(world, robot=task.robot, perception=task.perception, seed=task.seed,
                      time_limit_s=task.time_limit_s, classifier=task.classifier,
                      nav_config=task.nav_config, keep_frames=task.out_dir is not None,
                      pose_source=task.pose_source, depth_model=task.depth_model)
    result = NavRun(spec).run()
    if task.out_dir:
        result.write(Path(task.out_dir) / f"{world.name}_{task.perception}_s{task.seed}")
    return {**result.metrics, "world": world.name, "time_limit_s": task.time_limit_s,
            "wall_s": round(time.perf_counter() - t0, 1)}


def summarise(rows: List[Dict]) -> List[Dict]:
    """Per (robot, perception): runs, success rate, runs with a collision, collisions, rolled over,
    mean time of the successful runs."""
    out = []
    for key in sorted({(r["robot"], r["perception"]) for r in rows}):
        rs = [r for r in rows if (r["robot"], r["perception"]) == key]
        ok = [r for r in rs if r["goal_reached"] and r["collisions"] == 0]
        out.append({"robot": key[0], "perception": key[1], "runs": len(rs),
                    "worlds": len({r["world"] for r in rs}),
                    "success": len(ok) / len(rs),
                    "reached": sum(r["goal_reached"] for r in rs),
                    "runs_with_collision": sum(r["collisions"] > 0 for r in rs),
                    "collisions": sum(r["collisions"] for r in rs),
                    "rolled_over": sum(bool(r.get("rolled_over")) for r in rs),
                    "stops_no_free_arc": sum(r["stops_no_free_arc"] for r in rs),
                    "mean_time_s": float(np.mean([r["time_s"] for r in ok])) if ok else math.nan,
                    "outcomes": {o: sum(r.get("outcome") == o for r in rs) for o in OUTCOMES},
                    "median_miss_m": _median([r.get("closest_to_goal_m") for r in rs if not r["goal_reached"]]),
                    "contacts_by_mode": {m: sum(int(r.get(f"contacts_{m}", 0)) for r in rs) for m in MODES},
                    **_estimation(rs)})
    return out


def _estimation(rs: List[Dict]) -> Dict:
    """What the runs' pose source and depth were and how far the pose was from the truth: the mean of
    the runs' xy RMSE, the largest xy error, the total time tracking was lost (nav_pose_source)."""
    rmse = [r["pose_error_xy_rmse_m"] for r in rs if r.get("pose_error_xy_rmse_m") is not None]
    worst = [r["pose_error_xy_max_m"] for r in rs if r.get("pose_error_xy_max_m") is not None]
    return {"pose_sources": sorted({str(r.get("pose_source", "-")) for r in rs}),
            "depth_models": sorted({str(r.get("depth_model", "-")) for r in rs}),
            "pose_error_xy_rmse_m": float(np.mean(rmse)) if rmse else math.nan,
            "pose_error_xy_max_m": float(max(worst)) if worst else math.nan,
            "tracking_lost_s": float(sum(float(r.get("tracking_lost_s") or 0.0) for r in rs))}


def estimation_table(summary: List[Dict]) -> str:
    """Per (robot, perception): the pose source, the depth model, the pose error against the truth
    (mean of the runs' xy RMSE, the largest xy error) and the time tracking was lost over all runs."""
    lines = ["| robot | perception | pose source | depth | pose error xy, mean RMSE (m) | pose error xy, max (m) "
             "| tracking lost, total (s) |", "|---|---|---|---|---|---|---|"]
    for s in summary:
        fmt = ["-" if math.isnan(s[k]) else f"{s[k]:.3f}" for k in ("pose_error_xy_rmse_m", "pose_error_xy_max_m")]
        lines.append(f"| {s['robot']} | {s['perception']} | {', '.join(s['pose_sources'])} | "
                     f"{', '.join(s['depth_models'])} | {fmt[0]} | {fmt[1]} | {s['tracking_lost_s']:.1f} |")
    return "\n".join(lines)


def _median(values) -> float:
    v = [float(x) for x in values if x is not None and x == x]
    return float(np.median(v)) if v else math.nan


OUTCOMES = ("success", "reached_with_contact", "rolled_over", "circling_goal", "stopped", "time_limit")


def outcome_table(summary: List[Dict]) -> str:
    """How the runs ended (nav_batch.NavRun._outcome), how near the failed ones came to the goal,
    and, of the contact episodes, what the follower was doing when each began."""
    lines = ["| robot | perception | " + " | ".join(o.replace("_", " ") for o in OUTCOMES)
             + " | closest to the goal's disc, median of the not reached (m) | contacts: "
             + " | ".join(m.replace("_", " ") for m in MODES) + " |",
             "|---|---|" + "---|" * (len(OUTCOMES) + 1 + len(MODES))]
    for s in summary:
        miss = "-" if math.isnan(s["median_miss_m"]) else f"{s['median_miss_m']:.2f}"
        lines.append(f"| {s['robot']} | {s['perception']} | "
                     + " | ".join(str(s["outcomes"][o]) for o in OUTCOMES) + f" | {miss} | "
                     + " | ".join(str(s["contacts_by_mode"][m]) for m in MODES) + " |")
    return "\n".join(lines)


def markdown_table(summary: List[Dict]) -> str:
    lines = ["| robot | perception | worlds | runs | success (reached, 0 collisions) | reached | runs with "
             "a collision | collisions | rolled over | stops (no free arc) | mean time of successes (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in summary:
        t = "-" if math.isnan(s["mean_time_s"]) else f"{s['mean_time_s']:.0f}"
        lines.append(f"| {s['robot']} | {s['perception']} | {s['worlds']} | {s['runs']} | "
                     f"{100 * s['success']:.0f} % | {s['reached']} | {s['runs_with_collision']} | "
                     f"{s['collisions']} | {s['rolled_over']} | {s['stops_no_free_arc']} | {t} |")
    return "\n".join(lines)
