"""The run's side of the master: find or start it, set /run_id, run the ``<rosparam>``
actions, upload the parameters, register the launch's XML-RPC server.

Like roslaunch: use the master at ROS_MASTER_URI when one answers (or wait for it with
``--wait``), else start the embedded one. The Python API asks for a fresh master on a free
port instead, so that parallel runs (pytest-xdist workers) never share a graph.
"""
from __future__ import annotations

import logging
import os
import time
import urllib.parse
import uuid
import xmlrpc.client
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from orchestra.app.options import RunOptions
from orchestra.errors import Location, OrchestraError
from orchestra.launch.plan import LaunchPlan
from orchestra.master import (
    MasterHandle,
    core_params,
    master_is_up,
    master_uri_from_env,
    port_from_uri,
    start_master,
    upload_params,
)
from orchestra.master.client import MasterUnreachable
from orchestra.rpc import TRANSPORT_ERRORS, call, proxy
from orchestra.supervise import stop_signals

logger = logging.getLogger(__name__)

Report = Callable[[str], None]

LOCAL_NAMES = {"localhost", "127.0.0.1", "::1", "localhost.localdomain", "ip6-localhost"}


@dataclass
class MasterConnection:
    uri: str
    handle: MasterHandle | None = None    # the embedded master, when we started it
    run_id: str = ""

    @property
    def embedded(self) -> bool:
        return self.handle is not None

    def close(self) -> None:
        if self.handle is not None:
            self.handle.shutdown("launch ended")


def is_loopback_uri(uri: str) -> bool:
    host = urllib.parse.urlsplit(uri).hostname or "localhost"
    return host in LOCAL_NAMES or host.startswith("127.")


def _existing_run_id(uri: str) -> str | None:
    try:
        code, _, value = call(uri, "getParam", "/roslaunch", "/run_id", timeout=5.0)
    except Exception:  # noqa: BLE001 - a master without /run_id is fine
        return None
    return value if code == 1 and isinstance(value, str) else None


def connect_master(options: RunOptions, report: Report, public: bool = False
                   ) -> MasterConnection:
    """Use the master at ROS_MASTER_URI if it answers, wait for it (--wait), or embed one.

    ``public``: other machines must reach an embedded master (the plan has remote nodes),
    so it listens on every interface even when ROS_MASTER_URI names localhost.
    """
    if options.fresh_master:
        handle = start_master("0.0.0.0" if public else "127.0.0.1", options.port or 0,
                              advertise=None if public else "localhost")
        report(f"started embedded master at {handle.uri}")
        return MasterConnection(handle.uri, handle, options.run_id or str(uuid.uuid1()))
    uri = options.master_uri or master_uri_from_env()
    if options.port is not None:
        parts = urllib.parse.urlsplit(uri)
        uri = f"http://{parts.hostname or 'localhost'}:{options.port}/"
    if master_is_up(uri):
        run_id = _existing_run_id(uri) or options.run_id or str(uuid.uuid1())
        return MasterConnection(uri, None, run_id)
    if options.wait:
        report(f"waiting for the master at {uri} ...")
        while not master_is_up(uri):
            if stop_signals.pending():   # recorded by the launch command (Ctrl-C)
                raise KeyboardInterrupt
            time.sleep(0.2)
        run_id = _existing_run_id(uri) or options.run_id or str(uuid.uuid1())
        return MasterConnection(uri, None, run_id)
    host = urllib.parse.urlsplit(uri).hostname or "localhost"
    bind = "127.0.0.1" if is_loopback_uri(uri) and not public else "0.0.0.0"
    handle = start_master(bind, port_from_uri(uri), advertise=host)
    report(f"started embedded master at {handle.uri}")
    return MasterConnection(handle.uri, handle, options.run_id or str(uuid.uuid1()))


def upload(plan: LaunchPlan, master: MasterConnection) -> None:
    """roscore's params when the master is ours, the plan's, /run_id; after clear_params."""
    params: dict[str, Any] = {}
    if master.embedded:
        params.update(core_params(master.run_id))
    params.update(plan.params)
    params["/run_id"] = master.run_id
    upload_params(master.uri, params, list(plan.clear_params))


def check_param_actions(plan: LaunchPlan) -> None:
    """A ``<rosparam command="dump">`` that cannot write its file, refused before anything
    starts (roslaunch only fails when it gets there, with the master already up)."""
    for action in plan.param_actions:
        if action.command != "dump":
            continue
        where = Location(action.filename, action.line) if action.filename else None
        if not action.file:
            raise OrchestraError("<rosparam command=\"dump\">: 'file' must be set to dump "
                                 f"[{action.param}] at launch time", where)
        folder = os.path.dirname(os.path.abspath(action.file))
        if not os.path.isdir(folder):
            raise OrchestraError(f"<rosparam command=\"dump\">: cannot write [{action.file}]: "
                                 f"no directory {folder}", where)


def run_param_actions(plan: LaunchPlan, uri: str, report: Report) -> None:
    """roslaunch's setup phase: every ``<rosparam>`` dump and delete, in document order.

    roslaunch runs them after the master is up and BEFORE clear_params and the upload, so
    a delete clears what an earlier launch left (this launch's params are set afterwards)
    and a dump writes the server as it was before this launch. As there (where ``rosparam``
    runs as a child whose exit status is ignored), a missing parameter or an unwritable file
    is reported and the launch goes on.
    """
    if not plan.param_actions:
        return
    server: Any = proxy(uri, timeout=30.0)   # XML-RPC answers are untyped
    with server:   # one connection for every action, closed at the end
        for action in plan.param_actions:
            where = f"{action.filename}:{action.line}: " if action.filename else ""
            try:
                if action.command == "delete" and action.param == "/":
                    code, message, _ = server.setParam("/roslaunch", "/", {})  # rosparam: empty it
                elif action.command == "delete":
                    code, message, _ = server.deleteParam("/roslaunch", action.param)
                else:
                    code, message, value = server.getParam("/roslaunch", action.param)
            except xmlrpc.client.Fault as exc:
                code, message = -1, exc.faultString
            except TRANSPORT_ERRORS as exc:
                raise MasterUnreachable(f"cannot reach the master at {uri}: {exc}") from None
            if code != 1:
                report(f"orchestra: warning: {where}rosparam {action.command}: {message}")
                continue
            if action.command == "delete":
                report(f"rosparam delete {action.param}")
                continue
            from orchestra.params.dump import dump_yaml  # (yaml: only when dumping)

            try:
                with open(action.file or "", "w", encoding="utf-8") as fh:
                    fh.write(dump_yaml(value))
            except OSError as exc:
                report(f"orchestra: warning: {where}rosparam dump: cannot write "
                       f"[{action.file}]: {exc.strerror}")
                continue
            report(f"rosparam dump {action.param} -> {action.file}")


def set_param(uri: str, key: str, value: Any) -> None:
    """Best effort: the launch runs without this entry."""
    try:
        call(uri, "setParam", "/roslaunch", key, value, timeout=5.0)
    except Exception as exc:  # noqa: BLE001 - the launch runs without this entry
        logger.warning("cannot set %s on the master: %s", key, exc)


def delete_param(uri: str, key: str) -> None:
    """Best effort: the master may be gone already."""
    try:
        call(uri, "deleteParam", "/roslaunch", key, timeout=5.0)
    except Exception as exc:  # noqa: BLE001 - master may be gone already
        logger.debug("cannot delete %s: %s", key, exc)
