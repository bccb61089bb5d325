"""Node runtime end to end: real node processes talking TCPROS on loopback via a master."""
from __future__ import annotations

import signal
import socket
import subprocess
import sys
import xmlrpc.client
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import Nodes, OneShotProxy, wait_for  # noqa: E402

from orchestra.master import start_master  # noqa: E402
from orchestra.node import tcpros  # noqa: E402

pytestmark = pytest.mark.timeout(60)


def system_state(master_uri: str):
    with xmlrpc.client.ServerProxy(master_uri) as master:
        return master.getSystemState("/test")[2]


def publishers_of(master_uri: str, topic: str) -> list[str]:
    for name, nodes in system_state(master_uri)[0]:
        if name == topic:
            return nodes
    return []


def test_subscriber_receives_string_messages_from_publisher(nodes):
    pub = nodes.start("pub.py", "chatter", "std_msgs/String", "data: hello $N")
    pub.ready()
    sub = nodes.start("sub.py", "chatter", "std_msgs/String")
    assert sub.ready()["topic"] == "/chatter"
    msg = sub.messages()
    assert msg["data"].startswith("hello ")
    assert msg != sub.messages()  # a stream, not one repeated message


def _subscribers(nodes, topic: str) -> list[str]:
    """The nodes the master lists as subscribed to ``topic``."""
    _, _, (_, subscribers, _) = nodes.master().getSystemState("/test")
    return [n for t, names in subscribers if t == topic for n in names]


def _live_connections(nodes, node: str, topic: str) -> list:
    """``node``'s connected inbound connections on ``topic`` (its slave API's bus info)."""
    _, _, uri = nodes.master().lookupNode("/test", node)
    _, _, info = OneShotProxy(uri).getBusInfo("/test")
    return [c for c in info if c[4] == topic and c[2] == "i" and c[5]]


def test_publisher_started_after_subscriber_is_found_via_publisher_update(nodes):
    sub = nodes.start("sub.py", "late", "geometry_msgs/Twist")
    sub.ready()
    wait_for(lambda: _subscribers(nodes, "/late"))  # registered before the publisher exists
    pub = nodes.start("pub.py", "late", "geometry_msgs/Twist", "{linear: {x: 1.5}, angular: {z: -2}}")
    pub.ready()
    msg = sub.messages()
    assert msg == {"linear": {"x": 1.5, "y": 0.0, "z": 0.0},
                   "angular": {"x": 0.0, "y": 0.0, "z": -2.0}}


def test_latched_message_is_delivered_to_a_subscriber_that_comes_later(nodes):
    pub = nodes.start("pub.py", "map_version", "std_msgs/Int32", "data: 42",
                      "--latch", "--count", "1")
    pub.expect(lambda d: d.get("sent") == 1)
    sub = nodes.start("sub.py", "map_version", "std_msgs/Int32")
    got = sub.expect(lambda d: "msg" in d)
    assert got == {"msg": {"data": 42}, "latching": "1"}


def test_custom_message_from_package_msg_file_round_trips(nodes):
    pub = nodes.start("pub.py", "nums", "test_msgs/Num",
                      "{num: $N, label: n$N, stamp: {secs: 7, nsecs: 9}, xyz: [1, 2, 3]}")
    pub.ready()
    sub = nodes.start("sub.py", "nums", "test_msgs/Num")
    msg = sub.messages()
    assert msg["label"] == f"n{msg['num']}"
    assert msg["stamp"] == {"secs": 7, "nsecs": 9}
    assert msg["xyz"] == [1.0, 2.0, 3.0]


def test_any_type_subscriber_learns_type_from_connection_header(nodes):
    nodes.start("pub.py", "anything", "std_msgs/String", "data: abc").ready()
    sub = nodes.start("sub.py", "anything", "*")
    assert sub.messages() == {"type": "std_msgs/String", "size": 7}


