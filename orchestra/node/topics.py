"""Topics: publications with per-subscriber writer queues, subscriptions with reconnecting
readers, and the ``Publisher`` / ``Subscriber`` handles user code holds.

Several handles on one topic share one implementation object (as in rospy), so a node that
creates two Publishers on ``/chatter`` registers once and serves each subscriber over one
connection. Threads: one writer per outgoing connection (a slow subscriber drops its own
oldest messages, never blocks ``publish``) and one reader per publisher we subscribe to
(it calls the callbacks, reconnects with backoff while that publisher is still listed).
"""
from __future__ import annotations

import collections
import logging
import select
import socket
import struct
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

from orchestra.node import context, tcpros
from orchestra.node.exceptions import ROSException, TransportException
from orchestra.node.masterapi import MasterError, raw_call
from orchestra.node.msg import AnyMsg, Message

_U32 = struct.Struct("<I")

if TYPE_CHECKING:
    from orchestra.node.runtime import NodeRuntime

log = logging.getLogger(__name__)

# (Subscription has a property named ``type``, which hides the builtin in its body)
MessageClass = type[Message]

RECONNECT_MIN = 0.05
_RECV_MIN = 65536  # receive buffer size of a connection
_RECV_KEEP = 4 << 20  # a buffer grown past this for one huge message shrinks back after it
RECONNECT_MAX = 2.0


def md5_compatible(a: str, b: str) -> bool:
    return a == "*" or b == "*" or a == b


# --- publishing -------------------------------------------------------------------------------

class OutConnection:
    """One subscriber of one of our topics: a bounded drop-oldest queue and a writer thread.

    A message published while the writer is idle and nothing waits is sent at once by
    ``publish`` itself, without blocking (``MSG_DONTWAIT``): waking the writer thread for
    it cost a thread switch per message, which is most of the latency of a small message
    and where its worst cases came from (the woken thread queues behind whatever else
    runs). What the socket does not take at once (a slow subscriber, a large message)
    goes through the queue and the writer as before, in order."""

    _ids = iter(range(1, 1 << 62))
    DIRECT_MAX = 65536  # bigger messages always go through the writer (a copy of that
    # size is better made off the publishing thread)

    def __init__(self, publication: Publication, sock: socket.socket, peer: str,
                 queue_size: int | None):
        self.id = next(OutConnection._ids)
        self.publication = publication
        self.sock = sock
        self.peer = peer
        self.queue: collections.deque = collections.deque(maxlen=queue_size or None)
        #: the unsent rest of a message ``enqueue`` began sending (goes out before the queue)
        self.rest: bytes | None = None
        self.writing = False  # the writer thread is sending something
        self.cond = threading.Condition()
        self.closed = False
        self.bytes_sent = 0
        self.messages_sent = 0
        self.dropped = 0
        self.thread = threading.Thread(target=self._run, daemon=True,
                                       name=f"pub{publication.topic}->{peer}")

    def enqueue(self, data) -> None:
        with self.cond:
            if self.closed:
                return
            if (not self.queue and not self.writing and self.rest is None
                    and len(data) <= self.DIRECT_MAX and self._send_now(data)):
                return
            if self.queue.maxlen is not None and len(self.queue) == self.queue.maxlen:
                self.dropped += 1
            self.queue.append(data)
            self.cond.notify()

    def _send_now(self, data) -> bool:
        """Send ``data`` without blocking (caller holds ``cond``); False when nothing was
        sent (the writer takes the message); a part sent leaves the rest to the writer."""
        buffers = tcpros.frame(data)
        total = 4 + len(data)
        # counted before it goes: a subscriber that has it must never find the publisher's
        # bus stats without it
        self.bytes_sent += total
        self.messages_sent += 1
        try:
            sent = self.sock.sendmsg(buffers, (), socket.MSG_DONTWAIT)
        except OSError:  # full (EAGAIN) or broken: the writer sends it (and counts it)
            self.bytes_sent -= total
            self.messages_sent -= 1
            return False
        if sent < total:
            self.rest = b"".join(bytes(b) for b in buffers)[sent:]
            self.cond.notify()
        return True

    def idle(self) -> bool:
        """Everything published so far has been handed to the socket."""
        with self.cond:
            return not self.queue and self.rest is None and not self.writing

    def _run(self) -> None:
        sock = self.sock
        while True:
            with self.cond:
                while not self.queue and self.rest is None and not self.closed:
                    self.cond.wait()
                if self.closed:
                    return
                rest, self.rest = self.rest, None
                data = self.queue.popleft() if rest is None else None
                self.writing = True
                if data is not None:   # counted before it goes, as in _send_now (a
                    # failed send ends the connection)
                    self.bytes_sent += len(data) + 4
                    self.messages_sent += 1
            try:
                if data is not None:
                    tcpros.send_message(sock, data)
                else:
                    sock.sendall(cast(bytes, rest))
            except OSError as exc:
                log.debug("subscriber %s of %s went away: %s", self.peer,
                          self.publication.topic, exc)
                self.publication.remove_connection(self)
                return
            with self.cond:
                self.writing = False

    def peer_closed(self) -> bool:
        """Whether the subscriber hung up. Subscribers send nothing after their header, so a
        readable socket means end of stream; checked when someone counts connections,
        since an idle writer would otherwise only notice at the next publish."""
        if self.closed:
            return True
        try:
            readable, _, _ = select.select([self.sock], [], [], 0)
            if readable and self.sock.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b"":
                return True
        except (OSError, ValueError):
            return True
        return False

    def close(self) -> None:
        with self.cond:
            self.closed = True
            self.cond.notify()
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()


