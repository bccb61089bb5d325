"""Message layer: definitions, md5 sums, wire format, YAML views (no processes)."""
from __future__ import annotations

import struct

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from orchestra.node import msgspec
from orchestra.node.msg import (
    FillError,
    MessageNotFound,
    Registry,
    fill_message,
    get_message_class,
    get_service_class,
    message_class_from_definition,
    to_plain,
    to_yaml_text,
)
from orchestra.node.rostime import Time

STORE = get_typestore(Stores.ROS1_NOETIC)
STANDARD = sorted(k.replace("/msg/", "/") for k in STORE.fielddefs
                  if not k.startswith("builtin_interfaces/"))


def test_md5_algorithm_matches_rosbags_for_every_standard_message():
    registry = Registry()
    mismatches = []
    for name in STANDARD:
        text, md5 = STORE.generate_msgdef(name.replace("/", "/msg/"))
        specs = msgspec.parse_full_text(text, name)
        mine = msgspec.compute_md5(specs[name], lambda t, specs=specs: specs.get(t) or registry.spec(t))
        if mine != md5:
            mismatches.append(name)
    assert mismatches == []
    assert len(STANDARD) > 100


@pytest.mark.parametrize("srv,md5", [
    ("std_srvs/Empty", "d41d8cd98f00b204e9800998ecf8427e"),
    ("std_srvs/Trigger", "937c9679a518e3a18d831e57125ea522"),
    ("std_srvs/SetBool", "09fb03525b03e7ea1fd3992bafd87e16"),
    ("nav_msgs/GetMap", "6cdd0a18e0aff5b0a3ca2326a89b54ff"),
])
def test_service_md5_is_computed_like_genmsg(srv, md5):
    assert get_service_class(srv)._md5sum == md5


def test_custom_service_and_message_from_package_files(tmp_path, monkeypatch):
    pkg = tmp_path / "demo_pkg"
    (pkg / "srv").mkdir(parents=True)
    (pkg / "msg").mkdir()
    (pkg / "package.xml").write_text("<package><name>demo_pkg</name></package>")
    (pkg / "srv" / "AddTwoInts.srv").write_text("int64 a\nint64 b\n---\nint64 sum\n")
    (pkg / "msg" / "Pose.msg").write_text("float32 x\nfloat32 y\nfloat32 theta\n\n"
                                          "float32 linear_velocity\nfloat32 angular_velocity\n")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path))
    registry = Registry()
    srv = registry.service_class("demo_pkg/AddTwoInts")
    assert srv._md5sum == "6a2e34150c00229791cc89ff309fff21"  # rospy_tutorials' AddTwoInts
    assert srv.Request(a=1, b=2).a == 1 and srv.Response().sum == 0
    pose = registry.message_class("demo_pkg/Pose")
    assert pose._md5sum == "863b248d5016ca62ea2e895ae5265cf9"  # turtlesim/Pose
    assert pose._type == "demo_pkg/Pose"


def test_tf2_message_missing_from_rosbags_is_bundled_with_the_right_md5():
    assert get_message_class("tf2_msgs/TFMessage")._md5sum == "94810edda583a504dfda3829e70d7eec"


def test_unknown_types_raise_message_not_found():
    with pytest.raises(MessageNotFound):
        get_message_class("no_such_pkg/Thing")
    with pytest.raises(MessageNotFound):
        get_service_class("std_msgs/NoSuchService")


def test_constructor_defaults_every_field_and_builds_nested_messages():
    Odometry = get_message_class("nav_msgs/Odometry")
    odom = Odometry()
    assert odom.header.stamp == Time() and odom.header.frame_id == ""
    assert odom.pose.pose.orientation.w == 0.0
    assert odom.pose.covariance == [0.0] * 36
    other = Odometry()
    other.pose.pose.position.x = 1.0
    assert odom.pose.pose.position.x == 0.0  # defaults are not shared between instances
    Image = get_message_class("sensor_msgs/Image")
    assert Image().data == b""
    assert get_message_class("rosgraph_msgs/Log")().topics == []


def test_constructor_takes_keywords_or_positional_values_and_rejects_unknown_fields():
    Vector3 = get_message_class("geometry_msgs/Vector3")
    assert Vector3(1.0, 2.0, 3.0) == Vector3(x=1.0, y=2.0, z=3.0)
    with pytest.raises(AttributeError, match="w is not an attribute of Vector3"):
        Vector3(w=1.0)
    with pytest.raises(TypeError, match="Invalid number of arguments"):
        Vector3(1.0, 2.0)
    with pytest.raises(TypeError, match="args OR keywords, not both"):
        Vector3(1.0, y=2.0, z=3.0)


