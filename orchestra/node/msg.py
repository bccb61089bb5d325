"""Message and service classes, built at run time from their definitions.

Where definitions come from, in order: rosbags' ROS 1 (noetic) type store for the standard
message packages, the few standard definitions rosbags lacks (``definitions/``: std_srvs,
tf2_msgs, ...), then ``msg/*.msg`` and ``srv/*.srv`` of the package found by
``orchestra.packages.find_package``. Classes are cached per process. A class has rospy's
shape: ``__slots__`` = fields, ``_type``, ``_md5sum``, ``_full_text``, ``_slot_types``, a
constructor taking positional or keyword field values (every other field defaulted).
"""
from __future__ import annotations

import threading
from typing import Any, ClassVar, cast

from orchestra.node import msgdefs, msgspec
from orchestra.node.exceptions import DeserializationError, ROSException, SerializationError
from orchestra.node.msgspec import MsgSpec, SrvSpec
from orchestra.node.rostime import Duration, Time
from orchestra.node.serialization import compile_codec


class MessageNotFound(ROSException):
    """No definition of a message or service type could be found."""


class Message:
    """Base of every message class; fields are the class's ``__slots__``."""

    __slots__ = ("_connection_header",)
    _connection_header: dict[str, str]  # set on received messages (the publisher's header)
    _type = ""
    _md5sum = ""
    _full_text = ""
    _has_header = False
    _slot_types: list[str] = []
    _fields: tuple[str, ...] = ()
    _spec: MsgSpec | None = None
    #: generated per class (serialization.compile_codec)
    _ser: ClassVar[Any]     # (msg, out: bytearray) -> out
    _deser: ClassVar[Any]   # (buf: bytes, pos) -> (msg, pos)

    def __init__(self, *args, **kwargs):
        # genpy's rules and messages: positional values for ALL fields, or keywords for
        # some; a field left out or given as None gets its default
        if args and kwargs:
            raise TypeError("Message constructor may only use args OR keywords, not both")
        self._defaults(self)
        if args:
            if len(args) != len(self._fields):
                raise TypeError(f"Invalid number of arguments, args should be "
                                f"{list(self._fields)} args are{args}")
            for name, value in zip(self._fields, args, strict=True):
                if value is not None:
                    setattr(self, name, value)
            return
        for name, value in kwargs.items():
            if name not in self._fields:
                raise AttributeError(f"{name} is not an attribute of {type(self).__name__}")
            if value is not None:
                setattr(self, name, value)

    @staticmethod
    def _defaults(m) -> None:  # replaced per class
        pass

    # --- wire format -------------------------------------------------------------------
    def serialize_bytes(self) -> bytes | bytearray:
        """The ROS 1 serialization of this message."""
        out = bytearray()
        try:
            self._ser(self, out)
        except SerializationError:
            raise
        except (TypeError, ValueError, AttributeError, OverflowError, Exception) as exc:
            raise SerializationError(f"cannot serialize {self._type}: {exc}") from exc
        return out

    @classmethod
    def deserialize_bytes(cls, data) -> Message:
        """A new message read from its ROS 1 serialization."""
        if not isinstance(data, bytes):
            data = bytes(data)
        try:
            msg, _ = cls._deser(data, 0)
        except DeserializationError:
            raise
        except Exception as exc:
            raise DeserializationError(f"cannot deserialize {cls._type}: {exc}") from exc
        return msg

    def serialize(self, buff) -> None:
        """rospy's spelling: write the serialization into a file-like ``buff``."""
        buff.write(self.serialize_bytes())

    def deserialize(self, data) -> Message:
        """rospy's spelling: fill this instance from ``data`` and return it."""
        other = self.deserialize_bytes(data)
        for name in self._fields:
            setattr(self, name, getattr(other, name))
        return self

    def serialize_numpy(self, buff, numpy=None) -> None:
        """genpy's numpy variant: numpy arrays (and scalars) serialize like lists already."""
        self.serialize(buff)

    def deserialize_numpy(self, data, numpy) -> Message:
        """genpy's numpy variant: numeric array fields (uint8[] stays bytes) become arrays of
        their ROS type's dtype, in nested messages too."""
        self.deserialize(data)
        _to_numpy(self, numpy)
        return self

    def _get_types(self) -> list[str]:
        return list(self._slot_types)

    # --- python niceties ----------------------------------------------------------------
    def __eq__(self, other) -> bool:
        if not isinstance(other, type(self)):
            return False
        for name in self._fields:
            a, b = getattr(self, name), getattr(other, name)
            if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
                if tuple(a) != tuple(b):
                    return False
            elif a != b:
                return False
        return True

    def __ne__(self, other) -> bool:
        return not self == other

    __hash__ = None  # type: ignore[assignment]  # mutable

    def __repr__(self) -> str:
        return to_yaml_text(self)

    __str__ = __repr__

    def __getstate__(self):
        return [getattr(self, n) for n in self._fields]

    def __setstate__(self, state) -> None:
        for name, value in zip(self._fields, state, strict=False):
            setattr(self, name, value)


