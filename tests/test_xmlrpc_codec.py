"""orchestra's XML-RPC reading and writing equals the stdlib's (xmlrpc.client), both ways.

The codec reads the documents ROS sends in one regex pass and hands everything else to
``xmlrpc.client.loads``; these tests pin that the result (value, method name, or the error)
is the stdlib's for generated values written every way a peer writes them, and for mutated
documents; and that the writers produce the stdlib's bytes. ``ORCHESTRA_FUZZ_EXAMPLES=N``
runs N examples per property (a long run).
"""
from __future__ import annotations

import math
import os
import re
import xmlrpc.client
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from orchestra import xmlrpc_codec

_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")

# ORCHESTRA_FUZZ_EXAMPLES=N runs N examples per test (a long run), as in test_fuzz.py
_LONG = int(os.environ.get("ORCHESTRA_FUZZ_EXAMPLES", "0"))
SETTINGS = settings(max_examples=_LONG or 150, deadline=None, database=None,
                    suppress_health_check=list(HealthCheck))

_TEXT = st.text(st.characters(blacklist_categories=("Cs",)), max_size=12) | st.sampled_from(
    ["", " ", "a&b", "<tag>", "]]", "x\r\ny", "\r", "&amp;", "tab\there", "é✓𝄞", "\x01",
     "\ufffe"])
_SCALARS = (_TEXT | st.integers(xmlrpc.client.MININT, xmlrpc.client.MAXINT)
            | st.integers() | st.booleans() | st.floats() | st.none()
            | st.binary(max_size=12))
_VALUES = st.recursive(
    _SCALARS,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(_TEXT, inner, max_size=4)
    | st.lists(inner, max_size=3).map(tuple),
    max_leaves=12)


def _canonical(value: Any) -> Any:
    """``value`` with types made explicit (True == 1 and nan != nan otherwise hide a
    difference, Binary/DateTime compare by content)."""
    if isinstance(value, (list, tuple)):
        return (type(value).__name__, [_canonical(v) for v in value])
    if isinstance(value, dict):
        return ("dict", [(k, _canonical(v)) for k, v in value.items()])
    if isinstance(value, float) and math.isnan(value):
        return ("float", "nan")
    if isinstance(value, xmlrpc.client.Binary):
        return ("Binary", value.data)
    if isinstance(value, xmlrpc.client.DateTime):
        return ("DateTime", value.value)
    return (type(value).__name__, value)


def _outcome(read, data: bytes) -> Any:
    try:
        return ("ok", _canonical(read(data)))
    except xmlrpc.client.Fault as fault:
        return ("fault", fault.faultCode, fault.faultString)
    except Exception as exc:  # the stdlib's error, whatever it is
        return ("error", type(exc).__name__, str(exc))


def _same_as_stdlib(data: bytes) -> None:
    assert _outcome(xmlrpc_codec.loads, data) == _outcome(xmlrpc.client.loads, data)


def _stdlib_dumps(values: tuple, **kw: Any) -> Any:
    try:
        return ("ok", xmlrpc.client.dumps(values, allow_none=True, **kw)
                .encode("utf-8", "xmlcharrefreplace"))
    except Exception as exc:
        return ("error", type(exc).__name__, str(exc))


def _ours(write, *args: Any) -> Any:
    try:
        return ("ok", write(*args))
    except Exception as exc:
        return ("error", type(exc).__name__, str(exc))


@SETTINGS
@given(_VALUES)
def test_response_bytes_equal_the_stdlib_marshaller(value):
    assert (_ours(xmlrpc_codec.dumps_response, value, True)
            == _stdlib_dumps((value,), methodresponse=True))


@SETTINGS
@given(st.sampled_from(["getParam", "setParam", "system.multicall"]),
       st.lists(_VALUES, max_size=4).map(tuple))
def test_call_bytes_equal_the_stdlib_marshaller(method, params):
    assert _ours(xmlrpc_codec.dumps_call, method, params, True) == _stdlib_dumps(
        params, methodname=method)


def test_none_is_refused_unless_allowed_as_by_the_stdlib():
    with pytest.raises(TypeError, match="allow_none"):
        xmlrpc_codec.dumps_response([1, "x", None])
    assert b"<nil/>" in xmlrpc_codec.dumps_response([1, "x", None], allow_none=True)


def test_objects_the_stdlib_writes_specially_are_written_by_it():
    stamp = xmlrpc.client.DateTime("20240102T03:04:05")
    value = {"when": stamp, "blob": xmlrpc.client.Binary(b"\x00\x01"), "flag": True}
    assert xmlrpc_codec.dumps_response(value) == xmlrpc.client.dumps(
        (value,), methodresponse=True).encode()


def test_faults_are_written_as_the_stdlib_writes_them():
    fault = xmlrpc.client.Fault(1, "<class 'Exception'>:method \"x\" is not supported")
    assert xmlrpc_codec.dumps_fault(fault) == xmlrpc.client.dumps(fault).encode()


# -- reading ------------------------------------------------------------------------------------

