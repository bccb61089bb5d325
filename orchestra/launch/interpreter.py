"""The launch interpreter: Entity trees in, one immutable ``LaunchPlan`` out.

It applies roslaunch's tag rules (``launch``, ``node``, ``test``, ``machine``, ``include``,
``group``, ``remap``, ``env``, ``param``, ``rosparam``, ``arg``) with their attribute rules,
``if``/``unless`` on every tag, arg scoping and remap/env/namespace inheritance (see
``context.py``). Both front ends (XML and YAML) produce Entities, so the rules live here once.

Every user mistake raises ``LaunchError`` naming the file, line, tag and attribute. The only
side effects are reading the files the launch file names and, for ``<param command=...>``,
running that command at load time as roslaunch does (unless ``no_exec``).
"""
from __future__ import annotations

import gc
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from orchestra.errors import Location, OrchestraError
from orchestra.launch import rules
from orchestra.launch.context import Scope, ScopeError
from orchestra.launch.entity import Entity
from orchestra.launch.files import read_bytes, read_text
from orchestra.launch.frontends import parse_file as parse_launch_file
from orchestra.launch.plan import LaunchPlan, Machine, Node, ParamAction, Test
from orchestra.launch.rules import LaunchError
from orchestra.launch.substitution import ArgNotSet, SubstitutionError, resolve
from orchestra.launch.values import convert_value
from orchestra.log_setup import logger
from orchestra.names import canonicalize, is_legal_name, is_private, make_global_ns, ns_join

log = logger(__name__)

ROSLAUNCH_VERSION = "1.16.0"
DEFAULT_TIMEOUT = 10.0
TEST_TIME_LIMIT = 60.0

__all__ = ["Binary", "Interpreter", "LaunchError", "LoadOptions", "binary_to_json", "load_launch",
           "parse_launch_file"]

# where a <param>'s value comes from: exactly one is written
_PARAM_SOURCES = ("value", "textfile", "binfile", "command")
_PARAM_SOURCE_SET = frozenset(_PARAM_SOURCES)

# Files deep an include chain may go (real trees are a handful deep; a chain of distinct files
# has no cycle to stop it).
MAX_INCLUDE_DEPTH = 100


def _pause_collector() -> bool:
    """Pause the cyclic garbage collector while files are read and interpreted; whether it
    was running (to resume it).

    A load builds tens of thousands of small containers (entities, their attribute dicts,
    scopes, params) that all stay alive until the plan is made and form no cycles: the
    collector's passes over them, which grow with the tree, find nothing (~13 % of a
    1,000-node load). Reference counting still frees everything dropped meanwhile."""
    if not gc.isenabled():
        return False
    gc.disable()
    return True


def _resume_collector(paused: bool) -> None:
    if paused:
        gc.enable()


class Binary(bytes):
    """A ``binfile`` / ``!!binary`` value (bytes; XML-RPC base64 on the wire)."""


@dataclass
class LoadOptions:
    """How to load: command-line args, whether ``command=`` params run, roscore params."""

    args: dict[str, str] = field(default_factory=dict)
    no_exec: bool = False
    roscore: bool = False
    ros_namespace: str | None = None
    # orchestra test: a broken <test> becomes an entry of Interpreter.broken_tests (reported
    # as that test's error) instead of failing the whole file, so the other tests still run
    keep_broken_tests: bool = False