class Publication:
    """Everything this node knows about one topic it publishes."""

    def __init__(self, runtime: NodeRuntime, topic: str, msg_class: type[Message],
                 latch: bool, queue_size: int | None):
        self.runtime = runtime
        self.topic = topic
        self.msg_class = msg_class
        self.latch = latch
        self.queue_size = queue_size
        self.lock = threading.Lock()
        self.connections: list[OutConnection] = []
        self.latched: bytes | bytearray | None = None
        self.handles = 0
        self.seq = 0
        self.messages = 0
        self.closed = False
        #: rospy SubscribeListener-style objects: ``peer_subscribe(topic, publish_to_all,
        #: publish_to_this_peer)`` when a subscriber connects, ``peer_unsubscribe(topic,
        #: remaining)`` when one leaves (e.g. to greet each new subscriber with a message)
        self.listeners: list[Any] = []

    @property
    def type(self) -> str:
        return self.msg_class._type

    def publish(self, msg: Message) -> None:
        if self.closed:
            if self.runtime.is_shutdown():
                # the usual `while not is_shutdown(): publish()` race with a signal: the
                # message has nowhere to go, and a traceback on Ctrl-C helps nobody
                log.debug("dropped a message on %s: node is shutting down", self.topic)
                return
            raise ROSException(f"publish() to {self.topic} after unregister()")
        if msg._type != self.msg_class._type and self.msg_class is not AnyMsg:
            raise ROSException(f"expected a {self.msg_class._type} message on {self.topic}, "
                               f"got {msg._type}")
        with self.lock:
            self.seq += 1
            if msg._has_header:
                # a generated field (the class has it when _has_header says so)
                cast(Any, msg).header.seq = self.seq & 0xFFFFFFFF  # uint32 on the wire
            data = msg.serialize_bytes()
            if self.latch:
                self.latched = data
            conns = list(self.connections)
            self.messages += 1
        for conn in conns:
            conn.enqueue(data)

    def add_connection(self, sock: socket.socket, header: dict[str, str],
                       reply: bytes | None = None) -> OutConnection:
        """A subscriber's connection; ``reply`` (our header) is the first thing it is sent."""
        conn = OutConnection(self, sock, header.get("callerid", "?"), self.queue_size)
        conn.rest = reply
        with self.lock:
            if self.latched is not None:
                conn.queue.append(self.latched)
            self.connections.append(conn)
        conn.thread.start()
        for listener in list(self.listeners):
            self._notify(listener.peer_subscribe, self.topic, self._publish_any,
                         lambda msg, conn=conn: conn.enqueue(self._coerce(msg).serialize_bytes()))
        return conn

    def _coerce(self, msg: Any) -> Message:
        return msg if isinstance(msg, Message) else self.msg_class(msg)

    def _publish_any(self, msg: Any) -> None:
        self.publish(self._coerce(msg))

    @staticmethod
    def _notify(method: Callable, *args: Any) -> None:
        try:
            method(*args)
        except Exception:
            log.exception("error in subscriber listener %r", method)

    def remove_connection(self, conn: OutConnection) -> None:
        with self.lock:
            known = conn in self.connections
            if known:
                self.connections.remove(conn)
            remaining = len(self.connections)
        conn.close()
        if known:
            for listener in list(self.listeners):
                self._notify(listener.peer_unsubscribe, self.topic, remaining)

    def prune(self) -> None:
        """Drop connections whose subscriber has gone away."""
        with self.lock:
            dead = [c for c in self.connections if c.peer_closed()]
        for conn in dead:
            self.remove_connection(conn)

    def num_connections(self) -> int:
        self.prune()
        with self.lock:
            return len(self.connections)

    def close(self) -> None:
        with self.lock:
            self.closed = True
            conns, self.connections = self.connections, []
        for conn in conns:
            conn.close()


