"""The one safe evaluator of user expressions, parameterised by a ``Policy``.

Two commands take a Python-looking expression from text someone may send you: launch files'
``$(eval EXPR)`` (roslaunch hands it to ``eval`` with only ``__`` banned) and ``bag filter``'s
EXPR (rosbag hands it to ``eval``). ``eval`` runs anything an expression can reach
(generator frames lead to ``os``), and ``'a'*10**10`` or ``sum(range(10**11))`` exhaust
memory or never end. So an expression is never compiled or executed: its AST is walked here
and only this grammar is given a meaning:

- literals (str, int, float, complex, bool, None; lists, tuples, sets, dicts of them) and
  f-strings;
- names: the policy's constants and functions (a choice among ``BUILTINS``: builtins and
  ``math`` members written or guarded here), the functions and variables the caller binds;
- arithmetic, bit operations, comparisons (chained), ``and``/``or``/``not``, ``x if c else y``,
  subscripts and slices, calls of those functions, and calls of the ``str`` methods the
  policy allows (a subset of ``STR_METHODS``);
- only when the policy names ``readable`` objects (bag messages and times): reads of their
  public attributes (never a name starting with ``_``; the value read must be data) and calls
  of the policy's ``object_methods`` on them.

Everything else (lambdas, comprehensions, generators, other attribute access, ``:=``,
``*``/``**`` unpacking) is refused before anything runs. Every value produced is bounded
(integers to ``MAX_INT_BITS`` bits, strings and containers to ``MAX_LENGTH`` characters/
elements counted through nesting), the expression tree to ``MAX_DEPTH`` levels, and the whole
evaluation to ``MAX_STEPS`` units of work (a node, an element visited, a block of characters
copied), so every expression ends quickly. Sizes are predicted *before* an operation that
could build a huge value (``*``, ``+``, ``**``, ``<<``, ``%``-formatting, padding,
``replace``, ``join``), so nothing huge is ever allocated. Data read from a readable object
already exists and is not re-measured, but anything built from it is.
"""
from __future__ import annotations

import ast
import builtins
import math
import re
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from orchestra.errors import clip

MAX_INT_BITS = 4096
MAX_LENGTH = 1_000_000
MAX_DEPTH = 100
MAX_STEPS = 250_000
MAX_EXPRESSION = 100_000
# characters copied by C code per step: copying is ~100x cheaper than a Python-level step
_CHARS_PER_STEP = 64

STR_METHODS = frozenset({
    "capitalize", "casefold", "center", "count", "endswith", "expandtabs", "find", "index",
    "isalnum", "isalpha", "isascii", "isdecimal", "isdigit", "isidentifier", "islower",
    "isnumeric", "isprintable", "isspace", "istitle", "isupper", "join", "ljust", "lower",
    "lstrip", "partition", "removeprefix", "removesuffix", "replace", "rfind", "rindex",
    "rjust", "rpartition", "rsplit", "rstrip", "split", "splitlines", "startswith", "strip",
    "swapcase", "title", "upper", "zfill",
})
# math functions of floats (and small ints): their cost does not depend on the values
_MATH_PLAIN = ("acos", "acosh", "asin", "asinh", "atan", "atan2", "atanh", "ceil",
               "copysign", "cos", "cosh", "degrees", "dist", "erf", "erfc", "exp", "expm1",
               "fabs", "floor", "fmod", "frexp", "fsum", "gamma", "gcd", "hypot", "isclose",
               "isfinite", "isinf", "isnan", "isqrt", "ldexp", "lgamma", "log", "log10",
               "log1p", "log2", "modf", "radians", "remainder", "sin", "sinh", "sqrt", "tan",
               "tanh", "trunc")
_PLAIN_BUILTINS = ("abs", "all", "any", "bin", "bool", "chr", "divmod", "float", "hex", "int",
                   "len", "oct", "ord", "repr", "str")


def _never(value: Any) -> bool:
    return False


