"""Priority/timeout multiplexing of velocity commands (yocs_cmd_vel_mux's rules), pure.

Each input has a priority (unique) and a timeout. A message on an input is forwarded when
no input is active, when it comes from the active input, or when its priority is higher
than the active one's; the input then becomes active. The active input stays active until
it has been silent for its own timeout; then the mux is idle and any input may take over.
So a safety controller (high priority, short timeout) overrides teleop only while it speaks,
and teleop (higher than navigation) silences navigation until the operator lets go.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import yaml

from orchestra.errors import Location, OrchestraError

IDLE = "idle"


class MuxConfigError(OrchestraError):
    """A mux configuration yocs would refuse (missing key, duplicate priority, bad value)."""


@dataclass(frozen=True)
class MuxInput:
    name: str
    topic: str
    timeout: float
    priority: int
    short_desc: str = ""


@dataclass(frozen=True)
class MuxConfig:
    inputs: tuple[MuxInput, ...]
    output: str = "output"


def parse_config(data: object, source: str = "<mux config>") -> MuxConfig:
    """Validate the YAML document yocs reads: ``subscribers: [{name, topic, timeout,
    priority[, short_desc]}]`` and optional ``publisher`` (output topic name)."""
    where = Location(source)
    if not isinstance(data, dict) or not isinstance(data.get("subscribers"), list):
        raise MuxConfigError("expected a 'subscribers' list", where)
    inputs: list[MuxInput] = []
    for i, entry in enumerate(data["subscribers"]):
        if not isinstance(entry, dict):
            raise MuxConfigError(f"subscribers[{i}] is not a mapping", where)
        missing = [k for k in ("name", "topic", "timeout", "priority") if k not in entry]
        if missing:
            raise MuxConfigError(f"subscribers[{i}] lacks {', '.join(missing)}", where)
        try:
            timeout = float(entry["timeout"])
            priority = int(entry["priority"])
        except (TypeError, ValueError):
            raise MuxConfigError(f"subscribers[{i}] ('{entry['name']}'): timeout must be a "
                                 "number and priority an integer", where) from None
        if timeout <= 0:
            raise MuxConfigError(f"subscribers[{i}] ('{entry['name']}'): timeout must be > 0",
                                 where)
        if priority < 0:
            raise MuxConfigError(f"subscribers[{i}] ('{entry['name']}'): priority must be "
                                 "an unsigned integer", where)
        inputs.append(MuxInput(str(entry["name"]), str(entry["topic"]), timeout, priority,
                               str(entry.get("short_desc", ""))))
    seen: dict[int, str] = {}
    for item in inputs:
        if item.priority in seen:
            raise MuxConfigError(f"priority {item.priority} is used by both '{seen[item.priority]}'"
                                 f" and '{item.name}' (priorities must be unique)", where)
        seen[item.priority] = item.name
    names = [item.name for item in inputs]
    if len(set(names)) != len(names):
        raise MuxConfigError("subscriber names must be unique", where)
    output = str(data.get("publisher", "output"))
    return MuxConfig(tuple(inputs), output)


def load_config(path: str) -> MuxConfig:
    if not os.path.isfile(path):
        raise MuxConfigError("mux configuration file not found", Location(path))
    with open(path, encoding="utf-8") as fh:
        try:
            data = yaml.safe_load(fh)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            raise MuxConfigError(f"invalid YAML: {getattr(exc, 'problem', exc)}",
                                 Location(path, mark.line + 1 if mark else None)) from None
    return parse_config(data, path)


class CmdVelMux:
    """Which input currently owns the output. Times are seconds on any monotonic clock."""

    def __init__(self, config: MuxConfig):
        self.config = config
        self.active: int | None = None
        self._last: list[float | None] = [None] * len(config.inputs)

    @property
    def active_name(self) -> str:
        return IDLE if self.active is None else self.config.inputs[self.active].name

    def expire(self, now: float) -> bool:
        """Release the active input if it has been silent too long; True when it changed."""
        if self.active is None:
            return False
        last = self._last[self.active]
        if last is None or now - last > self.config.inputs[self.active].timeout:
            self.active = None
            return True
        return False

    def on_message(self, index: int, now: float) -> tuple[bool, bool]:
        """A message arrived on input ``index``: (forward it?, did the active input change?)."""
        changed = self.expire(now)
        self._last[index] = now
        priority = self.config.inputs[index].priority
        if (self.active is None or self.active == index
                or priority > self.config.inputs[self.active].priority):
            if self.active != index:
                self.active = index
                changed = True
            return True, changed
        return False, changed
