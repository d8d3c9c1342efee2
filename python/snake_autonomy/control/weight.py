"""The proximity blend weight of thesis eq. 3.33 (section 3.7, figure 3.4).

w = 1 at the waypoint (the absolute yaw error, alignment with the waypoint heading, counts fully),
0.5 between 0.5 m and 1.0 m, 0 beyond 1.5 m (the relative yaw error, pointing at the waypoint, counts
fully), with smoothstep ramps in between: C1-continuous everywhere.
"""

#: Breakpoints of eq. 3.33, metres.
NEAR_M = 0.5
MID_M = 1.0
FAR_M = 1.5


def smoothstep(t: float) -> float:
    """S(t) = 3 t^2 - 2 t^3 on [0, 1] (t is clipped to that interval)."""
    t = min(1.0, max(0.0, t))
    return t * t * (3.0 - 2.0 * t)


def blend_weight(distance_m: float) -> float:
    """w(d) of eq. 3.33: the weight of the absolute yaw error at distance d from the waypoint."""
    d = distance_m
    if d <= 0.0:
        return 1.0
    if d <= NEAR_M:
        return 1.0 - 0.5 * smoothstep(d / NEAR_M)
    if d <= MID_M:
        return 0.5
    if d <= FAR_M:
        return 0.5 - 0.5 * smoothstep((d - MID_M) / (FAR_M - MID_M))
    return 0.0


def combined_yaw_error(yaw_error_abs_rad: float, yaw_error_rel_rad: float, w: float) -> float:
    """Algorithm 1 line 8: psi_e = w * abs + (1 - w) * rel."""
    return w * yaw_error_abs_rad + (1.0 - w) * yaw_error_rel_rad
