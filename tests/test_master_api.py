"""The master answers the ROS Master API over XML-RPC exactly as rosmaster does.

Every test drives a real master on an ephemeral port through ``xmlrpc.client``, the way
rospy talks to it, and uses small XML-RPC "slave" servers to receive the master's callbacks.
"""
from __future__ import annotations

import os
import socket
import sys
import threading
import time
import xmlrpc.client
from pathlib import Path
from xmlrpc.server import SimpleXMLRPCServer

import pytest

from orchestra.errors import OrchestraError
from orchestra.master import master_is_up, start_master, upload_params
from orchestra.master.notify import Notifier

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(60)


class Slave:
    """A minimal node slave API that records the master's callbacks in order."""

    def __init__(self) -> None:
        self.server = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=True)
        self.uri = f"http://127.0.0.1:{self.server.server_address[1]}/"
        self.calls: list[tuple] = []
        self.cond = threading.Condition()
        for name in ("publisherUpdate", "paramUpdate", "shutdown"):
            self.server.register_function(self._recorder(name), name)
        self.thread = threading.Thread(target=self.server.serve_forever, args=(0.05,),
                                       daemon=True)
        self.thread.start()

    def _recorder(self, name):
        def record(*args):
            with self.cond:
                self.calls.append((name, *args))
                self.cond.notify_all()
            return [1, "", 0]
        return record

    def wait_for(self, count: int, timeout: float = 10.0) -> list[tuple]:
        with self.cond:
            assert self.cond.wait_for(lambda: len(self.calls) >= count, timeout), self.calls
            return list(self.calls)

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture
def m(master):
    with xmlrpc.client.ServerProxy(master.uri) as proxy:
        yield proxy


@pytest.fixture
def slaves():
    made: list[Slave] = []

    def make() -> Slave:
        slave = Slave()
        made.append(slave)
        return slave
    yield make
    for slave in made:
        slave.close()


# --- lifecycle and probes -----------------------------------------------------------------------

def test_start_master_on_port_zero_picks_free_port_and_reports_uri(master, m):
    assert master.port != 11311 and master.port > 0
    assert master.uri == f"http://127.0.0.1:{master.port}/"
    assert m.getUri("/x") == [1, "", master.uri]
    assert m.getPid("/x") == [1, "", os.getpid()]
    assert master_is_up(master.uri)


def test_shutdown_is_idempotent_and_frees_the_port():
    handle = start_master(port=0)
    uri = handle.uri
    # a keep-alive connection open at shutdown time must not keep the server alive
    with xmlrpc.client.ServerProxy(uri) as proxy:
        proxy.getPid("/x")
        handle.shutdown()
        handle.shutdown()
        assert not master_is_up(uri, timeout=0.5)
    again = start_master(port=handle.port)  # the port is free again
    again.shutdown()


def test_master_is_up_false_when_nothing_listens():
    handle = start_master(port=0)
    handle.shutdown()
    assert master_is_up(handle.uri, timeout=0.5) is False


def test_remote_shutdown_call_stops_master(master, m):
    assert m.shutdown("/x", "bye") == [1, "shutdown", 0]
    assert master.wait(5)
    assert not master_is_up(master.uri, timeout=0.5)


def test_port_in_use_is_a_user_error(master):
    with pytest.raises(OrchestraError, match="cannot start a master"):
        start_master(port=master.port)


# --- registration round trips --------------------------------------------------------------------

def test_publisher_subscriber_round_trip_like_rospy(m, slaves):
    pub, sub = slaves(), slaves()
    code, msg, subs = m.registerPublisher("/talker", "/chatter", "std_msgs/String", pub.uri)
    assert (code, msg, subs) == (1, "Registered [/talker] as publisher of [/chatter]", [])
    code, msg, pubs = m.registerSubscriber("/listener", "/chatter", "std_msgs/String", sub.uri)
    assert (code, msg, pubs) == (1, "Subscribed to [/chatter]", [pub.uri])
    # a publisher registering later gets the subscriber list, the subscriber an update
    pub2 = slaves()
    _, _, subs = m.registerPublisher("/talker2", "/chatter", "std_msgs/String", pub2.uri)
    assert subs == [sub.uri]
    assert sub.wait_for(1) == [("publisherUpdate", "/master", "/chatter", [pub.uri, pub2.uri])]