class Publisher:
    """Publish messages of ``msg_class`` on ``topic`` (name resolved like rospy)."""

    def __init__(self, topic: str, msg_class: type[Message], queue_size: int | None = 10,
                 latch: bool = False, subscriber_listener: Any = None, **_ignored: Any):
        if not (isinstance(msg_class, type) and issubclass(msg_class, Message)):
            raise ValueError(f"Publisher needs a message class, not {msg_class!r}")
        self._rt = context.current()
        self.resolved_name = self.name = self._rt.resolve_name(topic)
        self.data_class = msg_class
        self.type = msg_class._type
        self.md5sum = msg_class._md5sum
        self._impl = self._rt.topics.acquire_publication(self.name, msg_class, latch, queue_size,
                                                         subscriber_listener)
        self._done = False

    def publish(self, *args, **kwargs) -> None:
        """Send a message: an instance, or the field values to build one from."""
        if self._done:
            raise ROSException(f"publish() to {self.name} after unregister()")
        if len(args) == 1 and not kwargs and isinstance(args[0], Message):
            msg = args[0]
        else:
            msg = self.data_class(*args, **kwargs)
        self._impl.publish(msg)

    def get_num_connections(self) -> int:
        return self._impl.num_connections()

    def wait_sent(self, timeout: float) -> bool:
        """Wait until every message published so far has left its connection queues (an
        orchestra extension: a short-lived publisher, ``orchestra topic pub -1``, must not
        exit before then). False when ``timeout`` seconds passed first."""
        deadline = time.monotonic() + timeout
        while True:
            with self._impl.lock:
                conns = list(self._impl.connections)
            if all(c.idle() for c in conns):
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.01)

    def unregister(self) -> None:
        if not self._done:
            self._done = True
            self._rt.topics.release_publication(self._impl)


# --- subscribing ------------------------------------------------------------------------------

