"""XML-RPC documents to Python values and back, fast for the shapes ROS sends.

Every master call, node notification and tool query is one XML-RPC document each way. The
stdlib's ``xmlrpc.client.loads`` drives expat through Python callbacks (an element costs
three calls into Python) and its ``Marshaller`` dispatches every value through a method
lookup; together they were ~60 % of the master's time per call. Here one regular expression
cuts a document into tokens (a scalar ``<value>`` element whole, a container's opening and
closing tags one token each) and one loop walks them, checking the nesting as XML-RPC defines
it; values are written by one function.

That walk takes only documents in a plain subset of XML (UTF-8, no comments, DOCTYPE, CDATA,
attributes, namespaces or processing instructions, only the predefined entities and character
references) shaped as XML-RPC defines them: what every ROS peer sends. For those the stdlib
gives the same values (tests/test_xmlrpc_codec.py pins it on generated and mutated
documents); every other document goes to ``xmlrpc.client.loads``, so anything unusual or
broken gets exactly the stdlib's answer or error, and hostile input costs what it costs the
stdlib plus linear scans. ``dumps_*`` write what ``xmlrpc.client.dumps`` writes, byte for
byte, and leave anything but the built-in types to it.
"""
from __future__ import annotations

import base64
import re
import xmlrpc.client
from typing import Any

_Binary = xmlrpc.client.Binary
_DateTime = xmlrpc.client.DateTime
MAXINT = xmlrpc.client.MAXINT
MININT = xmlrpc.client.MININT


class _Unusual(Exception):
    """The document is outside the plain subset: the stdlib reads it instead."""


# -- reading ------------------------------------------------------------------------------------

# The XML declaration as xmlrpc.client and rospy/roscpp write it (utf-8 is XML's default).
_DECL = re.compile(r"<\?xml[ \t\r\n]+version[ \t\r\n]*=[ \t\r\n]*(['\"])1\.0\1"
                   r"(?:[ \t\r\n]+encoding[ \t\r\n]*=[ \t\r\n]*(['\"])(?i:utf-8)\2)?"
                   r"(?:[ \t\r\n]+standalone[ \t\r\n]*=[ \t\r\n]*(['\"])(?:yes|no)\3)?"
                   r"[ \t\r\n]*\?>")
_PLAIN_DECL = "<?xml version='1.0'?>"
# characters XML 1.0 does not allow
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]").search
_NOT_XML_ASCII = bytes([*range(0x00, 0x09), 0x0b, 0x0c, *range(0x0e, 0x20)])  # (as bytes)
_REF = re.compile(r"&(?:(lt|gt|amp|quot|apos)|#([0-9]+)|#x([0-9a-fA-F]+));")
_ENTITIES = {"lt": "<", "gt": ">", "amp": "&", "quot": '"', "apos": "'"}


def _char_ref(match: re.Match[str]) -> str:
    name, decimal, hexadecimal = match.groups()
    if name:
        return _ENTITIES[name]
    code = int(decimal) if decimal else int(hexadecimal, 16)
    if not (code in (0x9, 0xA, 0xD) or 0x20 <= code <= 0xD7FF or 0xE000 <= code <= 0xFFFD
            or 0x10000 <= code <= 0x10FFFF):
        raise _Unusual  # not an XML character: expat's error
    return chr(code)


def _text(raw: str) -> str:
    """Character data with its references replaced, as expat reports it."""
    if "&" not in raw:
        return raw
    if raw.count("&") != len(_REF.findall(raw)):
        raise _Unusual  # a bare '&' or an entity XML does not predefine
    return _REF.sub(_char_ref, raw)


# One token per match: whitespace, then the alternative whose named group closes last (the
# match's ``lastindex``). A scalar ``<value>`` is one token; containers open and close in one
# token each. Anything else is the last alternative, one character: the document is not
# plain. Alternatives are nested by their first characters (the engine tries them in order).
_TOKEN = re.compile(
    "[ \t\n]*(?:<(?:"
    "(?P<value>value>(?:"
    "[ \t\n]*<(?P<type>string|int|i4|double|boolean|i8|i1|i2|biginteger|float|base64"
    "|dateTime\\.iso8601)>(?P<typed>[^<]*)</(?P=type)>[ \t\n]*"
    "|(?P<untyped>[^<]*)|[ \t\n]*(?P<nil><nil/>)[ \t\n]*)</value>)"
    "|(?P<array>value>[ \t\n]*<array>[ \t\n]*<data>)"
    "|(?P<struct>value>[ \t\n]*<struct>)"
    "|(?P<param>param>)"
    "|(?P<params>params>)"
    "|(?P<member>member>[ \t\n]*<name>(?P<name>[^<]*)</name>)"
    "|(?P<call>methodCall>[ \t\n]*<methodName>(?P<method>[^<]*)</methodName>)"
    "|(?P<response>methodResponse>)"
    "|/(?:(?P<end_param>param>)"
    "|(?P<end_array>data>[ \t\n]*</array>[ \t\n]*</value>)"
    "|(?P<end_member>member>)"
    "|(?P<end_struct>struct>[ \t\n]*</value>)"
    "|(?P<end_params>params>)"
    "|(?P<end_call>methodCall>)"
    "|(?P<end_response>methodResponse>)))"
    "|(?P<other>[^ \t\n]))")
