"""``orchestra export --to systemd``: a launch plan as systemd units, one per node.

For a robot that should run the same launch file at boot without a supervising orchestra:
systemd then restarts, orders and logs the nodes (journald). The mapping:

- one directory per machine (``local`` for nodes without a remote ``<machine>``), each with
  one ``.service`` per node and one ``.target`` that wants them all;
- the machine that runs the master (``local``) also gets ``<prefix>-master.service``
  (``orchestra core``: master, parameter server, rosout) and ``<prefix>-params.service``
  (a oneshot ``orchestra param load`` of the launch's parameters, written beside it); its
  nodes start after both;
- ``ExecStart`` is ``[ENV_LOADER] orchestra run PKG TYPE ARGS... REMAPS __name:=NAME`` --
  the executable is found on the machine at start, as a remote launch does, and ``orchestra
  run`` exec's it so the node's signals and exit status are systemd's to see;
- ``Environment``: ROS_MASTER_URI (as that machine reaches the master), ROS_NAMESPACE, the
  node's ``<env>``, PYTHONUNBUFFERED;
- ``respawn="true"`` -> ``Restart=always`` with ``RestartSec`` = ``respawn_delay`` (systemd's
  minimum 100 ms); otherwise ``Restart=no``;
- ``required="true"`` -> the machine's other nodes are ``BindsTo=`` + ``After=`` it: when it
  stops or dies, systemd stops them too (roslaunch stops the whole launch; across machines
  systemd cannot, which docs/remote.md says).

Pure functions: ``units(plan, ...)`` returns {relative path: file text}; the CLI writes them.
"""
from __future__ import annotations

import os
import re
import shlex
import urllib.parse
from dataclasses import dataclass
from typing import Any

from orchestra.launch.plan import LaunchPlan, Node

LOCAL = "local"


@dataclass(frozen=True)
class ExportOptions:
    prefix: str                   # unit name prefix, e.g. orchestra-robot
    master_uri: str               # the master as the local machine reaches it
    params_path: str              # absolute path the params file will have
    orchestra: str = "orchestra"  # the command on every machine
    public_master: bool = False   # remote machines exist: the master listens on all interfaces


def unit_name(text: str) -> str:
    """A unit-name-safe form of ``text`` (systemd allows ASCII letters, digits, ``:_.-``)."""
    return re.sub(r"[^A-Za-z0-9:_.-]", "_", text.strip("/").replace("/", "-")) or "root"


def quote_word(word: str) -> str:
    """One ExecStart word: double-quoted, with systemd's specifiers (% and $) escaped."""
    escaped = word.replace("\\", "\\\\").replace('"', '\\"').replace("%", "%%")
    return '"' + escaped.replace("$", "$$") + '"'


def quote_env(name: str, value: str) -> str:
    escaped = value.replace("\\", "\\\\").replace('"', '\\"').replace("%", "%%")
    return f'Environment="{name}={escaped}"'


def node_command(node: Node, orchestra: str, env_loader: str | None) -> list[str]:
    """``[ENV_LOADER] orchestra run PKG TYPE args... remaps __name:=NAME`` (roslaunch's argv
    without the launch-prefix: a prefix such as ``gdb -ex run --args`` needs a terminal)."""
    words = [env_loader] if env_loader else []
    words += [*orchestra.split(), "run", node.package, node.type]
    words += shlex.split(node.args) if node.args else []
    words += [f"{src}:={dst}" for src, dst in node.remap_args]
    words.append(f"__name:={node.name}")
    return words


def machine_of(plan: LaunchPlan, node: Node, is_remote: dict[str, bool]) -> str:
    name = node.machine_name or ""
    return name if name and is_remote.get(name) else LOCAL


def node_unit(node: Node, command: list[str], env: dict[str, str], after: list[str],
              binds: list[str], target: str, description: str) -> str:
    lines = ["[Unit]", f"Description={description}", f"PartOf={target}"]
    if after:
        lines.append("After=" + " ".join(after))
        lines.append("Wants=" + " ".join(after))
    if binds:
        lines.append("BindsTo=" + " ".join(binds))
    if node.respawn and not node.required:
        lines += ["StartLimitIntervalSec=0"]
    lines += ["", "[Service]", "Type=simple"]
    lines += [quote_env(k, v) for k, v in env.items()]
    lines.append("ExecStart=" + " ".join(quote_word(w) for w in command))
    lines.append("KillSignal=SIGINT")
    if node.respawn and not node.required:
        lines += ["Restart=always", f"RestartSec={max(node.respawn_delay, 0.1):g}"]
    else:
        lines.append("Restart=no")
    lines += ["", "[Install]", f"WantedBy={target}", ""]
    return "\n".join(lines)