class InConnection:
    """Our link to one publisher: connect, read, dispatch, reconnect with backoff."""

    def __init__(self, subscription: Subscription, publisher_uri: str):
        self.subscription = subscription
        self.uri = publisher_uri
        self.closed = threading.Event()
        self.sock: socket.socket | None = None
        self.connected = False
        self.header: dict[str, str] = {}
        self.bytes_received = 0
        self.messages_received = 0
        self.drops = 0
        #: the newest message of a latched publisher (``latching: 1``), replayed to callbacks
        #: added after it arrived, as rospy does (its #1852)
        self.latched: bytes | None = None
        self.id = next(OutConnection._ids)
        self.thread = threading.Thread(target=self._run, daemon=True,
                                       name=f"sub{subscription.topic}<-{publisher_uri}")

    def start(self) -> None:
        self.thread.start()

    def close(self) -> None:
        self.closed.set()
        sock = self.sock
        if sock is not None:
            try:
                sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass

    def _connect(self) -> socket.socket:
        sub = self.subscription
        rt = sub.runtime
        code, msg, proto = raw_call(self.uri, "requestTopic", rt.name, sub.topic, [["TCPROS"]],
                                    timeout=5.0)
        if code != 1 or not proto or proto[0] != "TCPROS":
            raise TransportException(f"publisher {self.uri} refused {sub.topic}: {msg}")
        sock = tcpros.connect(proto[1], int(proto[2]))
        try:
            cls = sub.msg_class
            tcpros.write_header(sock, {
                "callerid": rt.name, "topic": sub.topic, "md5sum": cls._md5sum,
                "type": cls._type, "message_definition": cls._full_text, "tcp_nodelay": "1"})
            header = tcpros.read_header(sock)
        except BaseException:
            sock.close()
            raise
        if "error" in header:
            sock.close()
            raise _Refused(header["error"])
        if not md5_compatible(cls._md5sum, header.get("md5sum", "*")):
            sock.close()
            raise _Refused(f"publisher sends {header.get('type')} "
                           f"(md5 {header.get('md5sum')}), we expect {cls._type} "
                           f"(md5 {cls._md5sum})")
        self.header = header
        return sock

    def _run(self) -> None:
        sub = self.subscription
        backoff = RECONNECT_MIN
        while not self.closed.is_set():
            try:
                sock = self._connect()
            except _Refused as exc:
                log.error("subscription to %s from %s refused: %s", sub.topic, self.uri, exc)
                return
            except (OSError, TransportException, MasterError) as exc:
                log.debug("cannot connect to %s for %s: %s", self.uri, sub.topic, exc)
                if self.closed.wait(backoff):
                    return
                backoff = min(backoff * 2, RECONNECT_MAX)
                continue
            self.sock = sock
            if self.closed.is_set():
                sock.close()
                return
            self.connected = True
            backoff = RECONNECT_MIN
            try:
                self._read_loop(sock)
            except (OSError, TransportException) as exc:
                log.debug("connection to %s for %s lost: %s", self.uri, sub.topic, exc)
            finally:
                self.connected = False
                self.sock = None
                sock.close()
            if self.closed.wait(backoff):
                return

    def _read_loop(self, sock: socket.socket) -> None:
        """Read whatever the socket holds, keep the newest ``queue_size`` complete messages,
        deliver them. This is rospy's queue_size rule: a slow callback sees fresh data, not
        a backlog piled up in socket buffers."""
        sub = self.subscription
        header = self.header
        keep = sub.queue_size
        # one reusable receive buffer filled in place (recv_into): a large message (an
        # image) costs no fresh allocation per recv call and no second copy to append it
        buf = bytearray(_RECV_MIN)
        filled = 0
        while not self.closed.is_set():
            if filled >= 4:
                need = 4 + _U32.unpack_from(buf, 0)[0]
                if need > tcpros.MAX_MESSAGE + 4:
                    raise TransportException(f"message of {need - 4} bytes refused")
                if need > len(buf):
                    buf.extend(bytes(need - len(buf)))
            with memoryview(buf) as view:
                n = sock.recv_into(view[filled:])
            if not n:
                raise TransportException("connection closed by peer")
            filled += n
            frames: list[bytes] = []
            pos = 0
            with memoryview(buf) as view:
                while filled - pos >= 4:
                    (size,) = _U32.unpack_from(view, pos)
                    if size > tcpros.MAX_MESSAGE:
                        raise TransportException(f"message of {size} bytes refused")
                    if filled - pos - 4 < size:
                        break
                    frames.append(bytes(view[pos + 4:pos + 4 + size]))
                    pos += 4 + size
            if not frames:
                continue
            rest = filled - pos
            if len(buf) > _RECV_KEEP and rest <= _RECV_MIN:
                buf = bytearray(buf[pos:filled]) + bytearray(_RECV_MIN - rest)
            else:
                buf[:rest] = buf[pos:filled]
            filled = rest
            if keep and len(frames) > keep:
                self.drops += len(frames) - keep
                frames = frames[-keep:]
            latching = header.get("latching") == "1"
            for data in frames:
                self.bytes_received += len(data) + 4
                self.messages_received += 1
                sub.deliver_raw(data, header, self.uri, self if latching else None)


class _Refused(Exception):
    """The publisher refused us for a reason retrying will not fix (type mismatch)."""