# A call whose arguments are all scalars (most calls a master gets), matched whole by the
# pattern for its number of <param>s (the document says how many: a scalar's text cannot
# hold a '<'): one match gives the method name and every value's type, text, untyped text
# and nil, no walk needed. Same subset and spacing rules as the tokens above.
_SCALAR_TYPES = ("string|int|i4|double|boolean|i8|i1|i2|biginteger|float|base64"
                 "|dateTime\\.iso8601")


def _flat_call(params: int) -> re.Pattern[str]:
    one = ("[ \t\n]*<param>[ \t\n]*<value>(?:[ \t\n]*<(?P<t{0}>" + _SCALAR_TYPES
           + ")>([^<]*)</(?P=t{0})>[ \t\n]*|([^<]*)|[ \t\n]*(<nil/>)[ \t\n]*)</value>"
           "[ \t\n]*</param>")
    return re.compile(
        "[ \t\n]*<methodCall>[ \t\n]*<methodName>([^<]*)</methodName>[ \t\n]*<params>"
        + "".join(one.format(i) for i in range(params))
        + "[ \t\n]*</params>[ \t\n]*</methodCall>")


# up to 8 params (the Master API's longest call has 4); longer calls take the walk below.
# Each is compiled when a call of its length first comes: compiling all nine costs ~6 ms,
# paid by every process that imports this module (the launcher, every node), which mostly
# see calls of 1 to 4 params. (Two threads may both compile one: the same pattern.)
_FLAT_CALLS: list[re.Pattern[str] | None] = [None] * 9


def _flat_pattern(params: int) -> re.Pattern[str] | None:
    """The whole-call pattern for ``params`` params, or None beyond the longest one."""
    if params >= len(_FLAT_CALLS):
        return None
    pattern = _FLAT_CALLS[params]
    if pattern is None:
        pattern = _FLAT_CALLS[params] = _flat_call(params)
    return pattern


_T = _TOKEN.groupindex
_TYPE, _TYPED, _UNTYPED, _NIL = _T["type"], _T["typed"], _T["untyped"], _T["nil"]
_NAME, _METHOD = _T["name"], _T["method"]
_INT_TYPES = frozenset(("int", "i4", "i8", "i1", "i2", "biginteger"))

# frames of the walk: what the innermost open element is
_NONE, _PARAMS, _PARAM, _ARRAY, _STRUCT, _MEMBER = range(6)


def loads(data: bytes | bytearray | str) -> tuple[tuple[Any, ...], str | None]:
    """``(params, method name or None)`` of an XML-RPC document, as ``xmlrpc.client.loads``
    gives them (Binary for base64, DateTime for dateTime.iso8601; a fault raises it)."""
    if isinstance(data, (bytes, bytearray)):
        try:
            result = _loads_plain(data)
        except Exception:  # not the plain subset, or an error: the stdlib's answer
            result = None
        if result is not None:
            return result
    return xmlrpc.client.loads(data)


def _scalar(kind: str | None, typed: str, untyped: str, nil: str) -> Any:
    """The value of one scalar ``<value>`` token, as the stdlib Unmarshaller makes it."""
    if kind is None:
        if nil:
            return None
        return _text(untyped) if "&" in untyped else untyped
    if "&" in typed:
        typed = _text(typed)
    if kind == "string":
        return typed
    if kind in _INT_TYPES:
        return int(typed)
    if kind == "double" or kind == "float":
        return float(typed)
    if kind == "boolean":
        if typed == "0":
            return False
        if typed == "1":
            return True
        raise _Unusual  # the stdlib's "bad boolean value"
    if kind == "base64":
        binary = _Binary()
        binary.decode(typed.encode("ascii"))
        return binary
    stamp = _DateTime()
    stamp.decode(typed)
    return stamp


