"""The plan's figures (matplotlib, Agg): the ZMP path of every stage in its support polygon U and
the next one U' (paper fig. 7: ZMP red, U' orange), and the head height over time."""
import numpy as np

from .plan_io import stage_samples
from .planner import Plan
from .support import convex_hull, polygon_coords


def _closed(coords):
    c = np.asarray(coords + coords[:1], float)
    return c[:, 0], c[:, 1]


def write_figures(plan: Plan, out_dir, period_s: float = 0.05, pipe=None) -> list:
    import matplotlib  # lazy: matplotlib is heavy and only this path needs it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    chain = plan.chain
    samples = stage_samples(plan, period_s)
    poses = [chain.pose(q) for _, _, q in samples]
    zmp = np.array([p.zmp for p in poses])
    head = np.array([p.head[2] for p in poses])
    times = np.array([t for _, t, _ in samples])
    stage_of = np.array([k for k, _, _ in samples])
    paths = []

    n = len(plan.stages)
    cols = min(4, n)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.4 * rows), squeeze=False)
    for k, stage in enumerate(plan.stages):
        ax = axes[k // cols][k % cols]
        m = stage.active_modules
        u = polygon_coords(convex_hull(chain.base_contacts(m)))
        nxt = next((s.active_modules for s in plan.stages[k + 1:] if s.active_modules != m), None)
        if u:
            ax.plot(*_closed(u), color="0.3", label=f"U ({chain.num_modules - m} base modules)")
        if nxt is not None:
            u2 = polygon_coords(convex_hull(chain.base_contacts(nxt)))
            if u2:
                ax.plot(*_closed(u2), color="orange", label="U' (next)")
        lying = poses[np.flatnonzero(stage_of == k)[-1]].positions
        ax.plot(lying[:, 0], lying[:, 1], color="0.75", lw=3, zorder=0, label="robot at the end")
        sel = stage_of == k
        ax.plot(zmp[sel, 0], zmp[sel, 1], color="red", lw=1.5, label="ZMP")
        ax.plot(*zmp[sel][-1], "o", color="red", ms=3)
        if pipe is not None:
            ax.add_patch(plt.Circle((pipe.x_m, pipe.y_m), pipe.radius_m, fill=False, color="blue"))
        ax.set_title(f"{k + 1}: {stage.kind}, {m} active, K1 = {stage.k1:.2f}", fontsize=9)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        if k == 0:
            ax.legend(fontsize=6, loc="best")
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.suptitle(f"{plan.robot_name}: ZMP in the support polygons per stage (x, y in m)")
    paths.append(_save(fig, f"{out_dir}/zmp_stages.png"))

    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(times, head, color="C0")
    t0 = 0.0
    for stage in plan.stages:
        ax.axvline(t0, color="0.85", lw=0.8)
        ax.text(t0 + 0.05, head.max() * 1.02, str(stage.active_modules), fontsize=7, color="0.4")
        t0 += stage.t_end_s
    ax.set_xlabel("t (s)")
    ax.set_ylabel("head height (m)")
    ax.set_title(f"{plan.robot_name}: head height (stage boundaries, active modules)")
    paths.append(_save(fig, f"{out_dir}/head_height.png"))
    return paths


def _save(fig, path: str) -> str:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    import matplotlib.pyplot as plt  # lazy: matplotlib is heavy and only this path needs it
    plt.close(fig)
    return path