_DTYPES = {"bool": "bool", "int8": "int8", "byte": "int8", "uint8": "uint8", "char": "uint8",
           "int16": "int16", "uint16": "uint16", "int32": "int32", "uint32": "uint32",
           "int64": "int64", "uint64": "uint64", "float32": "float32", "float64": "float64"}


def _to_numpy(msg: Message, numpy: Any) -> None:
    for f in msg._spec.fields if msg._spec is not None else ():
        value = getattr(msg, f.name)
        if f.array is not None and f.base in _DTYPES and f.base not in ("uint8", "char"):
            setattr(msg, f.name, numpy.array(value, dtype=numpy.dtype(_DTYPES[f.base])))
        elif isinstance(value, Message):
            _to_numpy(value, numpy)
        elif f.array is not None and not f.is_builtin:
            for item in value:
                _to_numpy(item, numpy)


class AnyMsg(Message):
    """Subscribe to any type: the callback gets the raw bytes in ``_buff`` and the publisher's
    connection header (``type``, ``md5sum``, ``message_definition``) in ``_connection_header``."""

    __slots__ = ("_buff",)
    _type = "*"
    _md5sum = "*"

    def __init__(self, *args):
        self._buff = args[0] if args else b""

    def serialize_bytes(self) -> bytes:
        return self._buff

    @classmethod
    def deserialize_bytes(cls, data) -> AnyMsg:
        return cls(bytes(data))


class ServiceDefinition:
    """Base of service classes: ``_type``, ``_md5sum``, ``_request_class``/``Request``, ..."""

    _type = ""
    _md5sum = ""
    _request_class: type[Message] = Message
    _response_class: type[Message] = Message
    Request: type[Message] = Message
    Response: type[Message] = Message


# --- the registry ---------------------------------------------------------------------------

def normalise_type(name: str) -> str:
    """``pkg/msg/Name`` (ROS 2 / rosbags spelling) and ``pkg/Name`` both mean ``pkg/Name``."""
    name = name.strip()
    parts = name.split("/")
    if len(parts) == 3 and parts[1] in ("msg", "srv"):
        return f"{parts[0]}/{parts[2]}"
    if name == "Header":
        return "std_msgs/Header"
    return name


