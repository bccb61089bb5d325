"""``orchestra param``: rosparam's commands against any master (ours or a real rosmaster).

Same names, same resolution (relative names in ROS_NAMESPACE, ``~x`` under the tool's own
node name), same output formats; ``set`` and ``load`` merge dictionaries key by key as
rosparam does. Unlike rosparam, ``load`` checks every value of every document first and
sends them in one multicall: a bad file uploads nothing.
"""
from __future__ import annotations

import os
import sys
import xmlrpc.client
from typing import Any

import click

from orchestra.errors import Location, OrchestraError
from orchestra.params.dump import dump_yaml, format_get
from orchestra.params.tree import SEP, ParamValueError, canonical, check_value, ns_join, resolve
from orchestra.rpc import (
    TRANSPORT_ERRORS,
    MasterUnreachable,
    master_uri_from_env,
    multicall_results,
    proxy,
)

NS_KEY = "_ns"  # a YAML document's own namespace, as rosparam reads it


class ParamCommandError(OrchestraError):
    """The master refused the request (parameter not set...): rosparam exits 1 here."""

    exit_code = 1


def _caller_id() -> str:
    return f"/orchestra_param_{os.getpid()}"


def _cli_name(name: str | None, environ: dict[str, str] | None = None) -> str:
    """Resolve a command-line name like rosparam: in ROS_NAMESPACE, ``~`` under the tool."""
    env = os.environ if environ is None else environ
    ns = env.get("ROS_NAMESPACE") or SEP
    if not ns.startswith(SEP):
        ns = SEP + ns
    tool = ns_join(ns, "rosparam")
    return resolve(name or "", tool)


class _Master:
    """The few parameter calls the commands make, with rosparam's error reporting."""

    def __init__(self, uri: str, server: Any):
        self.uri = uri
        self.server = server
        self.caller_id = _caller_id()

    def call(self, method: str, *args: Any) -> Any:
        try:
            code, message, value = getattr(self.server, method)(self.caller_id, *args)
        except xmlrpc.client.Fault as exc:
            raise ParamCommandError(f"master at {self.uri} failed: {exc.faultString}") from None
        except TRANSPORT_ERRORS as exc:
            raise MasterUnreachable(f"unable to communicate with master at {self.uri}: {exc}"
                                    ) from None
        if code != 1:
            raise ParamCommandError(message)
        return value

    def set_many(self, items: list[tuple[str, Any]]) -> None:
        """Set every (name, value) in one multicall (values already checked)."""
        multi = xmlrpc.client.MultiCall(self.server)
        for name, value in items:
            multi.setParam(self.caller_id, name, value)
        try:
            results = multicall_results(multi)
        except xmlrpc.client.Fault as exc:
            raise ParamCommandError(f"master at {self.uri} failed: {exc.faultString}") from None
        except TRANSPORT_ERRORS as exc:
            raise MasterUnreachable(f"unable to communicate with master at {self.uri}: {exc}"
                                    ) from None
        for (name, _), (code, message, _) in zip(items, results, strict=False):
            if code != 1:
                raise ParamCommandError(f"{name}: {message}")


def _leaf_sets(name: str, value: Any, location: Location | None = None
               ) -> list[tuple[str, Any]]:
    """rosparam's set semantics: a dict updates key by key (an empty dict sets nothing)."""
    if isinstance(value, dict):
        out: list[tuple[str, Any]] = []
        for key, sub in value.items():
            if not isinstance(key, str):
                raise ParamValueError(f"parameter '{name}': YAML dictionary key {key!r} is not "
                                      "a string", location)
            out.extend(_leaf_sets(ns_join(name, key) if name != SEP else SEP + key, sub,
                                  location))
        return out
    check_value(name, value, location)
    return [(name, value)]


@click.group()
@click.option("--master-uri", envvar="ROS_MASTER_URI", default=None, metavar="URI",
              help="Master to talk to (default: ROS_MASTER_URI or http://localhost:11311/).")
@click.pass_context
def param(ctx: click.Context, master_uri: str | None) -> None:
    """Get, set, list, delete, load and dump parameters (rosparam compatible)."""
    uri = master_uri or master_uri_from_env()
    # closed with the context: the command may run in-process (tests, click's CliRunner)
    ctx.obj = _Master(uri, ctx.with_resource(proxy(uri, timeout=30.0)))


@param.command("list")
@click.argument("namespace", required=False)
@click.pass_obj
def list_cmd(master: _Master, namespace: str | None) -> None:
    """List parameter names, sorted, optionally only those below NAMESPACE."""
    prefix = _cli_name(namespace) if namespace else SEP
    if not prefix.endswith(SEP):
        prefix += SEP
    names = sorted(n for n in master.call("getParamNames") if n.startswith(prefix))
    for name in names:
        click.echo(name)


