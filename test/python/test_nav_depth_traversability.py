"""Traversability from depth (perception/depth_traversability.py) on rendered held-out scenes."""
import numpy as np
import pytest

from snake_autonomy.perception.depth_traversability import (DepthTraversability,
                                                            DepthTraversabilityParams, fit_ground_plane)
from snake_autonomy.perception.ground_region import precision_recall, traversable
from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera


def test_ransac_plane_fit_ignores_an_obstacle():
    rng = np.random.default_rng(1)
    floor = np.column_stack([rng.uniform(-1, 1, 400), rng.uniform(-1, 1, 400), np.full(400, 2.0)])
    wall = np.column_stack([rng.uniform(-1, 1, 200), np.full(200, 0.5), rng.uniform(0, 2, 200)])
    n, d, inliers = fit_ground_plane(np.vstack([floor, wall]), DepthTraversabilityParams(), rng)
    assert abs(n @ [0, 0, 1]) == pytest.approx(1.0, abs=1e-4)
    assert abs(d) == pytest.approx(2.0, abs=1e-3) and inliers >= 400


def test_depth_traversability_matches_the_segmentation_on_held_out_scenes(root):
    from snake_autonomy import _core
    from snake_autonomy.runs.render_set import render_scenes
    from snake_autonomy.sim.config import SimConfig
    cfg = NavConfig.from_yaml()
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    params = SimConfig.from_yaml(str(root / "config" / "sim.yaml")).draw(seed=0)
    frames = list(render_scenes(robot, params, 3, seed=7, intrinsics=cfg.intrinsics, mount=cfg.mount))
    dt = DepthTraversability(cfg.intrinsics, T_ground_camera(cfg.mount, robot.link_radius_m + 0.001),
                             cfg.depth)
    for f in frames:
        pred = dt(f.depth_m)
        truth = traversable(f.ground_truth_ground(), cfg.depth.block_px)
        prec, rec = precision_recall(pred, truth)
        assert dt.last_plane_fitted
        assert prec > 0.95 and rec > 0.95, (prec, rec)
        # an image of floor everywhere the depth says "nothing" (sky) is not ground
        assert not pred[f.depth_m == 0].any()