class Registry:
    """Type name -> spec -> class, loaded on first use from the sources listed above."""

    def __init__(self, preloaded: dict[str, MsgSpec] | None = None,
                 parent: Registry | None = None):
        self._lock = threading.RLock()
        self._specs: dict[str, MsgSpec] = dict(preloaded or {})
        self._md5: dict[str, str] = {}
        self._classes: dict[str, type[Message]] = {}
        self._srv_classes: dict[str, type[ServiceDefinition]] = {}
        self._parent = parent

    def spec(self, msg_type: str) -> MsgSpec:
        msg_type = normalise_type(msg_type)
        with self._lock:
            found = self._specs.get(msg_type)
            if found is not None:
                return found
            if self._parent is not None:
                try:
                    return self._parent.spec(msg_type)
                except MessageNotFound:
                    pass
            if "/" not in msg_type:
                raise MessageNotFound(f"message type {msg_type!r} must be 'package/Name'")
            definition = msgdefs.find_message(msg_type)
            if definition is None:
                pkg, _, name = msg_type.partition("/")
                raise MessageNotFound(f"cannot find message type {msg_type} (not a standard "
                                      f"type, and no {pkg}/msg/{name}.msg in a package)")
            spec = msgspec.parse_msg(definition.text, msg_type, definition.path or None,
                                     definition.first_line)
            self._specs[msg_type] = spec
            return spec

    def md5(self, msg_type: str) -> str:
        msg_type = normalise_type(msg_type)
        with self._lock:
            if msg_type not in self._md5:
                if self._parent is not None and msg_type not in self._specs:
                    try:
                        return self._parent.md5(msg_type)
                    except MessageNotFound:
                        pass
                spec = self.spec(msg_type)
                if msg_type not in self._md5:
                    self._md5[msg_type] = msgspec.compute_md5(spec, self.spec, self.md5)
            return self._md5[msg_type]

    # classes ------------------------------------------------------------------------------
    def message_class(self, msg_type: str) -> type[Message]:
        msg_type = normalise_type(msg_type)
        with self._lock:
            cls = self._classes.get(msg_type)
            if cls is None:
                if self._parent is not None and msg_type not in self._specs:
                    try:
                        return self._parent.message_class(msg_type)
                    except MessageNotFound:
                        pass
                cls = self._build(self.spec(msg_type))
            return cls

    def _nested(self, spec: MsgSpec) -> dict[str, type[Message]]:
        """The classes of ``spec``'s nested types; an unknown one is an error of ``spec``'s
        definition, named at the line of the field that uses it."""
        nested: dict[str, type[Message]] = {}
        for f in spec.fields:
            if f.is_builtin or f.base in nested:
                continue
            try:
                nested[f.base] = self.message_class(f.base)
            except MessageNotFound:
                raise msgspec.MsgSpecError(
                    f"{spec.where(f)}: unknown type {f.base!r} of field '{f.name}' in "
                    f"{spec.type} (no such message type)") from None
        return nested

    def _build(self, spec: MsgSpec, md5: str | None = None) -> type[Message]:
        nested = self._nested(spec)
        attrs: dict[str, Any] = {
            "__slots__": tuple(f.name for f in spec.fields),
            "_type": spec.type,
            "_md5sum": md5 or self.md5(spec.type),
            "_full_text": msgspec.full_text(spec, self.spec),
            "_slot_types": [f.type_text for f in spec.fields],
            "_fields": tuple(f.name for f in spec.fields),
            "_has_header": bool(spec.fields) and spec.fields[0].base == "std_msgs/Header",
            "_spec": spec,
            "__module__": f"{spec.package}.msg",
        }
        for const in spec.constants:
            if const.name not in attrs["_fields"]:
                attrs[const.name] = const.value
        cls = cast(type[Message], type(spec.type.split("/")[1], (Message,), attrs))
        ser, deser, defaults, _source = compile_codec(cls, spec, nested)
        cls._ser = staticmethod(ser)
        cls._deser = staticmethod(deser)
        cls._defaults = staticmethod(defaults)  # type: ignore[method-assign]
        self._classes[spec.type] = cls
        return cls

    def service_class(self, srv_type: str) -> type[ServiceDefinition]:
        srv_type = normalise_type(srv_type)
        with self._lock:
            cls = self._srv_classes.get(srv_type)
            if cls is not None:
                return cls
            if "/" not in srv_type:
                raise MessageNotFound(f"service type {srv_type!r} must be 'package/Name'")
            definition = msgdefs.find_service(srv_type)
            if definition is None:
                pkg, _, name = srv_type.partition("/")
                raise MessageNotFound(f"cannot find service type {srv_type} "
                                      f"(no {pkg}/srv/{name}.srv in a package)")
            spec = msgspec.parse_srv(definition.text, srv_type, definition.path or None)
            cls = self._build_service(spec)
            self._srv_classes[srv_type] = cls
            return cls

    def _build_service(self, spec: SrvSpec) -> type[ServiceDefinition]:
        for part in (spec.request, spec.response):
            self._specs[part.type] = part
        request = self.message_class(spec.request.type)
        response = self.message_class(spec.response.type)
        request.__module__ = response.__module__ = f"{spec.type.split('/')[0]}.srv"
        md5 = msgspec.compute_srv_md5(spec, self.spec, self.md5)
        return type(spec.type.split("/")[1], (ServiceDefinition,), {
            "_type": spec.type, "_md5sum": md5,
            "_request_class": request, "_response_class": response,
            "Request": request, "Response": response, "__module__": f"{spec.type.split('/')[0]}.srv",
        })


