"""nodelet: name resolution for hosted nodelets, plugin discovery, the manager's book-keeping."""
from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "nodelet" / "src"))

from nodelet import Nodelet, names  # noqa: E402
from nodelet.manager import LoadError, Manager  # noqa: E402
from nodelet.plugins import PluginError, find_declaration, load_plugin  # noqa: E402


# ---- names -----------------------------------------------------------------------------
@pytest.mark.parametrize("name, expected", [
    ("odom", "/odom"),
    ("~odom", "/mobile_base/odom"),
    ("/diagnostics", "/diagnostics"),
    ("sensors//imu", "/sensors/imu"),
])
def test_resolve_against_the_nodelets_own_name(name, expected):
    assert names.resolve(name, "/mobile_base") == expected


def test_resolve_in_a_namespace():
    assert names.resolve("odom", "/robot1/mobile_base") == "/robot1/odom"
    assert names.resolve("~odom", "/robot1/mobile_base") == "/robot1/mobile_base/odom"


def test_remaps_from_loader_argv_apply_to_resolved_names():
    remaps = names.parse_remaps(["manager", "mobile_base/odom:=odom", "_param:=1",
                                 "__name:=mobile_base", "~enable:=/enable"], "/mobile_base")
    assert remaps == {"/mobile_base/odom": "/odom", "/mobile_base/enable": "/enable"}
    assert names.resolve("~odom", "/mobile_base", remaps) == "/odom"
    assert names.resolve("~joint_states", "/mobile_base", remaps) == "/mobile_base/joint_states"


def test_strip_ros_args_keeps_plain_words():
    assert names.strip_ros_args(["load", "a/B", "mgr", "x:=y", "__name:=n"]) == ["load", "a/B", "mgr"]


# ---- plugins ---------------------------------------------------------------------------
def make_plugin_package(root: Path, pkg: str, module: str, body: str,
                        class_name: str = "Thing", type_name: str | None = None) -> None:
    directory = root / pkg
    (directory / "py" / module).mkdir(parents=True)
    (directory / "package.xml").write_text(textwrap.dedent(f"""\
        <package format="2"><name>{pkg}</name><version>0.0.0</version>
          <description>d</description><maintainer email="a@b.c">m</maintainer>
          <license>BSD</license>
          <export><nodelet plugin="${{prefix}}/plugins.xml"/></export>
        </package>"""))
    (directory / "plugins.xml").write_text(
        f'<library path="py"><class name="{type_name or pkg + "/" + class_name}" '
        f'type="{module}.impl:{class_name}" base_class_type="nodelet::Nodelet"/></library>')
    (directory / "py" / module / "__init__.py").write_text("")
    (directory / "py" / module / "impl.py").write_text(textwrap.dedent(body))


@pytest.fixture
def workspace(tmp_path, monkeypatch):
    from orchestra.packages.index import reset_index
    ws = tmp_path / "ws"
    ws.mkdir()
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ws))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "ros_home"))
    reset_index()
    yield ws
    reset_index()


GOOD = """
    from nodelet import Nodelet
    class Thing(Nodelet):
        def on_init(self):
            self.started = self.resolve("~out")
        def on_shutdown(self):
            self.stopped = True
"""


def test_plugin_declared_in_package_xml_export_is_found_and_imported(workspace, tmp_path):
    module = f"plug_{tmp_path.name}"
    make_plugin_package(workspace, "my_pkg", module, GOOD)
    decl = find_declaration("my_pkg/Thing")
    assert decl.type == f"{module}.impl:Thing"
    assert issubclass(load_plugin("my_pkg/Thing"), Nodelet)


def test_plugin_exported_by_another_package_is_found(workspace, tmp_path):
    make_plugin_package(workspace, "provider", f"prov_{tmp_path.name}", GOOD,
                        type_name="other_name/Thing")
    assert find_declaration("other_name/Thing").name == "other_name/Thing"


def test_unknown_plugin_type_is_a_clear_error(workspace):
    with pytest.raises(PluginError, match="declared by no package"):
        find_declaration("nobody/Nothing")