class Interpreter:
    """Builds one plan; use ``load_file``/``load_entity`` once, then ``plan()``.

    Tag rules (attributes, required ones, children, value kinds) come from ``rules.TAGS``,
    the table ``orchestra check`` reads too. Subclass hooks (``orchestra check`` relies on
    them; keep their signatures): ``_children(children, scope, default_machine) ->
    default_machine`` dispatches the elements of a ``<launch>``/``<group>`` body, and
    ``_warn(entity, message, code, attribute)`` receives every non-fatal problem (unknown
    tags and attributes, defunct ``<master>``, ...).
    """

    def __init__(self, options: LoadOptions | None = None):
        self.options = options or LoadOptions()
        self.params: dict[str, Any] = {}
        self.clear_params: list[str] = []
        self.param_actions: list[ParamAction] = []
        self.nodes: list[Node] = []
        self.tests: list[Test] = []
        self.broken_tests: list[tuple[str, LaunchError]] = []   # (label, why); see LoadOptions
        self.machines: dict[str, Machine] = {"": Machine(name="")}
        self.files: list[str] = []
        self.warnings: list[str] = []
        self._node_names: dict[str, Location] = {}
        self._parse: Callable[[str], Entity] = parse_launch_file

    # ================================================================ entry points
    def load_file(self, path: str) -> None:
        paused = _pause_collector()
        try:
            root = self._parse(path)
            self.load_entity(root, path)
        finally:
            _resume_collector(paused)

    def load_entity(self, root: Entity, filename: str) -> None:
        """Interpret a parsed root ``<launch>`` entity read from ``filename``."""
        paused = _pause_collector()
        try:
            self._load_entity(root, filename)
        finally:
            _resume_collector(paused)

    def _load_entity(self, root: Entity, filename: str) -> None:
        if self.options.roscore and not self.files:
            self._roscore()
        self.files.append(filename)
        ns = self.options.ros_namespace
        if ns is None:
            ns = os.environ.get("ROS_NAMESPACE", "/") or "/"
        if ns.startswith("~"):
            raise LaunchError(f"ROS_NAMESPACE [{ns}] must be a global or relative namespace",
                              Location(filename))
        scope = Scope(ns, filename, include_stack=(os.path.abspath(filename),))
        scope.args = dict(self.options.args)
        self._check_launch_tag(root, scope)
        self._children(root.children, scope, None)

    def plan(self) -> LaunchPlan:
        return LaunchPlan(params=self.params, clear_params=tuple(self.clear_params),
                          nodes=tuple(self.nodes), tests=tuple(self.tests),
                          machines=self.machines, files_loaded=tuple(self.files),
                          param_actions=tuple(self.param_actions))

    # ================================================================ helpers
    def _error(self, entity: Entity, message: str, attr: str | None = None,
               code: str = rules.INVALID) -> LaunchError:
        where = f"<{entity.tag}>" + (f" attribute '{attr}'" if attr else "")
        return LaunchError(f"{where}: {message}", entity.location, tag=entity.tag,
                           attribute=attr, code=code, exact=entity.where(attr))

    def _warn(self, entity: Entity, message: str, code: str = rules.INVALID,
              attribute: str | None = None) -> None:
        text = f"{entity.location}: {message}"
        self.warnings.append(text)
        log.warning(text)

    def _resolve(self, entity: Entity, attr: str, scope: Scope, raw: str | None = None
                 ) -> str | None:
        value = entity.attributes.get(attr) if raw is None else raw
        if value is None or "$" not in value:
            return value
        try:
            return resolve(value, scope)
        except ArgNotSet as exc:
            raise self._error(entity, f"arg '{exc.name}' is not set here (declare it with "
                              "<arg> or pass it as name:=value)", attr) from None
        except OrchestraError as exc:
            if exc.location is not None and exc.location.line is not None:
                raise
            raise self._error(entity, exc.message, attr) from None

    def _opt(self, entity: Entity, scope: Scope, *attrs: str) -> list[str | None]:
        get = entity.attributes.get
        out: list[str | None] = []
        for a in attrs:
            value = get(a)
            # fast path: most attribute values hold no substitution at all
            out.append(value if value is None or "$" not in value
                       else self._resolve(entity, a, scope))
        return out

    def _rosmon_attrs(self, entity: Entity, scope: Scope) -> dict[str, Any]:
        """rosmon's node attributes as Node fields (only those set, so plans stay equal)."""
        if not entity.attributes.keys() & rules.ROSMON_NODE_FIELDS.keys():
            return {}
        found: dict[str, Any] = {}
        for attr, field_name in rules.ROSMON_NODE_FIELDS.items():
            (text,) = self._opt(entity, scope, attr)
            if text is not None:
                found[field_name] = self._typed(entity, attr, text)
        return found

    def _req(self, entity: Entity, scope: Scope, *attrs: str) -> list[str]:
        """The resolved values of attributes the table requires (``_check_attrs`` made sure
        they are there)."""
        get = entity.attributes.get
        out: list[str] = []
        for a in attrs:
            value = get(a)
            # fast path: most attribute values hold no substitution at all
            out.append(value if value is not None and "$" not in value
                       else self._resolve(entity, a, scope) or "")
        return out

    def _check_attrs(self, entity: Entity) -> None:
        """The table's attribute rules for ``entity``: unknown attributes are warned about
        and ignored, a missing required or a forbidden one is an error."""
        rule = rules.rule(entity.tag)
        assert rule is not None  # only known tags are dispatched
        present = entity.attributes.keys()
        if not present <= rule.allowed:
            for attr in entity.attributes:
                if attr not in rule.allowed:
                    self._warn(entity, f"unknown <{entity.tag}> attribute '{attr}'",
                               rules.UNKNOWN_ATTRIBUTE, attr)
        for attr in rule.required:
            if attr not in present:
                raise LaunchError(f"<{entity.tag}>: missing required attribute '{attr}'",
                                  entity.location, tag=entity.tag, attribute=attr,
                                  code=rules.MISSING_ATTRIBUTE, exact=entity.where())
        for attr in rule.forbidden:
            if attr in present:
                raise self._error(entity, f"<{entity.tag}> cannot have this attribute", attr,
                                  rules.FORBIDDEN_ATTRIBUTE)
        if entity.children and not rule.children:
            for child in entity.children:
                if not (entity.tag == "machine" and child.tag == "env"):  # an error, below
                    self._warn(child, f"unrecognized <{child.tag}> tag in <{entity.tag}>",
                               rules.UNKNOWN_TAG)

    def _typed(self, entity: Entity, attr: str, value: str | None, default: Any = None) -> Any:
        """``value`` (resolved) read as the kind the table gives ``attr``; ``default`` when
        the attribute is not written."""
        if value is None:
            return default
        try:
            parsed = rules.parse(entity.tag, attr, value)
        except ValueError as exc:
            raise self._error(entity, str(exc), attr, rules.BAD_VALUE) from None
        return default if parsed is None else parsed

    def _enabled(self, entity: Entity, scope: Scope) -> bool:
        """roslaunch's if/unless: both is an error; values must be true/false/1/0."""
        has_if, has_unless = "if" in entity.attributes, "unless" in entity.attributes
        if not has_if and not has_unless:
            return True
        if has_if and has_unless:
            raise self._error(entity, "cannot set both 'if' and 'unless' on the same tag",
                              "unless", rules.IF_UNLESS)
        attr = "if" if has_if else "unless"
        flag = self._typed(entity, attr, self._resolve(entity, attr, scope) or "")
        return flag if has_if else not flag

    def _set_param(self, name: str, value: Any) -> None:
        key = canonicalize(name)
        self.params[key] = value

    # ================================================================ tags
    def _check_launch_tag(self, entity: Entity, scope: Scope) -> None:
        if entity.tag != "launch":
            raise self._error(entity, "the root element must be <launch>",
                              code=rules.UNKNOWN_TAG)
        if self._enabled(entity, scope):
            self._check_attrs(entity)
            deprecated = entity.attributes.get("deprecated")
            if deprecated:
                self._warn(entity, f"DEPRECATED: {deprecated}")

    def _children(self, children: list[Entity], scope: Scope,
                  default_machine: Machine | None) -> Machine | None:
        for entity in children:
            tag = entity.tag
            handler = _TAGS.get(tag)
            if handler is None:
                self._warn(entity, f"unrecognized tag <{tag}>", rules.UNKNOWN_TAG)
                continue
            try:
                result = handler(self, entity, scope, default_machine)
            except RecursionError:
                # groups inside includes inside groups... deeper than Python's stack: the
                # innermost element reached is where the file is refused
                raise self._error(entity, "elements and includes nest too deeply") from None
            if tag in ("group", "include", "machine") and result is not None:
                default_machine = result
        return default_machine

    def _ns_and_clear_params(self, entity: Entity, scope: Scope, node_name: str | None = None,
                             include_file: str | None = None) -> Scope:
        ns = None
        if "ns" in entity.attributes:
            ns = self._resolve(entity, "ns", scope)
            if not ns:
                raise self._error(entity, "empty namespace", "ns")
        try:
            if include_file is not None:
                child = scope.include_child(ns, include_file)
            elif entity.tag in ("node", "test"):
                child = scope.node_child(ns)
            else:
                child = scope.child(ns)
        except ScopeError as exc:
            raise self._error(entity, str(exc), "ns") from None
        clear = self._resolve(entity, "clear_params", scope)
        if self._typed(entity, "clear_params", clear, False):
            if entity.tag in ("node", "test"):
                if not node_name:
                    raise self._error(entity, "'name' must be set to use clear_params",
                                      "clear_params")
                self.clear_params.append(make_global_ns(ns_join(child.ns, node_name)))
            else:
                if not ns:
                    raise self._error(entity, "'ns' must be set to use clear_params",
                                      "clear_params")
                self.clear_params.append(child.ns)
        return child

    def _group(self, entity: Entity, scope: Scope, default_machine: Machine | None
               ) -> Machine | None:
        if not self._enabled(entity, scope):
            return None
        self._check_attrs(entity)
        child = self._ns_and_clear_params(entity, scope)
        child.params = dict(child.params)
        return self._children(entity.children, child, default_machine)

    # ---------------------------------------------------------------- arg
    def _arg(self, entity: Entity, scope: Scope, default_machine: Machine | None = None
             ) -> None:
        if not self._enabled(entity, scope):
            return None
        self._check_attrs(entity)
        (name,) = self._req(entity, scope, "name")
        value, default, _doc = self._opt(entity, scope, "value", "default", "doc")
        if value is not None and default is not None:
            raise self._error(entity, "<arg> may have only one of value/default")
        try:
            scope.add_arg(name, default=default, value=value)
        except ScopeError as exc:
            raise self._error(entity, str(exc), "name") from None
        return None

    # ---------------------------------------------------------------- env
    def _env(self, entity: Entity, scope: Scope, default_machine: Machine | None = None
             ) -> None:
        if not self._enabled(entity, scope):
            return None
        self._check_attrs(entity)
        name, value = self._req(entity, scope, "name", "value")
        if not name:
            raise self._error(entity, "'name' must be non-empty", "name")
        scope.env_args.append((name, value))
        return None

    # ---------------------------------------------------------------- remap
    def _remap_pair(self, entity: Entity, scope: Scope) -> tuple[str, str] | None:
        if not self._enabled(entity, scope):
            return None
        self._check_attrs(entity)
        src, dst = self._req(entity, scope, "from", "to")
        return src, dst

    def _add_remap(self, entity: Entity, target: Scope, pair: tuple[str, str]) -> None:
        try:
            target.add_remap(*pair)
        except ScopeError as exc:
            raise self._error(entity, str(exc)) from None

    def _remap(self, entity: Entity, scope: Scope, default_machine: Machine | None = None
               ) -> None:
        pair = self._remap_pair(entity, scope)
        if pair is not None:
            self._add_remap(entity, scope, pair)
        return None

    # ---------------------------------------------------------------- machine
    def _machine(self, entity: Entity, scope: Scope, default_machine: Machine | None = None
                 ) -> Machine | None:
        if not self._enabled(entity, scope):
            return None
        scope = scope.child(None)
        legacy = self._opt(entity, scope, "ros-root", "ros-package-path", "ros-ip",
                           "ros-hostname")
        if any(legacy):
            raise self._error(entity, "ros-* attributes are not supported since ROS Fuerte; "
                              "use env-loader instead")
        self._check_attrs(entity)
        name, address = self._req(entity, scope, "name", "address")
        env_loader, ssh_port, user, password, default, timeout = self._opt(
            entity, scope, "env-loader", "ssh-port", "user", "password", "default", "timeout")
        port = self._typed(entity, "ssh-port", ssh_port or "")
        default = self._typed(entity, "default", default or "")
        for child in entity.children:
            if child.tag == "env":
                raise self._error(child, "<env> inside <machine> is not supported since ROS "
                                  "Fuerte; use env-loader instead")
        timeout_value = self._typed(entity, "timeout", timeout, DEFAULT_TIMEOUT)
        if not env_loader:
            distro = os.environ.get("ROS_DISTRO", "")
            env_loader = f"/opt/ros/{distro}/env.sh" if distro else None
        machine = Machine(name=name, address=address, env_loader=env_loader, ssh_port=port,
                          user=user or None, password=password or None,
                          timeout=timeout_value, assignable=default != "never")
        existing = self.machines.get(name)
        if existing is not None and existing != machine:
            raise self._error(entity, f"machine [{name}] already defined differently", "name")
        if existing is None:
            self.machines[name] = machine
        return machine if default == "true" else None

    # ---------------------------------------------------------------- param
    def _param(self, entity: Entity, scope: Scope, default_machine: Machine | None = None,
               force_local: bool = False) -> None:
        if not self._enabled(entity, scope):
            return None
        self._check_attrs(entity)
        attributes = entity.attributes
        ptype = self._typed(entity, "type", attributes.get("type") or "")
        found = _PARAM_SOURCE_SET.intersection(attributes)
        if len(found) != 1:
            self._opt(entity, scope, *_PARAM_SOURCES)  # a bad substitution is named first
            given = [s for s in _PARAM_SOURCES if s in found]
            raise self._error(entity, "<param> must have exactly one of value/textfile/"
                              f"binfile/command (has {', '.join(given) or 'none'})")
        (source,) = found
        raw = attributes[source]
        if "$" in raw:
            raw = self._resolve(entity, source, scope) or ""
        name = attributes["name"].strip()
        if "$" in name:
            name = self._resolve(entity, "name", scope, name) or ""
        if source == "value":
            value = self._convert(entity, raw.strip(), ptype, source)
        else:
            value = self._param_value(entity, name, ptype, source, raw)
        if is_private(name) or force_local:
            scope.add_param(name, value)
        else:
            self._set_param(ns_join(scope.ns, name), value)
        return None

    def _param_value(self, entity: Entity, name: str, ptype: str, source: str, raw: str
                     ) -> Any:
        """The value of a <param> whose ``source`` is not ``value`` (a file or a command)."""
        if source == "textfile":
            try:
                text = read_text(raw)
            except (OSError, UnicodeDecodeError) as exc:
                raise self._error(entity, f"cannot read [{raw}]: {exc}", "textfile") from None
            return self._convert(entity, text, ptype, source)
        if source == "binfile":
            try:
                return Binary(read_bytes(raw))
            except OSError as exc:
                raise self._error(entity, f"cannot read [{raw}]: {exc}", "binfile") from None
        if self.options.no_exec:
            return {"__command__": raw}
        return self._convert(entity, self._run_command(entity, name, raw), ptype, source)

    def _convert(self, entity: Entity, text: str, ptype: str, source: str) -> Any:
        """``text`` typed by ``ptype``; a bad value or bad YAML is an error at the tag."""
        try:
            if ptype == "yaml":
                # the YAML loader is imported for type="yaml" only (the CLI's start-up time)
                from orchestra.params.yaml import RosparamYamlError, load_yaml_value
                try:
                    return load_yaml_value(text, entity.location.file)
                except RosparamYamlError as exc:
                    raise self._error(entity, exc.message, source) from None
            return convert_value(text, ptype)
        except ValueError as exc:
            raise self._error(entity, str(exc), "type" if ptype != "auto" else source) from None

    def _run_command(self, entity: Entity, name: str, command: str) -> str:
        """roslaunch runs ``command=`` at load time, shell-split but without a shell."""
        import shlex  # here, like subprocess: most loads run no command (CLI start-up time)
        import subprocess

        try:
            argv = shlex.split(command)
        except ValueError as exc:
            raise self._error(entity, f"cannot split command [{command}]: {exc}",
                              "command") from None
        if not argv:
            raise self._error(entity, "empty command", "command")
        try:
            proc = subprocess.run(argv, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL,
                                  check=False)
        except OSError as exc:
            raise self._error(entity, f"cannot run [{command}]: {exc.strerror}",
                              "command") from None
        if proc.returncode != 0:
            raise self._error(entity, f"command for param [{name}] failed with exit code "
                              f"{proc.returncode}: [{command}]", "command")
        return proc.stdout.decode("utf-8", "replace")

    # ---------------------------------------------------------------- rosparam
    def _rosparam(self, entity: Entity, scope: Scope, default_machine: Machine | None = None
                  ) -> None:
        if not self._enabled(entity, scope):
            return None
        self._check_attrs(entity)
        cmd, ns, file_, param, subst = self._opt(entity, scope, "command", "ns", "file",
                                                  "param", "subst_value")
        subst_value = self._typed(entity, "subst_value", subst, False)
        param = ns_join(ns or "", param or "")
        cmd = self._typed(entity, "command", cmd or "")
        if file_ is not None:
            if cmd == "load" and not os.path.isfile(file_):
                raise self._error(entity, f"file does not exist [{file_}]", "file")
            if cmd == "delete":
                raise self._error(entity, "'file' is invalid with command='delete'", "file")
        full = ns_join(scope.ns, param) if param else scope.ns
        if cmd != "load":
            self._param_action(entity, cmd, full, file_)
            return None
        source = file_ or entity.location.file
        if file_:
            try:
                text = read_text(file_)
            except (OSError, UnicodeDecodeError) as exc:
                raise self._error(entity, f"cannot read [{file_}]: {exc}", "file") from None
        else:
            text = entity.text or ""
        if subst_value:
            try:
                text = resolve(text, scope) or ""
            except ArgNotSet as exc:
                raise self._error(entity, f"arg '{exc.name}' is not set here",
                                  "subst_value") from None
            except SubstitutionError as exc:
                raise self._error(entity, exc.message, "subst_value") from None
        from orchestra.params.yaml import RosparamYamlError, load_rosparam_yaml
        try:
            data = load_rosparam_yaml(text, source)
        except RosparamYamlError as exc:
            if file_:
                raise
            raise self._error(entity, f"inline YAML: {exc.message}") from None
        if not param and not isinstance(data, dict):
            raise self._error(entity, "'param' must be set for non-dictionary values", "param")
        self._add_rosparam(entity, full, data)
        return None

    def _param_action(self, entity: Entity, cmd: str, full: str, file_: str | None) -> None:
        """Record a dump/delete for launch time (roslaunch runs ``rosparam`` then).

        roslaunch hands the name to the rosparam tool, which resolves a private ``~name``
        under its own node name ``/rosparam``; the name is resolved here the same way, once.
        """
        if is_private(full):
            resolved = canonicalize(ns_join("/rosparam/", full[1:]))
            self._warn(entity, f"private name '{full}' in <rosparam command=\"{cmd}\"> means "
                       f"[{resolved}] (rosparam resolves it under its own node name)")
            full = resolved
        self.param_actions.append(ParamAction(
            command=cmd, param=canonicalize(full), file=file_,
            filename=entity.location.file, line=entity.location.line))

    def _add_rosparam(self, entity: Entity, name: str, value: Any) -> None:
        if name == "/" and not isinstance(value, dict):
            raise self._error(entity, "cannot load a non-dictionary into the global namespace")
        from orchestra.params.yaml import flatten
        for key, val in flatten(name, value):
            self._set_param(key, Binary(val) if isinstance(val, bytes) else val)

    # ---------------------------------------------------------------- node / test
    def _node(self, entity: Entity, scope: Scope, default_machine: Machine | None
              ) -> None:
        self._node_or_test(entity, scope, default_machine, is_test=False)
        return None

    def _test(self, entity: Entity, scope: Scope, default_machine: Machine | None
              ) -> None:
        if not self.options.keep_broken_tests:
            self._node_or_test(entity, scope, default_machine, is_test=True)
            return None
        try:
            self._node_or_test(entity, scope, default_machine, is_test=True)
        except LaunchError as exc:
            label = (entity.attributes.get("test-name") or entity.attributes.get("name")
                     or f"<test> at {entity.location}")
            self.broken_tests.append((label, exc))
        return None

    def _test_attrs(self, entity: Entity, scope: Scope) -> tuple[str, float, int]:
        (test_name,) = self._req(entity, scope, "test-name")
        time_limit_raw = self._resolve(entity, "time-limit", scope) or ""
        retry_raw = self._resolve(entity, "retry", scope) or ""
        time_limit = self._typed(entity, "time-limit", time_limit_raw, TEST_TIME_LIMIT)
        retry = self._typed(entity, "retry", retry_raw, 0)
        return test_name, time_limit, retry

    def _node_or_test(self, entity: Entity, scope: Scope, default_machine: Machine | None,
                      is_test: bool) -> None:
        if not self._enabled(entity, scope):
            return
        self._check_attrs(entity)
        if is_test:
            (name,) = self._opt(entity, scope, "name")
            test_name, time_limit, retry = self._test_attrs(entity, scope)
            if not name:
                name = test_name
        else:
            (name,) = self._req(entity, scope, "name")
        if not is_legal_name(name):
            self._warn(entity, f"illegal node name '{name}'")
        child = self._ns_and_clear_params(entity, scope, node_name=name)
        try:
            param_scope = child.node_child(name)
        except ScopeError as exc:
            raise self._error(entity, str(exc), "name") from None
        param_scope.params = {}
        pkg, node_type = self._req(entity, scope, "pkg", "type")
        machine, args, output, respawn, respawn_delay, cwd, launch_prefix, required = \
            self._opt(entity, scope, "machine", "args", "output", "respawn", "respawn_delay",
                      "cwd", "launch-prefix", "required")
        if "machine" in entity.attributes and not (machine or "").strip():
            raise self._error(entity, "must be non-empty", "machine")
        if not machine and default_machine is not None:
            machine = default_machine.name
        required_flag = self._typed(entity, "required", required, False)
        respawn_flag = self._typed(entity, "respawn", respawn, False) if not is_test else False
        delay = self._typed(entity, "respawn_delay", respawn_delay, 0.0) if not is_test else 0.0
        rosmon = self._rosmon_attrs(entity, scope)

        # the node's own remaps and <env>s, each in a scope of its own (made when the node
        # has any: most have none, and then the surrounding scope's are the node's)
        remap_scope = env_scope = scope
        rule = rules.TAGS["test" if is_test else "node"]
        for sub in entity.children:
            tag = rule.child_tag(sub.tag)
            if tag is None:
                self._warn(sub, f"unrecognized <{sub.tag}> tag in <{entity.tag}>",
                           rules.UNKNOWN_TAG)
            elif tag == "remap":
                pair = self._remap_pair(sub, scope)
                if pair is not None:
                    if remap_scope is scope:
                        remap_scope = scope.child("")
                    self._add_remap(sub, remap_scope, pair)
            elif tag == "param":
                self._param(sub, param_scope, force_local=True)
            elif tag == "rosparam":
                self._rosparam(sub, param_scope)
            elif tag == "env":
                if env_scope is scope:
                    env_scope = scope.child("")
                self._env(sub, env_scope)

        node_ns, set_param = param_scope.ns, self._set_param
        for params in (scope.params, param_scope.params):
            for key, value in params.items():
                set_param(node_ns + (key[1:] if is_private(key) else key), value)

        if respawn_flag and required_flag:
            raise self._error(entity, "respawn and required cannot both be true")
        if name and "/" in name:
            raise self._error(entity, "node name cannot contain a namespace", "name")
        if not pkg.strip():
            raise self._error(entity, "package must be non-empty", "pkg")
        if not node_type.strip():
            raise self._error(entity, "type must be non-empty", "type")
        cwd = self._typed(entity, "cwd", cwd)
        if cwd == "ros_home":
            cwd = "ROS_HOME"
        common: dict[str, Any] = dict(package=pkg, type=node_type, name=name or None,
                      namespace=make_global_ns(child.ns), machine_name=machine or None,
                      args=args or "", remap_args=tuple(remap_scope.remap_args()),
                      env_args=tuple(env_scope.env_args), cwd=cwd,
                      launch_prefix=launch_prefix or None, filename=scope.filename,
                      line=entity.location.line)
        if is_test:
            self.tests.append(Test(output="log", test_name=test_name, time_limit=time_limit,
                                   retry=retry, **common))
            return
        output = self._typed(entity, "output", output)
        node = Node(respawn=respawn_flag, respawn_delay=delay, output=output,
                    required=required_flag, **common, **rosmon)
        full = node.full_name
        if name and full in self._node_names:
            raise self._error(entity, f"duplicate node name [{full}] (first declared at "
                              f"{self._node_names[full]}); use unique names or $(anon id) "
                              "with different ids", "name")
        self._node_names[full] = entity.location
        self.nodes.append(node)

    # ---------------------------------------------------------------- include
    def _include(self, entity: Entity, scope: Scope, default_machine: Machine | None
                 ) -> Machine | None:
        if not self._enabled(entity, scope):
            return None
        self._check_attrs(entity)
        (filename,) = self._req(entity, scope, "file")
        pass_all = self._typed(entity, "pass_all_args",
                               self._resolve(entity, "pass_all_args", scope), False)
        child = self._ns_and_clear_params(entity, scope, include_file=filename)
        if pass_all:
            for name, value in scope.args.items():
                child.add_arg(name, value=value)
            child.pass_all_args = True
        rule = rules.TAGS["include"]
        for sub in entity.children:
            tag = rule.child_tag(sub.tag)
            if tag == "env":
                self._env(sub, child)
            elif tag == "arg":
                self._arg(sub, child)
            else:
                self._warn(sub, f"unrecognized <{sub.tag}> tag in <include>", rules.UNKNOWN_TAG)
        try:
            child.enter_include()
        except ScopeError as exc:
            raise self._error(entity, str(exc)) from None

        key = os.path.abspath(filename)
        if key in scope.include_stack:
            chain = " -> ".join([*scope.include_stack, key])
            raise self._error(entity, f"include cycle: {chain}", "file")
        if len(scope.include_stack) >= MAX_INCLUDE_DEPTH:
            raise self._error(entity, f"includes nest more than {MAX_INCLUDE_DEPTH} files deep",
                              "file")
        try:
            root = self._parse(filename)
        except OrchestraError:
            # a missing file is named as this <include>'s error, not the reader's (asked
            # only on failure: a stat of every included file cost as much as its read)
            if not os.path.isfile(filename):
                raise self._error(entity, f"included file does not exist: [{filename}]",
                                  "file") from None
            raise
        child.include_stack = (*scope.include_stack, key)
        self.files.append(filename)
        try:
            self._check_launch_tag(root, child)
            result = self._children(root.children, child, default_machine)
        except LaunchError as exc:
            # keep the inner location; say how the file was reached
            raise LaunchError(f"{exc.message} (included from {entity.location})",
                              exc.location) from None
        if not pass_all:
            unused = child.unused_include_args()
            if unused:
                raise self._error(entity, f"unused args [{', '.join(unused)}] for include of "
                                  f"[{filename}] (the included file does not declare them)")
        return result

    # ---------------------------------------------------------------- roscore
    def _roscore(self) -> None:
        """What roslaunch's roscore.xml adds before the user's files (run and list modes)."""
        self._set_param("/rosversion", ROSLAUNCH_VERSION + "\n")
        self._set_param("/rosdistro", os.environ.get("ROS_DISTRO", "noetic") + "\n")


