"""snake_autonomy.control: the 1 Hz waypoint tracker (thesis Algorithm 1), ROS-free.

- :class:`WaypointTracker` / :class:`TrackerParams` / :class:`TrackerCommand`: Algorithm 1.
- :class:`YawMovingAverage`: the 10-sample yaw filter with unwrapping at +-pi (section 3.2.2).
- :func:`blend_weight`: the proximity weight w(d) of eq. 3.33.
"""
from .angles import clamp, wrap
from .waypoint_tracker import (
    MODE_FAR_TURN, MODE_NEAR_TURN, MODE_SIDEWIND, TRACKER_GAITS, TrackerCommand, TrackerParams,
    WaypointTracker)
from .weight import blend_weight, combined_yaw_error, smoothstep
from .yaw_filter import YawMovingAverage

__all__ = [
    "WaypointTracker", "TrackerParams", "TrackerCommand", "YawMovingAverage", "blend_weight",
    "combined_yaw_error", "smoothstep", "wrap", "clamp", "TRACKER_GAITS", "MODE_SIDEWIND",
    "MODE_FAR_TURN", "MODE_NEAR_TURN",
]
