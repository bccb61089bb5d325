"""``orchestra node|topic|service|graph``: rosnode/rostopic/rosservice/rqt_graph, in one CLI.

Output follows the ROS tools' conventions (``topic echo`` prints each message as YAML then a
``---`` line; ``topic hz`` prints ``average rate`` blocks), so scripts written against them
keep working. Everything goes through the master at ROS_MASTER_URI, which may be orchestra's
or a real rosmaster.
"""
from __future__ import annotations

import math
import queue
import re
import time

import click
import yaml

from orchestra.errors import OrchestraError
from orchestra.node import introspect
from orchestra.node.exceptions import ROSException
from orchestra.node.loggers import LEVEL_NAMES
from orchestra.node.tool import (
    master_uri,
    split_field_path,
    start_cli_node,
    stop_cli_node,
    wait_for_topic,
)


class CommandFailed(OrchestraError):
    """The command ran but what it asked for failed (a service error, ...): exit 1."""

    exit_code = 1


def graph_name(name: str) -> str:
    """A name as typed on the command line (``talker``, ``/ns/talker``) as a global graph
    name; an illegal one is the user's mistake (exit 2)."""
    from orchestra.node.names import canonical, is_legal_name
    if not is_legal_name(name) or name.startswith("~"):
        raise OrchestraError(f"illegal graph name '{name}'")
    return canonical(name if name.startswith("/") else "/" + name)


def _parse_yaml(texts: tuple[str, ...], what: str):
    """One YAML value from the command-line words (several words = a list of field values)."""
    try:
        values = [yaml.safe_load(t) for t in texts]
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise OrchestraError(f"malformed YAML for {what}{where}: {problem}") from None
    if not values:
        return None
    return values[0] if len(values) == 1 else values


def _fill(cls, value, what: str):
    from orchestra.node.msg import FillError, fill_message
    try:
        return fill_message(cls(), value)
    except (FillError, TypeError, ValueError) as exc:
        raise OrchestraError(f"cannot build {what} from the given YAML: {exc}") from None


def _message_class(type_name: str):
    from orchestra.node.msg import MessageNotFound, get_message_class
    from orchestra.node.msgspec import MsgSpecError
    try:
        return get_message_class(type_name)
    except (MessageNotFound, MsgSpecError) as exc:
        raise OrchestraError(str(exc)) from None


# --- node -------------------------------------------------------------------------------------

@click.group()
def node() -> None:
    """Running nodes: list, info, kill, ping, cleanup (like rosnode); loggers and
    set-logger-level (like rosconsole list/get/set)."""


@node.command("list")
def node_list() -> None:
    """Print every node known to the master."""
    for name in introspect.system_state(master_uri()).nodes:
        click.echo(name)


def _bullets(items: list[str]) -> str:
    return "\n".join(f" * {i}" for i in items) + "\n" if items else ""


@node.command("info")
@click.argument("name")
def node_info(name: str) -> None:
    """Publications, subscriptions, services and connections of NAME."""
    uri_master = master_uri()
    name = graph_name(name)
    state = introspect.system_state(uri_master)
    uri = introspect.lookup_node(uri_master, name)
    click.echo("-" * 80)
    click.echo(f"Node [{name}]")
    for title, items in (("Publications", [f"{t} [{state.types.get(t, '*')}]"
                                           for t in state.node_publications(name)]),
                         ("Subscriptions", [f"{t} [{state.types.get(t, 'unknown type')}]"
                                            for t in state.node_subscriptions(name)]),
                         ("Services", state.node_services(name))):
        if items:
            click.echo(f"{title}: \n{_bullets(items)}")
        else:
            click.echo(f"{title}: None\n")
    click.echo(f"\ncontacting node {uri} ...")
    pid, info = introspect.node_bus_info(uri)
    if pid is None:
        click.echo("ERROR: communication with node failed")
        return
    click.echo(f"Pid: {pid}")
    if info:
        click.echo("Connections:")
        node_uris: dict[str, str | None] = {}
        for row in info:
            _cid, dest, direction, transport, topic = row[:5]
            if len(row) > 5 and not row[5]:
                continue  # rosnode lists live connections only
            click.echo(f" * topic: {topic}")
            click.echo(f"    * to: {_peer(uri_master, state, topic, dest, node_uris)}")
            way = {"o": "outbound", "i": "inbound"}.get(direction, "unknown")
            # rospy and roscpp describe the socket in a 7th field; rosnode shows it too
            socket_info = CONNECTION_TEXT.match(row[6]) if len(row) > 6 else None
            if socket_info:
                way += " ({} - {}) [{}]".format(*socket_info.groups())
            click.echo(f"    * direction: {way}")
            click.echo(f"    * transport: {transport}")
    click.echo("")  # rosnode prints the whole block, then a blank line


