"""The node runtime: one per process, created by ``init_node``.

It owns the node's identity (name, namespace, remaps), its two servers (slave XML-RPC and
TCPROS, both on ephemeral ports), its topics and services, and shutdown. Shutdown is the
part rospy gets wrong most often, so it is explicit here: ``signal_shutdown`` marks the node
as shutting down at once (``is_shutdown()`` turns true, sleeps wake up) and starts a
non-daemon cleanup thread that runs the user's hooks, unregisters everything from the
master and closes the sockets; ``spin()`` and interpreter exit wait for that thread, so a
node never leaves stale registrations behind when it is interrupted.
"""
from __future__ import annotations

import atexit
import inspect
import logging
import os
import queue
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any
from urllib.parse import urlparse

from orchestra.node import context, names, rostime, tcpros
from orchestra.node.exceptions import (
    ROSException,
    ROSInitException,
    ROSInterruptException,
    TransportException,
)
from orchestra.node.masterapi import Master, MasterError
from orchestra.node.topics import Publisher, Subscriber, TopicManager
from orchestra.rpc import master_uri_from_env

if TYPE_CHECKING:
    from orchestra.node.services import Service, ServiceServer
    from orchestra.node.slave import SlaveServer

log = logging.getLogger(__name__)
_UNSET = object()


def _advertise_host(special: dict[str, str], master_uri: str) -> str:
    """The host other nodes should use to reach us (ROS_IP/ROS_HOSTNAME rules)."""
    for key in ("__ip", "__hostname"):
        if special.get(key):
            return special[key]
    for var in ("ROS_IP", "ROS_HOSTNAME"):
        if os.environ.get(var):
            return os.environ[var]
    master_host = urlparse(master_uri).hostname or "localhost"
    if master_host in ("localhost", "127.0.0.1", "::1") or master_host.startswith("127."):
        return "127.0.0.1"
    return socket.gethostname()


class TcprosServer:
    """Accepts TCPROS connections and hands each to the topic or service it asks for.

    Threads take turns at ``accept`` (leader/followers): the thread that accepts a
    connection serves it itself while another waits for the next one. A thread created
    per connection (and the hand-off to it) cost about as much as a whole service call on a
    kept connection, and a plain service call is a connection. ``SPARE`` threads wait in
    ``accept``; when the last one takes a connection it starts another before serving, so
    someone is always accepting; a thread done serving goes back to ``accept`` unless
    ``SPARE`` already wait there, and ends."""

    SPARE = 2

    def __init__(self, runtime: NodeRuntime, bind_host: str, advertise_host: str,
                 port: int = 0):
        self.rt = runtime
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind((bind_host, port))
        self.sock.listen(128)
        self.port = self.sock.getsockname()[1]
        self.host = advertise_host
        self.closed = False
        self._lock = threading.Lock()
        self._waiting = 0  # threads in (or about to enter) accept

    def start(self) -> None:
        for _ in range(self.SPARE):
            self._add_thread()

    def _add_thread(self) -> None:
        with self._lock:
            self._waiting += 1
        threading.Thread(target=self._accept_loop, name="tcpros-accept", daemon=True).start()

    def _accept_loop(self) -> None:
        while True:
            try:
                conn, addr = self.sock.accept()
            except OSError:  # closed by stop()
                return
            with self._lock:
                self._waiting -= 1
                alone = self._waiting == 0
            if alone and not self.closed:
                self._add_thread()
            self._handle(conn, addr)
            with self._lock:
                if self.closed or self._waiting >= self.SPARE:
                    return
                self._waiting += 1

    def _handle(self, conn: socket.socket, addr) -> None:
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        reader = tcpros.Reader(conn)
        try:
            conn.settimeout(10.0)
            header = reader.header()
            conn.settimeout(None)
        except (OSError, TransportException) as exc:
            log.debug("bad TCPROS handshake from %s: %s", addr, exc)
            conn.close()
            return
        try:
            if "service" in header:
                server = self.rt.services.get(header["service"])
                if server is None:
                    log.warning("%s asked for unknown service %s", header.get("callerid"),
                                header["service"])
                    tcpros.refuse(conn, f"no service [{header['service']}] provided by "
                                        f"{self.rt.name}")
                    return
                server.handle(conn, reader, header)
            elif "topic" in header:
                self.rt.topics.handle_subscriber(conn, header)
            else:
                log.warning("connection from %s named neither a topic nor a service", addr)
                tcpros.refuse(conn, "no topic or service name detected")
        except OSError as exc:
            log.debug("TCPROS connection from %s failed: %s", addr, exc)
            conn.close()

    def stop(self) -> None:
        self.closed = True
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()


