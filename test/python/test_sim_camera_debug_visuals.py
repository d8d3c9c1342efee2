"""The simulated head camera draws only what a real camera would see: MuJoCo's sites and the geoms of
the debug groups (3-5) are not in its colour, depth or segmentation renders."""
import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from snake_autonomy.perception.camera_model import CameraIntrinsics  # noqa: E402
from snake_autonomy.sim.camera import HeadCamera, LinkMount  # noqa: E402

# the camera at the origin looking along +x (LinkMount: x forward); a red site sphere 0.5 m ahead, a
# blue debug-group geom beside it, a green wall 2 m ahead filling the view
_XML = """
<mujoco>
  <worldbody>
    <light dir="1 0 -0.3" directional="true" diffuse="0.8 0.8 0.8"/>
    <geom name="wall" type="box" pos="2 0 0" size="0.05 3 3" rgba="0.1 0.8 0.1 1"/>
    <site name="marker" pos="0.5 0 0" size="0.1" rgba="1 0 0 1"/>
    <geom name="debug_geom" type="sphere" pos="0.6 0.15 0" size="0.05" group="4" rgba="0 0 1 1"
          contype="0" conaffinity="0"/>
  </worldbody>
</mujoco>
"""


@pytest.fixture(scope="module")
def camera():
    model = mujoco.MjModel.from_xml_string(_XML)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    cam = HeadCamera(model, CameraIntrinsics(160, 120, 100.0, 100.0, 79.5, 59.5), mount=LinkMount(np.eye(4)))
    yield cam, data
    cam.close()


def _red(rgb):
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    return (r > 100) & (r > 2 * g) & (r > 2 * b)


def _blue(rgb):
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    return (b > 100) & (b > 2 * g) & (b > 2 * r)


def test_sites_and_debug_group_geoms_are_not_rendered(camera):
    cam, data = camera
    frame = cam.render(data, np.eye(4))
    assert not _red(frame.rgb).any() and not _blue(frame.rgb).any()
    # the depth sees through them to the wall 1.95 m ahead
    centre = frame.depth_m[50:70, 70:90]
    np.testing.assert_allclose(centre, 1.95, atol=0.01)


def test_the_same_scene_with_the_site_group_on_shows_the_site(camera):
    """The check above can fail: MuJoCo's default site groups draw the marker in the view's centre."""
    cam, data = camera
    saved = cam.scene_option.sitegroup[0]
    cam.scene_option.sitegroup[0] = 1
    try:
        frame = cam.render(data, np.eye(4), depth=True, labels=False)
    finally:
        cam.scene_option.sitegroup[0] = saved
    red = _red(frame.rgb)
    assert red[50:70, 70:90].all()
    assert frame.depth_m[60, 80] == pytest.approx(0.4, abs=0.01)
