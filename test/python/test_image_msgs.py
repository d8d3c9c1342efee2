"""nodes/image_msgs: the planner's and vio_node's image and camera_info conversions through cv_bridge and
image_geometry, with the Debian builds of both under the venv's pinned numpy: every encoding round-trips,
RealSense millimetres become metres, and a message that cannot be read is refused naming its field."""
import numpy as np
import pytest

pytest.importorskip("sensor_msgs.msg")
pytest.importorskip("cv_bridge")
pytest.importorskip("image_geometry")

from snake_autonomy.nodes.image_msgs import from_camera_info, from_image, to_camera_info, to_image  # noqa: E402
from snake_autonomy.perception.camera_model import CameraIntrinsics  # noqa: E402

K = CameraIntrinsics(640, 480, 615.0, 610.0, 320.0, 240.0)
RGB = np.random.default_rng(0).integers(0, 255, (4, 5, 3), dtype=np.uint8)
DEPTH_M = np.linspace(0, 3, 20, dtype=np.float32).reshape(4, 5)


def test_colour_round_trips_as_rgb_from_rgb8_and_bgr8():
    for encoding, sent in (("rgb8", RGB), ("bgr8", RGB[..., ::-1])):
        msg = to_image(sent, encoding, None, "cam")
        assert (msg.encoding, msg.width, msg.height, msg.step) == (encoding, 5, 4, 15)
        back = from_image(msg)
        assert back.dtype == np.uint8 and np.array_equal(back, RGB), encoding
        back[0, 0] = 0                                          # a copy the caller may change


def test_depth_in_metres_from_32fc1_and_millimetres_from_16uc1():
    back = from_image(to_image(DEPTH_M, "32FC1", None, "cam"))
    assert back.dtype == np.float32 and np.array_equal(back, DEPTH_M)
    mm = (DEPTH_M * 1000).round().astype(np.uint16)
    back = from_image(to_image(mm, "16UC1", None, "cam"))
    assert back.dtype == np.float32 and back == pytest.approx(DEPTH_M, abs=0.5e-3)   # whole mm
    assert back[0, 0] == 0.0                                    # 0 mm: no depth, as 0 m is
    mono = np.arange(20, dtype=np.uint8).reshape(4, 5)
    assert np.array_equal(from_image(to_image(mono, "mono8", None, "cam")), mono)


def test_big_endian_and_padded_rows_are_read_right():
    msg = to_image(DEPTH_M, "32FC1", None, "cam")
    msg.data, msg.is_bigendian = DEPTH_M.astype(">f4").tobytes(), 1
    assert np.array_equal(from_image(msg), DEPTH_M)
    msg = to_image(RGB, "rgb8", None, "cam")
    rows = np.zeros((4, 20), np.uint8)                          # 15 bytes of pixels + 5 of padding a row
    rows[:, :15] = RGB.reshape(4, 15)
    msg.data, msg.step = rows.tobytes(), 20
    assert np.array_equal(from_image(msg), RGB)


def test_stamp_and_frame_are_set_and_a_wrong_encoding_is_refused():
    msg = to_image(DEPTH_M, "32FC1", None, "camera_depth_optical_frame")
    assert msg.header.frame_id == "camera_depth_optical_frame"
    with pytest.raises(ValueError, match="image encoding 'bgra8': expected one of"):
        to_image(RGB, "bgra8", None, "cam")


def test_images_that_cannot_be_read_name_the_field():
    depth = np.ones((4, 5), np.float32)
    m = to_image(depth, "32FC1", None, "cam")
    m.encoding = "64FC3"
    with pytest.raises(ValueError, match="image encoding '64FC3': expected one of"):
        from_image(m)
    m = to_image(depth, "32FC1", None, "cam")
    m.data = m.data[:-3]
    with pytest.raises(ValueError, match="image data 77 bytes: height 4 x step 20 needs 80"):
        from_image(m)
    m = to_image(depth, "32FC1", None, "cam")
    m.step = 8
    with pytest.raises(ValueError, match="image step 8: a 32FC1 row of width 5 needs 20 bytes"):
        from_image(m)
    m.height = 0
    with pytest.raises(ValueError, match="image height 0"):
        from_image(m)


def test_camera_info_round_trips_through_the_pinhole_model():
    assert from_camera_info(to_camera_info(K, None, "cam")) == K


def test_camera_info_binning_and_roi_scale_the_intrinsics():
    info = to_camera_info(K, None, "cam")
    info.binning_x = info.binning_y = 2
    assert from_camera_info(info) == CameraIntrinsics(320, 240, 307.5, 305.0, 160.0, 120.0)
    info = to_camera_info(K, None, "cam")
    info.roi.x_offset, info.roi.y_offset, info.roi.width, info.roi.height = 100, 40, 200, 100
    assert from_camera_info(info) == CameraIntrinsics(200, 100, 615.0, 610.0, 220.0, 200.0)
    info.roi.width = 0
    with pytest.raises(ValueError, match="camera_info roi 0x100 binned 1x1"):
        from_camera_info(info)


def test_camera_infos_that_cannot_be_used_name_the_field():
    info = to_camera_info(K, None, "cam")
    info.K = (0.0,) + tuple(info.K[1:])
    with pytest.raises(ValueError, match=r"camera_info K\[0\] \(fx\) 0.0: must be finite and > 0"):
        from_camera_info(info)
    info = to_camera_info(K, None, "cam")
    info.K = list(info.K[:5]) + [float("nan")] + list(info.K[6:])
    with pytest.raises(ValueError, match=r"K\[5\] \(cy\) nan: must be finite"):
        from_camera_info(info)
    info = to_camera_info(K, None, "cam")
    info.width = 0
    with pytest.raises(ValueError, match="camera_info width 0"):
        from_camera_info(info)
    info = to_camera_info(K, None, "cam")
    info.K = list(info.K[:8])
    with pytest.raises(ValueError, match="camera_info K: 8 values, expected 9"):
        from_camera_info(info)