class NodeRuntime:
    """This process's node. Created once by ``init_node``; see the module docstring."""

    def __init__(self, name: str, namespace: str, master_uri: str, remaps: dict[str, str],
                 host: str, argv: list[str]):
        self.name = name
        self.namespace = namespace
        self.master_uri = master_uri
        self.remaps = remaps
        self.argv = argv
        self.master = Master(master_uri, name)
        bind = host if host.startswith("127.") else "0.0.0.0"
        self.topics = TopicManager(self)
        self.services: dict[str, ServiceServer] = {}
        self._services_lock = threading.Lock()
        self._slave: SlaveServer | None = None
        self._tcpros: TcprosServer | None = None
        self._host, self._bind = host, bind
        self._shutdown_requested = threading.Event()
        self._shutdown_reason = ""
        self._cleanup: threading.Thread | None = None
        # set (a plain bool: the signal handler reads it without a lock) when the cleanup ends
        self.cleanup_finished = False
        # re-entrant: a signal handler runs on the main thread, possibly while that thread is
        # inside signal_shutdown() (e.g. at process exit); it must find the cleanup under way
        # instead of waiting for a lock its own thread holds
        self._cleanup_lock = threading.RLock()
        self._hooks: list[Callable[..., Any]] = []
        self.params: dict[str, Any] = {}
        # what init_node adds once the node is registered (see init_node)
        self.rosout: Publisher | None = None
        self.clock_sub: Subscriber | None = None
        self.logger_services: list[Service] = []

    def start(self, xmlrpc_port: int = 0, tcpros_port: int = 0) -> None:
        """Open both servers (port 0 = any free port, the default) and start serving."""
        from orchestra.node.slave import SlaveServer

        tcpros_server: TcprosServer | None = None
        try:
            tcpros_server = TcprosServer(self, self._bind, self._host, tcpros_port)
            slave = SlaveServer(self, self._bind, self._host, xmlrpc_port)
        except OSError as exc:
            if tcpros_server is not None:
                tcpros_server.stop()
            raise ROSInitException(f"cannot open the node's ports on {self._bind}: {exc}") from exc
        self._tcpros, self._slave = tcpros_server, slave
        tcpros_server.start()
        slave.start()
        rostime._set_shutdown_event(self._shutdown_requested)

    @property
    def uri(self) -> str:
        return self._slave.uri if self._slave else ""

    @property
    def tcpros_address(self) -> tuple[str, int]:
        if self._tcpros is None:
            raise ROSInitException("the node has not been started")
        return self._tcpros.host, self._tcpros.port

    # names ----------------------------------------------------------------------------------
    def resolve_name(self, name: str) -> str:
        if not names.is_legal_name(name):
            raise ValueError(f"illegal ROS name: {name!r}")
        return names.resolve(name, self.namespace, self.name, self.remaps)

    # master registration ------------------------------------------------------------------
    def master_register(self, method: str, name: str, type_: str) -> Any:
        """Register with the master, waiting for it to come up (as rospy does)."""
        return self.master_retry(method, name, type_, self.uri)

    def master_retry(self, method: str, *args: Any) -> Any:
        """A master call that waits for the master to come up (used during start-up)."""
        delay = 0.1
        while True:
            try:
                return self.master.call(method, *args)
            except MasterError as exc:
                if exc.code is not None:
                    raise ROSException(f"{method}: {exc}") from exc
                if self.is_shutdown():
                    raise ROSInterruptException(
                        f"shutdown while waiting for the master ({method})") from exc
                if delay == 0.1:
                    log.warning("cannot reach the master at %s, will keep trying",
                                self.master_uri)
                self._shutdown_requested.wait(delay)
                delay = min(delay * 2, 2.0)

    def master_unregister(self, method: str, name: str, api: str | None = None) -> None:
        try:
            self.master.call(method, name, api or self.uri)
        except MasterError as exc:
            log.debug("%s %s failed: %s", method, name, exc)

    # services ---------------------------------------------------------------------------------
    def add_service(self, server: ServiceServer) -> ServiceServer:
        with self._services_lock:
            if server.name in self.services:
                raise ROSException(f"service {server.name} is already provided by this node")
            self.services[server.name] = server
        host, port = self.tcpros_address
        try:
            self.master_retry("registerService", server.name, f"rosrpc://{host}:{port}", self.uri)
        except ROSException as exc:
            with self._services_lock:
                self.services.pop(server.name, None)
            raise ROSException(f"cannot register service {server.name}: {exc}") from exc
        return server

    def remove_service(self, server: ServiceServer) -> None:
        with self._services_lock:
            if self.services.get(server.name) is not server:
                return
            del self.services[server.name]
        host, port = self.tcpros_address
        self.master_unregister("unregisterService", server.name, f"rosrpc://{host}:{port}")
        server.close()

    # introspection ----------------------------------------------------------------------------
    def bus_stats(self) -> list:
        pubs, subs = self.topics.bus_stats()
        with self._services_lock:
            servers = list(self.services.values())
        # ROS: serviceStats = [numRequests, bytesReceived, bytesSent]
        from orchestra.node.topics import xmlrpc_int
        return [pubs, subs, [xmlrpc_int(sum(s.calls for s in servers)),
                             xmlrpc_int(sum(s.bytes_in for s in servers)),
                             xmlrpc_int(sum(s.bytes_out for s in servers))]]

    def bus_info(self) -> list:
        return self.topics.bus_info()

    def param_updated(self, key: str, value: Any) -> None:
        self.params[key] = value

    # shutdown -------------------------------------------------------------------------------------
    def is_shutdown(self) -> bool:
        return self._shutdown_requested.is_set()

    def add_hook(self, hook: Callable[..., Any]) -> None:
        if self.is_shutdown():
            _call_hook(hook, self._shutdown_reason)
            return
        self._hooks.append(hook)

    def signal_shutdown(self, reason: str) -> None:
        with self._cleanup_lock:
            if self._cleanup is not None:
                return
            self._shutdown_reason = reason
            log.info("shutdown: %s", reason)
            # recorded before start(): a re-entrant call (a signal arriving during start)
            # returns instead of starting a second cleanup
            self._cleanup = threading.Thread(target=self._do_cleanup, name="node-shutdown",
                                             daemon=False)
            self._shutdown_requested.set()
            self._cleanup.start()

    def spin(self) -> None:
        """Block until the node is shut down (and its cleanup has finished)."""
        try:
            while not self._shutdown_requested.wait(0.5):
                pass
        except KeyboardInterrupt:
            self.signal_shutdown("keyboard interrupt")
        self.wait_shutdown_done()

    def wait_shutdown_done(self, timeout: float | None = 10.0) -> None:
        with self._cleanup_lock:
            thread = self._cleanup
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)

    def _do_cleanup(self) -> None:
        rostime._wake_sleepers()  # waits on /clock see the shutdown now (not from a signal)
        for hook in list(self._hooks):
            _call_hook(hook, self._shutdown_reason)
        self.topics.close_all()
        with self._services_lock:
            servers = list(self.services.values())
        for server in servers:
            self.remove_service(server)
        if self._tcpros:
            self._tcpros.stop()
        if self._slave:
            self._slave.stop()
        self.cleanup_finished = True


