"""The settings of one run (``RunOptions``) and the parsing of their command-line forms.

Plain values only: the CLI turns click's flags into a RunOptions at its edge, the Python API
builds one from keyword arguments, and LaunchRun reads nothing else.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from orchestra.errors import OrchestraError
from orchestra.supervise.process import RestartPolicy
from orchestra.supervise.specs import SpecOptions


@dataclass(frozen=True)
class RunOptions(SpecOptions):
    """Everything ``orchestra launch`` can be told about a run (cli.run_options has the help).

    ``master_uri`` None means ROS_MASTER_URI; ``fresh_master`` starts an embedded master on a
    free port whatever answers there (the API's default, so parallel runs never share one);
    ``log_root`` None means ROS_LOG_DIR / ROS_HOME/log; ``ros_home`` replaces ROS_HOME for the
    run's nodes (their working directory and log root: isolated parallel runs).
    """

    wait: bool = False
    local: bool = False
    disable_title: bool = False
    port: int | None = None
    run_id: str | None = None
    backoff_max: float = RestartPolicy.backoff_max
    crash_limit: int = RestartPolicy.crash_limit
    log_max_bytes: int = 0
    log_backups: int = 5
    status_view: bool | None = None
    ui: bool = False
    with_tests: bool = False
    no_rosout: bool = False
    master_uri: str | None = None
    fresh_master: bool = False
    log_root: str | None = None
    ros_home: str | None = None

    @classmethod
    def from_kwargs(cls, options: Mapping[str, Any]) -> RunOptions:
        """Only the known, set (not None) entries; ``node_timeouts`` may be CLI words."""
        known = {f.name for f in fields(cls)}
        values = {k: v for k, v in options.items() if k in known and v is not None}
        if "node_timeouts" in values and not isinstance(values["node_timeouts"], Mapping):
            values["node_timeouts"] = parse_node_timeouts(values["node_timeouts"])
        return cls(**values)

    def restart_policy(self) -> RestartPolicy:
        return RestartPolicy(backoff_max=self.backoff_max, crash_limit=self.crash_limit)


def parse_node_timeouts(items: Any) -> dict[str, tuple[float | None, float | None]]:
    """``/node=SIGINT[,SIGTERM]`` words -> {"/node": (sigint, sigterm)}."""
    result: dict[str, tuple[float | None, float | None]] = {}
    for item in items or ():
        name, sep, spec = str(item).partition("=")
        parts = spec.split(",")
        try:
            if not sep or not name or len(parts) > 2:
                raise ValueError
            sigint = float(parts[0]) if parts[0] else None
            sigterm = float(parts[1]) if len(parts) > 1 and parts[1] else None
            if (sigint is not None and sigint < 0) or (sigterm is not None and sigterm < 0):
                raise ValueError
        except ValueError:
            raise OrchestraError(f"--node-timeout {item!r}: expected NODE=SIGINT_SECONDS"
                                 "[,SIGTERM_SECONDS], e.g. /camera=30,5") from None
        result[name if name.startswith("/") else "/" + name] = (sigint, sigterm)
    return result


def parse_size(text: str | int | None) -> int:
    """``100M`` / ``512K`` / ``1G`` / bytes -> bytes (0 = no rotation)."""
    if text is None:
        return 0
    if isinstance(text, int):
        return text
    value = text.strip().upper()
    scale = 1
    if value and value[-1] in "KMG":
        scale = 1024 ** ("KMG".index(value[-1]) + 1)
        value = value[:-1]
    try:
        size = int(float(value) * scale)
    except ValueError:
        raise OrchestraError(f"--log-max-size {text!r}: expected a size like 100M") from None
    if size < 0:
        raise OrchestraError(f"--log-max-size {text!r}: must not be negative")
    return size