def test_subscriber_with_wrong_type_is_refused_and_publisher_keeps_running(nodes):
    pub = nodes.start("pub.py", "typed", "std_msgs/String", "data: x")
    pub.ready()
    wrong = nodes.start("sub.py", "typed", "std_msgs/Int32", "--name", "wrong")
    wrong.ready()
    right = nodes.start("sub.py", "typed", "std_msgs/String", "--name", "right")
    right.ready()
    assert right.messages() == {"data": "x"}
    wait_for(lambda: any("typed" in line for line in pub.stderr_lines))
    assert any("md5" in line or "expects" in line for line in pub.stderr_lines)
    assert pub.proc.poll() is None and wrong.proc.poll() is None
    assert wrong.lines.empty()


def test_wrong_md5_on_connect_gets_an_error_header(nodes):
    pub = nodes.start("pub.py", "typed2", "std_msgs/String", "data: x")
    pub.ready()
    node_uri = wait_for(lambda: OneShotProxy(nodes.master_uri)
                        .lookupNode("/test", "/pub")[2])
    code, _, proto = OneShotProxy(node_uri).requestTopic(
        "/test", "/typed2", [["TCPROS"]])
    assert code == 1 and proto[0] == "TCPROS"
    with tcpros.connect(proto[1], proto[2]) as sock:
        tcpros.write_header(sock, {"callerid": "/test", "topic": "/typed2",
                                   "md5sum": "0" * 32, "type": "std_msgs/Int32"})
        header = tcpros.read_header(sock)
    assert "error" in header and "md5" in header["error"]
    # the publisher still serves a well-formed subscriber
    with tcpros.connect(proto[1], proto[2]) as sock:
        tcpros.write_header(sock, {"callerid": "/test", "topic": "/typed2", "md5sum": "*",
                                   "type": "*"})
        header = tcpros.read_header(sock)
        assert header["type"] == "std_msgs/String"
        assert header["md5sum"] == "992ce8a1687cec8c8bd883ec73ca41d1"
        assert "string data" in header["message_definition"]
        body = tcpros.read_message(sock)
    assert body == b"\x01\x00\x00\x00x"


def test_subscriber_survives_dead_publisher_and_reconnects_when_it_returns(nodes):
    sub = nodes.start("sub.py", "flaky", "std_msgs/String")
    name = sub.ready()["ready"]
    first = nodes.start("pub.py", "flaky", "std_msgs/String", "data: first", "--name", "talker")
    first.ready()
    assert sub.messages() == {"data": "first"}
    first.signal(signal.SIGKILL)  # dies without unregistering
    first.wait()
    wait_for(lambda: not _live_connections(nodes, name, "/flaky"))  # the drop was noticed
    assert sub.proc.poll() is None
    second = nodes.start("pub.py", "flaky", "std_msgs/String", "data: second", "--name", "talker")
    second.ready()
    sub.expect(lambda d: d.get("msg") == {"data": "second"})


def test_remaps_namespace_and_private_params_from_argv(nodes, master):
    OneShotProxy(master.uri).setParam("/test", "/robot/shared", 3)
    proc = nodes.start("names_node.py", "extra", "chatter:=/remapped", "_rate:=5.5",
                       "_label:=[a, b]", "__ns:=/robot", "__name:=renamed")
    report = proc.expect(lambda d: "name" in d)
    assert report["name"] == "/robot/renamed"
    assert report["namespace"] == "/robot/"
    assert report["chatter"] == "/remapped"
    assert report["private"] == "/robot/renamed/x"
    assert report["global"] == "/abs"
    assert report["argv"] == ["extra"]
    assert report["rate"] == 5.5
    assert report["label"] == ["a", "b"]
    assert report["missing"] == "dflt"
    assert report["search"] == "/robot/shared"


def test_ros_namespace_environment_places_the_node(nodes):
    proc = nodes.start("names_node.py", env={"ROS_NAMESPACE": "/ns1"})
    report = proc.expect(lambda d: "name" in d)
    assert report["name"] == "/ns1/namer"
    assert report["chatter"] == "/ns1/chatter"