# "TCPROS connection on port 36527 to [127.0.0.1:43264 on socket 8]"
CONNECTION_TEXT = re.compile(r"\w+ connection on port (\d+) to \[(.*) on socket (\d+)\]")


def _peer(master_uri: str, state, topic: str, dest: str, cache: dict) -> str:
    """rosnode's name for a connection's far end: an inbound connection reports the
    publisher's slave URI, shown as ``/node (uri)`` when a node on the topic has that URI;
    anything else (an outbound connection reports the subscriber's name) as it is."""
    for node in (*state.publishers.get(topic, ()), *state.subscribers.get(topic, ())):
        if node not in cache:
            try:
                cache[node] = introspect.lookup_node(master_uri, node)
            except OrchestraError:
                cache[node] = None
        if cache[node] == dest:
            return f"{node} ({dest})"
    return dest


@node.command("kill")
@click.argument("names", nargs=-1)
@click.option("-a", "--all", "kill_all", is_flag=True, help="Kill every node.")
def node_kill(names: tuple[str, ...], kill_all: bool) -> None:
    """Ask NAMES to shut down (through their slave API, as rosnode kill does)."""
    uri = master_uri()
    targets = introspect.system_state(uri).nodes if kill_all else [graph_name(n) for n in names]
    if not targets:
        raise OrchestraError("give the node names to kill, or --all")
    failed = []
    for name in targets:
        click.echo(f"killing {name}")
        try:
            introspect.kill_node(uri, name)
        except introspect.GraphError as exc:
            click.echo(f"ERROR: {exc}", err=True)
            failed.append(name)
    if failed:
        raise CommandFailed(f"could not kill {', '.join(failed)}")
    click.echo("killed")


@node.command("ping")
@click.argument("name")
@click.option("-c", "count", type=click.IntRange(min=1), default=1, show_default=True,
              help="Number of pings.")
def node_ping(name: str, count: int) -> None:
    """Check that NAME answers on its XML-RPC API, and how fast."""
    uri_master = master_uri()
    name = graph_name(name)
    for i in range(count):
        uri, rtt = introspect.ping_node(uri_master, name)
        if rtt is None:
            raise CommandFailed(f"node [{name}] at {uri} does not answer")
        click.echo(f"xmlrpc reply from {uri}\ttime={rtt * 1000:.6f}ms")
        if i + 1 < count:
            time.sleep(1.0)


@node.command("cleanup")
@click.option("-y", "--yes", is_flag=True, help="Purge without asking.")
def node_cleanup(yes: bool) -> None:
    """Unregister nodes that died without unregistering (their API no longer answers)."""
    uri = master_uri()
    state = introspect.system_state(uri)
    dead = introspect.unreachable_nodes(uri, state)
    if not dead:
        click.echo("no unreachable nodes")
        return
    click.echo("Unable to contact the following nodes:")
    for name in dead:
        click.echo(f" * {name}")
    if not yes and not click.confirm("Purge them from the master?", default=False):
        return
    for name in dead:
        introspect.purge_node(uri, state, name)
        click.echo(f"unregistered {name}")


