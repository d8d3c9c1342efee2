"""snake_autonomy.estimation: camera odometry to base pose (eq. 3.1) and lost-tracking detection."""
from .pose_remap import (GateParams, GateResult, PoseRemapper, TrackingGate, base_covariance, head_in_base,
                         load_gate_params, load_camera_calibration)

__all__ = ["PoseRemapper", "TrackingGate", "GateParams", "GateResult", "base_covariance", "head_in_base",
           "load_camera_calibration", "load_gate_params"]
