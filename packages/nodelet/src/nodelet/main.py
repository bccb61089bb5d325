"""The ``nodelet`` command: ``manager``, ``load``, ``standalone``, ``unload``.

Same command line as ROS's nodelet executable, so launch files written for it run as is::

    nodelet manager
    nodelet load pkg/Type manager [args...]
    nodelet standalone pkg/Type [args...]
    nodelet unload name manager
"""
from __future__ import annotations

import signal
import sys
import threading

from nodelet import names

USAGE = """usage: nodelet manager
       nodelet load pkg/Type manager [args...]
       nodelet standalone pkg/Type [args...]
       nodelet unload name manager"""

LOAD_WAIT_WARN = 10.0   # seconds between "still waiting for the manager" warnings
WATCH_PERIOD = 1.0      # how often a loader checks that its manager is still there
BOND_CHECK_PERIOD = 1.0  # how often a manager checks that its nodelets' loaders still run


def _srv(name: str):
    from orchestra.node.msg import get_service_class
    return get_service_class(name)


def run_manager() -> int:
    from nodelet.manager import LoadError, Manager, uri_alive
    from orchestra import node

    node.init_node("manager")
    manager = Manager()
    load_cls, unload_cls, list_cls = (_srv("nodelet/NodeletLoad"), _srv("nodelet/NodeletUnload"),
                                      _srv("nodelet/NodeletList"))

    def on_load(req):
        remaps = dict(zip(req.remap_source_args, req.remap_target_args, strict=False))
        try:
            manager.load(req.name, req.type, remaps, list(req.my_argv), req.bond_id)
        except LoadError as exc:
            node.logerr("failed to load nodelet '%s' of type '%s': %s", req.name, req.type, exc)
            return load_cls.Response(success=False)
        return load_cls.Response(success=True)

    def on_unload(req):
        ok = manager.unload(req.name)
        if not ok:
            # normal while shutting down: the manager unloads everything before loaders ask
            node.logdebug("unload of unknown nodelet '%s'", req.name)
        return unload_cls.Response(success=ok)

    def on_list(_req):
        return list_cls.Response(nodelets=manager.list())

    node.Service("~load_nodelet", load_cls, on_load)
    node.Service("~unload_nodelet", unload_cls, on_unload)
    node.Service("~list", list_cls, on_list)
    node.on_shutdown(manager.unload_all)
    while not node.is_shutdown():
        try:
            node.sleep(BOND_CHECK_PERIOD)
        except node.ROSInterruptException:
            break
        manager.unload_orphans(uri_alive)
    return 0


def _call_with_timeout(func, timeout: float):
    """Run a blocking call on a helper thread; None when it did not answer in time."""
    result: list = []

    def target():
        try:
            result.append(func())
        except Exception as exc:  # reported by the caller
            result.append(exc)
    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(timeout)
    return result[0] if result else None


def run_loader(type_name: str, manager_name: str, extra: list[str]) -> int:
    from orchestra import node

    stop = threading.Event()
    node.init_node("nodelet", disable_signals=True)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    name = node.get_name()
    remaps = names.parse_remaps(sys.argv[1:], name)
    manager = names.resolve(manager_name, name)
    load_name, unload_name = manager + "/load_nodelet", manager + "/unload_nodelet"

    while not stop.is_set():
        try:
            node.wait_for_service(load_name, timeout=LOAD_WAIT_WARN)
            break
        except node.ROSException:
            node.logwarn("waiting for nodelet manager %s to offer %s", manager, load_name)
    if stop.is_set():
        node.signal_shutdown("interrupted")
        return 0
    load = node.ServiceProxy(load_name, _srv("nodelet/NodeletLoad"))
    try:
        resp = load(name=name, type=type_name, remap_source_args=list(remaps),
                    remap_target_args=list(remaps.values()), my_argv=extra,
                    bond_id=node.get_node_uri())
    except node.ServiceException as exc:
        node.logerr("loading nodelet %s of type %s failed: %s", name, type_name, exc)
        node.signal_shutdown("load failed")
        return 1
    if not resp.success:
        node.logerr("manager %s refused to load nodelet %s of type %s (see its log)",
                    manager, name, type_name)
        node.signal_shutdown("load failed")
        return 1
    node.loginfo("nodelet %s (%s) loaded into %s", name, type_name, manager)

    code, unload_at_exit = 0, True
    while not stop.wait(WATCH_PERIOD):
        if node.is_shutdown():
            # the master shut us down: a new node took our name and owns the nodelet now
            unload_at_exit = False
            break
        # the manager going away takes our nodelet with it: say so and exit (ROS's bond)
        try:
            node.wait_for_service(load_name, timeout=WATCH_PERIOD)
        except node.ROSException:
            if node.is_shutdown():
                unload_at_exit = False
                break
            node.logerr("nodelet manager %s went away; nodelet %s is gone", manager, name)
            code, unload_at_exit = 1, False
            break
    if unload_at_exit:
        unload = node.ServiceProxy(unload_name, _srv("nodelet/NodeletUnload"))
        outcome = _call_with_timeout(lambda: unload(name=name), 2.0)
        if outcome is None or isinstance(outcome, Exception):
            node.logwarn("could not unload %s from %s: %s", name, manager, outcome or "timeout")
    node.signal_shutdown("loader exiting")
    return code


def run_standalone(type_name: str, extra: list[str]) -> int:
    from nodelet.plugins import load_plugin
    from orchestra import node

    node.init_node("nodelet")
    name = node.get_name()
    instance = load_plugin(type_name)(name, names.parse_remaps(sys.argv[1:], name), extra)
    try:
        instance.on_init()
    except Exception as exc:
        from nodelet.manager import is_user_error
        instance.shutdown()
        if not is_user_error(exc):
            raise
        node.logerr("nodelet %s (%s) failed to initialise: %s", name, type_name, exc)
        node.signal_shutdown("init failed")
        return 1
    node.on_shutdown(instance.shutdown)
    node.spin()
    return 0


def run_unload(nodelet_name: str, manager_name: str) -> int:
    from orchestra import node
    node.init_node("nodelet_unload", anonymous=True)
    manager = names.resolve(manager_name, node.get_name())
    node.wait_for_service(manager + "/unload_nodelet", timeout=10.0)
    unload = node.ServiceProxy(manager + "/unload_nodelet", _srv("nodelet/NodeletUnload"))
    ok = unload(name=names.resolve(nodelet_name, node.get_name())).success
    node.signal_shutdown("done")
    return 0 if ok else 1


def main(argv: list[str] | None = None) -> int:
    from orchestra.errors import OrchestraError
    from orchestra.node import ROSException, ROSInterruptException

    argv = sys.argv[1:] if argv is None else argv
    words = names.strip_ros_args(argv)
    if not words:
        sys.stderr.write(USAGE + "\n")
        return 2
    command, rest = words[0], words[1:]
    try:
        if command == "manager":
            return run_manager()
        if command == "load" and len(rest) >= 2:
            return run_loader(rest[0], rest[1], rest[2:])
        if command == "standalone" and len(rest) >= 1:
            return run_standalone(rest[0], rest[1:])
        if command == "unload" and len(rest) >= 2:
            return run_unload(rest[0], rest[1])
    except OrchestraError as exc:
        sys.stderr.write(f"nodelet: error: {exc}\n")
        return exc.exit_code
    except ROSInterruptException:
        return 0
    except ROSException as exc:  # e.g. no master to talk to: one line, not a traceback
        sys.stderr.write(f"nodelet: {exc}\n")
        return 1
    sys.stderr.write(USAGE + "\n")
    return 2