def _master(self: Interpreter, entity: Entity, scope: Scope, dm: Machine | None) -> None:
    self._check_attrs(entity)
    self._warn(entity, "ignoring defunct <master> tag", "defunct-tag")


_TAGS: dict[str, Callable[..., Any]] = {
    "group": Interpreter._group,
    "node": Interpreter._node,
    "test": Interpreter._test,
    "param": Interpreter._param,
    "remap": Interpreter._remap,
    "machine": Interpreter._machine,
    "rosparam": Interpreter._rosparam,
    "master": _master,
    "include": Interpreter._include,
    "env": Interpreter._env,
    "arg": Interpreter._arg,
}
assert sorted(_TAGS) == sorted(rules.SCOPE_CHILDREN), "rules.SCOPE_CHILDREN is what dispatches"


def load_launch(path: str, args: dict[str, str] | None = None, *, no_exec: bool = False,
                roscore: bool = False) -> LaunchPlan:
    """Interpret the launch file at ``path`` with command-line ``args``; the plan."""
    interp = Interpreter(LoadOptions(args=dict(args or {}), no_exec=no_exec, roscore=roscore))
    interp.load_file(path)
    return interp.plan()


def binary_to_json(value: Any) -> Any:
    """JSON form of values the plan may hold that JSON lacks (bytes, dates)."""
    if isinstance(value, (bytes, bytearray)):
        import base64

        return {"__binary_b64__": base64.b64encode(bytes(value)).decode("ascii")}
    if hasattr(value, "isoformat"):
        return value.isoformat()
    raise TypeError(f"cannot encode {type(value).__name__}")