class Subscription:
    """Everything this node knows about one topic it subscribes to."""

    def __init__(self, runtime: NodeRuntime, topic: str, msg_class: type[Message],
                 queue_size: int | None = None):
        self.runtime = runtime
        self.topic = topic
        self.msg_class = msg_class
        self.queue_size = queue_size or 0
        self.lock = threading.Lock()
        # held while callbacks run; re-entrant so a callback may subscribe to its own topic
        self.callback_lock = threading.RLock()
        self.callbacks: list[tuple[Callable, Any, MessageClass]] = []
        self.connections: dict[str, InConnection] = {}
        self.closed = False

    @property
    def type(self) -> str:
        return self.msg_class._type

    def add_callback(self, cb: Callable, cb_args: Any, cls: MessageClass) -> None:
        """Add a callback; it is first given the newest message of each latched publisher
        already received (rospy's rule), then every message that arrives.

        The connection threads connect as soon as the master answers, before the Subscriber
        handle adds its callback: a fast latched publisher (roscpp sends right after the
        header) would otherwise deliver to nobody. Holding ``callback_lock`` while adding and
        replaying makes each latched message reach the new callback exactly once."""
        with self.callback_lock:
            with self.lock:
                self.callbacks = self.callbacks + [(cb, cb_args, cls)]
                if self.msg_class is AnyMsg and cls is not AnyMsg:
                    self.msg_class = cls  # connections made from now on check the real md5
                latched = [(c.latched, c.header, c.uri) for c in self.connections.values()
                           if c.latched is not None]
            for data, header, origin in latched:
                self._dispatch(data, header, origin, [(cb, cb_args, cls)])

    def remove_callback(self, cb: Callable, cb_args: Any) -> int:
        with self.lock:
            for i, (c, a, _cls) in enumerate(self.callbacks):
                if c is cb and a is cb_args:
                    self.callbacks = self.callbacks[:i] + self.callbacks[i + 1:]
                    break
            return len(self.callbacks)

    def deliver_raw(self, data: bytes, header: dict[str, str], origin: str,
                    latched_on: InConnection | None = None) -> None:
        """Decode once per message class the callbacks asked for, then call them in order.
        ``latched_on``: the connection of a latched publisher, which keeps the message for
        callbacks added later."""
        with self.callback_lock:
            if latched_on is not None:
                latched_on.latched = data
            self._dispatch(data, header, origin, self.callbacks)

    def _dispatch(self, data: bytes, header: dict[str, str], origin: str,
                  callbacks: list[tuple[Callable, Any, MessageClass]]) -> None:
        decoded: dict[type, Message | None] = {}
        for cb, args, cls in callbacks:
            if cls not in decoded:
                try:
                    msg = AnyMsg(data) if cls is AnyMsg else cls.deserialize_bytes(data)
                    msg._connection_header = header
                except ROSException as exc:
                    log.error("bad message on %s from %s: %s", self.topic, origin, exc)
                    msg = None
                decoded[cls] = msg
            msg = decoded[cls]
            if msg is None:
                continue
            try:
                if args is None:
                    cb(msg)
                else:
                    cb(msg, args)
            except Exception:  # a user callback must not kill the connection
                log.exception("error in callback for %s", self.topic)

    def update_publishers(self, uris: list[str], additive: bool = False) -> None:
        """Connect to listed publishers we lack, drop those no longer listed (idempotent).

        ``additive`` (the registerSubscriber answer) only adds: a publisherUpdate sent
        after the master answered may overtake that answer, and must not be undone by it.
        """
        with self.lock:
            if self.closed:
                return
            wanted = list(dict.fromkeys(uris))
            gone = [] if additive else [u for u in self.connections if u not in wanted]
            for uri in gone:
                self.connections.pop(uri).close()
            new = []
            for uri in wanted:
                if uri not in self.connections:
                    conn = InConnection(self, uri)
                    self.connections[uri] = conn
                    new.append(conn)
        for conn in new:
            conn.start()

    def num_connections(self) -> int:
        with self.lock:
            return sum(1 for c in self.connections.values() if c.connected)

    def close(self) -> None:
        with self.lock:
            self.closed = True
            conns = list(self.connections.values())
            self.connections.clear()
        for conn in conns:
            conn.close()


