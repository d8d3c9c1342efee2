"""plan.json, the issue's contract:

    {"robot": str, "joint_names": [...], "masses_kg": [...],
     "samples": [{"t_s": float, "positions_rad": [...], "frames_world_m": [[x, y, z], ...],
                  "active_modules": int, "zmp_m": [x, y], "support_polygon_m": [[x, y], ...]}, ...],
     "final_head_height_m": float, "restarts": int, "planning_time_s": float}

Samples at most 50 ms apart (the stages' sample grids, concatenated); frames in the kinematics
binding's order (base_link, head_link, link_1 ... link_N) with the robot YAML's masses; zmp_m is the
CoG with each module's mass at its centre, as in the MJCF (chain.module_frame_weights); support_polygon_m is U,
the hull of the contacts of the base at that sample (not shrunk by the planner's margin).
"""
import json

import numpy as np

from .planner import Plan
from .stage import sample_times
from .support import Support, convex_hull, polygon_coords

MAX_SAMPLE_GAP_S = 0.05
TOP_KEYS = {"robot", "joint_names", "masses_kg", "samples", "final_head_height_m", "restarts",
            "planning_time_s"}
SAMPLE_KEYS = {"t_s", "positions_rad", "frames_world_m", "active_modules", "zmp_m",
               "support_polygon_m"}


def stage_samples(plan: Plan, period_s: float):
    """[(stage index, time in the plan, joint angles)] on every stage's grid, concatenated."""
    out, t0 = [], 0.0
    for k, stage in enumerate(plan.stages):
        times = sample_times(stage.t_end_s, period_s)
        q = stage.joints(times)
        for i, t in enumerate(times):
            if k > 0 and i == 0:
                continue           # the previous stage's last sample
            out.append((k, t0 + float(t), q[i]))
        t0 += stage.t_end_s
    return out


def to_dict(plan: Plan, period_s: float = MAX_SAMPLE_GAP_S) -> dict:
    chain = plan.chain
    polygons = {}
    samples = []
    for k, t, q in stage_samples(plan, period_s):
        m = plan.stages[k].active_modules
        if m not in polygons:
            polygons[m] = polygon_coords(convex_hull(chain.base_contacts(m)))
        pose = chain.pose(q)
        samples.append({
            "t_s": round(t, 9),
            "positions_rad": [float(v) for v in q],
            "frames_world_m": pose.positions.tolist(),
            "active_modules": int(m),
            "zmp_m": [float(v) for v in pose.zmp],
            "support_polygon_m": polygons[m],
        })
    return {
        "robot": plan.robot_name,
        "joint_names": list(chain.joint_names),
        "masses_kg": [float(m) for m in chain.masses],
        "samples": samples,
        "final_head_height_m": plan.final_head_height_m,
        "restarts": int(plan.restarts),
        "planning_time_s": float(plan.planning_time_s),
    }


def write(plan: Plan, path, period_s: float = MAX_SAMPLE_GAP_S) -> dict:
    doc = to_dict(plan, period_s)
    with open(path, "w") as f:
        json.dump(doc, f)
    return doc


def problems(doc: dict, num_joints: int = None, num_frames: int = None) -> list:
    """What in `doc` breaks the contract (empty when it holds), the ZMP inside U included."""
    out = []
    if set(doc) != TOP_KEYS:
        out.append(f"top-level keys {sorted(doc)} != {sorted(TOP_KEYS)}")
        return out
    n = num_joints if num_joints is not None else len(doc["joint_names"])
    n_f = num_frames if num_frames is not None else len(doc["masses_kg"])
    if len(doc["joint_names"]) != n:
        out.append(f"joint_names: {len(doc['joint_names'])} names, expected {n}")
    if len(doc["masses_kg"]) != n_f:
        out.append(f"masses_kg: {len(doc['masses_kg'])} masses, expected {n_f}")
    if not isinstance(doc["restarts"], int) or isinstance(doc["restarts"], bool):
        out.append(f"restarts: expected an int, got {doc['restarts']!r}")
    samples = doc["samples"]
    if not samples:
        return out + ["samples: empty"]
    times = np.array([s.get("t_s", np.nan) for s in samples], float)
    if np.any(np.diff(times) <= 0) or np.any(np.diff(times) > MAX_SAMPLE_GAP_S + 1e-9):
        out.append(f"samples: gaps between {np.diff(times).min():.4f} and "
                   f"{np.diff(times).max():.4f} s (must be in (0, {MAX_SAMPLE_GAP_S}])")
    for i, s in enumerate(samples):
        if set(s) != SAMPLE_KEYS:
            out.append(f"samples[{i}]: keys {sorted(s)} != {sorted(SAMPLE_KEYS)}")
            break
        if len(s["positions_rad"]) != n or np.shape(s["frames_world_m"]) != (n_f, 3):
            out.append(f"samples[{i}]: {len(s['positions_rad'])} positions, frames "
                       f"{np.shape(s['frames_world_m'])}, expected {n} and ({n_f}, 3)")
            break
        polygon = Support.of(s["support_polygon_m"])
        if not polygon.contains_point(s["zmp_m"]):
            out.append(f"samples[{i}] (t = {s['t_s']} s): ZMP {s['zmp_m']} outside the support polygon")
            break
    head = samples[-1]["frames_world_m"][0][2]
    if abs(head - doc["final_head_height_m"]) > 1e-6:
        out.append(f"final_head_height_m {doc['final_head_height_m']} != the last sample's head {head}")
    return out