def test_node_name_clash_shuts_down_the_older_node(nodes):
    older = nodes.start("sub.py", "clash", "std_msgs/String", "--name", "twin")
    older.ready()
    newer = nodes.start("sub.py", "clash", "std_msgs/String", "--name", "twin")
    newer.ready()
    older.expect(lambda d: d.get("shutdown"))
    assert older.wait() == 0
    assert newer.proc.poll() is None


def test_sigterm_unregisters_everything_from_the_master(nodes, master):
    pub = nodes.start("pub.py", "bye", "std_msgs/String", "data: x", "--name", "leaver")
    pub.ready()
    assert "/leaver" in publishers_of(master.uri, "/bye")
    pub.signal(signal.SIGTERM)
    assert pub.wait() == 0
    state = system_state(master.uri)
    assert all("/leaver" not in nodes_ for group in state for _, nodes_ in group)


def test_service_calls_plain_persistent_probe_and_handler_error(nodes, master, monkeypatch):

    srv = nodes.start("adder.py", "add")
    assert srv.ready()["service"] == "/add"
    m = OneShotProxy(master.uri)
    uri = m.lookupService("/test", "/add")[2]
    host, port = tcpros.parse_rosrpc_uri(uri)
    from orchestra.node.msg import Registry
    monkeypatch.setenv("ROS_PACKAGE_PATH", nodes.env["ROS_PACKAGE_PATH"])
    cls = Registry().service_class("test_msgs/AddTwoInts")
    req = cls.Request(a=2, b=40).serialize_bytes()

    # probe: header only, then the server closes
    with tcpros.connect(host, port) as sock:
        tcpros.write_header(sock, {"callerid": "/test", "service": "/add", "md5sum": "*",
                                   "probe": "1"})
        header = tcpros.read_header(sock)
        assert header["type"] == "test_msgs/AddTwoInts"
        assert header["md5sum"] == cls._md5sum == "6a2e34150c00229791cc89ff309fff21"
        assert sock.recv(1) == b""

    # plain: one call per connection
    with tcpros.connect(host, port) as sock:
        tcpros.write_header(sock, {"callerid": "/test", "service": "/add",
                                   "md5sum": cls._md5sum})
        tcpros.read_header(sock)
        tcpros.send_message(sock, req)
        ok, body = tcpros.read_service_response(sock)
        assert ok and cls.Response.deserialize_bytes(body).sum == 42
        assert sock.recv(1) == b""

    # persistent: many calls, and a handler error keeps the connection usable
    with tcpros.connect(host, port) as sock:
        tcpros.write_header(sock, {"callerid": "/test", "service": "/add",
                                   "md5sum": cls._md5sum, "persistent": "1"})
        tcpros.read_header(sock)
        for a in range(3):
            tcpros.send_message(sock, cls.Request(a=a, b=1).serialize_bytes())
            ok, body = tcpros.read_service_response(sock)
            assert ok and cls.Response.deserialize_bytes(body).sum == a + 1
        tcpros.send_message(sock, cls.Request(a=-1, b=1).serialize_bytes())
        ok, body = tcpros.read_service_response(sock)
        assert not ok and b"negative a" in body
        tcpros.send_message(sock, req)
        ok, body = tcpros.read_service_response(sock)
        assert ok

    # wrong md5: refused with an error header; the service keeps serving
    with tcpros.connect(host, port) as sock:
        tcpros.write_header(sock, {"callerid": "/test", "service": "/add", "md5sum": "f" * 32})
        assert "error" in tcpros.read_header(sock)
    assert srv.proc.poll() is None
    wait_for(lambda: any("refused" in line for line in srv.stderr_lines))