def _call_hook(hook: Callable[..., Any], reason: str) -> None:
    try:
        params: Mapping[str, inspect.Parameter]
        try:
            params = inspect.signature(hook).parameters
        except (TypeError, ValueError):
            params = {}
        if params:
            hook(reason)
        else:
            hook()
    except Exception:
        log.exception("error in shutdown hook %r", hook)


# --- the process-wide node --------------------------------------------------------------------

def get_runtime() -> NodeRuntime:
    """The process's node (held by ``context``); ROSInitException before ``init_node``."""
    return context.current()


def reset(reason: str) -> None:
    """Shut this process's node down and forget it, so ``init_node`` may run again (tools
    that make a short-lived node per command)."""
    rt = context.current_or_none()
    if rt is not None:
        rt.signal_shutdown(reason)
        rt.wait_shutdown_done()
        context.set_current(None)


def _parse_master_uri(uri: str) -> str:
    return uri if uri.endswith("/") else uri + "/"


def init_node(name: str, argv: list[str] | None = None, anonymous: bool = False,
              log_level: int | None = None, disable_rostime: bool = False,
              disable_rosout: bool = False, disable_signals: bool = False,
              xmlrpc_port: int = 0, tcpros_port: int = 0) -> None:
    """Make this process the node ``name`` (see rospy.init_node; same argv conventions).

    When the parameter ``/use_sim_time`` is true (and not ``disable_rostime``), ROS time is
    the simulated time of ``/clock`` (rosgraph_msgs/Clock), as in rospy."""
    argv = list(sys.argv if argv is None else argv)
    parsed = names.parse_args(argv)
    special = parsed.special
    if "__name" in special:
        name = special["__name"]
        anonymous = False
    if not name or "/" in name or "~" in name or not names.is_legal_name(name):
        raise ValueError(f"illegal node name {name!r}: no namespaces or '~' in node names")
    if anonymous:
        name = names.anonymous_name(name)
    namespace = names.make_global_ns(special.get("__ns") or os.environ.get("ROS_NAMESPACE") or "/")
    full_name = namespace + name
    with context.lock:
        existing = context.current_or_none()
        if existing is not None:
            if existing.name == full_name:
                return
            raise ROSInitException(f"init_node() was already called as {existing.name}")
        master_uri = _parse_master_uri(special.get("__master") or master_uri_from_env())
        remaps = names.resolve_remaps(parsed.remaps, namespace, full_name)
        host = _advertise_host(special, master_uri)
        runtime = NodeRuntime(full_name, namespace, master_uri, remaps, host, argv)
        runtime.start(xmlrpc_port, tcpros_port)
        context.set_current(runtime)
    _setup_logging(log_level)
    atexit.register(_at_exit)
    if not disable_signals and threading.current_thread() is threading.main_thread():
        _install_signal_handlers()
    for key, text in parsed.private_params.items():
        try:
            value = _yaml().safe_load(text) if text != "" else ""
        except _yaml().YAMLError:
            value = text
        runtime.master_retry("setParam", runtime.resolve_name("~" + key), value)
    # as rospy: every node offers them (disable_rosout or not; rospy has no flag for them).
    # Offered from a second thread while this one sets up /rosout and the clock: the
    # master round trips overlap (a node's start-up is mostly waiting on them)
    loggers = _Background(_offer_logger_services)
    if not disable_rosout:
        runtime.rosout = _make_rosout()
    if not disable_rostime and _param_is_true(runtime, "/use_sim_time"):
        runtime.clock_sub = _follow_clock()
    runtime.logger_services = loggers.result()