def _loads_plain(data: bytes | bytearray) -> tuple[tuple[Any, ...], str | None] | None:
    """The document read in one pass over its tokens, when it is in the plain subset and
    shaped as XML-RPC documents are (then the stdlib reads it the same); None (or an
    exception) otherwise, and for a fault."""
    if data.isascii():  # the usual case: a C scan for control characters is enough
        if len(data.translate(None, _NOT_XML_ASCII)) != len(data):
            return None
        text = data.decode("ascii")
    else:
        text = data.decode("utf-8")
        if _NOT_XML(text):
            return None
    if "]]>" in text:
        return None
    if "\r" in text:  # XML's end-of-line handling, before references can make one
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    # trailing whitespace would cost the tokenizer a retry per character (quadratic)
    text = text.rstrip(" \t\n")
    start = 0
    if text.startswith(_PLAIN_DECL):  # what xmlrpc.client (and so rospy) writes
        start = len(_PLAIN_DECL)
    elif text.startswith("<?"):
        decl = _DECL.match(text)
        if decl is None:
            return None
        start = decl.end()
    params_count = text.count("<param>")
    pattern = _flat_pattern(params_count)
    flat = pattern.fullmatch(text, start) if pattern is not None else None
    if flat is not None:
        name, *groups = flat.groups("")
        return (tuple([_scalar(groups[i] or None, groups[i + 1], groups[i + 2], groups[i + 3])
                       for i in range(0, len(groups), 4)]),
                _text(name) if "&" in name else name)
    value_token, array_token, struct_token = _T["value"], _T["array"], _T["struct"]
    param_token, end_param_token, end_array_token = _T["param"], _T["end_param"], _T["end_array"]
    member_token, end_member_token = _T["member"], _T["end_member"]
    end_struct_token = _T["end_struct"]
    method: str | None = None
    root = ""         # "" before the root element, its name inside it, "/" after it
    params: list[Any] | None = None
    frames: list[int] = []
    containers: list[Any] = []
    frame = _NONE     # the innermost open element
    here: Any = None  # and its container: a list (params, array), a dict, a member [key]
    for match in _TOKEN.finditer(text, start):
        token = match.lastindex
        if token == value_token:
            value = _scalar(match[_TYPE], match[_TYPED], match[_UNTYPED], match[_NIL])
        elif token == end_param_token:
            if frame != _PARAM:
                return None
            frame = frames.pop()
            continue
        elif token == param_token:
            if frame != _PARAMS:
                return None
            frames.append(frame)
            frame = _PARAM
            continue
        elif token == array_token or token == struct_token:
            if not (frame == _PARAM or frame == _ARRAY or frame == _MEMBER and len(here) == 1):
                return None
            frames.append(frame)
            containers.append(here)
            if token == array_token:
                frame, here = _ARRAY, []
            else:
                frame, here = _STRUCT, {}
            continue
        elif token == end_array_token:
            if frame != _ARRAY:
                return None
            value = here
            frame, here = frames.pop(), containers.pop()
        elif token == member_token:
            if frame != _STRUCT:
                return None
            name = match[_NAME]
            frames.append(frame)
            containers.append(here)
            frame, here = _MEMBER, [_text(name) if "&" in name else name]
            continue
        elif token == end_member_token:
            if frame != _MEMBER or len(here) != 2:
                return None
            key, value = here
            frame, here = frames.pop(), containers.pop()
            here[key] = value
            continue
        elif token == end_struct_token:
            if frame != _STRUCT:
                return None
            value = here
            frame, here = frames.pop(), containers.pop()
        elif token == _T["params"]:
            if not root or root == "/" or frame != _NONE or params is not None:
                return None
            frames.append(frame)
            containers.append(here)
            frame, here = _PARAMS, []
            params = here
            continue
        elif token == _T["end_params"]:
            if frame != _PARAMS:
                return None
            frame, here = frames.pop(), containers.pop()
            continue
        elif token == _T["call"]:
            if root:
                return None
            root = "methodCall"
            name = match[_METHOD]
            method = _text(name) if "&" in name else name
            continue
        elif token == _T["response"]:
            if root:
                return None
            root = "methodResponse"
            continue
        elif token == _T["end_call"] or token == _T["end_response"]:
            if frame != _NONE or root != ("methodCall" if token == _T["end_call"]
                                          else "methodResponse"):
                return None
            root = "/"
            continue
        else:  # anything else
            return None
        # a value: into the open param, array or member
        if frame == _PARAM or frame == _ARRAY:
            here.append(value)
        elif frame == _MEMBER and len(here) == 1:
            here.append(value)
        else:
            return None
    if root != "/" or (params is None and method is None):
        return None
    return (tuple(params) if params else ()), method


# -- writing ------------------------------------------------------------------------------------

def _escape(text: str) -> str:
    if "&" in text:
        text = text.replace("&", "&amp;")
    if "<" in text:
        text = text.replace("<", "&lt;")
    if ">" in text:
        text = text.replace(">", "&gt;")
    return text