_REGISTRY = Registry()


def get_message_class(msg_type: str) -> type[Message]:
    """The class of ``pkg/Name`` (``MessageNotFound`` when no definition exists)."""
    return _REGISTRY.message_class(msg_type)


def get_service_class(srv_type: str) -> type[ServiceDefinition]:
    """The service class of ``pkg/Name``: ``.Request``, ``.Response``, ``_type``, ``_md5sum``."""
    return _REGISTRY.service_class(srv_type)


def message_class_from_definition(msg_type: str, definition: str) -> type[Message]:
    """A class built from a connection header's full text: how ``topic echo`` decodes types
    it has no ``.msg`` file for. Kept out of the process registry."""
    msg_type = normalise_type(msg_type)
    specs = msgspec.parse_full_text(definition, msg_type)
    return Registry(preloaded=specs).message_class(msg_type)


# --- YAML views (rostopic conventions) -----------------------------------------------------

def to_plain(value: Any) -> Any:
    """A message as plain dicts/lists (time -> {secs, nsecs}, uint8[] -> list of ints)."""
    if isinstance(value, Message):
        return {name: to_plain(getattr(value, name)) for name in value._fields}
    if isinstance(value, (Time, Duration)):
        return {"secs": value.secs, "nsecs": value.nsecs}
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    if isinstance(value, (list, tuple)):
        return [to_plain(v) for v in value]
    return value


def _strify(value: Any, indent: str, slot_type: str = "") -> str:
    if isinstance(value, bool) or isinstance(value, (int, float)):
        return str(value)
    if isinstance(value, str):
        if not value:
            return "''"
        import yaml  # here: a message import should not pay for YAML until one is printed

        return yaml.dump(value, default_style='"').rstrip("\n")
    if isinstance(value, (Time, Duration)):
        return f"\n{indent}secs: {value.secs}\n{indent}nsecs: {value.nsecs:9d}"
    if isinstance(value, (bytes, bytearray)) and (not slot_type or "uint8[" in slot_type):
        value = list(value)   # genpy shows uint8[] as numbers (char[] stays bytes)
    if isinstance(value, (list, tuple)):
        if not value:
            return "[]"
        first = value[0]
        if isinstance(first, str):
            # genpy: a YAML block list, one "- item" line per string at this field's indent
            import yaml

            text = yaml.dump(list(value), default_flow_style=False)
            return "\n" + "\n".join(indent + line for line in text.splitlines())
        if type(first) in (int, float, bool):
            return str(list(value))
        prefix = indent + "- "
        inner = indent + "  "
        return "\n" + "\n".join(prefix + _strify(v, inner) for v in value)
    if isinstance(value, Message):
        child = "  " + indent
        lines = [f"{indent}{name}: {_strify(getattr(value, name), child, t)}"
                 for name, t in zip(value._fields, value._slot_types, strict=False)]
        text = "\n".join(lines)
        return "\n" + text if indent else text
    return str(value)


def strify_message(val: Any, indent: str = "") -> str:
    """genpy's ``strify_message``: the text ``str(msg)`` gives; with ``indent``, a message's
    lines are indented and preceded by a newline (how nested values are laid out)."""
    return _strify(val, indent)


def to_yaml_text(msg: Any) -> str:
    """A message (or one field's value) as ``rostopic echo`` prints it (genpy's layout,
    e.g. ``nsecs`` right-aligned to width 9)."""
    return _strify(msg, "").lstrip("\n")


class FillError(ROSException):
    """A YAML value that does not fit the message it should fill."""