def test_constructor_gives_defaults_for_fields_left_out_or_none_as_genpy():
    Pose = get_message_class("geometry_msgs/PoseStamped")
    p = Pose(header=None)
    assert p.header.frame_id == "" and p.pose.orientation.w == 0.0
    assert Pose(None, None) == Pose()


def test_class_exposes_type_md5_full_text_and_constants():
    Log = get_message_class("rosgraph_msgs/Log")
    assert Log._type == "rosgraph_msgs/Log"
    assert Log._md5sum == "acffd30cd6b6de30f120938c17c593fb"
    assert "MSG: std_msgs/Header" in Log._full_text
    assert Log.ERROR == 8 and Log.FATAL == 16


def _all_defaults_round_trip():
    for name in STANDARD:
        cls = get_message_class(name)
        msg = cls()
        yield name, cls, msg


def test_every_standard_message_round_trips_and_matches_rosbags_bytes():
    for name, cls, msg in _all_defaults_round_trip():
        data = bytes(msg.serialize_bytes())
        assert cls.deserialize_bytes(data) == msg, name
        rb = STORE.deserialize_ros1(data, name.replace("/", "/msg/"))
        assert bytes(STORE.serialize_ros1(rb, name.replace("/", "/msg/"))) == data, name


def test_filled_messages_decode_identically_in_rosbags():
    Image = get_message_class("sensor_msgs/Image")
    img = Image(height=2, width=3, encoding="rgb8", step=9, data=bytes(range(18)))
    img.header.stamp = Time(12, 345)
    img.header.frame_id = "cam"
    rb = STORE.deserialize_ros1(bytes(img.serialize_bytes()), "sensor_msgs/msg/Image")
    assert (rb.height, rb.width, rb.encoding, rb.step) == (2, 3, "rgb8", 9)
    assert rb.header.stamp.sec == 12 and rb.header.stamp.nanosec == 345
    assert bytes(rb.data) == bytes(range(18))

    NavSatFix = get_message_class("sensor_msgs/NavSatFix")
    fix = NavSatFix(latitude=1.5, position_covariance=[float(i) for i in range(9)])
    fix.status.status = -1
    rb = STORE.deserialize_ros1(bytes(fix.serialize_bytes()), "sensor_msgs/msg/NavSatFix")
    assert rb.latitude == 1.5 and rb.status.status == -1
    assert np.array_equal(rb.position_covariance, np.arange(9.0))

    TF = get_message_class("tf2_msgs/TFMessage")
    Transform = get_message_class("geometry_msgs/TransformStamped")
    tf = TF(transforms=[Transform(child_frame_id="a"), Transform(child_frame_id="b")])
    tf.transforms[1].transform.rotation.w = 1.0
    back = TF.deserialize_bytes(tf.serialize_bytes())
    assert [t.child_frame_id for t in back.transforms] == ["a", "b"]
    assert back.transforms[1].transform.rotation.w == 1.0

    Log = get_message_class("rosgraph_msgs/Log")
    log = Log(level=Log.WARN, name="/n", msg="héllo", topics=["/a", "/bb"])
    rb = STORE.deserialize_ros1(bytes(log.serialize_bytes()), "rosgraph_msgs/msg/Log")
    assert rb.msg == "héllo" and rb.topics == ["/a", "/bb"]


def test_wire_layout_of_a_string_is_length_prefixed_utf8():
    String = get_message_class("std_msgs/String")
    assert bytes(String(data="hi").serialize_bytes()) == struct.pack("<I", 2) + b"hi"


def test_wrong_values_raise_serialization_error_naming_the_type():
    from orchestra.node.exceptions import SerializationError
    Int8 = get_message_class("std_msgs/Int8")
    with pytest.raises(SerializationError, match="std_msgs/Int8"):
        Int8(data=1000).serialize_bytes()
    NavSatFix = get_message_class("sensor_msgs/NavSatFix")
    with pytest.raises(SerializationError, match="9 elements"):
        NavSatFix(position_covariance=[1.0]).serialize_bytes()
    String = get_message_class("std_msgs/String")
    with pytest.raises(SerializationError):
        String.deserialize_bytes(b"\x05\x00\x00\x00ab")


def test_yaml_text_follows_rostopic_echo_layout():
    Header = get_message_class("std_msgs/Header")
    text = to_yaml_text(Header(seq=3, stamp=Time(5, 7), frame_id="map"))
    assert text == ('seq: 3\nstamp: \n  secs: 5\n  nsecs:         7\nframe_id: "map"')
    Float = get_message_class("std_msgs/Float64MultiArray")
    msg = Float(data=[1.0, 2.5])
    assert "data: [1.0, 2.5]" in to_yaml_text(msg)
    assert "dim: []" in to_yaml_text(msg)


