"""The standard topics a run's bag records besides the mission node's own, so that a run replays in
rviz and the usual tools (`rosbag play --clock run.bag` + `roslaunch snake_autonomy rviz.launch
load_description:=true use_sim_time:=true`): TF, static TF and diagnostics.

/tf_static is latched: robot_state_publisher sends it once, long before a run starts. The recorder
keeps the latest static transforms (merged by child frame) and writes them into the bag when the run
starts (:meth:`StaticTransforms.replay`), so each bag is complete on its own.
"""
import importlib
import threading

#: topic -> message type, recorded into every run's bag.
STANDARD_TOPICS = {
    "/tf": "tf2_msgs/TFMessage",
    "/tf_static": "tf2_msgs/TFMessage",
    "/diagnostics": "diagnostic_msgs/DiagnosticArray",
}
STATIC_TF_TOPIC = "/tf_static"


def message_class(type_name: str):
    """The Python class of 'package/Type' (the package's messages must be installed)."""
    package, _, name = type_name.partition("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


def standard_topic_types():
    """{topic: message class} of STANDARD_TOPICS."""
    return {topic: message_class(t) for topic, t in STANDARD_TOPICS.items()}


class StaticTransforms:
    """The latest static transform of each child frame, from every /tf_static publisher (thread-safe)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._by_child = {}

    def keep(self, msg) -> None:
        with self._lock:
            for t in msg.transforms:
                self._by_child[t.child_frame_id] = t

    def message(self):
        """One TFMessage with every static transform kept, or None when none arrived yet."""
        with self._lock:
            if not self._by_child:
                return None
            out = message_class(STANDARD_TOPICS[STATIC_TF_TOPIC])()
            out.transforms = [self._by_child[k] for k in sorted(self._by_child)]
            return out

    def replay(self, log, t_s: float) -> bool:
        """Writes the static transforms into a RunLog (at the run's start); False when there are none."""
        msg = self.message()
        if msg is None:
            return False
        log.write(STATIC_TF_TOPIC, msg, t_s)
        return True


#: sim/contacts (visualization_msgs/Marker, one per contact episode of the simulated robot): its text is
#: "LINK touched OBSTACLE" (nodes/planner_display.contact_marker writes it, runs/nav_record.py reads it)
CONTACT_TEXT = " touched "
