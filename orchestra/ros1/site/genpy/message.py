"""genpy.message for the layer: ``Message``, the errors and ``strify_message`` (genpy's
YAML-like text of a message, which ``str(msg)`` also gives)."""
from orchestra.node.exceptions import DeserializationError, SerializationError
from orchestra.node.msg import Message, strify_message

MessageException = SerializationError

__all__ = ["DeserializationError", "Message", "MessageException", "SerializationError",
           "strify_message"]