def test_relative_topic_resolves_in_callers_namespace(m, slaves):
    pub = slaves()
    m.registerPublisher("/robot/cam", "image", "sensor_msgs/Image", pub.uri)
    m.registerPublisher("/robot/cam", "~info", "sensor_msgs/CameraInfo", pub.uri)
    state = m.getSystemState("/x")[2]
    assert sorted(t for t, _ in state[0]) == ["/robot/cam/info", "/robot/image"]


def test_get_system_state_format(m, slaves):
    a, b = slaves(), slaves()
    m.registerPublisher("/a", "/t", "std_msgs/Int32", a.uri)
    m.registerSubscriber("/b", "/t", "std_msgs/Int32", b.uri)
    m.registerSubscriber("/a", "/t", "std_msgs/Int32", a.uri)
    m.registerService("/b", "/srv", "rosrpc://127.0.0.1:1234", b.uri)
    assert m.getSystemState("/x") == [1, "current system state", [
        [["/t", ["/a"]]],
        [["/t", ["/b", "/a"]]],
        [["/srv", ["/b"]]],
    ]]


def test_unregister_publisher_notifies_subscribers_with_remaining_publishers(m, slaves):
    p1, p2, s = slaves(), slaves(), slaves()
    m.registerSubscriber("/s", "/t", "std_msgs/Int32", s.uri)
    m.registerPublisher("/p1", "/t", "std_msgs/Int32", p1.uri)
    m.registerPublisher("/p2", "/t", "std_msgs/Int32", p2.uri)
    assert m.unregisterPublisher("/p1", "/t", p1.uri) == [
        1, "Unregistered [/p1] as provider of [/t]", 1]
    calls = s.wait_for(3)
    # in order: each update carries the list as it was at that moment
    assert [c[3] for c in calls] == [[p1.uri], [p1.uri, p2.uri], [p2.uri]]
    assert m.unregisterPublisher("/p1", "/t", p1.uri)[2] == 0


def test_publisher_updates_arrive_in_order_per_node(m, slaves):
    s = slaves()
    m.registerSubscriber("/s", "/t", "std_msgs/Int32", s.uri)
    pubs = [slaves() for _ in range(5)]
    for i, p in enumerate(pubs):
        m.registerPublisher(f"/p{i}", "/t", "std_msgs/Int32", p.uri)
    for i, p in enumerate(pubs):
        m.unregisterPublisher(f"/p{i}", "/t", p.uri)
    calls = s.wait_for(10)
    assert [len(c[3]) for c in calls] == [1, 2, 3, 4, 5, 4, 3, 2, 1, 0]


def test_hung_subscriber_blocks_neither_registration_nor_other_nodes(m, slaves):
    # a slave that accepts connections but never answers
    hung = socket.socket()
    hung.bind(("127.0.0.1", 0))
    hung.listen(8)
    try:
        m.registerSubscriber("/hung", "/t", "std_msgs/Int32",
                             f"http://127.0.0.1:{hung.getsockname()[1]}/")
        healthy = slaves()
        m.registerSubscriber("/ok", "/t", "std_msgs/Int32", healthy.uri)
        start = time.monotonic()
        pub = slaves()
        m.registerPublisher("/p", "/t", "std_msgs/Int32", pub.uri)
        # blocked would mean waiting out the hung slave's 10 s call timeout
        assert time.monotonic() - start < 5.0
        assert healthy.wait_for(1, timeout=5) == [
            ("publisherUpdate", "/master", "/t", [pub.uri])]
    finally:
        hung.close()