def _scalar_xml(value: Any) -> str | None:
    """A str, an int in range, a bool or a float as the stdlib writes it; None otherwise."""
    kind = type(value)
    if kind is str:
        if "&" in value or "<" in value or ">" in value:
            value = _escape(value)
        return f"<value><string>{value}</string></value>\n"
    if kind is int:
        if MININT <= value <= MAXINT:
            return f"<value><int>{value}</int></value>\n"
        return None
    if kind is float:
        return f"<value><double>{value!r}</double></value>\n"
    if kind is bool:
        return "<value><boolean>1</boolean></value>\n" if value else \
            "<value><boolean>0</boolean></value>\n"
    return None


def _write(value: Any, out: list[str], allow_none: bool, depth: int) -> None:
    """Append ``value`` as the stdlib Marshaller writes it; anything but the built-in types
    (subclasses, wrappers, instances), a None not allowed and very deep nesting are
    ``_Unusual``: the stdlib writes (or refuses) those. A container's scalars are written in
    its own loop (most values of a parameter tree are leaves)."""
    append = out.append
    kind = type(value)
    if kind is dict:
        if depth > 64:
            raise _Unusual  # the stdlib tells recursion from depth
        append("<value><struct>\n")
        for key, item in value.items():
            if type(key) is not str:
                raise _Unusual
            if "&" in key or "<" in key or ">" in key:
                key = _escape(key)
            leaf = _scalar_xml(item)
            if leaf is not None:
                append(f"<member>\n<name>{key}</name>\n{leaf}</member>\n")
            else:
                append(f"<member>\n<name>{key}</name>\n")
                _write(item, out, allow_none, depth + 1)
                append("</member>\n")
        append("</struct></value>\n")
    elif kind is list or kind is tuple:
        if depth > 64:
            raise _Unusual
        append("<value><array><data>\n")
        for item in value:
            leaf = _scalar_xml(item)
            if leaf is not None:
                append(leaf)
            else:
                _write(item, out, allow_none, depth + 1)
        append("</data></array></value>\n")
    elif kind is int and not MININT <= value <= MAXINT:
        raise OverflowError("int exceeds XML-RPC limits")
    elif kind is str or kind is int or kind is float or kind is bool:
        append(_scalar_xml(value) or "")
    elif value is None and allow_none:
        append("<value><nil/></value>")
    elif kind is bytes or kind is bytearray:
        append(f"<value><base64>\n{base64.encodebytes(value).decode('ascii')}"
               "</base64></value>\n")
    else:
        raise _Unusual


def _params(values: tuple[Any, ...], allow_none: bool) -> str:
    out = ["<params>\n"]
    for value in values:
        out.append("<param>\n")
        _write(value, out, allow_none, 0)
        out.append("</param>\n")
    out.append("</params>\n")
    return "".join(out)


def dumps_response(result: Any, allow_none: bool = False) -> bytes:
    """The methodResponse carrying ``result``, as ``xmlrpc.client.dumps((result,),
    methodresponse=True)`` writes it, encoded as a server sends it."""
    kind = type(result)
    if (kind is tuple or kind is list) and len(result) == 3:
        # a ROS answer [code, statusMessage, value] with a scalar value: most master
        # answers, written in one piece
        code, message, value = result
        code_xml, message_xml, value_xml = _scalar_xml(code), _scalar_xml(message), \
            _scalar_xml(value)
        if code_xml and message_xml and value_xml:
            return ("<?xml version='1.0'?>\n<methodResponse>\n<params>\n<param>\n"
                    "<value><array><data>\n" + code_xml + message_xml + value_xml
                    + "</data></array></value>\n</param>\n</params>\n</methodResponse>\n"
                    ).encode("utf-8", "xmlcharrefreplace")
    try:
        body = _params((result,), allow_none)
    except _Unusual:
        return xmlrpc.client.dumps((result,), methodresponse=True, allow_none=allow_none
                                   ).encode("utf-8", "xmlcharrefreplace")
    return ("<?xml version='1.0'?>\n<methodResponse>\n" + body + "</methodResponse>\n"
            ).encode("utf-8", "xmlcharrefreplace")


def dumps_fault(fault: xmlrpc.client.Fault, allow_none: bool = False) -> bytes:
    """The methodResponse carrying ``fault``, as ``xmlrpc.client.dumps(fault)`` writes it."""
    return xmlrpc.client.dumps(fault, allow_none=allow_none).encode("utf-8", "xmlcharrefreplace")


def dumps_call(method: str, params: tuple[Any, ...], allow_none: bool = False) -> bytes:
    """The methodCall of ``method(*params)``, as ``xmlrpc.client.dumps(params, method)``
    writes it, encoded as a client sends it."""
    try:
        body = _params(params, allow_none)
    except _Unusual:
        return xmlrpc.client.dumps(params, method, allow_none=allow_none
                                   ).encode("utf-8", "xmlcharrefreplace")
    return (f"<?xml version='1.0'?>\n<methodCall>\n<methodName>{method}</methodName>\n"
            + body + "</methodCall>\n").encode("utf-8", "xmlcharrefreplace")