def _node_loggers(uri_master: str, node_name: str) -> list[tuple[str, str]]:
    """(logger, level) pairs from the node's ``~get_loggers`` service, in its order."""
    from orchestra.node.msg import get_service_class
    cls = get_service_class("roscpp/GetLoggers")
    name = _logger_service(uri_master, node_name, "get_loggers", cls)
    response = _call_service(uri_master, name, cls, cls._request_class())
    return [(logger.name, logger.level) for logger in response.loggers]


def _logger_service(uri_master: str, node_name: str, suffix: str, cls) -> str:
    """``NODE/suffix``, checked to be there and of the expected type (rosconsole's check)."""
    name = f"{node_name}/{suffix}"
    try:
        header = introspect.service_header(uri_master, name)
    except introspect.GraphError as exc:
        raise introspect.GraphError(f"node [{node_name}] does not exist or offers no logger "
                                    f"services: {exc}") from None
    if header.get("md5sum") not in (None, "*", cls._md5sum):
        raise CommandFailed(f"service [{name}] is not a {cls._type} "
                            f"({header.get('type', 'unknown type')})")
    return name


@node.command("loggers")
@click.argument("name")
@click.argument("logger", required=False)
@click.option("-l", "--levels", is_flag=True, help="Print each logger's level after its name.")
def node_loggers(name: str, logger: str | None, levels: bool) -> None:
    """Print the loggers of node NAME, one per line (as rosconsole list); with LOGGER, print
    that logger's level (as rosconsole get)."""
    uri_master = master_uri()
    name = graph_name(name)
    loggers = _node_loggers(uri_master, name)
    if logger is not None:
        table = dict(loggers)
        if logger not in table:
            raise OrchestraError(f"node {name} does not contain logger {logger}")
        click.echo(table[logger])
        return
    width = max((len(n) for n, _ in loggers), default=0)
    for logger_name, level in loggers:
        click.echo(f"{logger_name:<{width}}  {level}" if levels else logger_name)


@node.command("set-logger-level")
@click.argument("name")
@click.argument("logger")
@click.argument("level", metavar="LEVEL",
                type=click.Choice(LEVEL_NAMES, case_sensitive=False))
def node_set_logger_level(name: str, logger: str, level: str) -> None:
    """Set LOGGER of node NAME to LEVEL (debug, info, warn, error or fatal) at once, as
    rosconsole set does."""
    from orchestra.node.msg import get_service_class
    uri_master = master_uri()
    name = graph_name(name)
    if logger not in dict(_node_loggers(uri_master, name)):
        raise OrchestraError(f"node {name} does not contain logger {logger}")
    cls = get_service_class("roscpp/SetLoggerLevel")
    service = _logger_service(uri_master, name, "set_logger_level", cls)
    _call_service(uri_master, service, cls, cls._request_class(logger=logger,
                                                               level=level.lower()))


# --- topic --------------------------------------------------------------------------------------

@click.group()
def topic() -> None:
    """Topics: list, find, info, type, echo, pub, hz (like rostopic)."""


@topic.command("list")
@click.argument("namespace", required=False)
@click.option("-v", "--verbose", is_flag=True, help="Group by publishers and subscribers.")
def topic_list(namespace: str | None, verbose: bool) -> None:
    """Print every topic with a publisher or a subscriber (in NAMESPACE, if given)."""
    state = introspect.system_state(master_uri())
    within = _in_namespace(graph_name(namespace)) if namespace else (lambda t: True)
    if not verbose:
        for t in state.topics:
            if within(t):
                click.echo(t)
        return
    for title, table in (("Published topics", state.publishers),
                         ("Subscribed topics", state.subscribers)):
        click.echo(f"\n{title}:")
        for t in sorted(filter(within, table)):
            n = len(table[t])
            click.echo(f" * {t} [{state.types.get(t, 'unknown type')}] {n} "
                       f"{'publisher' if title.startswith('Pub') else 'subscriber'}"
                       f"{'s' if n != 1 else ''}")
    click.echo("")