class _Background:
    """``fn()`` on its own thread; ``result()`` joins it and returns (or raises) its outcome."""

    def __init__(self, fn: Callable[[], Any]):
        self._value: Any = None
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, args=(fn,), daemon=True,
                                        name="node-start")
        self._thread.start()

    def _run(self, fn: Callable[[], Any]) -> None:
        try:
            self._value = fn()
        except BaseException as exc:  # handed to the caller of result()
            self._error = exc

    def result(self) -> Any:
        self._thread.join()
        if self._error is not None:
            raise self._error
        return self._value


def _yaml() -> Any:
    """PyYAML, for ``_param:=value`` words only: most nodes have none, and importing it is a
    tenth of the runtime's import time (bench/bench_rospy_layer.py)."""
    import yaml
    return yaml


def _param_is_true(runtime: NodeRuntime, key: str) -> bool:
    """Whether the master has ``key`` set to a true value (waiting for the master)."""
    try:
        return bool(runtime.master_retry("getParam", key))
    except ROSInterruptException:
        raise
    except ROSException:  # not set
        return False


def _follow_clock():
    """Simulated time: ROS time is 0 until the first /clock message, then the last one."""
    from orchestra.node.msg import get_message_class
    from orchestra.node.topics import Subscriber

    rostime._use_sim_time()
    return Subscriber("/clock", get_message_class("rosgraph_msgs/Clock"),
                      lambda msg: rostime._set_sim_time(msg.clock), queue_size=1)


