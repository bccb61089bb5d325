"""``orchestra msg`` and ``orchestra srv``: rosmsg's and rossrv's commands, same output.

``show`` prints a definition the way rosmsg does: constants then fields, each nested type
expanded under its field with two more spaces, a blank line at the end; ``-r`` prints the
definition as written (from the package's file when there is one, with comments). A bare
name (``show Pose``) shows every package's type of that name under a ``[pkg/Name]:`` line.
The sources are orchestra's (``msgdefs``): rosbags' standard store, the bundled definitions
and the package path, so the listings include the standard packages even without ROS.
"""
from __future__ import annotations

import sys
from collections.abc import Callable

import click

from orchestra.errors import OrchestraError
from orchestra.node import msgdefs
from orchestra.node.msgspec import BUILTINS, MsgSpec, MsgSpecError

MODES = {"msg": "message", "srv": "service"}


class TypeNotFound(OrchestraError):
    """A message or service type no source defines."""


def spec_text(spec: MsgSpec, lookup: Callable[[str], MsgSpec], indent: str = "") -> str:
    """rosmsg's expanded view of one definition (every line ends with a newline)."""
    lines = [f"{indent}{c.type} {c.name}={c.text}\n" for c in spec.constants]
    for f in spec.fields:
        lines.append(f"{indent}{f.type_text} {f.name}\n")
        if f.base not in BUILTINS:
            lines.append(spec_text(lookup(f.base), lookup, indent + "  "))
    return "".join(lines)


def _spec(type_name: str) -> MsgSpec:
    """A message's spec, through its class: building the class checks every nested type, so
    a broken definition is reported at its file:line rather than as a missing type."""
    from orchestra.node.msg import get_message_class

    spec = get_message_class(type_name)._spec
    assert spec is not None
    return spec


def _from_stdin(value: str | None) -> str:
    """rosmsg's pipe form (``orchestra topic type /x | orchestra msg show``): the argument, or
    the first non-empty line of stdin."""
    if value:
        return value
    for line in sys.stdin:
        if line.strip():
            return line.strip()
    raise click.UsageError("give a type (or pipe one in, as from `orchestra topic type`)")


def _check_name(type_name: str | None, kind: str) -> str:
    type_name = _from_stdin(type_name)
    if type_name.endswith("." + kind):
        type_name = type_name[: -len(kind) - 1]
    if "::" in type_name or "." in type_name:
        raise click.UsageError(f"invalid {MODES[kind]} type '{type_name}': refer to types as "
                               "'package_name/Type'")
    return type_name


def show_text(type_name: str, kind: str, raw: bool) -> str:
    """What ``ros<kind> show [-r] pkg/Name`` prints (without print's final newline)."""
    from orchestra.node.msg import MessageNotFound, get_service_class

    try:
        if raw:
            definition = msgdefs.find_raw(type_name, kind)
            if definition is None:
                raise MessageNotFound(type_name)
            return definition.text
        if kind == "msg":
            return spec_text(_spec(type_name), _spec)
        cls = get_service_class(type_name)
        request, response = cls._request_class._spec, cls._response_class._spec
        assert request is not None and response is not None
        return spec_text(request, _spec) + "---\n" + spec_text(response, _spec)
    except MessageNotFound:
        raise TypeNotFound(f"cannot find {MODES[kind]} type {type_name} (looked in "
                           f"{msgdefs.where_searched()})") from None
    except MsgSpecError as exc:
        raise TypeNotFound(str(exc)) from None


def search(base_name: str, kind: str) -> list[str]:
    """``pkg/Name`` of every package's type called ``base_name`` (sorted by package)."""
    return [f"{pkg}/{base_name}" for pkg in msgdefs.packages(kind)
            if base_name in msgdefs.package_types(pkg, kind)]


def md5_of(type_name: str, kind: str) -> str:
    from orchestra.node.msg import MessageNotFound, get_message_class, get_service_class

    try:
        if kind == "msg":
            return get_message_class(type_name)._md5sum
        return get_service_class(type_name)._md5sum
    except MessageNotFound:
        raise TypeNotFound(f"cannot find {MODES[kind]} type {type_name}") from None
    except MsgSpecError as exc:
        raise TypeNotFound(str(exc)) from None


def package_listing(pkg: str, kind: str) -> list[str]:
    names = msgdefs.package_types(pkg, kind)
    if not names and msgdefs.package_dir(pkg) is None and pkg not in msgdefs.packages(kind):
        raise TypeNotFound(f"unknown package '{pkg}' (looked in {msgdefs.where_searched()})")
    return [f"{pkg}/{name}" for name in names]


def _group(kind: str) -> click.Group:
    noun = MODES[kind]

    @click.group(name=kind, help=f"{noun.capitalize()} types (like ros{kind}): show, md5, "
                                 "list, package, packages.")
    def group() -> None:
        pass

    @group.command("show", help=f"Show the fields of {noun} TYPE (pkg/Name, or Name to "
                                "search every package).")
    @click.option("-r", "--raw", is_flag=True, help="The definition as written, with comments.")
    @click.argument("type_name", metavar="TYPE", required=False)
    def show(raw: bool, type_name: str | None) -> None:
        type_name = _check_name(type_name, kind)
        if "/" in type_name:
            click.echo(show_text(type_name, kind, raw))
            return
        found = search(type_name, kind)
        if not found:
            click.echo(f"Could not find {kind} '{type_name}'", err=True)
            raise SystemExit(1)
        for full in found:
            click.echo(f"[{full}]:")
            click.echo(show_text(full, kind, raw))

    @group.command("md5", help=f"The md5 sum of {noun} TYPE.")
    @click.argument("type_name", metavar="TYPE", required=False)
    def md5(type_name: str | None) -> None:
        type_name = _check_name(type_name, kind)
        if "/" in type_name:
            click.echo(md5_of(type_name, kind))
            return
        found = search(type_name, kind)
        if not found:
            click.echo(f"No messages matching the name [{type_name}]", err=True)
            raise SystemExit(1)
        for full in found:
            click.echo(f"[{full}]: {md5_of(full, kind)}")

    @group.command("list", help=f"Every {noun} type of every package.")
    def list_cmd() -> None:
        for pkg in msgdefs.packages(kind):
            for name in msgdefs.package_types(pkg, kind):
                click.echo(f"{pkg}/{name}")

    @group.command("package", help=f"The {noun} types of PACKAGE.")
    @click.option("-s", "single_line", is_flag=True, help="On one line.")
    @click.argument("package", required=False)
    def package(single_line: bool, package: str | None) -> None:
        listing = package_listing(_from_stdin(package), kind)
        click.echo((" " if single_line else "\n").join(listing))

    @group.command("packages", help=f"The packages that have {noun} types.")
    @click.option("-s", "single_line", is_flag=True, help="On one line.")
    def packages(single_line: bool) -> None:
        click.echo((" " if single_line else "\n").join(msgdefs.packages(kind)))

    return group


msg = _group("msg")
srv = _group("srv")
