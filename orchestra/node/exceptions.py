"""Exceptions of the node API, with rospy's names so that ported scripts catch the same things."""
from __future__ import annotations


class ROSException(Exception):
    """Base error of the node runtime (timeouts, no master, bad state)."""


class ROSInterruptException(ROSException, KeyboardInterrupt):
    """Raised by blocking calls (``Rate.sleep``, ``wait_for_*``) once the node is shutting down.

    It is also a KeyboardInterrupt, as in rospy, so an uncaught one ends a script quietly-ish.
    """


class ROSTimeMovedBackwardsException(ROSInterruptException):
    """Simulated time (``/clock``) jumped backwards while ``sleep``/``Rate.sleep`` waited.

    ``time`` is the size of the jump in seconds. A subclass of ROSInterruptException, as in
    rospy, so loops that stop on an interrupt stop on a jump too.
    """

    def __init__(self, time: float):
        super().__init__("ROS time moved backwards")
        self.time = time


class ROSInitException(ROSException):
    """``init_node`` could not be completed (bad name, called twice with another name)."""


class ServiceException(ROSException):
    """A service call failed: unknown service, refused connection, or the handler raised."""


class TransportException(ROSException):
    """A TCPROS connection broke or spoke an unexpected protocol."""


class SerializationError(ROSException):
    """A message value does not fit its declared field type."""


class DeserializationError(SerializationError):
    """Bytes that are not a serialized message of the expected type (genpy's name)."""