_previous_handlers: dict[int, Any] = {}


_exiting = False

# the signals the handler received, for the signal thread (SimpleQueue.put is re-entrant:
# safe in a signal handler, even one that interrupted another put)
_signals: queue.SimpleQueue[int] = queue.SimpleQueue()
_signal_thread: threading.Thread | None = None


def _install_signal_handlers() -> None:
    """SIGINT/SIGTERM shut the node down; the work runs on the "node-signals" thread."""
    global _signal_thread
    if _signal_thread is None:
        _signal_thread = threading.Thread(target=_handle_signals, name="node-signals",
                                          daemon=True)
        _signal_thread.start()
    for sig in (signal.SIGINT, signal.SIGTERM):
        _previous_handlers[sig] = signal.signal(sig, _on_signal)


def _on_signal(signum, frame) -> None:
    """Runs on the main thread between two bytecodes of whatever it was doing: inside a
    ``Condition.wait`` of a sleep, holding a logging or runtime lock, or inside an earlier
    run of this handler (two SIGINTs within a millisecond). So it takes no lock and logs
    nothing: it queues the signal, and the signal thread shuts the node down.

    A SIGINT after the shutdown's cleanup has finished goes to the previous handler
    (KeyboardInterrupt), for scripts that never look at ``is_shutdown()``; not while the
    cleanup runs (the script is on its way out: an exception raised inside its lock waits
    would corrupt them) and not once the script has ended (``_exiting``: there a
    KeyboardInterrupt would only cut the unregistration short)."""
    rt = context.current_or_none()
    previous = _previous_handlers.get(signum)
    if (signum == signal.SIGINT and rt is not None and rt.cleanup_finished
            and callable(previous) and not _exiting):
        previous(signum, frame)
        return
    _signals.put(signum)


def _handle_signals() -> None:
    """The signal thread: the shutdown work of each signal, on a normal thread."""
    while True:
        signum = _signals.get()
        signal_shutdown(f"signal {signal.Signals(signum).name}")


def _at_exit() -> None:
    global _exiting
    _exiting = True
    rt = context.current_or_none()
    if rt is not None:
        rt.signal_shutdown("process exit")
        rt.wait_shutdown_done()


# --- the rospy-style functions -----------------------------------------------------------------

def is_initialized() -> bool:
    """Whether ``init_node`` has made this process a node (rospy.core.is_initialized)."""
    return context.current_or_none() is not None


def get_name() -> str:
    return get_runtime().name


def get_namespace() -> str:
    return get_runtime().namespace


def get_caller_id() -> str:
    return get_runtime().name


def get_node_uri() -> str:
    return get_runtime().uri


def get_master_uri() -> str:
    return get_runtime().master_uri


def resolve_name(name: str, caller_id: str | None = None) -> str:
    rt = get_runtime()
    if caller_id is None:
        return rt.resolve_name(name)
    return names.resolve(name, names.namespace_of(caller_id), caller_id, rt.remaps)


def remap_name(name: str) -> str:
    return get_runtime().remaps.get(name, name)


def myargv(argv: list[str] | None = None) -> list[str]:
    """``argv`` (default ``sys.argv``) without the ROS ``name:=value`` arguments."""
    argv = sys.argv if argv is None else argv
    return [a for a in argv if not names.is_remap_arg(a)]


def is_shutdown() -> bool:
    rt = context.current_or_none()
    return rt is not None and rt.is_shutdown()