def test_a_service_serves_many_connections_open_at_once(nodes, master, monkeypatch):
    """Each connection has a thread of its own while it lasts: clients that connect and
    wait before calling (more of them than the server keeps threads waiting in accept)
    are all answered, in any order."""
    nodes.start("adder.py", "add").ready()
    uri = OneShotProxy(master.uri).lookupService("/test", "/add")[2]
    host, port = tcpros.parse_rosrpc_uri(uri)
    from orchestra.node.msg import Registry
    monkeypatch.setenv("ROS_PACKAGE_PATH", nodes.env["ROS_PACKAGE_PATH"])
    cls = Registry().service_class("test_msgs/AddTwoInts")
    socks = [tcpros.connect(host, port, timeout=10) for _ in range(12)]
    try:
        for sock in socks:
            sock.settimeout(10)
            tcpros.write_header(sock, {"callerid": "/test", "service": "/add",
                                       "md5sum": cls._md5sum, "persistent": "1"})
            assert "error" not in tcpros.read_header(sock)
        for i, sock in reversed(list(enumerate(socks))):
            tcpros.send_message(sock, cls.Request(a=i, b=100).serialize_bytes())
            ok, body = tcpros.read_service_response(sock)
            assert ok and cls.Response.deserialize_bytes(body).sum == i + 100
    finally:
        for sock in socks:
            sock.close()


def test_a_plain_proxy_follows_its_service_when_it_moves_or_goes(nodes, master, monkeypatch):
    """Every plain call looks the service up (rospy's rule), however the connection is
    opened: a service restarted on another port is found there, one that is gone is
    ``unavailable``, one that is back is called again."""
    from orchestra.node.exceptions import ServiceException
    from orchestra.node.msg import Registry
    from orchestra.node.services import ServiceProxy

    monkeypatch.setenv("ROS_PACKAGE_PATH", nodes.env["ROS_PACKAGE_PATH"])
    monkeypatch.setenv("ROS_MASTER_URI", master.uri)
    cls = Registry().service_class("test_msgs/AddTwoInts")
    first = nodes.start("adder.py", "add")
    first.ready()
    proxy = ServiceProxy("/add", cls)  # not a node: rospy allows that too
    assert proxy(a=1, b=2).sum == 3
    where = OneShotProxy(master.uri).lookupService("/test", "/add")[2]
    first.signal(signal.SIGTERM)
    assert first.wait() == 0
    with pytest.raises(ServiceException, match=r"service \[/add\] unavailable"):
        proxy(a=1, b=1)
    second = nodes.start("adder.py", "add")
    second.ready()
    assert OneShotProxy(master.uri).lookupService("/test", "/add")[2] != where
    assert [proxy(a=i, b=10).sum for i in range(3)] == [10, 11, 12]


def test_service_proxy_from_a_node_process(nodes):
    nodes.start("adder.py", "math/add").ready()
    caller = nodes.start("caller.py", "math/add")
    report = caller.expect(lambda d: "plain" in d)
    assert report == {"plain": 5, "persistent": [1, 2, 3], "error": True,
                      "missing": True, "timeout": True}


def test_slave_api_reports_pid_publications_subscriptions_and_bus_info(nodes, master):
    pub = nodes.start("pub.py", "info_topic", "std_msgs/String", "data: x", "--name", "infopub")
    pub.ready()
    sub = nodes.start("sub.py", "info_topic", "std_msgs/String", "--name", "infosub")
    sub.ready()
    sub.messages()
    m = OneShotProxy(master.uri)
    api = OneShotProxy(m.lookupNode("/test", "/infopub")[2])
    assert api.getPid("/test") == [1, "", pub.proc.pid]
    assert ["/info_topic", "std_msgs/String"] in api.getPublications("/test")[2]
    assert api.getMasterUri("/test")[2] == master.uri
    info = api.getBusInfo("/test")[2]
    assert any(row[1] == "/infosub" and row[2] == "o" and row[4] == "/info_topic" for row in info)
    stats = api.getBusStats("/test")[2]
    assert any(row[0] == "/info_topic" and row[1] > 0 for row in stats[0])
    sub_api = OneShotProxy(m.lookupNode("/test", "/infosub")[2])
    assert sub_api.getSubscriptions("/test")[2] == [["/info_topic", "std_msgs/String"]]
    assert sub_api.requestTopic("/test", "/nope", [["TCPROS"]])[0] == -1
    # publisherUpdate is idempotent: repeating the current list changes nothing
    pubs = [m.lookupNode("/test", "/infopub")[2]]
    assert sub_api.publisherUpdate("/master", "/info_topic", pubs)[0] == 1
    assert sub_api.publisherUpdate("/master", "/info_topic", pubs)[0] == 1
    sub.messages()
    rows = [r for r in sub_api.getBusInfo("/test")[2] if r[4] == "/info_topic"]
    assert len(rows) == 1 and rows[0][2] == "i"
    assert api.shutdown("/test", "bye")[0] == 1
    assert pub.wait() == 0


