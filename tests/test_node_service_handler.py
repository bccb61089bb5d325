"""What a service handler's return value becomes on the wire: a response, or, as rospy
answers, an error for the caller when the handler returns None or something that is not the
response (``service cannot process request: ...``) or raises (``error processing
request: ...``). The server is driven over a socket pair: no master, no processes."""
from __future__ import annotations

import socket

import pytest

from orchestra.node import tcpros
from orchestra.node.msg import get_service_class
from orchestra.node.services import ServiceServer

TRIGGER = get_service_class("std_srvs/Trigger")


def _reply(handler):
    server = ServiceServer(None, "/svc", TRIGGER, handler)
    ours, theirs = socket.socketpair()
    with ours, theirs:
        server._answer(ours, TRIGGER._request_class().serialize_bytes(), "/caller")
        return tcpros.read_service_response(theirs)


def test_a_handler_returning_a_response_answers_ok():
    ok, body = _reply(lambda req: TRIGGER._response_class(success=True, message="done"))
    assert ok and TRIGGER._response_class.deserialize_bytes(body).message == "done"


@pytest.mark.parametrize("handler, error", [
    (lambda req: None, "service cannot process request: service handler returned None"),
    (lambda req: get_service_class("std_srvs/SetBool")._response_class(),
     "service cannot process request: handler returned a std_srvs/SetBoolResponse"),
    (lambda req: 1 / 0, "error processing request: division by zero"),
])
def test_a_handler_without_a_response_is_an_error_for_the_caller(handler, error):
    ok, body = _reply(handler)
    assert not ok and body.decode().startswith(error)