def signal_shutdown(reason: str) -> None:
    rt = context.current_or_none()
    if rt is not None:
        rt.signal_shutdown(reason)


def on_shutdown(h: Callable[..., Any]) -> None:
    get_runtime().add_hook(h)


def spin() -> None:
    """Block until the node is shut down (and its cleanup has finished)."""
    get_runtime().spin()


# params -------------------------------------------------------------------------------------------

# (parameter names are rospy's: callers may pass them as keywords)

def get_param(param_name: str, default: Any = _UNSET) -> Any:
    rt = get_runtime()
    key = rt.resolve_name(param_name)
    code, msg, value = rt.master.raw("getParam", key)
    if code != 1:
        if default is _UNSET:
            raise KeyError(param_name)
        return default
    return value


def get_param_cached(param_name: str, default: Any = _UNSET) -> Any:
    return get_param(param_name, default)


def set_param(param_name: str, param_value: Any) -> None:
    rt = get_runtime()
    rt.master.call("setParam", rt.resolve_name(param_name), param_value)


def has_param(param_name: str) -> bool:
    rt = get_runtime()
    return bool(rt.master.call("hasParam", rt.resolve_name(param_name)))


def delete_param(param_name: str) -> None:
    rt = get_runtime()
    code, msg, _ = rt.master.raw("deleteParam", rt.resolve_name(param_name))
    if code != 1:
        raise KeyError(param_name)


def search_param(param_name: str) -> str | None:
    rt = get_runtime()
    code, msg, value = rt.master.raw("searchParam", param_name)
    return value if code == 1 and value else None


def get_param_names() -> list[str]:
    return list(get_runtime().master.call("getParamNames"))


def get_published_topics(namespace: str = "/") -> list[list[str]]:
    return [list(t) for t in get_runtime().master.call("getPublishedTopics", namespace)]


# waiting ----------------------------------------------------------------------------------------

def wait_for_message(topic: str, topic_type, timeout: float | None = None):
    """The next message on ``topic``; ``ROSException`` if none arrives within ``timeout``."""
    from orchestra.node.topics import Subscriber

    got: list = []
    event = threading.Event()

    def callback(msg):
        if not got:
            got.append(msg)
            event.set()

    sub = Subscriber(topic, topic_type, callback)
    try:
        deadline = None if timeout is None else time.monotonic() + timeout
        while not event.is_set():
            if is_shutdown():
                raise ROSInterruptException("rospy shutdown")
            remaining = 0.2 if deadline is None else min(0.2, deadline - time.monotonic())
            if remaining <= 0:
                raise ROSException(f"timeout exceeded while waiting for message on "
                                   f"{sub.resolved_name}")
            event.wait(remaining)
        return got[0]
    finally:
        sub.unregister()


# logging ----------------------------------------------------------------------------------------

_LEVELS = {logging.DEBUG: ("DEBUG", 1), logging.INFO: ("INFO", 2), logging.WARNING: ("WARN", 4),
           logging.ERROR: ("ERROR", 8), logging.CRITICAL: ("FATAL", 16)}
_user_log = logging.getLogger("rosout")


class _ConsoleHandler(logging.Handler):
    """rospy's console format: ``[INFO] [secs.usecs]: text``; warnings and worse on stderr."""

    def emit(self, record: logging.LogRecord) -> None:
        label = _LEVELS.get(record.levelno, ("INFO", 2))[0]
        stream = sys.stdout if record.levelno < logging.WARNING else sys.stderr
        try:
            stream.write(f"[{label}] [{record.created:.6f}]: {record.getMessage()}\n")
            stream.flush()
        except (OSError, ValueError):
            pass


def _explicitly_lowered(record: logging.LogRecord) -> bool:
    """Warnings and worse from orchestra's library; lower levels only from a logger whose
    own level, or an ancestor's below the root, was set (``~set_logger_level``, or the
    script): ``set_logger_level /node orchestra.node.topics debug`` shows its debug lines."""
    if record.levelno >= logging.WARNING:
        return True
    logger = logging.getLogger(record.name)
    while logger is not None and logger.parent is not None:
        if logger.level != logging.NOTSET:
            return True
        logger = logger.parent
    return False