def _untyped(document: str) -> str:
    """Strings written as roscpp (XmlRpc++) writes them: ``<value>text</value>``."""
    return document.replace("<value><string>", "<value>").replace("</string></value>",
                                                                  "</value>")


def _spaced(document: str) -> str:
    """Whitespace where XML allows it and XML-RPC ignores it, CRLF line ends, double quotes."""
    return (document.replace("<value><", "<value>\r\n  <").replace("></value>", ">\t</value>")
            .replace("<data>", "<data>\r\n").replace("\n", "\r\n")
            .replace("<?xml version='1.0'?>", '<?xml version="1.0" encoding="UTF-8"?>'))


_SHAPES = [lambda d: d, _untyped, _spaced, lambda d: _spaced(_untyped(d))]


@SETTINGS
@given(st.lists(_VALUES, max_size=4).map(tuple), st.sampled_from(_SHAPES),
       st.sampled_from(["response", "call"]))
def test_documents_read_as_the_stdlib_reads_them(params, shape, kind):
    if kind == "response":
        params = params[:1] or ("x",)
    try:
        document = xmlrpc.client.dumps(params, methodname="setParam" if kind == "call" else None,
                                       methodresponse=kind == "response", allow_none=True)
    except (OverflowError, TypeError):
        return  # not writable: nothing to read
    data = shape(document).encode("utf-8", "xmlcharrefreplace")
    _same_as_stdlib(data)


@SETTINGS
@given(st.lists(_VALUES, max_size=3).map(tuple))
def test_ros_documents_are_read_without_the_stdlib(params):
    """The plain path is taken for what ROS peers write (else the speed is lost silently)."""
    try:
        document = xmlrpc.client.dumps(params, "setParam", allow_none=True)
    except OverflowError:
        return
    if _NOT_XML.search(document):
        return  # text that is not XML: the stdlib's to refuse
    for shape in _SHAPES:
        data = shape(document).encode()
        assert xmlrpc_codec._loads_plain(data) is not None, data


_EDITS = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 6),
                            st.binary(max_size=4) | st.sampled_from(
                                [b"\x00", b"\xff", b"<", b">", b"&", b"&#0;", b"&#65;",
                                 b"&lt;", b"&bogus;", b"]]>", b"<!-- c -->", b"<![CDATA[x]]>",
                                 b"<value>", b"</value>", b"<array><data>", b"</data></array>",
                                 b"<struct>", b"<member><name>k</name>", b"</member>",
                                 b"<nil/>", b"<value/>", b"<bogus/>", b"<fault>", b"<param>",
                                 b" a='1'", b"ex:", b"\r\n", b"\t", b"\xef\xbb\xbf",
                                 b"<?xml version='1.0'?>", b"<!DOCTYPE x>"])),
                  min_size=1, max_size=5)


@settings(max_examples=_LONG or 400, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(st.lists(_VALUES, max_size=3).map(tuple), st.sampled_from(_SHAPES), _EDITS)
def test_mutated_documents_get_the_stdlibs_answer_or_error(params, shape, edits):
    try:
        document = xmlrpc.client.dumps(params, "setParam", allow_none=True)
    except (OverflowError, TypeError):
        return
    data = shape(document).encode("utf-8", "xmlcharrefreplace")
    for position, delete, insert in edits:
        at = position % (len(data) + 1)
        data = data[:at] + insert + data[at + delete:]
    _same_as_stdlib(data)


@pytest.mark.parametrize("document", [
    b"<?xml version='1.0'?><methodResponse><fault><value><struct><member><name>faultCode"
    b"</name><value><int>1</int></value></member><member><name>faultString</name><value>"
    b"<string>no</string></value></member></struct></value></fault></methodResponse>",
    b"<methodCall><methodName>m</methodName></methodCall>",
    b"<methodCall><methodName>m</methodName><params/></methodCall>",
    b"<methodResponse><params><param><value><bigdecimal>1.5</bigdecimal></value></param>"
    b"</params></methodResponse>",
    b"<methodResponse><params><param><value><dateTime.iso8601>20240102T03:04:05"
    b"</dateTime.iso8601></value></param></params></methodResponse>",
    b"<methodResponse><params><param><value><base64>AAE=</base64></value></param></params>"
    b"</methodResponse>",
    b"<methodResponse><params></params></methodResponse><methodResponse>",
    b"<methodResponse><params><param><value><i4> 7 </i4></value></param></params>"
    b"</methodResponse>   \n\t  ",
    b"<methodResponse><params><param><value><struct><member><name>a</name><value>1</value>"
    b"<value>2</value></member></struct></value></param></params></methodResponse>",
    b"<methodCall><methodName>a&amp;b&#x41;&#66;</methodName><params><param><value>&lt;"
    b"&gt;&quot;&apos;</value></param></params></methodCall>",
    b"",
    b"   ",
    b"<methodResponse>" + b" " * 10000,
])
def test_edge_documents_get_the_stdlibs_answer_or_error(document):
    _same_as_stdlib(document)