class Subscriber:
    """Call ``callback(msg)`` (or ``callback(msg, callback_args)``) for each message on
    ``topic``, from a receive thread. When messages arrive faster than the callback runs,
    only the newest ``queue_size`` of those waiting are delivered (None/0: all)."""

    def __init__(self, topic: str, msg_class: type[Message], callback: Callable | None = None,
                 callback_args: Any = None, queue_size: int | None = 10, **_ignored: Any):
        if not (isinstance(msg_class, type) and issubclass(msg_class, Message)):
            raise ValueError(f"Subscriber needs a message class, not {msg_class!r}")
        self._rt = context.current()
        self.resolved_name = self.name = self._rt.resolve_name(topic)
        self.data_class = msg_class
        self.type = msg_class._type
        self.callback = callback
        self.callback_args = callback_args
        self._impl = self._rt.topics.acquire_subscription(self.name, msg_class, queue_size)
        if callback is not None:
            self._impl.add_callback(callback, callback_args, msg_class)
        self._done = False

    def get_num_connections(self) -> int:
        return self._impl.num_connections()

    def unregister(self) -> None:
        if not self._done:
            self._done = True
            self._rt.topics.release_subscription(self._impl, self.callback, self.callback_args)


# --- the per-node table -----------------------------------------------------------------------