def _fill_field(current: Any, value: Any, base: str, array: int | None, path: str) -> Any:
    from orchestra.node.msgspec import PRIMITIVES

    if array is not None:
        if base in ("uint8", "char") and isinstance(value, (bytes, str)):
            return value.encode() if isinstance(value, str) else value
        if not isinstance(value, (list, tuple)):
            raise FillError(f"field {path} must be a list, not {type(value).__name__}")
        if array >= 0 and len(value) != array:
            raise FillError(f"field {path} must have {array} elements, not {len(value)}")
        if base in PRIMITIVES or base == "string":
            items = [_fill_field(None, v, base, None, f"{path}[{i}]") for i, v in enumerate(value)]
            return bytes(items) if base in ("uint8", "char") else items
        if base in ("time", "duration"):
            tcls = Time if base == "time" else Duration
            return [_fill_field(tcls(), v, base, None, f"{path}[{i}]") for i, v in enumerate(value)]
        mcls = get_message_class(base) if not isinstance(current, list) or not current \
            else type(current[0])
        return [fill_message(mcls(), v, f"{path}[{i}]") for i, v in enumerate(value)]
    if base in ("time", "duration"):
        cls = Time if base == "time" else Duration
        if isinstance(value, dict):
            unknown = set(value) - {"secs", "nsecs"}
            if unknown:
                raise FillError(f"field {path}: unknown keys {sorted(unknown)} (secs, nsecs)")
            parts = []
            for key in ("secs", "nsecs"):
                try:
                    parts.append(int(value.get(key, 0)))
                except (TypeError, ValueError):
                    raise FillError(f"field {path}.{key} must be an integer, "
                                    f"not {value[key]!r}") from None
            return cls(*parts)
        if value == "now" and base == "time":
            return Time.now()
        if isinstance(value, int) and not isinstance(value, bool):
            return cls(0, value)   # as genpy (rostopic pub): a bare integer is nanoseconds
        if isinstance(value, float):
            return cls.from_sec(value)   # genpy refuses a float; seconds is what it means
        now = ", a number or 'now'" if base == "time" else " or a number"
        raise FillError(f"field {path} must be {{secs, nsecs}}{now}, not {value!r}")
    if base == "string":
        if not isinstance(value, str):
            if isinstance(value, (dict, list)):
                raise FillError(f"field {path} must be a string")
            value = str(value)
        return value
    if base in ("float32", "float64"):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise FillError(f"field {path} must be a number, not {value!r}")
        return float(value)
    if base == "bool":
        if isinstance(value, bool) or value in (0, 1):
            return bool(value)
        raise FillError(f"field {path} must be true or false, not {value!r}")
    if base in PRIMITIVES:
        if isinstance(value, bool) or not isinstance(value, int):
            raise FillError(f"field {path} must be an integer, not {value!r}")
        return value
    return fill_message(current if isinstance(current, Message) else get_message_class(base)(),
                        value, path)


def fill_message(msg: Message, value: Any, path: str = "") -> Message:
    """Fill ``msg`` from YAML data: a dict by field name, a list in field order, or a single
    value for a one-field message (what ``rostopic pub`` accepts)."""
    spec = msg._spec
    fields = spec.fields if spec is not None else ()
    if value is None:
        return msg
    if msg._type == "std_msgs/Header" and value == "auto":
        # rostopic pub's substitution: a header stamped now (seq is the publisher's, frame_id
        # empty); here also for a whole std_msgs/Header message, which rostopic refuses
        for name, now in (("seq", 0), ("stamp", Time.now()), ("frame_id", "")):
            setattr(msg, name, now)
        return msg
    if isinstance(value, dict):
        by_name = {f.name: f for f in fields}
        for key, val in value.items():
            if key not in by_name:
                raise FillError(f"{msg._type} has no field {path + '.' if path else ''}{key} "
                                f"(fields: {', '.join(by_name) or 'none'})")
            f = by_name[key]
            sub = f"{path}.{key}" if path else key
            setattr(msg, key, _fill_field(getattr(msg, key), val, f.base, f.array, sub))
        return msg
    if isinstance(value, list) and not (len(fields) == 1 and fields[0].array is not None):
        if len(value) != len(fields):
            raise FillError(f"{msg._type} takes {len(fields)} values "
                            f"({', '.join(f.name for f in fields)}), got {len(value)}")
        for f, val in zip(fields, value, strict=False):
            sub = f"{path}.{f.name}" if path else f.name
            setattr(msg, f.name, _fill_field(getattr(msg, f.name), val, f.base, f.array, sub))
        return msg
    if len(fields) == 1:
        f = fields[0]
        setattr(msg, f.name, _fill_field(getattr(msg, f.name), value, f.base, f.array, f.name))
        return msg
    hint = " (or 'auto')" if msg._type == "std_msgs/Header" else ""
    raise FillError(f"cannot fill {msg._type} from {value!r}: give a mapping of its "
                    f"fields{hint}")

