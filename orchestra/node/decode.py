"""Decode raw messages (bytes plus the publisher's connection header) into message objects.

Used by ``topic echo`` (raw subscriptions) and the bag tools (messages from a bag): a
message is decoded with our own class for its type when the md5 matches, else with a class
built from the definition that travelled with it, so any type decodes, even without its
.msg file.
"""
from __future__ import annotations

from orchestra.node.exceptions import ROSException
from orchestra.node.msg import Message, MessageNotFound, get_message_class, message_class_from_definition


class RawDecoder:
    """Message classes per (type, md5), built once."""

    def __init__(self) -> None:
        self._classes: dict[tuple[str, str], type[Message]] = {}

    def message_class(self, header: dict[str, str]) -> type[Message]:
        key = (header.get("type", ""), header.get("md5sum", ""))
        cls = self._classes.get(key)
        if cls is None:
            found: type[Message] | None
            try:
                found = get_message_class(key[0])
                if found._md5sum != key[1]:
                    found = None
            except (MessageNotFound, ROSException):
                found = None
            cls = found or message_class_from_definition(
                key[0], header.get("message_definition", ""))
            self._classes[key] = cls
        return cls

    def decode(self, header: dict[str, str], data: bytes) -> Message:
        return self.message_class(header).deserialize_bytes(data)

    def __call__(self, raw) -> Message:
        """Decode an ``AnyMsg`` received on a raw subscription."""
        return self.decode(raw._connection_header, raw._buff)
