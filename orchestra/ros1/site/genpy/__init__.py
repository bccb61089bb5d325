"""genpy for orchestra's ROS 1 layer: the message base class, time types and errors.

Code written against generated messages sometimes imports genpy itself (``genpy.Message``
for isinstance checks, ``genpy.Time``/``genpy.Duration``, ``genpy.DeserializationError``);
these are the very classes orchestra's message classes use, so checks and ``except``
clauses see the same objects. The message classes themselves come from ``<pkg>.msg``
modules (orchestra.ros1.finder), not from generated code.
"""
from orchestra.node.exceptions import DeserializationError, SerializationError
from orchestra.node.msg import Message
from orchestra.node.rostime import Duration, Time
from orchestra.node.rostime import _TimeBase as TVal

#: genpy's common base of its two errors
MessageException = SerializationError

__all__ = ["DeserializationError", "Duration", "Message", "MessageException",
           "SerializationError", "TVal", "Time"]
