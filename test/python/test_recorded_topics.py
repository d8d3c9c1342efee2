"""The standard topics of a run's bag (runs/recorded_topics.py): types resolve, static TF from
several publishers is merged by child frame and written into the bag at the run's start."""
import rosbag
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TransformStamped
from tf2_msgs.msg import TFMessage

from snake_autonomy.runs.recorded_topics import STANDARD_TOPICS, StaticTransforms, standard_topic_types
from snake_autonomy.runs.run_log import RunLog


def _tf(child, x):
    t = TransformStamped()
    t.header.frame_id, t.child_frame_id = "head_link", child
    t.transform.translation.x = x
    t.transform.rotation.w = 1.0
    return t


def test_standard_topics_are_tf_static_tf_and_diagnostics():
    types = standard_topic_types()
    assert set(types) == {"/tf", "/tf_static", "/diagnostics"} == set(STANDARD_TOPICS)
    assert types["/tf"] is TFMessage and types["/tf_static"] is TFMessage
    assert types["/diagnostics"] is DiagnosticArray


def test_static_transforms_merge_by_child_frame_and_replay_into_the_bag(tmp_path):
    static = StaticTransforms()
    log = RunLog(tmp_path / "run", "m", [(1.0, 0.0, 0.0)], 10.0)
    assert not static.replay(log, 10.0)              # nothing arrived yet: nothing written
    static.keep(TFMessage(transforms=[_tf("camera_link", 0.1), _tf("link_1", 0.2)]))
    static.keep(TFMessage(transforms=[_tf("camera_link", 0.3)]))   # a later publisher updates one frame
    assert static.replay(log, 10.0)
    log.close("end", plots=False)
    with rosbag.Bag(str(tmp_path / "run" / "run.bag")) as bag:
        msgs = [m for _, m, _ in bag.read_messages(topics=["/tf_static"])]
    assert len(msgs) == 1
    by_child = {t.child_frame_id: t.transform.translation.x for t in msgs[0].transforms}
    assert by_child == {"camera_link": 0.3, "link_1": 0.2}
