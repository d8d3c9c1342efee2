"""Where the whole body goes on an arc: the rectilinear body as a curve.

The rectilinear gait bends the body to one curvature kappa (the lateral joints' bias, the
`curvature` steering law) and moves it along its own tangent: at a constant kappa every point of
the body follows the same circle, the tail in the head's track. When kappa changes the body
reshapes about its middle (measured with bench/nav_body_sweep: the head swings
(L^2 / 8) dkappa = 0.28 m per 1/m to the inside on COBRA, L 1.51 m, and its heading turns by
(L / 2) dkappa = 0.75 rad per 1/m at once; that swing is what drove COBRA's head and tail into
obstacles beside a head-only arc). The planner's guards (planner.py: the swing guard, the crawl guard,
backing off, the turn in place) judge the body's sweep with this model: the middle's pose is
base_link's pose carried back half the body along the current curvature, and body_poses gives the
body's shapes from the current kappa to a new one. (Planning arcs of the middle with the whole body
checked, an option no shipped config set, was removed: the arcs are the head's, with the body's swept
width.)

Measured with the gait map (test/python/test_nav_body_model.py): on COBRA the first premise does
not hold at small curvatures. Below about 0.35-0.4 /m the body does not turn at all (omega 0.0002 rad/s at
0.35 /m against the line's 0.0032); it translates along its middle's tangent, kappa L/2 off the
head's heading, so the head and the body side-step instead of following the circle (the crawl
guard, planner._crawl_bounds, predicts that). And reshaping keeps the body's centroid, not its
middle: body_poses(keep_centroid=True), sampler.reshape_keeps_centroid (on for COBRA in
config/nav.yaml; the 12-link robot keeps the middle).
Poses are (x_m, y_m, theta_rad) on the floor; arc lengths s in metres along the arc.
"""
from dataclasses import dataclass
from typing import List, Tuple

import numpy as np

from .unicycle import arc_poses

RESHAPE_FRACTIONS = (1.0 / 3.0, 2.0 / 3.0, 1.0)     # the body's shapes checked from the current kappa to the new


@dataclass(frozen=True)
class BodyGeometry:
    half_length_m: float      # base_link (the head's front) to the middle of the body, along it
    width_m: float            # the body's width (the links' diameter)

    @classmethod
    def of_robot(cls, robot) -> "BodyGeometry":
        """From a RobotModel: head + links, the body's middle at half their length."""
        length = float(robot.head_length_m) + robot.num_joints * float(robot.link_length_m)
        return cls(0.5 * length, 2.0 * float(robot.link_radius_m))


def middle_pose(head_pose, kappa_per_m: float, half_length_m: float) -> Tuple[float, float, float]:
    """The middle's pose from base_link's: back along the body's current curvature."""
    if half_length_m <= 0:
        return tuple(float(v) for v in head_pose)
    p = arc_poses(kappa_per_m, -half_length_m, half_length_m, start=head_pose)[-1]
    return float(p[0]), float(p[1]), float(p[2])


def body_poses(middle, kappa_now: float, curvature_per_m: float, half_length_m: float,
               spacing_m: float, keep_centroid: bool = False) -> List[np.ndarray]:
    """The body (tail to head, poses along it) in each shape from the current kappa to the new
    curvature (RESHAPE_FRACTIONS), all about the middle: what reshaping sweeps. keep_centroid (round
    20, sampler.reshape_keeps_centroid): each shape is moved so that the body's centroid stays where
    the current shape's is (the middle's heading kept), as measured on COBRA: bending from straight to
    0.5 / 1 /m moved the centroid 0.009 / 0.029 m, the frames at the middle 0.04 / 0.075 m to the
    outside, the head 0.077 / 0.172 m and the tail 0.104 / 0.197 m to the inside (the middle-fixed
    model: 0, and 0.143 / 0.285 m at both ends; the centroid-fixed one: 0.048 / 0.095 m and 0.095 /
    0.19 m). A uniform arc's centroid lies (1 - sin(u) / u) / kappa towards its centre from the
    middle, u = kappa L/2: kappa L^2/24 for small u."""
    def shape(k):
        tail = arc_poses(k, -half_length_m, spacing_m, start=middle)[::-1]
        head = arc_poses(k, half_length_m, spacing_m, start=middle)[1:]
        return np.vstack([tail, head])

    anchor = shape(kappa_now)[:, :2].mean(axis=0) if keep_centroid else None
    out = []
    for f in RESHAPE_FRACTIONS:
        poses = shape(kappa_now + f * (curvature_per_m - kappa_now))
        if keep_centroid:
            poses[:, :2] += anchor - poses[:, :2].mean(axis=0)
        out.append(poses)
    return out