def _in_namespace(name: str):
    """rostopic list's filter: the name itself, or anything under ``name/``."""
    prefix = name.rstrip("/") + "/"
    return lambda topic: topic == name or topic.startswith(prefix)


@topic.command("type")
@click.argument("name")
def topic_type(name: str) -> None:
    """Print the message type of NAME."""
    name = graph_name(name)
    state = introspect.system_state(master_uri())
    if name not in state.types:
        raise OrchestraError(f"unknown topic {name} (nobody publishes it)")
    click.echo(state.types[name])


@topic.command("find")
@click.argument("type_name", metavar="TYPE")
def topic_find(type_name: str) -> None:
    """Print the published topics of message type TYPE."""
    from orchestra.node.msg import normalise_type
    wanted = normalise_type(type_name)
    for name, type_ in sorted(introspect.system_state(master_uri()).types.items()):
        if type_ == wanted:
            click.echo(name)


@topic.command("info")
@click.argument("name")
def topic_info(name: str) -> None:
    """Type, publishers and subscribers of NAME."""
    name = graph_name(name)
    uri = master_uri()
    state = introspect.system_state(uri)
    if name not in state.publishers and name not in state.subscribers:
        raise OrchestraError(f"unknown topic {name}")
    click.echo(f"Type: {state.types.get(name, 'unknown type')}\n")
    for title, table in (("Publishers", state.publishers), ("Subscribers", state.subscribers)):
        nodes_ = table.get(name, [])
        if not nodes_:
            click.echo(f"{title}: None\n")
            continue
        click.echo(f"{title}: ")
        for n in nodes_:
            try:
                api = introspect.lookup_node(uri, n)
            except introspect.GraphError:
                api = "unknown address"
            click.echo(f" * {n} ({api})")
        click.echo("")
    click.echo("")  # rostopic prints the whole text, then a blank line


def _subscribe_raw(rospy, name: str):
    from orchestra.node.msg import AnyMsg
    inbox: queue.Queue = queue.Queue()
    sub = rospy.Subscriber(name, AnyMsg, lambda m: inbox.put((time.monotonic(), m)),
                           queue_size=0)
    return sub, inbox


@topic.command("echo")
@click.argument("name")
@click.option("-n", "count", type=click.IntRange(min=1), default=None,
              help="Exit after N messages.")
@click.option("--noarr", is_flag=True, help="Print arrays as their length.")
def topic_echo(name: str, count: int | None, noarr: bool) -> None:
    """Print each message on NAME as YAML followed by a '---' line."""
    from orchestra.node.decode import RawDecoder
    from orchestra.node.msg import to_yaml_text
    name = graph_name(name)
    rospy = start_cli_node()
    decode = RawDecoder()
    printed = 0
    try:
        state = introspect.system_state(master_uri())
        topic, fields = split_field_path(name, state.topics)
        if topic not in state.publishers:
            click.echo(f"WARNING: topic [{topic}] does not appear to be published yet", err=True)
        if topic not in state.topics:  # maybe TOPIC/FIELD: which part is the topic comes later
            topic, fields = wait_for_topic(name)
        name = topic
        _sub, inbox = _subscribe_raw(rospy, name)
        while count is None or printed < count:
            try:
                _, raw = inbox.get(timeout=0.2)
            except queue.Empty:
                continue
            msg = decode(raw)
            if fields:
                msg = pick_field(msg, fields)
            if noarr and hasattr(msg, "_fields"):
                hide_arrays(msg)
            click.echo(to_yaml_text(msg) + "\n---")
            printed += 1
    except KeyboardInterrupt:
        pass
    finally:
        stop_cli_node("topic echo done")