@dataclass(frozen=True)
class Policy:
    """What one use of the evaluator lets an expression name, call and read.

    ``functions`` are names among ``BUILTINS``; the caller binds its own functions and
    variables per evaluation. ``readable`` says which objects' public attributes may be read
    (none by default: attributes then exist only to call an allowed str method).
    """

    functions: frozenset[str]
    str_methods: frozenset[str]
    constants: Mapping[str, Any] = field(default_factory=dict)
    readable: Callable[[Any], bool] = _never
    object_methods: frozenset[str] = frozenset()
    max_expression: int = MAX_EXPRESSION
    # roslaunch refuses any ``__`` in the text; kept where the result must match roslaunch
    no_double_underscore: bool = False
    # what an unknown name's error lists as the names there are
    known_names: str = ""
    # exceptions of the caller's own functions that pass through unchanged
    passthrough: tuple[type[BaseException], ...] = ()

    @property
    def reads_attributes(self) -> bool:
        return self.readable is not _never


class ExpressionError(Exception):
    """An expression that is refused or fails; the message says why (the caller says where)."""


class _Refused(Exception):
    """Raised inside the walk; turned into an ``ExpressionError``."""


@dataclass
class _Budget:
    steps: int = MAX_STEPS
    # objects that count as one element (the policy's readable ones: messages, times)
    opaque: Callable[[Any], bool] = _never

    def charge(self, units: int) -> None:
        self.steps -= units
        if self.steps < 0:
            raise _Refused(f"needs more than {MAX_STEPS} steps of work")


# ------------------------------------------------------------------------------ sizes


def _int_bits(value: int) -> int:
    return value.bit_length()


def _weight(value: Any, budget: _Budget, limit: int = MAX_LENGTH) -> int:
    """Size of ``value`` (chars, elements and digits through nesting); stops past ``limit``.

    Walking costs a step per element, so repeated walks of big values exhaust the budget.
    """
    total = 0
    stack = [value]
    while stack:
        item = stack.pop()
        budget.charge(1)
        if isinstance(item, (bool, float, complex, _Function)) or item is None:
            total += 1
        elif isinstance(item, int):
            if _int_bits(item) > MAX_INT_BITS:
                raise _Refused(f"an integer has more than {MAX_INT_BITS} bits")
            total += 1 + _int_bits(item) // 4
        elif isinstance(item, (str, bytes)):
            total += 1 + len(item)
        elif isinstance(item, range):
            total += 1 + _range_len(item)
        elif isinstance(item, dict):
            total += 1
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, (list, tuple, set, frozenset)):
            total += 1
            stack.extend(item)
        elif budget.opaque(item):
            total += 1
        else:
            raise _Refused(f"a value of type {type(item).__name__} is not supported")
        if total > limit:
            raise _Refused(f"a value would be longer than {limit} elements or characters")
    return total


def _range_len(value: range) -> int:
    try:
        return len(value)
    except OverflowError:
        return MAX_LENGTH + 1


