"""pose_remap_node's shutdown: rospy runs the node's on_shutdown hook (stop) before it closes the
topics; stop waits for a callback under way and no callback does any work after it, so nothing is
published to a closed topic (the node used to log a "publish() to a closed topic" traceback when an
odometry message arrived during shutdown)."""
import threading

from snake_autonomy.nodes.pose_remap_node import PoseRemapNode


class FakeTimer:
    def __init__(self):
        self.stopped = False

    def shutdown(self):
        self.stopped = True


class ClosingPublisher:
    """A publisher that fails once closed, as rospy's does."""

    def __init__(self):
        self.closed, self.sent = False, 0

    def publish(self):
        if self.closed:
            raise RuntimeError("publish() to a closed topic")
        self.sent += 1


def node_for_shutdown():
    """The node's shutdown state only (no ROS master): remap and check_state publish on pub."""
    node = PoseRemapNode.__new__(PoseRemapNode)
    node.lock, node.stopped, node.timer = threading.Lock(), False, FakeTimer()
    node.pub = ClosingPublisher()
    node.remap = lambda _msg: node.pub.publish()
    node.check_state = node.pub.publish
    return node


def test_stop_waits_for_the_callback_under_way_before_the_topics_close():
    node = node_for_shutdown()
    inside, release = threading.Event(), threading.Event()

    def slow_remap(_msg):           # an odometry callback still running when shutdown begins
        inside.set()
        release.wait(5.0)
        node.pub.publish()
    node.remap = slow_remap
    callback = threading.Thread(target=node.on_odom, args=(None,))
    callback.start()
    assert inside.wait(5.0)

    def shutdown():                 # rospy's order: client hooks, then the topics close
        node.stop()
        node.pub.closed = True
    closer = threading.Thread(target=shutdown)
    closer.start()
    closer.join(0.2)
    assert closer.is_alive() and not node.pub.closed      # stop waits for the callback
    release.set()
    callback.join(5.0)
    closer.join(5.0)
    assert node.pub.sent == 1 and node.pub.closed and node.timer.stopped


def test_after_stop_no_callback_publishes():
    node = node_for_shutdown()
    node.on_odom(None)
    node.on_timer(None)
    assert node.pub.sent == 2
    node.stop()
    node.pub.closed = True
    node.on_odom(None)              # would raise on the closed publisher
    node.on_timer(None)
    assert node.pub.sent == 2
    reply = node.srv_reset(None)
    assert not reply.success and "shutting down" in reply.message