def _notify_workers() -> set[threading.Thread]:
    return {t for t in threading.enumerate() if t.name == "master notify"}


def test_notifier_reuses_its_waiting_workers_and_close_lets_them_go(slaves):
    notifier = Notifier()
    first, second = slaves(), slaves()
    before = _notify_workers()  # other notifiers' workers, maybe on their way out
    notifier.send(first.uri, "paramUpdate", "/master", "/a/", 1)
    assert notifier.wait_idle(5) and first.wait_for(1)
    mine = _notify_workers() - before
    assert len(mine) == 1  # drained, and waiting for the next node
    for value in range(3):
        notifier.send(second.uri, "paramUpdate", "/master", "/b/", value)
    assert notifier.wait_idle(5)
    assert [call[3] for call in second.wait_for(3)] == [0, 1, 2]  # in order
    assert _notify_workers() - before == mine  # the same worker took the second node
    notifier.close()
    wait_for(lambda: not mine & _notify_workers(), timeout=5)


def test_lookup_node_returns_slave_api_and_unknown_node_is_error(m, slaves):
    s = slaves()
    m.registerSubscriber("/ns/node", "/t", "std_msgs/Int32", s.uri)
    assert m.lookupNode("/x", "/ns/node") == [1, "node api", s.uri]
    assert m.lookupNode("/ns/other", "node") == [1, "node api", s.uri]
    assert m.lookupNode("/x", "/ghost") == [-1, "unknown node [/ghost]", ""]


def test_node_forgotten_after_last_unregister(m, slaves):
    s = slaves()
    m.registerSubscriber("/n", "/t", "std_msgs/Int32", s.uri)
    assert m.unregisterSubscriber("/n", "/t", s.uri) == [
        1, "Unregistered [/n] as provider of [/t]", 1]
    assert m.lookupNode("/x", "/n")[0] == -1
    assert m.unregisterSubscriber("/n", "/t", s.uri) == [1, "[/n] is not a registered node", 0]


def test_services_register_lookup_unregister(m, slaves):
    s = slaves()
    assert m.registerService("/srv_node", "add", "rosrpc://h:5555", s.uri) == [
        1, "Registered [/srv_node] as provider of [/add]", 1]
    assert m.lookupService("/x", "/add") == [1, "rosrpc URI: [rosrpc://h:5555]",
                                             "rosrpc://h:5555"]
    assert m.unregisterService("/srv_node", "/add", "rosrpc://other:1")[2] == 0
    assert m.unregisterService("/srv_node", "/add", "rosrpc://h:5555") == [
        1, "Unregistered [/srv_node] as provider of [/add]", 1]
    assert m.lookupService("/x", "/add") == [-1, "no provider", ""]


def test_published_topics_and_topic_types(m, slaves):
    s = slaves()
    m.registerPublisher("/n", "/a/x", "std_msgs/Int32", s.uri)
    m.registerPublisher("/n", "/b/y", "std_msgs/String", s.uri)
    m.registerSubscriber("/n", "/c", "std_msgs/Bool", s.uri)
    m.registerSubscriber("/n", "/d", "*", s.uri)
    assert m.getPublishedTopics("/x", "") == [1, "current topics", [
        ["/a/x", "std_msgs/Int32"], ["/b/y", "std_msgs/String"]]]
    assert m.getPublishedTopics("/x", "/a")[2] == [["/a/x", "std_msgs/Int32"]]
    types = dict(m.getTopicTypes("/x")[2])
    assert types == {"/a/x": "std_msgs/Int32", "/b/y": "std_msgs/String", "/c": "std_msgs/Bool"}


def test_anytype_publisher_does_not_override_known_type(m, slaves):
    s = slaves()
    m.registerPublisher("/a", "/t", "std_msgs/Int32", s.uri)
    m.registerPublisher("/b", "/t", "*", slaves().uri)
    assert dict(m.getTopicTypes("/x")[2])["/t"] == "std_msgs/Int32"