def hide_arrays(msg) -> None:
    """``--noarr``: each array field of ``msg`` (top level only) becomes rostopic's
    ``<array type: T, length: N>`` text; T is the field type with its trailing brackets
    stripped as rostopic strips them (``float64[3]`` gives ``float64[3``)."""
    for field_name, slot_type in zip(msg._fields, msg._slot_types, strict=False):
        if "[" in slot_type:
            length = len(getattr(msg, field_name))
            setattr(msg, field_name,
                    f"<array type: {slot_type.rstrip('[]')}, length: {length}>")


def pick_field(msg, fields: list[str]):
    value = msg
    for f in fields:
        if isinstance(value, (list, tuple)) and f.isdigit() and int(f) < len(value):
            value = value[int(f)]
        elif hasattr(value, "_fields") and f in value._fields:
            value = getattr(value, f)
        else:
            raise OrchestraError(f"{getattr(msg, '_type', 'message')} has no field "
                                 f"{'/'.join(fields)}")
    return value


@topic.command("pub")
@click.argument("name")
@click.argument("type_name", metavar="TYPE")
@click.argument("values", nargs=-1)
@click.option("-r", "--rate", type=float, default=None, help="Publish at HZ (not latched).")
@click.option("-1", "--once", is_flag=True, help="Publish once, let subscribers get it, exit.")
@click.option("-l", "--latch", is_flag=True, help="Latch (the default without -r).")
@click.option("-s", "--substitute-keywords", "substitute", is_flag=True,
              help="With -r: evaluate 'now' and 'auto' again for each message (without it, "
                   "once at start).")
@click.option("--wait", "wait_time", type=float, default=3.0, show_default=True,
              help="With -1: longest wait for known subscribers to connect.")
def topic_pub(name: str, type_name: str, values: tuple[str, ...], rate: float | None,
              once: bool, latch: bool, substitute: bool, wait_time: float) -> None:
    """Publish a TYPE message built from YAML VALUES on NAME.

    A time field given as 'now' is the current (wall) time, a Header given as 'auto' is one
    stamped now; both are evaluated once, at start, unless -s asks for each message."""
    name = graph_name(name)
    cls = _message_class(type_name)
    value = _parse_yaml(values, type_name)
    msg = _fill(cls, value, type_name)
    if rate is not None and rate <= 0:
        raise OrchestraError("--rate must be positive")
    rospy = start_cli_node()
    try:
        latched = latch or rate is None
        pub = rospy.Publisher(name, cls, queue_size=100, latch=latched)
        if once:
            expected = len(introspect.system_state(master_uri()).subscribers.get(name, []))
            click.echo(f"publishing and latching message for up to {wait_time:g} seconds "
                       f"({expected} subscriber{'s' if expected != 1 else ''})")
            pub.publish(msg)
            deadline = time.monotonic() + wait_time
            while pub.get_num_connections() < expected and time.monotonic() < deadline:
                time.sleep(0.01)
            _drain(pub, deadline)
        elif rate is None:
            click.echo("publishing and latching message. Press ctrl-C to terminate")
            pub.publish(msg)
            rospy.spin()
        else:
            r = rospy.Rate(rate)
            while True:
                if substitute:  # a fresh message: 'now' and 'auto' evaluated again
                    msg = _fill(cls, value, type_name)
                pub.publish(msg)
                r.sleep()
    except (KeyboardInterrupt, rospy.ROSInterruptException):
        pass
    finally:
        stop_cli_node("topic pub done")


def _drain(pub, deadline: float) -> None:
    """Wait until every connection's queue is written out (or the deadline passes)."""
    if pub.wait_sent(max(0.0, deadline - time.monotonic())):
        time.sleep(0.05)  # let the kernel hand the last bytes over


@topic.command("hz")
@click.argument("name")
@click.option("-w", "--window", type=click.IntRange(min=2), default=None,
              help="Use the last N messages only.")
@click.option("-n", "reports", type=click.IntRange(min=1), default=None,
              help="Exit after N reports (an orchestra extension).")
