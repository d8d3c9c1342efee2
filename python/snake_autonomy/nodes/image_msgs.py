"""sensor_msgs/Image and CameraInfo <-> numpy, without cv_bridge (the encodings the simulated head
camera and the planner use: rgb8, bgr8, mono8, 32FC1 depth in m, 16UC1 depth in mm as a RealSense
publishes it). A message that cannot be read raises ValueError naming the field and its value."""
import math

import numpy as np
from sensor_msgs.msg import CameraInfo, Image

from snake_autonomy.perception.camera_model import CameraIntrinsics

_CHANNELS = {"rgb8": (3, np.uint8), "bgr8": (3, np.uint8), "mono8": (1, np.uint8),
             "32FC1": (1, np.float32), "16UC1": (1, np.uint16)}
MAX_SIDE_PX = 8192        # a camera image's width or height beyond this is a corrupt header


def to_image(array: np.ndarray, encoding: str, stamp, frame_id: str) -> Image:
    ch, dtype = _CHANNELS[encoding]
    a = np.ascontiguousarray(array, dtype=dtype)
    m = Image()
    m.header.stamp, m.header.frame_id = stamp, frame_id
    m.height, m.width = a.shape[0], a.shape[1]
    m.encoding = encoding
    m.is_bigendian = 0
    m.step = a.shape[1] * ch * a.itemsize
    m.data = a.tobytes()
    return m


def from_image(msg: Image) -> np.ndarray:
    """(H, W) or (H, W, 3) array; rgb for colour (bgr8 is swapped), metres (float32) for depth."""
    if msg.encoding not in _CHANNELS:
        raise ValueError(f"image encoding {msg.encoding[:40]!r}: expected one of {', '.join(_CHANNELS)}")
    ch, dtype = _CHANNELS[msg.encoding]
    dt = np.dtype(dtype).newbyteorder(">" if msg.is_bigendian else "<")
    for key in ("width", "height"):
        if not 1 <= getattr(msg, key) <= MAX_SIDE_PX:
            raise ValueError(f"image {key} {getattr(msg, key)}: expected 1..{MAX_SIDE_PX}")
    if msg.step < msg.width * ch * dt.itemsize:
        raise ValueError(f"image step {msg.step}: a {msg.encoding} row of width {msg.width} needs "
                         f"{msg.width * ch * dt.itemsize} bytes")
    if len(msg.data) != msg.step * msg.height:
        raise ValueError(f"image data {len(msg.data)} bytes: height {msg.height} x step {msg.step} "
                         f"needs {msg.step * msg.height}")
    row = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)
    a = row[:, :msg.width * ch * dt.itemsize].copy().view(dt).reshape(msg.height, msg.width, ch)
    a = a[..., 0] if ch == 1 else a
    if msg.encoding == "bgr8":
        a = a[..., ::-1]
    if msg.encoding == "16UC1":
        return a.astype(np.float32) / 1000.0
    return a.astype(np.float32) if msg.encoding == "32FC1" else a


def to_camera_info(k: CameraIntrinsics, stamp, frame_id: str) -> CameraInfo:
    d = k.camera_info(frame_id)
    m = CameraInfo()
    m.header.stamp, m.header.frame_id = stamp, frame_id
    m.width, m.height = d["width"], d["height"]
    m.distortion_model = d["distortion_model"]
    m.D, m.K, m.R, m.P = d["D"], d["K"], d["R"], d["P"]
    return m


def from_camera_info(msg: CameraInfo) -> CameraIntrinsics:
    """The pinhole intrinsics of a camera_info; ValueError naming the field of an unusable one."""
    for key in ("width", "height"):
        if not 1 <= getattr(msg, key) <= MAX_SIDE_PX:
            raise ValueError(f"camera_info {key} {getattr(msg, key)}: expected 1..{MAX_SIDE_PX}")
    if len(msg.K) != 9:
        raise ValueError(f"camera_info K: {len(msg.K)} values, expected 9")
    fx, fy, cx, cy = (float(msg.K[i]) for i in (0, 4, 2, 5))
    for key, v in (("K[0] (fx)", fx), ("K[4] (fy)", fy)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"camera_info {key} {v!r}: must be finite and > 0")
    for key, v in (("K[2] (cx)", cx), ("K[5] (cy)", cy)):
        if not math.isfinite(v):
            raise ValueError(f"camera_info {key} {v!r}: must be finite")
    return CameraIntrinsics(int(msg.width), int(msg.height), fx, fy, cx, cy)
