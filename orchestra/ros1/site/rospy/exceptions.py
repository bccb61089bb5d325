"""rospy.exceptions: orchestra's exception classes (what its runtime raises), under rospy's
names. The three rospy has and orchestra's runtime never raises are subclasses, so
``except`` clauses written for them are valid and catch what rospy's documentation says."""
from orchestra.node.exceptions import (
    ROSException,
    ROSInitException,
    ROSInterruptException,
    ROSTimeMovedBackwardsException,
    TransportException,
)
from orchestra.node.exceptions import SerializationError as ROSSerializationException


class ROSInternalException(Exception):
    """Base of rospy's internal errors (not a ROSException, as in rospy)."""


class TransportTerminated(TransportException):
    """A connection was closed while in use."""


class TransportInitError(TransportException):
    """A connection could not be set up."""


__all__ = ["ROSException", "ROSInitException", "ROSInterruptException", "ROSInternalException",
           "ROSSerializationException", "ROSTimeMovedBackwardsException",
           "TransportException", "TransportInitError", "TransportTerminated"]
