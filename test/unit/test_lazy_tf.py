"""LazyTransformBuffer answers as a tf2_ros.Buffer fed every /tf message would, for the latest
transform, while deserializing only the newest messages of each stream. Messages are real
serialized tf2_msgs/TFMessage bytes, fed to on_tf as rospy.AnyMsg delivers them."""
import io
import math

import pytest

rospy = pytest.importorskip('rospy')
tf2_ros = pytest.importorskip('tf2_ros')
from geometry_msgs.msg import TransformStamped  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402

from mbot_slam_navigation.lazy_tf import LazyTransformBuffer, first_child_frame  # noqa: E402


@pytest.fixture(autouse=True)
def ros_time():
    # Without init_node, rospy.Time.now() is the wall clock once marked initialized; the tests set
    # simulated time explicitly where they need it.
    was = rospy.rostime.is_rostime_initialized()
    rospy.rostime.set_rostime_initialized(True)
    yield
    rospy.rostime._rostime_current = None  # back to the wall clock
    rospy.rostime.set_rostime_initialized(was)


def stamped(parent, child, t, x, y=0.0, yaw=0.0):
    m = TransformStamped()
    m.header.stamp = rospy.Time.from_sec(t)
    m.header.frame_id = parent
    m.child_frame_id = child
    m.transform.translation.x, m.transform.translation.y = x, y
    m.transform.rotation.z, m.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return m


def raw(*transforms, caller='/sim'):
    buf = io.BytesIO()
    TFMessage(list(transforms)).serialize(buf)
    msg = rospy.AnyMsg()
    msg.deserialize(buf.getvalue())
    msg._connection_header = {'callerid': caller}
    return msg


def feed_both(lazy, full, msg):
    lazy.on_tf(msg)
    m = TFMessage()
    m.deserialize(msg._buff)
    for t in m.transforms:
        full.set_transform(t, msg._connection_header['callerid'])


def test_first_child_frame_reads_the_first_transforms_child_only():
    assert first_child_frame(raw(stamped('odom', 'base_footprint', 1.0, 0.0),
                                 stamped('base_footprint', 'wheel', 1.0, 0.0))._buff) == b'base_footprint'
    assert first_child_frame(raw()._buff) == b''
    assert first_child_frame(b'\x01\x00') == b'?'


def test_latest_pose_is_the_one_a_full_listener_gives_with_few_messages_deserialized():
    lazy = LazyTransformBuffer(subscribe=False, keep=2)
    full = tf2_ros.Buffer(debug=False)
    for k in range(200):  # 10 s: odometry at 20 Hz with the wheels in the same message, SLAM at 10 Hz
        t = 0.05 * k
        feed_both(lazy, full, raw(stamped('odom', 'base_footprint', t, 0.1 * t, 0.02 * t, 0.05 * t),
                                  stamped('base_footprint', 'wheel_left', t, 0.0, 0.1)))
        if k % 2 == 0:
            feed_both(lazy, full, raw(stamped('map', 'odom', t, 0.5 + 0.001 * k, -0.2, 0.01), caller='/slam'))
        if k % 40 == 39:  # a lookup every 2 s, as the explorer's path recording does
            a = lazy.lookup_transform('map', 'base_footprint', rospy.Time(0))
            b = full.lookup_transform('map', 'base_footprint', rospy.Time(0))
            assert a.header.stamp == b.header.stamp
            assert a.transform.translation.x == pytest.approx(b.transform.translation.x, abs=1e-9)
            assert a.transform.translation.y == pytest.approx(b.transform.translation.y, abs=1e-9)
            assert a.transform.rotation.z == pytest.approx(b.transform.rotation.z, abs=1e-9)
    assert lazy.received == 300
    assert lazy.inserted == 5 * (2 + 2)  # 5 lookups, 2 newest of each of the two streams
    # the wheel, only in the simulator's odometry messages, is there too
    assert lazy.can_transform('base_footprint', 'wheel_left', rospy.Time(0))


def test_a_stream_that_alternates_child_frames_keeps_both():
    # One node publishing two kinds of message (a robot's odometry, another's) must not lose either.
    lazy = LazyTransformBuffer(subscribe=False, keep=1)
    for k in range(10):
        lazy.on_tf(raw(stamped('odom', 'robot1/base', 0.1 * k, k)))
        lazy.on_tf(raw(stamped('odom', 'robot2/base', 0.1 * k, -k)))
    assert lazy.lookup_transform('odom', 'robot1/base', rospy.Time(0)).transform.translation.x == 9
    assert lazy.lookup_transform('odom', 'robot2/base', rospy.Time(0)).transform.translation.x == -9


def test_unknown_frame_raises_as_tf2_does_and_static_transforms_are_kept():
    lazy = LazyTransformBuffer(subscribe=False)
    lazy.on_tf(raw(stamped('odom', 'base_footprint', 1.0, 2.0)))
    with pytest.raises(tf2_ros.LookupException):
        lazy.lookup_transform('map', 'base_footprint', rospy.Time(0))
    static = TFMessage([stamped('base_footprint', 'laser_link', 0.0, 0.1)])
    static._connection_header = {'callerid': '/robot_state_publisher'}
    lazy.on_tf_static(static)
    t = lazy.lookup_transform('odom', 'laser_link', rospy.Time(0))
    assert t.transform.translation.x == pytest.approx(2.1)


def test_time_jumping_back_clears_the_buffer_as_a_listener_does():
    rospy.rostime._set_rostime(rospy.Time(100))
    lazy = LazyTransformBuffer(subscribe=False)
    lazy.on_tf(raw(stamped('odom', 'base_footprint', 99.0, 5.0)))
    assert lazy.lookup_transform('odom', 'base_footprint', rospy.Time(0)).transform.translation.x == 5.0
    rospy.rostime._set_rostime(rospy.Time(1))  # reset_simulation
    lazy.on_tf(raw(stamped('odom', 'base_footprint', 0.5, 0.0)))
    t = lazy.lookup_transform('odom', 'base_footprint', rospy.Time(0))
    assert t.header.stamp == rospy.Time.from_sec(0.5)  # not the stale 99 s transform


def test_a_corrupt_message_is_skipped_with_the_others_still_read():
    lazy = LazyTransformBuffer(subscribe=False)
    bad = rospy.AnyMsg()
    bad.deserialize(b'\x05\x00\x00\x00\x00')
    bad._connection_header = {'callerid': '/broken'}
    lazy.on_tf(bad)
    lazy.on_tf(raw(stamped('odom', 'base_footprint', 1.0, 3.0)))
    assert lazy.lookup_transform('odom', 'base_footprint', rospy.Time(0)).transform.translation.x == 3.0