def topic_hz(name: str, window: int | None, reports: int | None) -> None:
    """Print the publishing rate of NAME every second."""
    name = graph_name(name)
    rospy = start_cli_node()
    stamps: list[float] = []
    done = 0
    try:
        _sub, inbox = _subscribe_raw(rospy, name)
        click.echo(f"subscribed to [{name}]")
        next_report = time.monotonic() + 1.0
        received = reported = 0  # counts, not len(stamps): a --window caps the list
        while reports is None or done < reports:
            timeout = max(0.0, next_report - time.monotonic())
            try:
                stamp, _ = inbox.get(timeout=timeout)
                stamps.append(stamp)
                received += 1
                keep = window if window is not None else 50000  # rostopic's default cap
                if len(stamps) > keep + 1:
                    del stamps[:-keep - 1]
                continue
            except queue.Empty:
                pass
            next_report += 1.0
            if len(stamps) < 2 or received == reported and not inbox.qsize():
                click.echo("no new messages")
            else:
                click.echo(hz_report(stamps))
            reported = received
            done += 1
    except KeyboardInterrupt:
        pass
    finally:
        stop_cli_node("topic hz done")


def hz_report(stamps: list[float]) -> str:
    """rostopic hz's block: average rate, then min/max/std dev of the periods and window."""
    periods = [b - a for a, b in zip(stamps, stamps[1:], strict=False)]
    mean = sum(periods) / len(periods)
    std = math.sqrt(sum((p - mean) ** 2 for p in periods) / len(periods))
    rate = 1.0 / mean if mean > 0 else 0.0
    return (f"average rate: {rate:.3f}\n\tmin: {min(periods):.3f}s max: {max(periods):.3f}s "
            f"std dev: {std:.5f}s window: {len(stamps)}")


# --- service -----------------------------------------------------------------------------------

@click.group()
def service() -> None:
    """Services: list, info, type, uri, args, call (like rosservice)."""


@service.command("list")
def service_list() -> None:
    """Print every service known to the master."""
    for name in sorted(introspect.system_state(master_uri()).services):
        click.echo(name)


@service.command("type")
@click.argument("name")
def service_type(name: str) -> None:
    """Print the service type of NAME (asked from the service itself)."""
    click.echo(introspect.service_header(master_uri(), graph_name(name)).get("type", ""))


@service.command("uri")
@click.argument("name")
def service_uri(name: str) -> None:
    """Print the rosrpc:// URI of NAME."""
    click.echo(introspect.service_uri(master_uri(), graph_name(name)))


@service.command("args")
@click.argument("name")
def service_args(name: str) -> None:
    """Print the request field names of NAME."""
    from orchestra.node.msg import MessageNotFound, get_service_class
    srv_type = introspect.service_header(master_uri(), graph_name(name)).get("type", "")
    try:
        click.echo(" ".join(get_service_class(srv_type)._request_class._fields))
    except (MessageNotFound, ROSException) as exc:
        raise OrchestraError(f"cannot tell the arguments of {name}: {exc}") from None


@service.command("info")
@click.argument("name")
def service_info(name: str) -> None:
    """Node, URI, type and request fields of NAME."""
    from orchestra.node.msg import MessageNotFound, get_service_class
    uri_master = master_uri()
    name = graph_name(name)
    header = introspect.service_header(uri_master, name)
    state = introspect.system_state(uri_master)
    providers = state.services.get(name, [])
    click.echo(f"Node: {providers[0] if providers else 'unknown'}")
    click.echo(f"URI: {introspect.service_uri(uri_master, name)}")
    click.echo(f"Type: {header.get('type', 'unknown')}")
    try:
        fields = get_service_class(header.get("type", ""))._request_class._fields
        click.echo(f"Args: {' '.join(fields)}")
    except (MessageNotFound, ROSException):
        click.echo("Args: (unknown: no definition of this service type here)")