def test_same_name_from_new_uri_shuts_old_node_down(m, slaves):
    old, new = slaves(), slaves()
    m.registerPublisher("/cam", "/img", "sensor_msgs/Image", old.uri)
    m.registerSubscriber("/cam", "/cmd", "std_msgs/String", new.uri)
    calls = old.wait_for(1)
    assert calls == [("shutdown", "/master", "[/cam] Reason: new node registered with same name")]
    assert m.lookupNode("/x", "/cam")[2] == new.uri
    # the old node's registrations are gone with it
    assert m.getSystemState("/x")[2][0] == []


# --- bad calls never crash the server -------------------------------------------------------------

@pytest.mark.parametrize("method,args,expected", [
    ("getParam", ("/x",), [-1, "Error: bad call arity", 0]),
    ("getParam", ("/x", "a", "b"), [-1, "Error: bad call arity", 0]),
    ("getParam", (), [-1, "missing required caller_id parameter", 0]),
    ("getParam", (5, "/a"), [-1, "caller_id must be a string", 0]),
    ("getParam", ("/x", ""), [-1, "ERROR: parameter [key] must be specified and non-empty", 0]),
    ("getParam", ("/x", 3), [-1, "ERROR: parameter [key] must be a string", 0]),
    ("hasParam", ("/x",), [-1, "Error: bad call arity", False]),
    ("getParamNames", ("/x", 1), [-1, "Error: bad call arity", []]),
    ("registerPublisher", ("/n", "/t", "BadType", "http://h:1/"),
     [-1, "ERROR: parameter [topic_type] is not a valid package resource name", 0]),
    ("registerPublisher", ("/n", "/t", "std_msgs/String", "localhost:1"),
     [-1, "ERROR: parameter [caller_api] is not an RPC URI", 0]),
    ("registerPublisher", ("/n", "http://t", "std_msgs/String", "http://h:1/"),
     [-1, "ERROR: parameter [topic] contains illegal chars", 0]),
    ("registerSubscriber", ("/n", "/", "std_msgs/String", "http://h:1/"),
     [-1, "ERROR: parameter [topic] cannot be the global namespace", 0]),
    ("lookupService", ("/n", ""), [-1, "ERROR: parameter [service] must be a non-empty string",
                                    ""]),
    ("subscribeParam", ("/n", 7, "/k"), [-1, "ERROR: parameter [caller_api] is not an XMLRPC URI",
                                         0]),
])
def test_bad_arguments_get_rosmaster_error_codes(m, method, args, expected):
    assert getattr(m, method)(*args) == expected
    assert m.getPid("/x")[0] == 1  # still serving


def test_unknown_method_is_a_fault_and_server_survives(m):
    with pytest.raises(xmlrpc.client.Fault):
        m.noSuchMethod("/x")
    assert m.getPid("/x")[0] == 1


# --- parameter server -----------------------------------------------------------------------------

def test_param_round_trip_and_messages(m):
    assert m.setParam("/n", "/a/b", 1) == [1, "parameter /a/b set", 0]
    assert m.getParam("/n", "/a/b") == [1, "Parameter [/a/b]", 1]
    assert m.getParam("/n", "/a") == [1, "Parameter [/a]", {"b": 1}]
    assert m.hasParam("/n", "/a/b") == [1, "/a/b", True]
    assert m.hasParam("/n", "/a/c") == [1, "/a/c", False]
    assert m.getParamNames("/n") == [1, "Parameter names", ["/a/b"]]
    assert m.deleteParam("/n", "/a") == [1, "parameter /a deleted", 0]
    assert m.deleteParam("/n", "/a") == [-1, "parameter [/a] is not set", 0]
    assert m.getParam("/n", "/a") == [-1, "Parameter [/a] is not set", 0]


