"""sensor_msgs/Image and CameraInfo <-> numpy through cv_bridge and image_geometry, for the encodings the
simulated head camera and the planner use: rgb8, bgr8, mono8, 32FC1 depth in m, 16UC1 depth in mm as a
RealSense publishes it. cv_bridge converts the pixels; this module checks the message first (Python's
cv_bridge trusts height, width and step), so a message that cannot be read raises ValueError naming the
field and its value."""
import copy
import math

import numpy as np
from cv_bridge import CvBridge, CvBridgeError
from image_geometry import PinholeCameraModel
from sensor_msgs.msg import CameraInfo, Image

from snake_autonomy.perception.camera_model import CameraIntrinsics

#: encoding -> (channels, element type)
_LAYOUT = {"rgb8": (3, np.uint8), "bgr8": (3, np.uint8), "mono8": (1, np.uint8), "32FC1": (1, np.float32),
           "16UC1": (1, np.uint16)}
MAX_SIDE_PX = 8192        # a camera image's width or height beyond this is a corrupt header
_BRIDGE = CvBridge()


def to_image(array: np.ndarray, encoding: str, stamp, frame_id: str) -> Image:
    """An Image of `array` cast to the encoding's type (rgb8: the array is rgb; bgr8: it is bgr)."""
    if encoding not in _LAYOUT:
        raise ValueError(f"image encoding {encoding[:40]!r}: expected one of {', '.join(_LAYOUT)}")
    m = _BRIDGE.cv2_to_imgmsg(np.ascontiguousarray(array, dtype=_LAYOUT[encoding][1]), encoding=encoding)
    m.header.stamp, m.header.frame_id = stamp, frame_id
    return m


def _checked(msg: Image) -> Image:
    """msg itself, or an unpadded copy when its rows are padded; ValueError naming a bad field."""
    if msg.encoding not in _LAYOUT:
        raise ValueError(f"image encoding {msg.encoding[:40]!r}: expected one of {', '.join(_LAYOUT)}")
    for key in ("width", "height"):
        if not 1 <= getattr(msg, key) <= MAX_SIDE_PX:
            raise ValueError(f"image {key} {getattr(msg, key)}: expected 1..{MAX_SIDE_PX}")
    ch, dtype = _LAYOUT[msg.encoding]
    row_bytes = msg.width * ch * np.dtype(dtype).itemsize
    if msg.step < row_bytes:
        raise ValueError(f"image step {msg.step}: a {msg.encoding} row of width {msg.width} needs {row_bytes} bytes")
    if len(msg.data) != msg.step * msg.height:
        raise ValueError(f"image data {len(msg.data)} bytes: height {msg.height} x step {msg.step} "
                         f"needs {msg.step * msg.height}")
    if msg.step == row_bytes:
        return msg
    rows = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.step)   # the bridge ignores step
    out = copy.copy(msg)
    out.data, out.step = rows[:, :row_bytes].tobytes(), row_bytes
    return out


def from_image(msg: Image) -> np.ndarray:
    """A writable (H, W) or (H, W, 3) array: rgb for colour (bgr8 converted by cv_bridge), mono8 as is,
    metres (float32) for depth (16UC1 millimetres / 1000; 0 stays 0: no depth)."""
    msg = _checked(msg)
    try:
        if msg.encoding in ("rgb8", "bgr8"):
            return _BRIDGE.imgmsg_to_cv2(msg, desired_encoding="rgb8")
        a = _BRIDGE.imgmsg_to_cv2(msg, desired_encoding="passthrough")
    except (CvBridgeError, TypeError) as exc:
        raise ValueError(f"image encoding {msg.encoding!r}: cv_bridge cannot convert it: {exc}") from exc
    if msg.encoding == "16UC1":
        return a.astype(np.float32) / np.float32(1000.0)
    return np.array(a, dtype=np.float32 if msg.encoding == "32FC1" else np.uint8)


def to_camera_info(k: CameraIntrinsics, stamp, frame_id: str) -> CameraInfo:
    d = k.camera_info(frame_id)
    m = CameraInfo()
    m.header.stamp, m.header.frame_id = stamp, frame_id
    m.width, m.height = d["width"], d["height"]
    m.distortion_model = d["distortion_model"]
    m.D, m.K, m.R, m.P = d["D"], d["K"], d["R"], d["P"]
    return m


def from_camera_info(msg: CameraInfo) -> CameraIntrinsics:
    """The pinhole intrinsics (K) of a camera_info through image_geometry's PinholeCameraModel, which also
    applies binning and region of interest; ValueError naming the field of an unusable one."""
    for key in ("width", "height"):
        if not 1 <= getattr(msg, key) <= MAX_SIDE_PX:
            raise ValueError(f"camera_info {key} {getattr(msg, key)}: expected 1..{MAX_SIDE_PX}")
    for key, n in (("K", 9), ("R", 9), ("P", 12)):       # the model would pad or cut a wrong length silently
        if len(getattr(msg, key)) != n:
            raise ValueError(f"camera_info {key}: {len(getattr(msg, key))} values, expected {n}")
    for key, i in (("K[0] (fx)", 0), ("K[4] (fy)", 4)):
        v = float(msg.K[i])
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"camera_info {key} {v!r}: must be finite and > 0")
    for key, i in (("K[2] (cx)", 2), ("K[5] (cy)", 5)):
        if not math.isfinite(float(msg.K[i])):
            raise ValueError(f"camera_info {key} {float(msg.K[i])!r}: must be finite")
    model = PinholeCameraModel()
    model.fromCameraInfo(msg)
    roi = model.raw_roi
    width, height = roi.width // model.binning_x, roi.height // model.binning_y
    if not (1 <= width <= msg.width and 1 <= height <= msg.height):
        raise ValueError(f"camera_info roi {roi.width}x{roi.height} binned {model.binning_x}x{model.binning_y}: "
                         f"expected a region inside {msg.width}x{msg.height}")
    k = np.asarray(model.intrinsicMatrix())
    return CameraIntrinsics(int(width), int(height), float(k[0, 0]), float(k[1, 1]), float(k[0, 2]),
                            float(k[1, 2]))
