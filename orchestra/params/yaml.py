"""rosparam's YAML rules: what a YAML document means as parameter values.

Loading is always *safe* (no arbitrary Python objects). On top of YAML 1.1 (PyYAML's rules,
which rosparam uses: ``yes``/``no`` are booleans, ``1e5`` without a dot is a string), rosparam
adds angle tags: ``!degrees 90`` / ``deg(90)`` become radians, ``!radians pi/2`` / ``rad(pi/2)``
evaluate a small arithmetic expression over ``pi``; ``!!binary`` is raw bytes. The expression
evaluator below only knows numbers, ``pi`` and arithmetic, unlike rosparam's ``eval``.
"""
from __future__ import annotations

import ast
import math
import operator
import re
from collections.abc import Callable
from typing import Any

import yaml

from orchestra.errors import Location, OrchestraError, offset_location
from orchestra.names import ns_join


class RosparamYamlError(OrchestraError):
    """A YAML document rosparam could not load."""


_BINOPS: dict[type[ast.operator], Callable[[float, float], float]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
    ast.Div: operator.truediv, ast.Pow: operator.pow, ast.Mod: operator.mod,
    ast.FloorDiv: operator.floordiv}
_UNARY: dict[type[ast.unaryop], Callable[[float], float]] = {ast.USub: operator.neg, ast.UAdd: operator.pos}


def _arith(node: ast.AST) -> float:
    if isinstance(node, ast.Expression):
        return _arith(node.body)
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
            and not isinstance(node.value, bool):
        # floats throughout: 9**9**9 overflows at once instead of building a huge integer
        return float(node.value)
    if isinstance(node, ast.Name) and node.id == "pi":
        return math.pi
    if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
        return _BINOPS[type(node.op)](_arith(node.left), _arith(node.right))
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _UNARY[type(node.op)](_arith(node.operand))
    raise ValueError("only numbers, pi and + - * / ** % are allowed")


def angle_expression(text: str) -> float:
    """Evaluate an angle expression such as ``pi/2`` or ``-1.5*pi`` (no names but ``pi``)."""
    if len(text) > 1000:
        raise ValueError("the expression is longer than 1000 characters")
    return float(_arith(ast.parse(text.strip(), mode="eval")))


def _unwrap(value: str, prefix: str) -> str:
    value = value.strip()
    if value.startswith(prefix + "(") and value.endswith(")"):
        return value[len(prefix) + 1:-1]
    return value