def test_fill_message_from_yaml_shapes():
    Twist = get_message_class("geometry_msgs/Twist")
    t = fill_message(Twist(), {"linear": {"x": 1}, "angular": [0, 0, 2]})
    assert (t.linear.x, t.angular.z) == (1.0, 2.0)
    String = get_message_class("std_msgs/String")
    assert fill_message(String(), "hello").data == "hello"
    Header = get_message_class("std_msgs/Header")
    assert fill_message(Header(), {"stamp": {"secs": 1, "nsecs": 2}}).stamp == Time(1, 2)
    Stamped = get_message_class("geometry_msgs/PointStamped")
    stamped = fill_message(Stamped(), {"header": "auto", "point": {"x": 1}})
    assert stamped.header.stamp.secs > 0
    assert fill_message(Stamped(), {"header": {"stamp": "now"}}).header.stamp.secs > 0
    with pytest.raises(FillError, match="no field linear.w"):
        fill_message(Twist(), {"linear": {"w": 1}})
    with pytest.raises(FillError, match="must be a number"):
        fill_message(Twist(), {"linear": {"x": "fast"}})
    plain = to_plain(fill_message(Header(), {"frame_id": "a"}))
    assert plain == {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": "a"}


def test_bare_integer_time_is_nanoseconds_as_in_rostopic_and_a_float_is_seconds():
    Clock = get_message_class("rosgraph_msgs/Clock")
    assert fill_message(Clock(), {"clock": 5}).clock == Time(0, 5)            # genpy's rule
    assert fill_message(Clock(), {"clock": 5_000_000_000}).clock == Time(5, 0)
    assert fill_message(Clock(), {"clock": 5.5}).clock == Time(5, 500_000_000)  # genpy refuses
    Header = get_message_class("std_msgs/Header")
    assert fill_message(Header(), {"stamp": 7}).stamp == Time(0, 7)


def test_class_from_connection_header_definition_decodes_unknown_types():
    definition = ("uint8 MODE=2\nfoo_msgs/Inner inner\nstring name\n" + "=" * 80 +
                  "\nMSG: foo_msgs/Inner\nint32[] values\n")
    cls = message_class_from_definition("foo_msgs/Outer", definition)
    msg = cls(name="x")
    msg.inner.values = [1, -2]
    back = cls.deserialize_bytes(msg.serialize_bytes())
    assert back.inner.values == [1, -2] and back.name == "x" and cls.MODE == 2


def test_msg_parser_rejects_bad_lines_with_location():
    with pytest.raises(msgspec.MsgSpecError, match="Bad.msg:2"):
        msgspec.parse_msg("int32 a\nint32\n", "p/Bad", "Bad.msg")
    with pytest.raises(msgspec.MsgSpecError, match="duplicate"):
        msgspec.parse_msg("int32 a\nint32 a\n", "p/Bad")
    with pytest.raises(msgspec.MsgSpecError, match="bad type"):
        msgspec.parse_msg("in-t32 a\n", "p/Bad")


def test_msg_parser_keeps_string_constants_verbatim_and_resolves_relative_types():
    spec = msgspec.parse_msg("string GREETING=hi # not a comment\nHeader header\nPoint p\n",
                             "pkg/M")
    assert spec.constants[0].value == "hi # not a comment"
    assert [f.base for f in spec.fields] == ["std_msgs/Header", "pkg/Point"]



def test_numpy_variants_give_numeric_arrays_of_the_field_dtype_as_genpy():
    import io

    Fix = get_message_class("sensor_msgs/NavSatFix")
    buff = io.BytesIO()
    Fix(position_covariance=np.arange(9.0)).serialize_numpy(buff, np)
    back = Fix().deserialize_numpy(buff.getvalue(), np)
    assert back.position_covariance.dtype == np.float64
    assert back.position_covariance.tolist() == list(range(9))
    Img = get_message_class("sensor_msgs/Image")
    raw = io.BytesIO()
    Img(data=b"\x01\x02").serialize(raw)
    assert Img().deserialize_numpy(raw.getvalue(), np).data == b"\x01\x02"  # uint8[]: bytes


def test_bad_bytes_raise_deserialization_error():
    from orchestra.node.exceptions import DeserializationError

    with pytest.raises(DeserializationError, match="cannot deserialize std_msgs/Header"):
        get_message_class("std_msgs/Header")().deserialize(b"\x01")