def _setup_logging(level: int | None) -> None:
    if not any(isinstance(h, _ConsoleHandler) for h in _user_log.handlers):
        _user_log.addHandler(_ConsoleHandler())
    library = logging.getLogger("orchestra.node")
    if not logging.getLogger().handlers and not library.handlers:
        # a node script that configured no logging still shows our warnings (refused
        # connections, handler errors) in the same console format as its own log lines
        handler = _ConsoleHandler()
        handler.addFilter(_explicitly_lowered)
        library.addHandler(handler)
    _user_log.propagate = False
    _user_log.setLevel(_python_level(level))


#: rospy's level constants (``init_node(log_level=rospy.DEBUG)``), as rosgraph_msgs/Log has them
DEBUG, INFO, WARN, ERROR, FATAL = 1, 2, 4, 8, 16
_FROM_ROSPY = {DEBUG: logging.DEBUG, INFO: logging.INFO, WARN: logging.WARNING,
               ERROR: logging.ERROR, FATAL: logging.CRITICAL}


def _python_level(level: int | None) -> int:
    """``init_node``'s ``log_level``: one of rospy's constants above or a ``logging`` level
    (10 and up); anything else is INFO, rospy's default."""
    if level in _FROM_ROSPY:
        return _FROM_ROSPY[level]
    return level if level is not None and level >= 10 else logging.INFO


def _offer_logger_services() -> list:
    """``~get_loggers`` and ``~set_logger_level`` (orchestra/node/loggers.py)."""
    from orchestra.node import loggers

    try:
        return loggers.offer_services()
    except ROSInterruptException:
        raise
    except ROSException as exc:
        log.warning("no logger services: %s", exc)
        return []


def _make_rosout():
    from orchestra.node.msg import get_message_class
    from orchestra.node.topics import Publisher

    try:
        return Publisher("/rosout", get_message_class("rosgraph_msgs/Log"), queue_size=100)
    except ROSException as exc:
        log.warning("no /rosout publisher: %s", exc)
        return None


def _log(level: int, msg: Any, args: tuple, kwargs: dict | None = None,
         depth: int = 2) -> None:
    """Print and publish one message; ``depth`` frames up is the user's call (file, line
    and function of the /rosout record). ``kwargs`` are rospy's: ``logger_name`` logs
    through the child logger ``rosout.<name>`` (so its level can be set apart); the rest
    (``exc_info``, ``stack_info``, ``extra``) go to Python's logging for the console."""
    kwargs = dict(kwargs or {})
    logger_name = kwargs.pop("logger_name", None)
    # below the level of the logger "rosout" (init_node's log_level, or ~set_logger_level
    # since) a message is neither printed nor published, as in rospy
    logger = _user_log.getChild(logger_name) if logger_name else _user_log
    if not logger.isEnabledFor(level):
        return
    text = str(msg) % args if args else str(msg)
    logger.log(level, text, **kwargs)
    rt = context.current_or_none()
    pub = rt.rosout if rt is not None else None
    if rt is None or pub is None or rt.is_shutdown():
        return
    frame = inspect.currentframe()
    caller = frame
    for _ in range(depth):
        caller = caller.f_back if caller is not None else None
    try:
        from orchestra.node.rostime import Time
        m: Any = pub.data_class(level=_LEVELS[level][1], name=rt.name, msg=text,
                           file=caller.f_code.co_filename if caller else "",
                           function=caller.f_code.co_name if caller else "",
                           line=caller.f_lineno if caller else 0,
                           topics=[t for t, _ in rt.topics.publication_list()])
        m.header.stamp = Time.now()
        pub.publish(m)
    except ROSException:
        pass
    finally:
        del frame, caller


def logdebug(msg: Any, *args: Any, **kwargs: Any) -> None:
    _log(logging.DEBUG, msg, args, kwargs)


def loginfo(msg: Any, *args: Any, **kwargs: Any) -> None:
    _log(logging.INFO, msg, args, kwargs)