def test_plugin_class_missing_from_module_names_the_description_file(workspace, tmp_path):
    make_plugin_package(workspace, "broken", f"brk_{tmp_path.name}", "X = 1\n")
    with pytest.raises(PluginError, match="has no class 'Thing'") as info:
        load_plugin("broken/Thing")
    assert "plugins.xml" in str(info.value)


def test_bundled_turtlebot_nodelets_are_declared():
    assert find_declaration("kobuki_node/KobukiNodelet").type == "kobuki_node.nodelet:KobukiNodelet"
    assert find_declaration("yocs_cmd_vel_mux/CmdVelMuxNodelet").name.startswith("yocs")


# ---- manager ---------------------------------------------------------------------------
def test_manager_loads_with_identity_and_unloads(workspace, tmp_path):
    make_plugin_package(workspace, "my_pkg", f"mgr_{tmp_path.name}", GOOD)
    manager = Manager()
    instance = manager.load("/ns/thing", "my_pkg/Thing", {"/ns/thing/out": "/elsewhere"}, ["a"])
    assert instance.started == "/elsewhere"
    assert instance.namespace == "/ns" and instance.my_argv == ["a"]
    assert manager.list() == ["/ns/thing"]
    assert manager.unload("/ns/thing") is True
    assert instance.stopped is True
    assert manager.list() == [] and manager.unload("/ns/thing") is False


def test_manager_refuses_a_second_nodelet_with_the_same_name(workspace, tmp_path):
    make_plugin_package(workspace, "my_pkg", f"dup_{tmp_path.name}", GOOD)
    manager = Manager()
    manager.load("/thing", "my_pkg/Thing", {}, [])
    with pytest.raises(LoadError, match="already loaded"):
        manager.load("/thing", "my_pkg/Thing", {}, [])
    assert manager.list() == ["/thing"]


def test_failing_on_init_leaves_nothing_loaded(workspace, tmp_path):
    make_plugin_package(workspace, "bad_init", f"bad_{tmp_path.name}", """
        from nodelet import Nodelet
        class Thing(Nodelet):
            def on_init(self):
                raise RuntimeError("no device")
    """)
    manager = Manager()
    with pytest.raises(LoadError, match="no device"):
        manager.load("/thing", "bad_init/Thing", {}, [])
    assert manager.list() == []


def test_class_that_is_not_a_nodelet_is_refused(workspace, tmp_path):
    make_plugin_package(workspace, "plain", f"plain_{tmp_path.name}", "class Thing:\n    pass\n")
    with pytest.raises(LoadError, match="not a nodelet"):
        Manager().load("/thing", "plain/Thing", {}, [])


def test_unknown_type_is_a_load_error_not_a_crash(workspace):
    with pytest.raises(LoadError, match="declared by no package"):
        Manager().load("/thing", "nobody/Nothing", {}, [])


def test_shutdown_stops_timers_and_is_idempotent():
    import threading
    ticks = []
    event = threading.Event()

    class Ticker(Nodelet):
        def on_init(self):
            self.create_timer(0.01, lambda now: (ticks.append(now), event.set()))

    ticker = Ticker("/ticker")
    ticker.on_init()
    assert event.wait(2.0)
    ticker.shutdown()
    ticker.shutdown()
    count = len(ticks)
    threading.Event().wait(0.05)
    assert len(ticks) <= count + 1


# ---- in-process bus --------------------------------------------------------------------
class FakeMsg:
    def __init__(self, value, type_="std_msgs/String"):
        self.value, self._type = value, type_


def collect(bus, topic, type_="std_msgs/String", queue_size=10):
    import threading
    got, event = [], threading.Event()

    def cb(msg):
        got.append(msg.value)
        event.set()
    return bus.subscribe(topic, type_, cb, queue_size), got, event