@service.command("call")
@click.argument("name")
@click.argument("values", nargs=-1)
def service_call(name: str, values: tuple[str, ...]) -> None:
    """Call NAME with a request built from YAML VALUES; print the response as YAML."""
    from orchestra.node.msg import MessageNotFound, get_service_class, to_yaml_text
    uri_master = master_uri()
    name = graph_name(name)
    header = introspect.service_header(uri_master, name)
    srv_type = header.get("type", "")
    try:
        cls = get_service_class(srv_type)
    except (MessageNotFound, ROSException) as exc:
        raise OrchestraError(f"cannot call {name}: {exc}") from None
    if header.get("md5sum") not in (None, "*", cls._md5sum):
        raise OrchestraError(f"service {name} is a different version of {srv_type} "
                             f"(md5 {header.get('md5sum')}, ours {cls._md5sum})")
    request = _fill(cls._request_class, _parse_yaml(values, srv_type + " request"),
                    srv_type + " request")
    # an empty response prints an empty line, as rosservice does
    click.echo(to_yaml_text(_call_service(uri_master, name, cls, request)))


def _call_service(uri_master: str, name: str, cls, request):
    """One call of the service ``name`` over a connection of its own (no node needed, as
    rosservice call); a refusal or an error response is CommandFailed (exit 1)."""
    from orchestra.node import tcpros
    from orchestra.node.exceptions import TransportException
    host, port = tcpros.parse_rosrpc_uri(introspect.service_uri(uri_master, name))
    try:
        with tcpros.connect(host, port) as sock:
            tcpros.write_header(sock, {"callerid": introspect.CALLER, "service": name,
                                       "md5sum": cls._md5sum, "type": cls._type})
            reply_header = tcpros.read_header(sock)
            if "error" in reply_header:
                raise CommandFailed(f"service [{name}] refused the call: {reply_header['error']}")
            tcpros.send_message(sock, request.serialize_bytes())
            ok, body = tcpros.read_service_response(sock)
    except (OSError, TransportException) as exc:
        raise CommandFailed(f"calling service [{name}] failed: {exc}") from None
    if not ok:
        raise CommandFailed(f"service [{name}] responded with an error: "
                            f"{body.decode('utf-8', 'replace')}")
    return cls._response_class.deserialize_bytes(body)


# --- graph -------------------------------------------------------------------------------------

@click.command()
@click.option("-o", "--out", "out", type=click.Path(dir_okay=False), default=None,
              help="Write to FILE (.svg, .dot; .png or .pdf through graphviz); "
                   "default: DOT on stdout.")
@click.option("--all", "show_all", is_flag=True, help="Include /rosout.")
def graph(out: str | None, show_all: bool) -> None:
    """Draw the running nodes and the topics between them."""
    from orchestra.node import graph as graphs
    g = graphs.build_graph(introspect.system_state(master_uri()), show_all=show_all)
    if out is None:
        click.echo(graphs.to_dot(g), nl=False)
        return
    lower = out.lower()
    suffix = lower.rsplit(".", 1)[-1] if "." in lower else ""
    if suffix in ("dot", "gv"):
        text = graphs.to_dot(g)
    elif suffix == "svg":
        text = graphs.to_svg(g)
    elif suffix in graphs.GRAPHVIZ_FORMATS:
        graphs.render_with_graphviz(graphs.to_dot(g), suffix, out)
        click.echo(f"wrote {out} ({g.number_of_nodes()} vertices, {g.number_of_edges()} "
                   "edges)", err=True)
        return
    else:
        raise OrchestraError(f"unknown graph format for '{out}': use .svg, .dot, .png or .pdf")
    try:
        with open(out, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as exc:
        raise OrchestraError(f"cannot write {out}: {exc.strerror or exc}") from None
    click.echo(f"wrote {out} ({g.number_of_nodes()} vertices, {g.number_of_edges()} edges)",
               err=True)