def _check(value: Any, budget: _Budget) -> Any:
    """``value`` once it is known to be within the bounds (raises otherwise)."""
    if isinstance(value, (str, bytes)):
        if len(value) > MAX_LENGTH:
            raise _Refused(f"a string would be longer than {MAX_LENGTH} characters")
        budget.charge(1 + len(value) // _CHARS_PER_STEP)
        return value
    if isinstance(value, (bool, float, complex)) or value is None:
        return value
    _weight(value, budget)
    return value


def _need_length(length: int) -> None:
    if length > MAX_LENGTH:
        raise _Refused(f"a value would be longer than {MAX_LENGTH} elements or characters")


def _need_bits(bits: int) -> None:
    if bits > MAX_INT_BITS:
        raise _Refused(f"an integer would have more than {MAX_INT_BITS} bits")


def _is_int(value: Any) -> bool:
    return isinstance(value, int)


def _sequence_len(value: Any) -> int | None:
    if isinstance(value, (str, bytes, list, tuple)):
        return len(value)
    return None


# --------------------------------------------------------------------------- operators

_FORMAT_NUMBER = re.compile(r"\d+")
_PERCENT_SPEC = re.compile(r"%(\([^)]*\))?([-#0 +*\d.]*)[a-zA-Z%]")


def _check_format_spec(spec: str) -> None:
    """Widths and precisions in a format spec must stay within ``MAX_LENGTH``."""
    if "*" in spec:
        raise _Refused("'*' widths are not supported in formats")
    for number in _FORMAT_NUMBER.findall(spec):
        if len(number) > 7 or int(number) > MAX_LENGTH:
            raise _Refused(f"a format width or precision is larger than {MAX_LENGTH}")


def _percent_format(left: str | bytes, right: Any) -> str | bytes:
    spec = left.decode("latin-1") if isinstance(left, bytes) else left
    for match in _PERCENT_SPEC.finditer(spec):
        _check_format_spec(match.group(2))
    return left % right


def _binop(op: ast.operator, left: Any, right: Any, budget: _Budget) -> Any:
    if isinstance(op, ast.Add):
        llen, rlen = _sequence_len(left), _sequence_len(right)
        if llen is not None and rlen is not None:
            _need_length(llen + rlen)
            budget.charge(1 + (llen + rlen) // _CHARS_PER_STEP)
        return left + right
    if isinstance(op, ast.Sub):
        return left - right
    if isinstance(op, ast.Mult):
        for seq, times in ((left, right), (right, left)):
            length = _sequence_len(seq)
            if length is not None and _is_int(times):
                if times > 0:
                    _need_length(length * times)
                    budget.charge(1 + length * times // _CHARS_PER_STEP)
                return seq * times
        if _is_int(left) and _is_int(right):
            _need_bits(_int_bits(left) + _int_bits(right) - 1)
        return left * right
    if isinstance(op, ast.Div):
        return left / right
    if isinstance(op, ast.FloorDiv):
        return left // right
    if isinstance(op, ast.Mod):
        if isinstance(left, (str, bytes)):
            return _percent_format(left, right)
        return left % right
    if isinstance(op, ast.Pow):
        return _power(left, right)
    if isinstance(op, ast.LShift):
        if _is_int(left) and _is_int(right) and right > 0 and left:
            _need_bits(_int_bits(left) + right)
        return left << right
    if isinstance(op, ast.RShift):
        return left >> right
    if isinstance(op, ast.BitAnd):
        return left & right
    if isinstance(op, ast.BitOr):
        return left | right
    if isinstance(op, ast.BitXor):
        return left ^ right
    raise _Refused(f"the operator {type(op).__name__} is not supported")


def _power(base: Any, exponent: Any) -> Any:
    if _is_int(base) and _is_int(exponent) and exponent > 0 and abs(base) > 1:
        _need_bits((_int_bits(base) - 1) * exponent + 1)
    if isinstance(exponent, (int, float)) and not isinstance(exponent, bool) \
            and abs(exponent) > MAX_INT_BITS and isinstance(base, complex):
        raise _Refused(f"complex powers are limited to exponents up to {MAX_INT_BITS}")
    return base ** exponent


_COMPARE: dict[type, Callable[[Any, Any], Any]] = {
    ast.Eq: lambda a, b: a == b, ast.NotEq: lambda a, b: a != b,
    ast.Lt: lambda a, b: a < b, ast.LtE: lambda a, b: a <= b,
    ast.Gt: lambda a, b: a > b, ast.GtE: lambda a, b: a >= b,
    ast.Is: lambda a, b: a is b, ast.IsNot: lambda a, b: a is not b,
    ast.In: lambda a, b: a in b, ast.NotIn: lambda a, b: a not in b,
}


# ---------------------------------------------------------------------------- functions


class _Function:
    """A callable the expression may use; calls are charged and their results bounded."""

    __slots__ = ("name", "impl")

    def __init__(self, name: str, impl: Callable[..., Any]):
        self.name = name
        self.impl = impl

    def __repr__(self) -> str:
        return f"<function {self.name}>"


def _materialize(value: Any, budget: _Budget) -> list[Any]:
    """The items of an iterable value as a list (iterables are only ever data here)."""
    if isinstance(value, dict):
        items = list(value)
    elif isinstance(value, (str, list, tuple, set, frozenset, range)):
        if isinstance(value, range):
            _need_length(_range_len(value))
        items = list(value)
    else:
        raise _Refused(f"a {type(value).__name__} is not iterable")
    budget.charge(1 + len(items) // _CHARS_PER_STEP)
    return items


class _Calls:
    """The builtins: plain ones guarded by bounds on their results, the rest written here
    so their loops are charged (``map``/``sum``...) or their sizes predicted (``range``)."""

    def __init__(self, budget: _Budget, call: Callable[..., Any]):
        self.budget = budget
        self.call = call

    def functions(self) -> dict[str, Callable[..., Any]]:
        own: dict[str, Callable[..., Any]] = {
            "range": self.range_, "list": self.list_, "tuple": self.tuple_, "set": self.set_,
            "dict": self.dict_, "sorted": self.sorted_, "reversed": self.reversed_,
            "min": self.min_, "max": self.max_, "sum": self.sum_, "map": self.map_,
            "filter": self.filter_, "zip": self.zip_, "enumerate": self.enumerate_,
            "round": self.round_, "pow": self.pow_, "factorial": self.factorial_,
            "comb": self.comb_, "perm": self.perm_, "prod": self.prod_, "lcm": self.lcm_,
            "all": self.all_, "any": self.any_,
        }
        for name in _PLAIN_BUILTINS:
            own.setdefault(name, getattr(builtins, name))
        for name in _MATH_PLAIN:
            own.setdefault(name, getattr(math, name))
        return own

    def _items(self, value: Any) -> list[Any]:
        return _materialize(value, self.budget)

    def range_(self, *args: Any) -> range:
        if not all(_is_int(a) for a in args):
            raise _Refused("range() takes integers")
        result = range(*args)
        _need_length(_range_len(result))
        return result

    def list_(self, value: Any = ()) -> list[Any]:
        return self._items(value)

    def tuple_(self, value: Any = ()) -> tuple[Any, ...]:
        return tuple(self._items(value))

    def set_(self, value: Any = ()) -> set[Any]:
        return set(self._items(value))

    def dict_(self, value: Any = (), **kwargs: Any) -> dict[Any, Any]:
        pairs = value.items() if isinstance(value, dict) else self._items(value)
        return dict(pairs, **kwargs)

    def sorted_(self, value: Any, key: Any = None, reverse: bool = False) -> list[Any]:
        items = self._items(value)
        self.budget.charge(len(items).bit_length() * len(items) // _CHARS_PER_STEP)
        wrapped = None if key is None else (lambda item: self.call(key, item))
        return sorted(items, key=wrapped, reverse=bool(reverse))

    def reversed_(self, value: Any) -> list[Any]:
        return list(reversed(self._items(value)))

    def _extreme(self, pick: Callable[..., Any], args: tuple[Any, ...], key: Any,
                 **default: Any) -> Any:
        items = self._items(args[0]) if len(args) == 1 else list(args)
        wrapped = None if key is None else (lambda item: self.call(key, item))
        return pick(items, key=wrapped, **default)

    def min_(self, *args: Any, key: Any = None, **default: Any) -> Any:
        return self._extreme(min, args, key, **default)

    def max_(self, *args: Any, key: Any = None, **default: Any) -> Any:
        return self._extreme(max, args, key, **default)

    def _fold(self, op: ast.operator, start: Any, value: Any) -> Any:
        total = start
        for item in self._items(value):
            total = _check(_binop(op, total, item, self.budget), self.budget)
        return total

    def sum_(self, value: Any, start: Any = 0) -> Any:
        return self._fold(ast.Add(), start, value)

    def prod_(self, value: Any, start: Any = 1) -> Any:
        return self._fold(ast.Mult(), start, value)

    def lcm_(self, *args: Any) -> int:
        total = 1
        for value in args:
            total = math.lcm(total, value)
            _need_bits(_int_bits(total))
        return total

    def all_(self, value: Any) -> bool:
        return all(self._items(value))

    def any_(self, value: Any) -> bool:
        return any(self._items(value))

    def map_(self, function: Any, *iterables: Any) -> list[Any]:
        columns = [self._items(i) for i in iterables]
        return [self.call(function, *args) for args in zip(*columns, strict=False)]

    def filter_(self, function: Any, value: Any) -> list[Any]:
        items = self._items(value)
        if function is None:
            return [item for item in items if item]
        return [item for item in items if self.call(function, item)]

    def zip_(self, *iterables: Any) -> list[tuple[Any, ...]]:
        return list(zip(*(self._items(i) for i in iterables), strict=False))

    def enumerate_(self, value: Any, start: int = 0) -> list[tuple[int, Any]]:
        return list(enumerate(self._items(value), start))

    def round_(self, number: Any, ndigits: Any = None) -> Any:
        if ndigits is None:
            return round(number)
        if _is_int(ndigits) and abs(ndigits) > 1000:
            raise _Refused("round() takes at most 1000 digits")
        return round(number, ndigits)

    def pow_(self, base: Any, exponent: Any) -> float:
        # roslaunch's eval sees math's names over the builtins: pow is math.pow (a float)
        return math.pow(base, exponent)

    def factorial_(self, value: Any) -> int:
        if _is_int(value) and value > 1000:
            raise _Refused(f"factorial({value}) would have more than {MAX_INT_BITS} bits")
        return math.factorial(value)

    def comb_(self, n: Any, k: Any) -> int:
        if _is_int(n) and n > 10_000:
            raise _Refused("comb() takes n up to 10000")
        return math.comb(n, k)

    def perm_(self, n: Any, k: Any = None) -> int:
        if _is_int(n) and n > 10_000:
            raise _Refused("perm() takes n up to 10000")
        return math.perm(n, k)


# The functions a policy may choose from.
BUILTINS = frozenset(_Calls(_Budget(), lambda *a: None).functions())


# --------------------------------------------------------------------------- str methods


def _str_method(text: str, name: str, args: list[Any], kwargs: dict[str, Any],
                budget: _Budget) -> Any:
    """Call ``text.<name>(...)`` once the result's size is known to be within bounds."""
    if name in ("center", "ljust", "rjust", "zfill"):
        width = args[0] if args else kwargs.get("width", 0)
        if _is_int(width):
            _need_length(width)
    elif name == "expandtabs":
        size = args[0] if args else kwargs.get("tabsize", 8)
        if _is_int(size):
            _need_length(len(text) + text.count("\t") * max(size, 0))
    elif name == "replace":
        old, new = (list(args) + [None, None])[:2]
        if isinstance(old, str) and isinstance(new, str):
            hits = text.count(old)
            limit = args[2] if len(args) > 2 else kwargs.get("count", -1)
            if _is_int(limit) and limit >= 0:
                hits = min(hits, limit)
            _need_length(len(text) + hits * max(len(new) - len(old), 0))
    elif name == "join":
        items = _materialize(args[0], budget) if args else []
        if all(isinstance(i, str) for i in items):
            _need_length(sum(len(i) for i in items) + len(text) * max(len(items) - 1, 0))
        args = [items]
    budget.charge(1 + len(text) // _CHARS_PER_STEP)
    return getattr(text, name)(*args, **kwargs)


# --------------------------------------------------------------------------- the walk


class _Evaluator:
    def __init__(self, policy: Policy, variables: Mapping[str, Any],
                 functions: Mapping[str, Callable[..., Any]]):
        self.policy = policy
        self.budget = _Budget(opaque=policy.readable)
        self.variables = variables
        calls = _Calls(self.budget, self.call)
        self.names: dict[str, Any] = dict(policy.constants)
        for name, impl in calls.functions().items():
            if name in policy.functions:
                self.names[name] = _Function(name, impl)
        for name, impl in functions.items():
            self.names[name] = _Function(name, impl)
        self.depth = 0

    def call(self, function: Any, *args: Any, **kwargs: Any) -> Any:
        if not isinstance(function, _Function):
            raise _Refused(f"a {type(function).__name__} is not callable")
        self.budget.charge(1)
        return _check(function.impl(*args, **kwargs), self.budget)

    def run(self, node: ast.AST) -> Any:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise _Refused(f"the expression is nested more than {MAX_DEPTH} levels deep")
        self.budget.charge(1)
        try:
            method = getattr(self, "_" + type(node).__name__, None)
            if method is None:
                raise _Refused(_describe_refused(node))
            if isinstance(node, ast.Attribute):
                return method(node)  # existing data, checked for its kind by _Attribute
            return _check(method(node), self.budget)
        finally:
            self.depth -= 1

    # -- leaves
    def _Constant(self, node: ast.Constant) -> Any:
        if isinstance(node.value, (bytes, type(...))):
            raise _Refused(f"{type(node.value).__name__} literals are not supported")
        return node.value

    def _Name(self, node: ast.Name) -> Any:
        name = node.id
        if name in self.names:
            return self.names[name]
        if name in self.variables:
            return self.variables[name]
        raise _Refused(_undefined(name, self.policy))

    # -- containers
    def _List(self, node: ast.List) -> list[Any]:
        return [self.run(e) for e in node.elts]

    def _Tuple(self, node: ast.Tuple) -> tuple[Any, ...]:
        return tuple(self.run(e) for e in node.elts)

    def _Set(self, node: ast.Set) -> set[Any]:
        return {self.run(e) for e in node.elts}

    def _Dict(self, node: ast.Dict) -> dict[Any, Any]:
        if any(k is None for k in node.keys):
            raise _Refused("'**' unpacking is not supported")
        return {self.run(k): self.run(v) for k, v in zip(node.keys, node.values, strict=True)
                if k is not None}

    def _JoinedStr(self, node: ast.JoinedStr) -> str:
        parts = [self.run(v) for v in node.values]
        _need_length(sum(len(p) for p in parts))
        return "".join(parts)

    def _FormattedValue(self, node: ast.FormattedValue) -> str:
        value = self.run(node.value)
        if isinstance(value, _Function):
            raise _Refused("a function cannot be formatted")
        spec = self.run(node.format_spec) if node.format_spec is not None else ""
        _check_format_spec(spec)
        conversion = {-1: None, 115: str, 114: repr, 97: ascii}[node.conversion]
        if conversion is not None:
            value = conversion(value)
        return format(value, spec)

    # -- operators
    def _BinOp(self, node: ast.BinOp) -> Any:
        return _binop(node.op, self.run(node.left), self.run(node.right), self.budget)

    def _UnaryOp(self, node: ast.UnaryOp) -> Any:
        value = self.run(node.operand)
        if isinstance(node.op, ast.Not):
            return not value
        if isinstance(node.op, ast.USub):
            return -value
        if isinstance(node.op, ast.UAdd):
            return +value
        return ~value

    def _BoolOp(self, node: ast.BoolOp) -> Any:
        value: Any = None
        for operand in node.values:
            value = self.run(operand)
            if isinstance(node.op, ast.And) and not value:
                return value
            if isinstance(node.op, ast.Or) and value:
                return value
        return value

    def _Compare(self, node: ast.Compare) -> bool:
        left = self.run(node.left)
        for op, comparator in zip(node.ops, node.comparators, strict=True):
            right = self.run(comparator)
            if not _COMPARE[type(op)](left, right):
                return False
            left = right
        return True

    def _IfExp(self, node: ast.IfExp) -> Any:
        return self.run(node.body) if self.run(node.test) else self.run(node.orelse)

    def _Subscript(self, node: ast.Subscript) -> Any:
        value = self.run(node.value)
        if not isinstance(value, (str, bytes, list, tuple, dict, range)):
            raise _Refused(f"a {type(value).__name__} cannot be subscripted")
        if isinstance(node.slice, ast.Slice):
            parts = [None if p is None else self.run(p)
                     for p in (node.slice.lower, node.slice.upper, node.slice.step)]
            return value[slice(*parts)]
        return value[self.run(node.slice)]

    # -- calls
    def _Call(self, node: ast.Call) -> Any:
        if any(isinstance(a, ast.Starred) for a in node.args) or \
                any(k.arg is None for k in node.keywords):
            raise _Refused("'*' and '**' unpacking are not supported")
        if isinstance(node.func, ast.Attribute):
            target = self.run(node.func.value)
            name = node.func.attr
            if isinstance(target, str):
                if name not in self.policy.str_methods:
                    raise _Refused(_method_refused(name, self.policy))
                method: Callable[..., Any] | None = None
            elif self.policy.readable(target) and name in self.policy.object_methods:
                method = getattr(target, name)
            else:
                raise _Refused(f"attribute '{name}' of a {type(target).__name__}: only "
                               f"{_callable_methods(self.policy)} may be called")
            args = [self.run(a) for a in node.args]
            kwargs = {k.arg: self.run(k.value) for k in node.keywords if k.arg}
            self.budget.charge(1)
            if method is not None:
                return method(*args, **kwargs)
            return _str_method(target, name, args, kwargs, self.budget)
        function = self.run(node.func)
        args = [self.run(a) for a in node.args]
        kwargs = {k.arg: self.run(k.value) for k in node.keywords if k.arg}
        return self.call(function, *args, **kwargs)

    def _Attribute(self, node: ast.Attribute) -> Any:
        if not self.policy.reads_attributes or node.attr.startswith("_"):
            raise _Refused(_attribute_refused(node.attr, self.policy))
        target = self.run(node.value)
        if not self.policy.readable(target):
            raise _Refused(f"attribute '{node.attr}' of a {type(target).__name__} cannot be "
                           "read")
        value = getattr(target, node.attr)
        if isinstance(value, _DATA) or self.policy.readable(value):
            return value
        raise _Refused(f"'.{node.attr}' of a {type(target).__name__} is a "
                       f"{type(value).__name__}, not data")


# what reading an attribute of a readable object may give (the fields of a message)
_DATA = (str, bytes, bool, int, float, complex, type(None), list, tuple)


def _undefined(name: str, policy: Policy, variables: frozenset[str] = frozenset()) -> str:
    known = ", ".join(sorted(variables)) + " and " if variables else ""
    return f"name '{name}' is not defined (the names are {known}{policy.known_names})"


def _callable_methods(policy: Policy) -> str:
    return "str methods" if not policy.object_methods else \
        f"the methods {', '.join(sorted(policy.object_methods))}"


def _method_refused(name: str, policy: Policy) -> str:
    if not policy.object_methods:
        return f"'{name}' is not an allowed str method"
    allowed = ", ".join(sorted(policy.str_methods | policy.object_methods))
    return f"method '{name}' is not allowed (allowed: {allowed})"


def _attribute_refused(name: str, policy: Policy) -> str:
    if not policy.reads_attributes:
        return f"attribute access ('.{name}') is only allowed to call a str method"
    return f"attribute '{name}' is not allowed (names starting with '_' are never read)"


_REFUSED = {
    "Lambda": "lambda expressions are not allowed",
    "GeneratorExp": "generator expressions are not allowed",
    "ListComp": "comprehensions are not allowed",
    "SetComp": "comprehensions are not allowed",
    "DictComp": "comprehensions are not allowed",
    "NamedExpr": "assignments (':=') are not allowed",
    "Starred": "'*' unpacking is not supported",
    "Await": "'await' is not allowed",
    "Yield": "'yield' is not allowed",
    "YieldFrom": "'yield' is not allowed",
}


def _describe_refused(node: ast.AST) -> str:
    kind = type(node).__name__
    return _REFUSED.get(kind, f"{kind} expressions are not supported")


def parse(text: str, policy: Policy) -> ast.Expression:
    """The AST of ``text`` (nothing is evaluated); raises ``ExpressionError`` for a text
    that is too long or not an expression."""
    try:
        return _parse(text, policy)
    except _Refused as exc:
        raise ExpressionError(str(exc)) from None


def _parse(text: str, policy: Policy) -> ast.Expression:
    if len(text) > policy.max_expression:
        raise _Refused(f"the expression is longer than {policy.max_expression} characters")
    if policy.no_double_underscore and "__" in text:
        raise _Refused("double underscores are not allowed")
    try:
        with warnings.catch_warnings():
            # '1if x else 2' parses with a SyntaxWarning: not a line for the user's console
            warnings.simplefilter("ignore", SyntaxWarning)
            return ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise _Refused(f"not a valid expression: {exc.msg} at {_error_place(text, exc)}") from None
    except (RecursionError, MemoryError):
        raise _Refused("the expression is nested too deeply") from None


def _error_place(text: str, exc: SyntaxError) -> str:
    """Where in ``text`` (as the user wrote it, leading blanks included) the syntax error
    is: "column N" (1-based), "line L column N" past the first line, or "the end" (column
    N) where Python reports none (offset 0: the input ended too early, as in "topic ==")."""
    stripped = text.strip()
    lead = len(text) - len(text.lstrip())
    line = exc.lineno or 1
    lines = stripped.split("\n")
    if line > 1 and line <= len(lines):
        column = exc.offset if exc.offset and exc.offset > 0 else len(lines[line - 1]) + 1
        return f"line {line} column {column}"
    if not exc.offset or exc.offset <= 0 or exc.offset > len(lines[0]):
        return f"the end (column {lead + len(lines[0]) + 1})"
    return f"column {lead + exc.offset}"


def validate(tree: ast.Expression, policy: Policy,
             variables: frozenset[str] | None = None) -> None:
    """Refuse grammar outside ``policy`` before anything is evaluated; with ``variables``
    (when they are known up front) also any name that is neither one of them nor the
    policy's. Raises ``ExpressionError``."""
    try:
        _validate(tree, policy, variables)
    except _Refused as exc:
        raise ExpressionError(str(exc)) from None


def _validate(tree: ast.Expression, policy: Policy, variables: frozenset[str] | None) -> None:
    if _tree_depth(tree) > MAX_DEPTH:
        raise _Refused(f"the expression is nested more than {MAX_DEPTH} levels deep")
    called = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    methods = policy.str_methods | policy.object_methods
    for node in ast.walk(tree):
        kind = type(node).__name__
        if kind in _REFUSED:
            raise _Refused(_REFUSED[kind])
        if isinstance(node, ast.Attribute):
            if id(node) not in called:
                if not policy.reads_attributes or node.attr.startswith("_"):
                    raise _Refused(_attribute_refused(node.attr, policy))
            elif node.attr not in methods:
                raise _Refused(_method_refused(node.attr, policy))
        if isinstance(node, ast.Name) and variables is not None and \
                node.id not in variables and node.id not in policy.functions and \
                node.id not in policy.constants:
            raise _Refused(_undefined(node.id, policy, variables))


def _tree_depth(tree: ast.AST) -> int:
    deepest = 0
    stack = [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        if depth <= MAX_DEPTH:
            stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))
    return deepest


def evaluate(tree: ast.Expression, policy: Policy, variables: Mapping[str, Any],
             functions: Mapping[str, Callable[..., Any]] | None = None) -> Any:
    """The value of a validated ``tree`` with ``variables`` and the caller's ``functions``
    bound. Raises ``ExpressionError`` for anything refused or failing (the exceptions in
    ``policy.passthrough``, raised by the caller's functions, pass unchanged)."""
    try:
        value = _Evaluator(policy, variables, functions or {}).run(tree.body)
        if isinstance(value, _Function):
            raise _Refused(f"the value is the function {value.name}, not data")
        return value
    except policy.passthrough:
        raise
    except _Refused as exc:
        raise ExpressionError(str(exc)) from None
    except RecursionError:
        raise ExpressionError("nested too deeply") from None
    except MemoryError:
        raise ExpressionError("out of memory") from None
    except Exception as exc:  # noqa: BLE001 - any runtime error of the user's expression
        raise ExpressionError(f"{type(exc).__name__}: {clip(str(exc))}") from None


def text_of(value: Any) -> str:
    """``str(value)``, refused (``ExpressionError``) when longer than ``MAX_LENGTH``."""
    text = str(value)
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"a value would be longer than {MAX_LENGTH} elements or "
                              "characters")
    return text
