"""The loader scope: what a tag sees of its surroundings while a launch file is interpreted.

A ``Scope`` holds the namespace, the args visible here, remaps and ``<env>`` settings in
effect, pending ``~private`` params and the include bookkeeping. ``<group>``, ``<node>`` and
``<include>`` open child scopes. The rules are roslaunch's, including its odd corners, because
real launch files depend on them:

- args are scoped: an arg declared in a ``<group>`` is gone after the group; an included file
  sees only the args its ``<include>`` passes (``<arg>`` children, or all with
  ``pass_all_args``), and every arg passed must be declared by the included file;
- an arg with ``value`` is fixed (redeclaring or overriding it is an error); one with
  ``default`` takes the value given from outside when there is one;
- a remap in a child scope replaces the inherited remap with the same ``from``;
- ``~private`` params are kept in an ordered mapping shared with child scopes (a group copies
  it): every later ``<node>`` in that scope receives them. As in roslaunch, a child created
  while it is still empty gets one of its own.
"""
from __future__ import annotations

from typing import Any

from orchestra.names import PRIVATE, canonicalize, is_legal_name, make_global_ns, ns_join


class ScopeError(ValueError):
    """A scope rule was broken (the interpreter adds the file:line)."""


class Scope:
    """One level of loader scope (see the module docstring for the rules)."""

    __slots__ = ("parent", "ns", "filename", "remaps", "params", "env_args", "args",
                 "arg_names", "include_args", "pass_all_args", "args_passed",
                 "include_stack", "pending_filename")

    def __init__(self, ns: str, filename: str | None, parent: Scope | None = None,
                 params: dict[str, Any] | None = None,
                 env_args: list[tuple[str, str]] | None = None,
                 args: dict[str, str] | None = None,
                 arg_names: list[str] | None = None,
                 include_args: dict[str, str] | None = None,
                 pass_all_args: bool = False,
                 include_stack: tuple[str, ...] = ()):
        self.parent = parent
        self.ns = make_global_ns(ns or "/")
        self.filename = filename
        self.remaps: list[tuple[str, str]] = []
        self.params = params if params else {}
        self.env_args = env_args if env_args is not None else []
        self.args = args if args is not None else {}
        self.arg_names = arg_names if arg_names is not None else []
        self.include_args = include_args
        self.pass_all_args = pass_all_args
        self.args_passed: list[str] = []
        self.include_stack = include_stack
        self.pending_filename: str | None = None

    # ------------------------------------------------------------------ children
    def child(self, ns: str | None) -> Scope:
        """A scope inheriting everything; ``ns`` (relative, global or ``~``) nests it."""
        # positional: a node or group makes several of these, and keyword calls cost more
        return Scope(self._child_ns(ns), self.filename, self, self.params, list(self.env_args),
                     dict(self.args), list(self.arg_names), self.include_args,
                     self.pass_all_args, self.include_stack)

    def node_child(self, ns: str | None) -> Scope:
        """``child`` for a ``<node>``/``<test>`` (its namespace, then its private params).
        Nothing read in there declares an arg or adds to this scope's ``<env>``s (a node's
        own ``<env>`` and ``<remap>`` get a ``child`` of their own), so the args and env
        are shared instead of copied: every node of a file with many args copied them
        twice."""
        return Scope(self._child_ns(ns), self.filename, self, self.params, self.env_args,
                     self.args, self.arg_names, self.include_args, self.pass_all_args,
                     self.include_stack)

    def _child_ns(self, ns: str | None) -> str:
        if ns:
            if ns[0] == "/":
                child_ns = ns
            elif ns == PRIVATE:
                child_ns = PRIVATE
            else:
                child_ns = ns_join(self.ns, ns)
        else:
            child_ns = self.ns
        if child_ns.startswith(PRIVATE):
            raise ScopeError(f"namespace [{child_ns}] is private: a namespace must be "
                             "relative or global")
        return child_ns

    def include_child(self, ns: str | None, filename: str) -> Scope:
        """The scope an ``<include>`` tag's own ``<arg>``/``<env>`` children are read in."""
        scope = self.child(ns)
        scope.arg_names = []
        # the <include>'s own children still resolve $(dirname) against the including file;
        # the included file's name takes over in enter_include()
        scope.pending_filename = filename
        scope.include_args = {}
        return scope

    # ------------------------------------------------------------------ params
    def add_param(self, key: str, value: Any) -> None:
        """A ``~param``: later nodes in this scope get it (same key: last one wins, and
        moves to the end)."""
        self.params.pop(key, None)
        self.params[key] = value

    # ------------------------------------------------------------------ remaps
    def add_remap(self, src: str, dst: str) -> None:
        src, dst = canonicalize(src), canonicalize(dst)
        if not src or not dst:
            raise ScopeError("remap from/to attributes cannot be empty")
        if not is_legal_name(src):
            raise ScopeError(f"remap from [{src}] is not a valid ROS name")
        if not is_legal_name(dst):
            raise ScopeError(f"remap to [{dst}] is not a valid ROS name")
        self.remaps = [r for r in self.remaps if r[0] != src]
        self.remaps.append((src, dst))

    def remap_args(self) -> list[tuple[str, str]]:
        """Effective remaps: inherited ones not overridden here, then this scope's own.

        Walks up the chain once; most scopes (deep includes and groups) add none."""
        chain: list[list[tuple[str, str]]] = []
        scope: Scope | None = self
        while scope is not None:
            if scope.remaps:
                chain.append(scope.remaps)
            scope = scope.parent
        effective: list[tuple[str, str]] = []
        for remaps in reversed(chain):  # outermost first
            own = {r[0] for r in remaps}
            effective = [r for r in effective if r[0] not in own] + remaps
        return effective

    # ------------------------------------------------------------------ args
    def add_arg(self, name: str, default: str | None = None, value: str | None = None) -> None:
        if name in self.arg_names:
            if not self.pass_all_args:
                raise ScopeError(f"arg '{name}' has already been declared")
        else:
            self.arg_names.append(name)
        target = self.args if self.include_args is None else self.include_args
        if value is not None:
            if name in target and not self.pass_all_args:
                raise ScopeError(f"cannot override arg '{name}', which has already been set")
            target[name] = value
        elif default is not None:
            if name not in target:
                target[name] = default

    def enter_include(self) -> None:
        """Switch from reading ``<include>``'s children to reading the included file."""
        passed = self.include_args or {}
        for name in self.arg_names:
            if name not in passed:
                raise ScopeError(f"include arg '{name}' must have a value")
        self.args_passed = list(passed)
        if self.pending_filename is not None:
            self.filename = self.pending_filename
            self.pending_filename = None
        self.arg_names = []
        self.args = passed
        self.include_args = None

    def unused_include_args(self) -> list[str]:
        """Args passed to the include that the included file never declared."""
        return [a for a in self.args_passed if a not in self.arg_names]
