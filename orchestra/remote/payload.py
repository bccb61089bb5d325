"""What the launching host tells the remote agent, as one shell-safe word.

The agent's command line passes through the remote user's shell (ssh runs every command with
``$SHELL -c``), so launch-file text -- node args, remaps, env values -- must never reach it as
shell words: it travels as base64url of JSON, an alphabet no shell interprets. Only the
machine's ``env-loader`` path and the master URI are separate (quoted) words, because the
remote command line is ``env ROS_MASTER_URI=... ENV_LOADER python3 -m orchestra.remote.agent``
exactly as roslaunch runs ``ENV_LOADER roslaunch -c ...`` there.
"""
from __future__ import annotations

import base64
import json
from typing import Any

from orchestra.launch.plan import Node

# the Node fields the remote side needs to build argv, env and cwd as roslaunch's child does
_NODE_FIELDS = ("package", "type", "name", "namespace", "args", "output", "cwd",
                "launch_prefix", "respawn", "required", "filename", "line")


def encode(data: dict[str, Any]) -> str:
    raw = json.dumps(data, separators=(",", ":"), sort_keys=True).encode()
    return base64.urlsafe_b64encode(raw).decode("ascii")


def decode(word: str) -> dict[str, Any]:
    value = json.loads(base64.urlsafe_b64decode(word.encode("ascii")))
    if not isinstance(value, dict):
        raise ValueError("payload is not an object")
    return value


def node_to_data(node: Node) -> dict[str, Any]:
    data: dict[str, Any] = {key: getattr(node, key) for key in _NODE_FIELDS}
    data["remap_args"] = [list(pair) for pair in node.remap_args]
    data["env_args"] = [list(pair) for pair in node.env_args]
    return data


def node_from_data(data: dict[str, Any]) -> Node:
    fields = {key: data[key] for key in _NODE_FIELDS if key in data}
    return Node(**fields,
                remap_args=tuple((str(a), str(b)) for a, b in data.get("remap_args", ())),
                env_args=tuple((str(a), str(b)) for a, b in data.get("env_args", ())))
