"""The camera calibration T_head^camera from config/camera.yaml (thesis 3.3.3, eq. 3.1).

File format (two keys, nothing else):
    translation_m: [x, y, z]          # camera origin in head_link, metres
    rotation_xyzw: [x, y, z, w]       # camera axes in head_link, unit quaternion
"""
from pathlib import Path

import numpy as np
import yaml

from .transforms import matrix_from_quat_xyzw, transform


def load_camera_calibration(path) -> np.ndarray:
    """4x4 T_head^camera (camera pose in head_link). Raises ValueError naming key and value."""
    path = Path(path)
    with open(path) as f:
        raw = yaml.safe_load(f) or {}
    errors = []
    if not isinstance(raw, dict):
        raise ValueError(f"{path}: expected a mapping with translation_m and rotation_xyzw")
    unknown = set(raw) - {"translation_m", "rotation_xyzw"}
    if unknown:
        errors.append(f"unknown keys {sorted(unknown)}")
    t, q = raw.get("translation_m"), raw.get("rotation_xyzw")
    if not _numbers(t, 3):
        errors.append(f"translation_m: expected 3 numbers, got {t!r}")
    if not _numbers(q, 4):
        errors.append(f"rotation_xyzw: expected 4 numbers, got {q!r}")
    elif abs(np.linalg.norm(q) - 1.0) > 1e-3:
        errors.append(f"rotation_xyzw: must be a unit quaternion, got {q!r} "
                      f"(norm {np.linalg.norm(q):.4f})")
    if errors:
        raise ValueError(f"{path}:\n  " + "\n  ".join(errors))
    return transform(matrix_from_quat_xyzw(q), t)


def _numbers(value, n) -> bool:
    return (isinstance(value, list) and len(value) == n
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value))