def units(plan: LaunchPlan, options: ExportOptions, is_remote: dict[str, bool],
          master_uris: dict[str, str]) -> dict[str, str]:
    """{``<machine>/<unit file>``: text} for every node of ``plan``.

    ``is_remote``: machine name -> remote? (roslaunch's rule, decided by the caller);
    ``master_uris``: remote machine name -> the master URI as that machine reaches it.
    """
    files: dict[str, str] = {}
    nodes = [n for n in plan.nodes if n.name]
    by_machine: dict[str, list[Node]] = {}
    for node in nodes:
        by_machine.setdefault(machine_of(plan, node, is_remote), []).append(node)
    core = [f"{options.prefix}-master.service", f"{options.prefix}-params.service"]
    for machine, members in by_machine.items():
        target = f"{options.prefix}.target"
        required = [f"{options.prefix}-{unit_name(n.full_name)}.service"
                    for n in members if n.required]
        loader = plan.machines[members[0].machine_name or ""].env_loader \
            if machine != LOCAL else None
        uri = options.master_uri if machine == LOCAL else master_uris[machine]
        for node in members:
            name = f"{options.prefix}-{unit_name(node.full_name)}.service"
            env = {"ROS_MASTER_URI": uri, "PYTHONUNBUFFERED": "1"}
            namespace = node.namespace.rstrip("/")
            if namespace:
                env["ROS_NAMESPACE"] = namespace
            env.update(dict(node.env_args))
            binds = [r for r in required if r != name]
            after = (core if machine == LOCAL else []) + binds
            where = f" ({node.filename}:{node.line})" if node.filename else ""
            files[f"{machine}/{name}"] = node_unit(
                node, node_command(node, options.orchestra, loader), env, after, binds,
                target, f"ROS node {node.full_name}{where}")
        files[f"{machine}/{options.prefix}.target"] = "\n".join([
            "[Unit]", f"Description=orchestra launch {options.prefix} on machine {machine}",
            "Wants=" + " ".join(f"{options.prefix}-{unit_name(n.full_name)}.service"
                                for n in members) + (" " + " ".join(core)
                                                     if machine == LOCAL else ""),
            "", "[Install]", "WantedBy=multi-user.target", ""])
    files.setdefault(f"{LOCAL}/{options.prefix}.target", "\n".join([
        "[Unit]", f"Description=orchestra launch {options.prefix} on machine {LOCAL}",
        "Wants=" + " ".join(core), "", "[Install]", "WantedBy=multi-user.target", ""]))
    files[f"{LOCAL}/{core[0]}"] = "\n".join([
        "[Unit]", f"Description=ROS master, parameter server and rosout ({options.prefix})",
        f"PartOf={options.prefix}.target", "", "[Service]", "Type=simple",
        "ExecStart=" + " ".join(quote_word(w) for w in [
            *options.orchestra.split(), "core", "-p", str(_port(options.master_uri)),
            *(["--host", "0.0.0.0"] if options.public_master else [])]),
        "KillSignal=SIGINT", "Restart=always", "RestartSec=1", "",
        "[Install]", f"WantedBy={options.prefix}.target", ""])
    files[f"{LOCAL}/{core[1]}"] = "\n".join([
        "[Unit]", f"Description=parameters of {options.prefix}", f"After={core[0]}",
        f"Requires={core[0]}", f"PartOf={options.prefix}.target", "",
        "[Service]", "Type=oneshot", "RemainAfterExit=yes",
        quote_env("ROS_MASTER_URI", options.master_uri),
        "ExecStart=" + " ".join(quote_word(w) for w in [
            *options.orchestra.split(), "param", "load", options.params_path, "/"]),
        "Restart=on-failure", "RestartSec=1", "",
        "[Install]", f"WantedBy={options.prefix}.target", ""])
    return files


def _port(uri: str) -> int:
    return urllib.parse.urlsplit(uri).port or 11311


def nested_params(params: dict[str, Any]) -> dict[str, Any]:
    """{"/a/b": 1} -> {"a": {"b": 1}}: what ``orchestra param load FILE /`` reads back."""
    tree: dict[str, Any] = {}
    for key, value in sorted(params.items()):
        parts = [p for p in key.split("/") if p]
        if not parts:
            continue
        branch = tree
        for part in parts[:-1]:
            branch = branch.setdefault(part, {})
        branch[parts[-1]] = value
    return tree


def default_prefix(files_loaded: tuple[str, ...]) -> str:
    stem = os.path.basename(files_loaded[0]).split(".")[0] if files_loaded else "launch"
    return "orchestra-" + unit_name(stem)