class TopicManager:
    """This node's publications and subscriptions, and their master registrations."""

    def __init__(self, runtime: NodeRuntime):
        self.rt = runtime
        self.lock = threading.RLock()
        self.publications: dict[str, Publication] = {}
        self.subscriptions: dict[str, Subscription] = {}

    def acquire_publication(self, topic: str, msg_class: type[Message], latch: bool,
                            queue_size: int | None, listener: Any = None) -> Publication:
        with self.lock:
            pub = self.publications.get(topic)
            if pub is not None:
                if pub.msg_class._md5sum != msg_class._md5sum:
                    raise ROSException(f"{topic} is already published here as {pub.type}, "
                                       f"cannot also publish {msg_class._type}")
                pub.latch = pub.latch or latch
                pub.handles += 1
                if listener is not None:
                    pub.listeners.append(listener)
                return pub
            pub = Publication(self.rt, topic, msg_class, latch, queue_size)
            pub.handles = 1
            if listener is not None:
                pub.listeners.append(listener)
            self.publications[topic] = pub
        self.rt.master_register("registerPublisher", topic, msg_class._type)
        return pub

    def release_publication(self, pub: Publication) -> None:
        with self.lock:
            pub.handles -= 1
            if pub.handles > 0 or self.publications.get(pub.topic) is not pub:
                return
            del self.publications[pub.topic]
        self.rt.master_unregister("unregisterPublisher", pub.topic)
        pub.close()

    def acquire_subscription(self, topic: str, msg_class: type[Message],
                             queue_size: int | None = None) -> Subscription:
        with self.lock:
            sub = self.subscriptions.get(topic)
            if sub is not None:
                if not md5_compatible(sub.msg_class._md5sum, msg_class._md5sum):
                    raise ROSException(f"{topic} is already subscribed here as {sub.type}, "
                                       f"cannot also subscribe as {msg_class._type}")
                if queue_size and (not sub.queue_size or queue_size > sub.queue_size):
                    sub.queue_size = queue_size
                elif not queue_size:
                    sub.queue_size = 0
                return sub
            sub = Subscription(self.rt, topic, msg_class, queue_size)
            self.subscriptions[topic] = sub
        publishers = self.rt.master_register("registerSubscriber", topic, msg_class._type)
        sub.update_publishers(list(publishers or []), additive=True)
        return sub

    def release_subscription(self, sub: Subscription, cb: Callable | None, args: Any) -> None:
        with self.lock:
            remaining = sub.remove_callback(cb, args) if cb is not None else len(sub.callbacks)
            if remaining > 0 or self.subscriptions.get(sub.topic) is not sub:
                return
            del self.subscriptions[sub.topic]
        self.rt.master_unregister("unregisterSubscriber", sub.topic)
        sub.close()

    def publisher_update(self, topic: str, uris: list[str]) -> None:
        with self.lock:
            sub = self.subscriptions.get(topic)
        if sub is not None:
            sub.update_publishers(uris)

    def has_publication(self, topic: str) -> bool:
        with self.lock:
            return topic in self.publications

    def publication_list(self) -> list[list[str]]:
        with self.lock:
            return [[t, p.type] for t, p in self.publications.items()]

    def subscription_list(self) -> list[list[str]]:
        with self.lock:
            return [[t, s.type] for t, s in self.subscriptions.items()]

    def handle_subscriber(self, sock: socket.socket, header: dict[str, str]) -> None:
        """A subscriber connected to our TCPROS port asking for ``header['topic']``."""
        topic = header.get("topic", "")
        with self.lock:
            pub = self.publications.get(topic)
        caller = header.get("callerid", "?")
        if pub is None:
            log.warning("%s asked for %s, which this node does not publish", caller, topic)
            tcpros.refuse(sock, f"no topic [{topic}] published by {self.rt.name}")
            return
        their_md5 = header.get("md5sum", "")
        cls = pub.msg_class
        if not md5_compatible(their_md5, cls._md5sum):
            log.warning("refused subscriber %s on %s: it expects %s (%s), we publish %s (%s)",
                        caller, topic, header.get("type"), their_md5, cls._type, cls._md5sum)
            tcpros.refuse(sock, f"Client [{caller}] wants topic {topic} to have datatype/md5sum "
                                f"[{header.get('type')}/{their_md5}], but our version has "
                                f"[{cls._type}/{cls._md5sum}]. Dropping connection.")
            return
        # the connection joins the publication first and its writer sends this header before
        # anything else: once the subscriber has read it, every later publish reaches it.
        # Written here and then added (as rospy does), a message published in between was
        # lost to a subscriber that already counted itself connected (actionlib's
        # wait_for_server, then the server's first feedback).
        pub.add_connection(sock, header, tcpros.encode_header({
            "callerid": self.rt.name, "topic": topic, "md5sum": cls._md5sum, "type": cls._type,
            "message_definition": cls._full_text, "latching": "1" if pub.latch else "0"}))

    def close_all(self) -> None:
        with self.lock:
            pubs = list(self.publications.values())
            subs = list(self.subscriptions.values())
            self.publications.clear()
            self.subscriptions.clear()
        for pub in pubs:
            self.rt.master_unregister("unregisterPublisher", pub.topic)
        for sub in subs:
            self.rt.master_unregister("unregisterSubscriber", sub.topic)
        for item in pubs + subs:
            item.close()

    def bus_stats(self) -> tuple[list, list]:
        pubs, subs = [], []
        for pub in list(self.publications.values()):
            pub.prune()
        with self.lock:
            for topic, pub in self.publications.items():
                conns = [[c.id, xmlrpc_int(c.bytes_sent), xmlrpc_int(c.messages_sent),
                          not c.closed] for c in list(pub.connections)]
                pubs.append([topic, xmlrpc_int(sum(c.bytes_sent for c in pub.connections)),
                             conns])
            for topic, sub in self.subscriptions.items():
                conns = [[c.id, xmlrpc_int(c.bytes_received), xmlrpc_int(c.drops), c.connected]
                         for c in list(sub.connections.values())]
                subs.append([topic, conns])
        return pubs, subs

    def bus_info(self) -> list:
        info = []
        for pub in list(self.publications.values()):
            pub.prune()
        with self.lock:
            for topic, pub in self.publications.items():
                for c in list(pub.connections):
                    info.append([c.id, c.peer, "o", "TCPROS", topic, True,
                                 describe_socket(c.sock)])
            for topic, sub in self.subscriptions.items():
                for conn in list(sub.connections.values()):
                    info.append([conn.id, conn.uri, "i", "TCPROS", topic, conn.connected,
                                 describe_socket(conn.sock)])
        return info


def describe_socket(sock: socket.socket | None) -> str:
    """The connection text rospy puts in getBusInfo's 7th field, which ``rosnode info``
    shows as ``(local port - peer) [fd]``: "" when there is no open socket."""
    if sock is None:
        return ""
    try:
        port = sock.getsockname()[1]
        host, peer_port = sock.getpeername()[:2]
        fd = sock.fileno()
    except OSError:
        return ""
    return f"TCPROS connection on port {port} to [{host}:{peer_port} on socket {fd}]"


def xmlrpc_int(n: int) -> int | float:
    """XML-RPC integers are 32-bit: byte counters of a camera stream pass 2**31 within
    seconds, so larger counts travel as doubles instead of failing the whole call."""
    return n if -2**31 <= n < 2**31 else float(n)