def test_param_names_resolve_relative_and_private_to_caller(m):
    m.setParam("/ns/node", "rel", 1)
    m.setParam("/ns/node", "~priv", 2)
    assert m.getParam("/x", "/")[2] == {"ns": {"rel": 1, "node": {"priv": 2}}}


def test_param_value_types_survive_xmlrpc(m):
    value = {"i": -5, "f": 2.5, "b": True, "s": "x", "l": [1, "two", [3.0]],
             "bin": xmlrpc.client.Binary(b"\x00\xff")}
    m.setParam("/n", "/v", value)
    got = m.getParam("/n", "/v")[2]
    assert got["bin"].data == b"\x00\xff"
    got["bin"] = value["bin"]
    assert got == value


def test_out_of_range_int_over_xmlrpc_is_refused_not_stored(master):
    body = ("<?xml version='1.0'?><methodCall><methodName>setParam</methodName><params>"
            "<param><value><string>/n</string></value></param>"
            "<param><value><string>/big</string></value></param>"
            "<param><value><i8>99999999999</i8></value></param>"
            "</params></methodCall>")
    import urllib.request
    req = urllib.request.Request(master.uri, data=body.encode(),
                                 headers={"Content-Type": "text/xml"})
    with urllib.request.urlopen(req, timeout=5) as resp:
        (code, msg, _), = xmlrpc.client.loads(resp.read())[0]
    assert code == -1 and "/big" in msg
    assert not master.params.has("/big")


def test_set_root_to_non_dict_is_caller_error(m):
    assert m.setParam("/n", "/", 1)[0] == -1
    assert m.setParam("/n", "/", {"a": 1})[0] == 1
    assert m.getParam("/n", "/")[2] == {"a": 1}


def test_search_param_upward_from_caller(m):
    m.setParam("/n", "/robot/rate", 10)
    assert m.searchParam("/robot/arm/node", "rate") == [1, "Found [/robot/rate]", "/robot/rate"]
    assert m.searchParam("/robot/arm/node", "nope") == [
        -1, "Cannot find parameter [nope] in an upwards search", ""]


def test_param_subscription_callbacks(master, m, slaves):
    s = slaves()
    m.setParam("/n", "/cfg/gain", 1.0)
    assert m.subscribeParam("/node", s.uri, "/cfg") == [
        1, "Subscribed to parameter [/cfg]", {"gain": 1.0}]
    m.setParam("/other", "/cfg/gain", 2.0)
    m.setParam("/other", "/unrelated", 0)
    m.deleteParam("/other", "/cfg")
    calls = s.wait_for(2)
    assert calls == [("paramUpdate", "/master", "/cfg/gain/", 2.0),
                     ("paramUpdate", "/master", "/cfg/", {})]
    assert m.unsubscribeParam("/node", s.uri, "/cfg") == [
        1, "Unregistered [/node] as provider of [/cfg/]", 1]
    m.setParam("/other", "/cfg/gain", 3.0)
    assert master.api.notifier.wait_idle(5)
    assert len(s.calls) == 2


def test_subscribe_unset_param_returns_empty_dict(m, slaves):
    assert m.subscribeParam("/node", slaves().uri, "/not/set") == [
        1, "Subscribed to parameter [/not/set]", {}]


def test_in_process_params_share_the_servers_tree(master, m):
    master.params.set("/fast", 1)
    assert m.getParam("/x", "/fast")[2] == 1


# --- upload -------------------------------------------------------------------------------------

def test_upload_params_clears_namespaces_then_sets_all(master, m):
    m.setParam("/n", "/ns/old", 1)
    m.setParam("/n", "/keep", 1)
    upload_params(master.uri, {"/ns/new": 2, "/bin": b"\x01\x02", "/t": (1, 2)},
                  ["/ns", "/never_set"])
    tree = m.getParam("/n", "/")[2]
    assert tree["ns"] == {"new": 2}
    assert tree["keep"] == 1
    assert tree["bin"].data == b"\x01\x02"
    assert tree["t"] == [1, 2]