def test_local_bus_delivers_to_same_topic_and_type_only():
    from nodelet.local import LocalBus
    bus = LocalBus()
    _, got, event = collect(bus, "/a")
    _, other, _ = collect(bus, "/b")
    assert bus.publish("/a", FakeMsg(1)) == 1
    assert bus.publish("/a", FakeMsg(2, "geometry_msgs/Twist")) == 0
    assert event.wait(2.0)
    assert got == [1] and other == []


def test_local_bus_gives_latched_message_to_late_subscriber():
    from nodelet.local import LocalBus
    bus = LocalBus()
    bus.publish("/active", FakeMsg("idle"), latch=True)
    _, got, event = collect(bus, "/active")
    assert event.wait(2.0) and got == ["idle"]


def test_local_bus_unregister_stops_delivery():
    from nodelet.local import LocalBus
    bus = LocalBus()
    sub, got, _ = collect(bus, "/a")
    sub.unregister()
    assert bus.publish("/a", FakeMsg(1)) == 0 and bus.count("/a") == 0


def test_slow_local_subscriber_does_not_block_publisher_and_drops_oldest():
    import threading
    import time

    from nodelet.local import LocalBus
    bus = LocalBus()
    release, got = threading.Event(), []

    def slow(msg):
        release.wait(5.0)
        got.append(msg.value)
    bus.subscribe("/a", "std_msgs/String", slow, queue_size=2)
    start = time.monotonic()
    for i in range(10):
        bus.publish("/a", FakeMsg(i))
    # blocked would mean waiting for the slow callback's 5 s release
    assert time.monotonic() - start < 2.5
    release.set()
    deadline = time.monotonic() + 2.0
    while got[-1:] != [9] and time.monotonic() < deadline:
        time.sleep(0.01)
    assert got[-1] == 9 and len(got) <= 3


# ---- bonds: a loader that died does not leave its nodelet behind ----------------------------
def test_request_from_a_new_loader_replaces_the_old_nodelet(workspace, tmp_path):
    make_plugin_package(workspace, "my_pkg", f"bond_{tmp_path.name}", GOOD)
    manager = Manager()
    old = manager.load("/thing", "my_pkg/Thing", {}, [], bond="http://h:1/")
    new = manager.load("/thing", "my_pkg/Thing", {}, [], bond="http://h:2/")
    assert old.stopped is True and new is not old
    assert manager.list() == ["/thing"]
    with pytest.raises(LoadError, match="already loaded"):   # same loader asking twice
        manager.load("/thing", "my_pkg/Thing", {}, [], bond="http://h:2/")


def test_unload_orphans_unloads_only_nodelets_whose_loader_is_dead(workspace, tmp_path):
    make_plugin_package(workspace, "my_pkg", f"orph_{tmp_path.name}", GOOD)
    manager = Manager()
    manager.load("/alive", "my_pkg/Thing", {}, [], bond="http://h:1/")
    manager.load("/dead", "my_pkg/Thing", {}, [], bond="http://h:2/")
    manager.load("/unbonded", "my_pkg/Thing", {}, [])
    assert manager.unload_orphans(lambda uri: uri.endswith(":1/")) == ["/dead"]
    assert manager.list() == ["/alive", "/unbonded"]


def test_uri_alive_tells_a_listening_port_from_a_closed_one():
    import socket

    from nodelet.manager import uri_alive
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    port = server.getsockname()[1]
    assert uri_alive(f"http://127.0.0.1:{port}/")
    server.close()
    assert not uri_alive(f"http://127.0.0.1:{port}/")
    assert uri_alive("not a uri")   # unknown: never unload on a guess


def test_tcpros_copies_of_this_process_messages_are_not_delivered_twice():
    from nodelet.base import from_other_process

    class Msg:
        __slots__ = ("_connection_header",)
    msg = Msg()
    assert from_other_process(msg, "/mgr")            # no header: not ours
    msg._connection_header = {"callerid": "/teleop"}
    assert from_other_process(msg, "/mgr")
    msg._connection_header = {"callerid": "/mgr"}
    assert not from_other_process(msg, "/mgr")