def test_publisher_counts_subscribers_as_they_come_and_go(nodes):
    pub = nodes.start("pub.py", "counted", "std_msgs/String", "data: x", "--report",
                      "--rate", "5")
    pub.ready()
    sub = nodes.start("sub.py", "counted", "std_msgs/String")
    sub.ready()
    pub.expect(lambda d: d.get("connections") == 1)
    sub.signal(signal.SIGTERM)
    assert sub.wait() == 0
    pub.expect(lambda d: d.get("connections") == 0)


def test_node_started_before_the_master_waits_for_it(package_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    group = Nodes(f"http://127.0.0.1:{port}/", package_path)
    try:
        sub = group.start("sub.py", "early", "std_msgs/String")
        with pytest.raises(subprocess.TimeoutExpired):  # it waits for the master, no exit
            sub.proc.wait(1.0)
        handle = start_master(host="127.0.0.1", port=port)
        try:
            assert sub.ready()["topic"] == "/early"
            group.start("pub.py", "early", "std_msgs/String", "data: late master").ready()
            assert sub.messages() == {"data": "late master"}
        finally:
            group.close()
            handle.shutdown()
    finally:
        group.close()


def test_slow_subscriber_with_queue_size_one_skips_to_the_newest_message(nodes):
    sub = nodes.start("sub.py", "burst", "std_msgs/Int32", "--queue", "1", "--slow", "0.3")
    sub.ready()
    pub = nodes.start("pub.py", "burst", "std_msgs/Int32", "data: $N", "--count", "200",
                      "--rate", "1000", "--latch")
    pub.expect(lambda d: d.get("sent") == 200)
    last = sub.expect(lambda d: d.get("msg") == {"data": 199}, timeout=15)
    received = [d["msg"]["data"] for d in sub.seen if "msg" in d]
    assert last and received == sorted(received)
    assert len(received) < 50  # most of the backlog was dropped, not queued


def test_garbage_and_unknown_requests_on_the_tcpros_port_do_not_hurt_the_node(nodes):
    pub = nodes.start("pub.py", "sturdy", "std_msgs/String", "data: ok", "--name", "sturdy")
    pub.ready()
    master = OneShotProxy(nodes.master_uri)
    api = OneShotProxy(wait_for(lambda: master.lookupNode("/t", "/sturdy")[2]))
    _, _, (_, host, port) = api.requestTopic("/t", "/sturdy", [["TCPROS"]])
    with socket.create_connection((host, port)) as sock:  # absurd header length
        sock.sendall(b"\xff\xff\xff\x7f garbage")
    with tcpros.connect(host, port) as sock:  # neither topic nor service
        tcpros.write_header(sock, {"callerid": "/t"})
        assert "error" in tcpros.read_header(sock)
    with tcpros.connect(host, port) as sock:  # a topic it does not publish
        tcpros.write_header(sock, {"callerid": "/t", "topic": "/other", "md5sum": "*"})
        assert "/other" in tcpros.read_header(sock)["error"]
    with tcpros.connect(host, port) as sock:  # an unknown service
        tcpros.write_header(sock, {"callerid": "/t", "service": "/nope", "md5sum": "*"})
        assert "/nope" in tcpros.read_header(sock)["error"]
    sub = nodes.start("sub.py", "sturdy", "std_msgs/String")
    assert sub.messages() == {"data": "ok"}
    assert pub.proc.poll() is None


def test_a_node_receives_its_own_publications_like_rospy(nodes):
    proc = nodes.start("echo_self.py")
    assert proc.expect(lambda d: "got" in d)["got"] == ["mine", "/self_loop"]
    assert proc.wait() == 0