def test_upload_params_is_one_multicall(master, monkeypatch):
    calls = []
    original = master.api._dispatch

    def spy(method, params):
        calls.append(method)
        return original(method, params)
    monkeypatch.setattr(master.api, "_dispatch", spy)
    upload_params(master.uri, {"/a": 1, "/b": 2}, ["/c"])
    assert calls == ["deleteParam", "setParam", "setParam"]  # all inside system.multicall


def test_upload_params_bad_value_names_param_and_uploads_nothing(master, m):
    with pytest.raises(OrchestraError, match="/robot/too_big"):
        upload_params(master.uri, {"/robot/ok": 1, "/robot/too_big": 2 ** 33}, ["/robot"])
    with pytest.raises(OrchestraError, match="/robot/none"):
        upload_params(master.uri, {"/robot/none": None}, [])
    assert m.getParamNames("/x")[2] == []


def test_upload_params_unreachable_master_is_user_error():
    handle = start_master(port=0)
    handle.shutdown()
    with pytest.raises(OrchestraError, match="cannot reach"):
        upload_params(handle.uri, {"/a": 1}, [])


def test_in_process_param_write_notifies_subscribed_nodes(master, m, slaves):
    s = slaves()
    m.subscribeParam("/node", s.uri, "/tuning")
    master.params.set("/tuning/kp", 0.5)
    assert s.wait_for(1) == [("paramUpdate", "/master", "/tuning/kp/", 0.5)]


def test_param_updates_to_one_node_arrive_in_write_order(master, m, slaves):
    s = slaves()
    m.subscribeParam("/node", s.uri, "/count")
    for i in range(20):
        m.setParam("/writer", "/count", i)
    assert [c[3] for c in s.wait_for(20)] == list(range(20))


def test_replaced_node_loses_its_param_subscriptions(master, m, slaves):
    old, new = slaves(), slaves()
    m.subscribeParam("/node", old.uri, "/p")
    m.registerSubscriber("/node", "/t", "std_msgs/Int32", new.uri)
    m.setParam("/w", "/p", 1)
    assert master.api.notifier.wait_idle(5)
    assert [c[0] for c in old.calls] == ["shutdown"]


def test_malformed_request_body_gets_a_fault_and_server_keeps_serving(master, m):
    import urllib.request
    req = urllib.request.Request(master.uri, data=b"<methodCall><not-xml",
                                 headers={"Content-Type": "text/xml"})
    with urllib.request.urlopen(req, timeout=5) as resp:
        with pytest.raises(xmlrpc.client.Fault):
            xmlrpc.client.loads(resp.read())
    assert m.getPid("/x")[0] == 1


def test_concurrent_clients_see_consistent_state(master):
    errors: list[BaseException] = []

    def worker(n: int) -> None:
        try:
            with xmlrpc.client.ServerProxy(master.uri) as p:
                for i in range(50):
                    assert p.setParam(f"/w{n}", f"/w{n}/v", i)[0] == 1
                    assert p.getParam(f"/w{n}", f"/w{n}/v")[2] == i
                    p.registerPublisher(f"/w{n}", f"/t{i % 5}", "std_msgs/Int32",
                                        f"http://127.0.0.1:{10000 + n}/")
                    p.getSystemState("/x")
                    p.getParam("/x", "/")
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)
    threads = [threading.Thread(target=worker, args=(n,)) for n in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert errors == []
    with xmlrpc.client.ServerProxy(master.uri) as proxy:
        state = proxy.getSystemState("/x")[2]
    assert {topic: sorted(ids) for topic, ids in state[0]} == {
        f"/t{i}": ["/w0", "/w1", "/w2", "/w3"] for i in range(5)}
    assert {f"/w{n}/v" for n in range(4)} == set(master.params.names())