def _construct_radians(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
    text = _unwrap(loader.construct_scalar(node), "rad")
    try:
        return angle_expression(text)
    except (ValueError, SyntaxError, ArithmeticError, TypeError, RecursionError,
            MemoryError) as exc:
        raise yaml.constructor.ConstructorError(
            None, None, f"invalid radian expression {text!r}: {exc}", node.start_mark) from None


def _construct_degrees(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
    text = _unwrap(loader.construct_scalar(node), "deg")
    try:
        return float(text) * math.pi / 180.0
    except ValueError:
        raise yaml.constructor.ConstructorError(
            None, None, f"invalid degree value {text!r}", node.start_mark) from None


# Bounds on what a YAML value may build (the same spirit as $(eval)'s): nesting levels, and
# the length of an integer's text (1300 digits is ~4300 bits; Python refuses to convert
# longer decimal text anyway, with no position).
MAX_DEPTH = 100
MAX_INT_TEXT = 1300
_INT_TAG = "tag:yaml.org,2002:int"


_resolve_tag = yaml.resolver.BaseResolver.resolve
# (text, implicit) -> tag of RosparamLoader's scalars of up to _KEPT_TEXT characters, at
# most _SCALAR_TAGS_LIMIT of them
_SCALAR_TAGS: dict[tuple[str, Any], str] = {}
_SCALAR_TAGS_LIMIT = 16384
_KEPT_TEXT = 200


class RosparamLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """PyYAML's safe loader (libyaml-backed when available: same results, much faster) plus
    rosparam's angle tags; a subclass, so the global loaders stay untouched."""

    def resolve(self, kind: type, value: Any, implicit: Any) -> Any:
        # a scalar's tag depends on its text and quoting alone (this loader has no path
        # resolvers and its implicit resolvers are fixed), and keys and values recur
        # throughout a document and across files: each text is matched against the
        # patterns once per process (the table is emptied when it grows past its limit)
        if kind is not yaml.ScalarNode:
            return _resolve_tag(self, kind, value, implicit)
        key = (value, implicit)
        tag = _SCALAR_TAGS.get(key)
        if tag is None:
            tag = _resolve_tag(self, kind, value, implicit)
            if len(value) <= _KEPT_TEXT:
                if len(_SCALAR_TAGS) >= _SCALAR_TAGS_LIMIT:
                    _SCALAR_TAGS.clear()
                _SCALAR_TAGS[key] = tag
        return tag

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        # a constructor's own ValueError (an impossible timestamp...) carries no position:
        # give it the node's
        try:
            return super().construct_object(node, deep)
        except (ValueError, OverflowError, TypeError) as exc:
            raise yaml.constructor.ConstructorError(
                None, None, f"invalid {node.tag.rsplit(':', 1)[-1]} value: {exc}",
                node.start_mark) from None


RosparamLoader.add_constructor("!radians", _construct_radians)
RosparamLoader.add_constructor("!degrees", _construct_degrees)
RosparamLoader.add_implicit_resolver("!radians", re.compile(r"^rad\([^)]*\)$"), ["r"])
RosparamLoader.add_implicit_resolver("!degrees", re.compile(r"^deg\([^)]*\)$"), ["d"])


def load_rosparam_yaml(text: str, filename: str = "<yaml>") -> Any:
    """The value rosparam loads from ``text``; an empty document is ``{}``.

    Errors become ``RosparamYamlError`` located at ``filename:line`` of the problem.
    """
    data = load_yaml_value(text, filename)
    return {} if data is None else data


def load_yaml_value(text: str, filename: str = "<yaml>") -> Any:
    """Like ``load_rosparam_yaml`` but an empty document is ``None`` (``type="yaml"`` params)."""
    loader = RosparamLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        try:  # one pass checks and builds a plain document (nearly all)
            return _PlainBuilder(loader, set()).checked(node, 1)
        except Exception:  # noqa: BLE001 - anything else: the passes below say what
            pass
        shared = _check_bounds(node, filename)
        if shared is not None:
            try:
                return _PlainBuilder(loader, shared).build(node)
            except Exception:  # noqa: BLE001 - PyYAML's own path below raises it as it does
                pass
        return loader.construct_document(node)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else 1
        col = mark.column + 1 if mark is not None else None
        raise RosparamYamlError(f"invalid YAML: {exc.problem or exc}",
                                Location(filename, line, col)) from None
    except yaml.reader.ReaderError as exc:
        raise RosparamYamlError(f"invalid YAML: character {char_name(exc.character)} is not "
                                f"allowed ({exc.reason})",
                                reader_error_location(exc, text, filename,
                                                      RosparamLoader)) from None
    except yaml.YAMLError as exc:
        raise RosparamYamlError(f"invalid YAML: {exc}", Location(filename, 1)) from None
    finally:
        loader.dispose()


def _check_bounds(root: yaml.Node, filename: str) -> set[int] | None:
    """Refuse nesting deeper than ``MAX_DEPTH`` and oversized integers, at their position.
    For a *plain* document (see ``_PlainBuilder``), the ids of the nodes an alias names
    again; None for any other document.

    Aliases make the node tree a graph: each node is visited once (its deepest level found
    via the order of a depth-first walk is enough to bound what construction recurses
    through), and an alias that contains itself stops the walk like a deep nesting would.
    """
    stack: list[tuple[yaml.Node, int]] = [(root, 1)]
    seen: dict[int, int] = {}
    shared: set[int] = set()
    plain = True
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise RosparamYamlError(f"nested more than {MAX_DEPTH} levels deep",
                                    _node_location(filename, node))
        known = seen.get(id(node))
        if known is not None:
            shared.add(id(node))  # named again by an alias: one object in both places
            if known >= depth:
                continue
        seen[id(node)] = depth
        tag = node.tag
        if isinstance(node, yaml.ScalarNode):
            if tag == _INT_TAG and len(node.value) > MAX_INT_TEXT:
                raise RosparamYamlError(f"integer of {len(node.value)} characters (at most "
                                        f"{MAX_INT_TEXT})", _node_location(filename, node))
            if tag not in _PLAIN_SCALAR_TAGS:
                plain = False
        elif isinstance(node, yaml.SequenceNode):
            if tag != _SEQ_TAG:
                plain = False
            stack.extend((child, depth + 1) for child in node.value)
        elif isinstance(node, yaml.MappingNode):
            if tag != _MAP_TAG:
                plain = False
            for key, value in node.value:
                if key.tag not in _PLAIN_SCALAR_TAGS or not isinstance(key, yaml.ScalarNode):
                    plain = False  # a merge (<<) or value (=) key, or a collection as a key
                stack.append((key, depth + 1))
                stack.append((value, depth + 1))
    return shared if plain else None


_STR_TAG = "tag:yaml.org,2002:str"
_SEQ_TAG = "tag:yaml.org,2002:seq"
_MAP_TAG = "tag:yaml.org,2002:map"
_PLAIN_SCALAR_TAGS = frozenset({_STR_TAG, _INT_TAG, "tag:yaml.org,2002:float",
                                "tag:yaml.org,2002:bool", "tag:yaml.org,2002:null"})


_SCALAR = yaml.ScalarNode


class _NotPlain(Exception):
    """The document is not one ``_PlainBuilder.checked`` builds."""


class _PlainBuilder:
    """What ``loader.construct_document(node)`` builds, for a plain document: only maps,
    sequences, strings, numbers, booleans and nulls, scalar keys, no merge keys (aliases
    are fine: a node named again gives the same object, as PyYAML's constructor does).
    Nearly every rosparam file is one; PyYAML's constructor spends most of its time on what
    such a document never needs (two-phase construction for recursive structures, merge
    keys, per-object bookkeeping). A scalar it would refuse raises here, and the caller
    then lets PyYAML's constructor raise its error as before.

    A scalar's value depends on its tag and text alone, and parameter files repeat the same
    few texts (``0.0``, ``false``, the rows of covariance matrices): each (tag, text) is
    constructed once per document. The values shared that way are immutable (numbers,
    booleans, None), whose identity nothing observes (PyYAML itself gives every ``.nan`` the
    same object)."""

    def __init__(self, loader: RosparamLoader, shared: set[int]):
        self.constructors = loader.yaml_constructors
        self.loader = loader
        self.shared = shared
        self.built: dict[int, Any] = {}
        self.scalars: dict[tuple[str, str], Any] = {}
        # for ``checked``: the levels below each collection met, the deepest level reached
        self.levels: dict[int, int] = {}
        self.deepest = 0

    def build(self, node: yaml.Node) -> Any:
        if self.shared and id(node) in self.shared:
            found = self.built.get(id(node), self)
            if found is self:
                found = self.built[id(node)] = self._build(node)
            return found
        return self._build(node)

    def scalar(self, node: yaml.ScalarNode) -> Any:
        """The value of a scalar node (a string as is; others constructed once per text);
        ``_NotPlain`` for a tag a plain document has not, or an oversized integer."""
        tag = node.tag
        if tag == _STR_TAG:
            return node.value
        key = (tag, node.value)
        value = self.scalars.get(key, _NotPlain)
        if value is _NotPlain:
            if tag not in _PLAIN_SCALAR_TAGS or (tag == _INT_TAG
                                                 and len(node.value) > MAX_INT_TEXT):
                raise _NotPlain
            value = self.scalars[key] = self.constructors[tag](self.loader, node)
        return value

    def checked(self, node: yaml.Node, depth: int) -> Any:
        """``build`` for a document that also makes ``_check_bounds``' checks on the way;
        ``_NotPlain`` for anything they or ``build`` would not pass. A collection an alias
        names again is the object already built, when its levels fit below the alias (and
        it is not inside itself; otherwise ``_NotPlain``, and the two-pass path decides).
        An alias of a scalar needs nothing: its value depends on its text alone and is
        immutable. (Scalar children are read here rather than through a call per child:
        most nodes of a parameter file are scalars in a list or a map.)"""
        if depth > MAX_DEPTH:
            raise _NotPlain
        kind = node.__class__
        if kind is _SCALAR:
            return self.scalar(node)  # type: ignore[arg-type]
        key = id(node)
        levels = self.levels.get(key)
        if levels is not None:  # named again by an alias
            if key not in self.built or depth + levels > MAX_DEPTH:
                raise _NotPlain
            self.deepest = max(self.deepest, depth + levels)
            return self.built[key]
        self.levels[key] = 0  # being built
        level, outer = depth, self.deepest
        depth += 1
        children = node.value
        if children:
            if depth > MAX_DEPTH:
                raise _NotPlain
            self.deepest = depth
        else:
            self.deepest = level
        scalar, checked = self.scalar, self.checked
        value: Any
        if kind is yaml.MappingNode and node.tag == _MAP_TAG:
            value = {}
            for k, v in children:
                if k.__class__ is not _SCALAR:
                    raise _NotPlain
                value[scalar(k)] = scalar(v) if v.__class__ is _SCALAR else checked(v, depth)
        elif kind is yaml.SequenceNode and node.tag == _SEQ_TAG:
            value = [scalar(child) if child.__class__ is _SCALAR else checked(child, depth)
                     for child in children]
        else:
            raise _NotPlain
        self.levels[key] = self.deepest - level
        self.built[key] = value
        if outer > self.deepest:
            self.deepest = outer
        return value

    def _build(self, node: yaml.Node) -> Any:
        tag = node.tag
        if tag == _STR_TAG:
            return node.value
        if tag == _MAP_TAG:
            build = self.build
            return {build(key): build(value) for key, value in node.value}
        if tag == _SEQ_TAG:
            return [self.build(child) for child in node.value]
        return self.scalar(node)  # type: ignore[arg-type]


def _node_location(filename: str, node: yaml.Node) -> Location:
    return Location(filename, node.start_mark.line + 1, node.start_mark.column + 1)


def char_name(character: str | int) -> str:
    code = character if isinstance(character, int) else ord(character)
    return f"U+{code:04X}"


try:
    from yaml._yaml import CParser as _C_PARSER
except ImportError:  # PyYAML built without libyaml
    _C_PARSER = ()  # type: ignore[misc, assignment]


def reader_error_location(exc: yaml.reader.ReaderError, text: str, filename: str,
                          loader: type) -> Location:
    """Where the YAML reader refused a character: it reports only an offset, in UTF-8 bytes
    with libyaml and in characters without it; the column is given in characters."""
    if not issubclass(loader, _C_PARSER):
        return offset_location(filename, text, exc.position)
    data = text.encode("utf-8")
    where = offset_location(filename, data, exc.position)
    line_start = data.rfind(b"\n", 0, exc.position) + 1
    column = len(data[line_start:exc.position].decode("utf-8", "replace")) + 1
    return Location(filename, where.line, column)


def flatten(name: str, value: Any) -> list[tuple[str, Any]]:
    """Unroll dictionaries into leaf parameters the way roslaunch stores ``<rosparam>``.

    ``flatten('/ns', {'a': {'b': 1}, 'c': 2})`` -> ``[('/ns/a/b', 1), ('/ns/c', 2)]``. An empty
    dictionary contributes nothing; a global key inside a dictionary escapes the namespace.
    """
    if not isinstance(value, dict):
        return [(name, value)]
    out: list[tuple[str, Any]] = []
    # depth first, in the dictionaries' order: one iterator per open dictionary (no
    # recursion: nesting is bounded by the caller, not by Python's stack)
    stack = [(name, iter(value.items()))]
    while stack:
        prefix, items = stack[-1]
        for key, val in items:
            full = ns_join(prefix, key if key.__class__ is str else str(key))
            if isinstance(val, dict):
                stack.append((full, iter(val.items())))
                break
            out.append((full, val))
        else:
            stack.pop()
    return out


__all__ = ["RosparamLoader", "RosparamYamlError", "angle_expression", "flatten",
           "char_name", "load_rosparam_yaml", "load_yaml_value", "reader_error_location"]
