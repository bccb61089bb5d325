"""``bag filter`` expressions: what they may read of messages and times, and that hostile
expressions (frame escapes through attributes, huge values, deep nesting) are refused by the
shared evaluator (``orchestra.expression``), quickly and with a one-line reason."""
from __future__ import annotations

import pytest

from orchestra.bag.expression import ExpressionError, compile_expression
from orchestra.node.msg import get_message_class
from orchestra.node.rostime import Time

NAMES = frozenset({"topic", "m", "t"})


def _values():
    twist = get_message_class("geometry_msgs/Twist")()
    twist.linear.x = 1.5
    image = get_message_class("sensor_msgs/Image")(data=b"\x01" * 4096)
    image.header.stamp = Time(5, 500_000_000)
    return {"twist": {"topic": "/cmd_vel", "m": twist, "t": Time(7, 0)},
            "image": {"topic": "/camera", "m": image, "t": Time(8, 0)}}


def _run(text, which="twist"):
    return compile_expression(text, NAMES).evaluate(_values()[which])


@pytest.mark.parametrize("text, which, expected", [
    ("m.linear.x > 1 and topic == '/cmd_vel'", "twist", True),
    ("m.angular.z", "twist", 0.0),
    ("t.to_sec() + t.secs", "twist", 14.0),
    ("m.header.stamp.to_sec()", "image", 5.5),
    ("len(m.data) == 4096 and m.data[:2] == m.data[2:4]", "image", True),
    ("topic.startswith('/cam') and m.width == 0", "image", True),
    ("max(m.linear.x, 2) if topic in ('/a', '/cmd_vel') else 0", "twist", 2),
])
def test_filter_reads_public_message_fields_and_time_methods(text, which, expected):
    assert _run(text, which) == expected


@pytest.mark.parametrize("text", [
    "m.__class__", "t.__class__.__mro__", "m._connection_header", "m._type",
    "topic.__class__", "len.__self__", "t.to_sec.__globals__", "m.linear._slot_types",
    "m.serialize(b'')", "t.gi_frame()", "m.data.format(m)", "topic.split()",
    "getattr(m, 'gi_frame')", "type(m)", "vars(m)", "__import__('os')", "(lambda: m)()",
    "[x for x in m.data]", "(x for x in m.data)", "(y := m)", "f(*m.data)",
])
def test_filter_refuses_escapes_before_reading_any_message(text):
    with pytest.raises(ExpressionError):
        compile_expression(text, NAMES)


@pytest.mark.parametrize("text, why", [
    ("m.gi_frame", "AttributeError"),
    ("m.f_globals", "AttributeError"),
    ("t.to_sec", "not data"),
    ("m.linear.serialize", "not data"),
    ("topic.upper", "cannot be read"),
    ("len(topic).real", "cannot be read"),
])
def test_filter_refuses_attributes_that_are_not_message_data(text, why):
    with pytest.raises(ExpressionError, match=why):
        _run(text)


@pytest.mark.parametrize("text", [
    "'a' * 10**10", "m.data * 10**9", "10**10**10", "[m] * 10**7", "[m.data] * 100000",
    "'%999999999d' % 1", "m.data + m.data * 300", "1 << 10**6",
    "[" * 150 + "]" * 150, "-" * 1500 + "1",
])
def test_filter_refuses_expressions_that_would_exhaust_memory_or_time(text):
    with pytest.raises(ExpressionError):
        _run(text, "image")


@pytest.mark.parametrize("text, place", [
    ("topic ==", "at the end (column 9)"),
    ("  topic = 1", "at column 9"),
    ("topic == 'a' and (m", "'(' was never closed at column 18"),
    ("a b", "at column 3"),
])
def test_a_syntax_error_names_the_column_where_it_is(text, place):
    with pytest.raises(ExpressionError) as info:
        compile_expression(text, frozenset({"topic", "m", "t"}))
    assert str(info.value).endswith(place)