@param.command("get")
@click.option("-p", "pretty", is_flag=True, help="Pretty print (not YAML-safe).")
@click.argument("name")
@click.pass_obj
def get_cmd(master: _Master, name: str, pretty: bool) -> None:
    """Print a parameter (a namespace prints as a YAML dictionary)."""
    value = master.call("getParam", _cli_name(name))
    click.echo(format_get(value, pretty), nl=False)


@param.command("set", context_settings={"ignore_unknown_options": True})
@click.option("-t", "--textfile", type=click.Path(exists=True, dir_okay=False),
              help="Set the parameter to the contents of a text file.")
@click.option("-b", "--binfile", type=click.Path(exists=True, dir_okay=False),
              help="Set the parameter to the contents of a binary file.")
@click.argument("name")
@click.argument("value", required=False)
@click.pass_obj
def set_cmd(master: _Master, name: str, value: str | None, textfile: str | None,
            binfile: str | None) -> None:
    """Set NAME to VALUE, read as YAML (a dictionary updates key by key)."""
    from orchestra.params.yaml import load_yaml_value

    target = _cli_name(name)
    if textfile and binfile:
        raise click.UsageError("you may only specify one of --textfile or --binfile")
    if textfile:
        with open(textfile, encoding="utf-8") as fh:
            items = _leaf_sets(target, fh.read())
    elif binfile:
        with open(binfile, "rb") as fh:
            items = _leaf_sets(target, xmlrpc.client.Binary(fh.read()))
    else:
        if value is None:
            raise click.UsageError("please specify a parameter value")
        # an empty word means the empty string (YAML would read null, which cannot be stored)
        parsed = load_yaml_value(value or "!!str", "<command line>")
        items = _leaf_sets(target, parsed, Location("<command line>"))
    master.set_many(items)


@param.command("delete")
@click.argument("name")
@click.pass_obj
def delete_cmd(master: _Master, name: str) -> None:
    """Delete a parameter or a whole namespace ('/' empties the server)."""
    target = _cli_name(name)
    if target == SEP:
        master.call("setParam", SEP, {})
    else:
        master.call("deleteParam", target)


@param.command("load")
@click.argument("file", type=click.Path(allow_dash=True, dir_okay=False))
@click.argument("namespace", required=False)
@click.pass_obj
def load_cmd(master: _Master, file: str, namespace: str | None) -> None:
    """Load a YAML file ('-' = stdin) into NAMESPACE; every document, _ns honoured."""
    if file == "-":
        text, filename = sys.stdin.read(), "<stdin>"
    else:
        try:
            with open(file, encoding="utf-8") as fh:
                text = fh.read()
        except OSError as exc:
            raise OrchestraError(f"cannot read '{file}': {exc.strerror}", Location(file)
                                 ) from None
        filename = file
    items = load_documents(text, filename, _cli_name(namespace))
    if items:
        master.set_many(items)


def load_documents(text: str, filename: str, default_ns: str) -> list[tuple[str, Any]]:
    """Every (name, value) rosparam would set for a YAML file, checked before any upload."""
    import yaml

    from orchestra.params.yaml import RosparamLoader, RosparamYamlError

    try:
        docs = list(yaml.load_all(text, Loader=RosparamLoader))  # noqa: S506 (safe subclass)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        location = Location(filename, mark.line + 1, mark.column + 1) if mark else \
            Location(filename)
        raise RosparamYamlError(f"invalid YAML: {exc.problem or exc}", location) from None
    except yaml.YAMLError as exc:
        raise RosparamYamlError(f"invalid YAML: {exc}", Location(filename)) from None
    items: list[tuple[str, Any]] = []
    for doc in docs:
        if doc is None:
            continue
        ns = default_ns
        if isinstance(doc, dict) and NS_KEY in doc:
            doc = dict(doc)
            ns = canonical(ns_join(default_ns, str(doc.pop(NS_KEY))))
        if ns == SEP and not isinstance(doc, dict):
            raise ParamValueError("global / can only be set to a dictionary", Location(filename))
        items.extend(_leaf_sets(ns, doc, Location(filename)))
    return items


@param.command("dump")
@click.argument("file", required=False)
@click.argument("namespace", required=False)
@click.pass_obj
def dump_cmd(master: _Master, file: str | None, namespace: str | None) -> None:
    """Write NAMESPACE (default: all) as YAML to FILE (default or '-': stdout)."""
    value = master.call("getParam", _cli_name(namespace))
    text = dump_yaml(value)
    if not file or file == "-":
        click.echo(text, nl=False)
        return
    try:
        with open(file, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as exc:
        raise OrchestraError(f"cannot write '{file}': {exc.strerror}", Location(file)) from None