def logwarn(msg: Any, *args: Any, **kwargs: Any) -> None:
    _log(logging.WARNING, msg, args, kwargs)


def logerr(msg: Any, *args: Any, **kwargs: Any) -> None:
    _log(logging.ERROR, msg, args, kwargs)


def logfatal(msg: Any, *args: Any, **kwargs: Any) -> None:
    _log(logging.CRITICAL, msg, args, kwargs)


# --- the rate-limited forms: each call site (file, line) keeps its own state, as in rospy;
# the helpers below are always called from a public log function, so the user's frame is
# three up from them and the /rosout record names the user's line (depth=3)

_site_state: dict[tuple, Any] = {}
_site_lock = threading.Lock()


def _call_site() -> tuple:
    frame = inspect.currentframe()
    for _ in range(3):
        frame = frame.f_back if frame is not None else None
    try:
        return (frame.f_code.co_filename, frame.f_lineno) if frame is not None else ("?", 0)
    finally:
        del frame


def _throttled(level: int, period: float, msg: Any, args: tuple, kwargs: dict) -> None:
    """At most one message per ``period`` seconds (ROS time, as rospy) from this call site."""
    key = ("throttle",) + _call_site()
    now = rostime.get_time()
    with _site_lock:
        last = _site_state.get(key)
        # a clock that jumped back (sim time reset) starts the period again
        due = last is None or now - last >= period or now < last
        if due:
            _site_state[key] = now
    if due:
        _log(level, msg, args, kwargs, depth=3)


def _throttled_identical(level: int, period: float, msg: Any, args: tuple,
                         kwargs: dict) -> None:
    """A message different from the call site's previous one at once; a repeat of it only
    when ``period`` seconds have passed since it was last logged."""
    key = ("identical",) + _call_site()
    text = str(msg) % args if args else str(msg)
    now = rostime.get_time()
    with _site_lock:
        last = _site_state.get(key)
        due = (last is None or last[1] != text or now - last[0] >= period or now < last[0])
        if due:
            _site_state[key] = (now, text)
    if due:
        _log(level, text, (), kwargs, depth=3)


def _once(level: int, msg: Any, args: tuple, kwargs: dict) -> None:
    """Only the first message from this call site."""
    key = ("once",) + _call_site()
    with _site_lock:
        due = key not in _site_state
        _site_state[key] = True
    if due:
        _log(level, msg, args, kwargs, depth=3)


def logdebug_throttle(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled(logging.DEBUG, period, msg, args, kwargs)


def loginfo_throttle(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled(logging.INFO, period, msg, args, kwargs)


def logwarn_throttle(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled(logging.WARNING, period, msg, args, kwargs)


def logerr_throttle(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled(logging.ERROR, period, msg, args, kwargs)


def logfatal_throttle(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled(logging.CRITICAL, period, msg, args, kwargs)


def logdebug_throttle_identical(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled_identical(logging.DEBUG, period, msg, args, kwargs)


def loginfo_throttle_identical(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled_identical(logging.INFO, period, msg, args, kwargs)


def logwarn_throttle_identical(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled_identical(logging.WARNING, period, msg, args, kwargs)


def logerr_throttle_identical(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled_identical(logging.ERROR, period, msg, args, kwargs)


def logfatal_throttle_identical(period: float, msg: Any, *args: Any, **kwargs: Any) -> None:
    _throttled_identical(logging.CRITICAL, period, msg, args, kwargs)


def logdebug_once(msg: Any, *args: Any, **kwargs: Any) -> None:
    _once(logging.DEBUG, msg, args, kwargs)


def loginfo_once(msg: Any, *args: Any, **kwargs: Any) -> None:
    _once(logging.INFO, msg, args, kwargs)


def logwarn_once(msg: Any, *args: Any, **kwargs: Any) -> None:
    _once(logging.WARNING, msg, args, kwargs)


def logerr_once(msg: Any, *args: Any, **kwargs: Any) -> None:
    _once(logging.ERROR, msg, args, kwargs)


def logfatal_once(msg: Any, *args: Any, **kwargs: Any) -> None:
    _once(logging.CRITICAL, msg, args, kwargs)
