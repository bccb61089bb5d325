"""TCPROS framing: connection headers, length-prefixed messages, service ok-byte replies."""
from __future__ import annotations

import socket
import struct

import pytest

from orchestra.node import tcpros
from orchestra.node.exceptions import TransportException


def test_header_encoding_is_length_prefixed_key_value_fields():
    data = tcpros.encode_header({"callerid": "/a", "md5sum": "*"})
    assert data == (struct.pack("<I", 4 + 11 + 4 + 8) + struct.pack("<I", 11) + b"callerid=/a"
                    + struct.pack("<I", 8) + b"md5sum=*")
    assert tcpros.decode_header(data[4:]) == {"callerid": "/a", "md5sum": "*"}


def test_header_values_may_contain_equals_and_newlines():
    fields = {"message_definition": "int32 A=1\nstring b\n", "type": "p/M"}
    assert tcpros.decode_header(tcpros.encode_header(fields)[4:]) == fields


@pytest.mark.parametrize("body", [b"\x05\x00\x00\x00abc", b"\x03\x00\x00\x00abc", b"\x01\x00"])
def test_malformed_header_is_a_transport_error(body):
    with pytest.raises(TransportException):
        tcpros.decode_header(body)


def test_messages_and_headers_travel_over_a_socket_pair():
    a, b = socket.socketpair()
    with a, b:
        tcpros.write_header(a, {"topic": "/t"})
        tcpros.send_message(a, b"payload")
        tcpros.send_message(a, bytearray(100_000))
        assert tcpros.read_header(b) == {"topic": "/t"}
        assert tcpros.read_message(b) == b"payload"
        assert tcpros.read_message(b) == bytes(100_000)


def test_service_reply_carries_an_ok_byte_before_the_body():
    a, b = socket.socketpair()
    with a, b:
        tcpros.send_service_response(a, True, b"\x2a" + bytes(7))
        tcpros.send_service_response(a, False, b"boom")
        raw_ok = b.recv(1)
        assert raw_ok == b"\x01"
        assert tcpros.read_message(b) == b"\x2a" + bytes(7)
        assert tcpros.read_service_response(b) == (False, b"boom")


def test_peer_closing_mid_message_is_reported():
    a, b = socket.socketpair()
    with b:
        a.sendall(struct.pack("<I", 10) + b"abc")
        a.close()
        with pytest.raises(TransportException, match="closed"):
            tcpros.read_message(b)


def test_oversized_header_is_refused_without_reading_it():
    a, b = socket.socketpair()
    with a, b:
        a.sendall(struct.pack("<I", tcpros.MAX_HEADER + 1))
        with pytest.raises(TransportException, match="refused"):
            tcpros.read_header(b)


def test_rosrpc_uri_parsing():
    assert tcpros.parse_rosrpc_uri("rosrpc://host.local:4567") == ("host.local", 4567)
    with pytest.raises(TransportException):
        tcpros.parse_rosrpc_uri("http://x:1/")


def test_bus_counters_beyond_32_bits_still_fit_in_xmlrpc():
    import xmlrpc.client

    from orchestra.node.topics import xmlrpc_int
    assert xmlrpc_int(5) == 5 and isinstance(xmlrpc_int(5), int)
    big = xmlrpc_int(3 * 2**31)
    assert xmlrpc.client.loads(xmlrpc.client.dumps(([big],)))[0][0] == [3 * 2**31]


def test_buffered_reader_reads_replies_in_order_whatever_one_recv_brings():
    import threading

    def send(sock):
        tcpros.write_header(sock, {"service": "/s"})
        tcpros.send_service_response(sock, True, b"one")
        tcpros.send_service_response(sock, False, b"two")
        tcpros.send_service_response(sock, True, bytes(range(256)) * 1000)  # > one recv
        tcpros.send_service_response(sock, True, b"")

    a, b = socket.socketpair()
    with a, b:
        writer = threading.Thread(target=send, args=(a,))
        writer.start()
        reader = tcpros.Reader(b)
        assert reader.header() == {"service": "/s"}
        assert reader.service_response() == (True, b"one")
        assert reader.service_response() == (False, b"two")
        assert reader.service_response() == (True, bytes(range(256)) * 1000)
        assert reader.service_response() == (True, b"")
        writer.join()
        a.sendall(struct.pack("<I", 10) + b"abc")
        a.close()
        with pytest.raises(TransportException, match="closed"):
            reader.message()
