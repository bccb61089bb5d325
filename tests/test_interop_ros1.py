"""Wire compatibility with REAL ROS 1: Debian's rospy, rosmaster and the ros* tools.

Every test puts real ROS 1 (run by ``/usr/bin/python3``, not orchestra's interpreter) on one
side and orchestra on the other: rospy nodes against orchestra's master, rospy nodes talking
TCPROS with orchestra nodes, the real command-line tools against orchestra, orchestra's tools
against a real ``rosmaster``, and real ``roslaunch`` resolving orchestra's launch files.
The node program on both sides is the same script (``ros1_nodes/peer.py``), so a failure one
way only is orchestra's. Masters are on ephemeral ports; every process is killed by a
finalizer. Skipped as a whole when Debian's ROS 1 is not installed.
"""
from __future__ import annotations

import json
import os
import re
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import ROS_PYTHON, NodeProcess, OneShotProxy, ProcessGroup, free_port, wait_for  # noqa: E402

HERE = Path(__file__).resolve().parent
PEER = HERE / "ros1_nodes" / "peer.py"
REPO = HERE.parent


def _real_ros_missing() -> str | None:
    if not os.access(ROS_PYTHON, os.X_OK):
        return f"{ROS_PYTHON} is not installed"
    probe = subprocess.run([ROS_PYTHON, "-c", "import rospy, rosmaster"], capture_output=True,
                           text=True, env=_ros_env({}))
    if probe.returncode != 0:
        return ("Debian's ROS 1 (python3-rospy, python3-rosmaster) is not installed for "
                f"{ROS_PYTHON}: {(probe.stderr.strip().splitlines() or ['?'])[-1]}")
    return None


def _ros_env(extra: dict[str, str]) -> dict[str, str]:
    """An environment for a real-ROS process: nothing of orchestra's interpreter leaks in."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTHON", "ROS_", "VIRTUAL_ENV", "PYENV"))}
    env["PYTHONUNBUFFERED"] = "1"
    env.update(extra)
    return env


_MISSING = _real_ros_missing()
pytestmark = [pytest.mark.skipif(_MISSING is not None, reason=_MISSING or ""),
              pytest.mark.timeout(60)]


class Side(ProcessGroup):
    """Processes of both kinds against one master; ``close()`` kills what is left."""

    def __init__(self, master_uri: str, ros_home: Path, package_path: str = ""):
        super().__init__(master_uri)
        common = {"ROS_MASTER_URI": master_uri, "ROS_HOME": str(ros_home),
                  "ROS_PACKAGE_PATH": package_path}
        self.ros_env = _ros_env(common)
        self.orch_env = dict(os.environ, PYTHONUNBUFFERED="1", **common)
        self.orch_env.pop("ROS_NAMESPACE", None)

    def rospy(self, *args: str, env: dict[str, str] | None = None) -> NodeProcess:
        """``peer.py`` as a real rospy node."""
        return self._start([ROS_PYTHON, str(PEER), *args], dict(self.ros_env, **(env or {})))

    def orch(self, *args: str, env: dict[str, str] | None = None) -> NodeProcess:
        """``peer.py`` as an orchestra.node node."""
        return self._start([sys.executable, str(PEER), "--orchestra", *args],
                           dict(self.orch_env, **(env or {})))

    def tool(self, *argv: str, timeout: float = 20) -> subprocess.CompletedProcess:
        """A real ROS 1 command-line tool (rostopic, rosparam, ...)."""
        return subprocess.run([ROS_PYTHON, f"/usr/bin/{argv[0]}", *argv[1:]],
                              env=self.ros_env, capture_output=True, text=True, timeout=timeout)

    def orchestra(self, *args: str, timeout: float = 20) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "orchestra", *args], env=self.orch_env,
                              capture_output=True, text=True, timeout=timeout)

    def background_tool(self, *argv: str) -> NodeProcess:
        return self._start([ROS_PYTHON, f"/usr/bin/{argv[0]}", *argv[1:]], self.ros_env)


@pytest.fixture
def side(master, tmp_path):
    """orchestra's master with room for real rospy and orchestra nodes."""
    group = Side(master.uri, tmp_path / "ros_home")
    yield group
    group.close()


@pytest.fixture
def real_master(tmp_path):
    """A real ``rosmaster --core`` on a free port."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    proc = subprocess.Popen([ROS_PYTHON, "/usr/bin/rosmaster", "--core", "-p", str(port)],
                            env=_ros_env({"ROS_HOME": str(tmp_path / "ros_home"),
                                          "ROS_MASTER_URI": uri}),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    proxy = OneShotProxy(uri)

    def up():
        try:
            return proxy.getPid("/test")[0] == 1
        except OSError:
            return False
    try:
        wait_for(up, timeout=15)
        yield uri
    finally:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture
def real_side(real_master, tmp_path):
    """A real rosmaster with room for real rospy and orchestra nodes."""
    group = Side(real_master, tmp_path / "ros_home")
    yield group
    group.close()


def messages(proc: NodeProcess, count: int, timeout: float = 10.0) -> list[dict]:
    return [proc.expect(lambda d: "msg" in d, timeout) for _ in range(count)]


# --- 1. a real rospy node against orchestra's master ---------------------------------------

def test_rospy_node_registers_and_lookup_node_returns_its_slave_api(side):
    talker = side.rospy("--name", "talker", "pub", "chatter", "std_msgs/String", "data: hi")
    talker.ready()
    code, _, uri = side.master().lookupNode("/probe", "/talker")
    assert code == 1
    assert OneShotProxy(uri).getPid("/probe")[2] == talker.proc.pid
    _, _, state = side.master().getSystemState("/probe")
    assert ["/chatter", ["/talker"]] in state[0]
    _, _, topics = side.master().getTopicTypes("/probe")
    assert ["/chatter", "std_msgs/String"] in topics


def test_rospy_node_unregisters_from_orchestra_master_when_it_shuts_down(side):
    talker = side.rospy("--name", "talker", "pub", "chatter", "std_msgs/String", "data: hi")
    server = side.rospy("--name", "server", "serve", "empty", "std_srvs/Empty")
    talker.ready()
    server.ready()
    talker.signal(signal.SIGINT)
    server.signal(signal.SIGINT)
    assert talker.wait(10) == 0 and server.wait(10) == 0
    pubs, subs, srvs = side.master().getSystemState("/probe")[2]
    assert not [t for t, nodes in pubs + subs + srvs if {"/talker", "/server"} & set(nodes)]
    assert side.master().lookupNode("/probe", "/talker")[0] != 1


@pytest.mark.parametrize("masters", ["orchestra_master", "real_rosmaster"])
def test_a_node_registering_a_taken_name_shuts_the_old_one_down(masters, request):
    """The master calls shutdown on the old node; rospy and orchestra nodes both obey."""
    group = request.getfixturevalue("side" if masters == "orchestra_master" else "real_side")
    old_rospy = group.rospy("--name", "twin", "pub", "a", "std_msgs/String", "data: x")
    old_rospy.ready()
    old_orch = group.orch("--name", "twin", "pub", "b", "std_msgs/String", "data: x")
    old_orch.ready()
    old_rospy.wait(10)  # the orchestra node took /twin from the rospy node ...
    group.rospy("--name", "twin", "pub", "c", "std_msgs/String", "data: x").ready()
    old_orch.wait(10)   # ... and a rospy node took it back
    _, _, uri = group.master().lookupNode("/probe", "/twin")
    assert OneShotProxy(uri).getPid("/probe")[2] == group.procs[-1].proc.pid


def _seed_params(params) -> None:
    params.set("/interop/ns/talker/gains", {"p": 1.5, "i": [0, 1]})
    params.set("/interop/ns/relative", "in ns")
    params.set("/absolute", 42)
    params.set("/interop/shared", "found upward")


def test_rospy_and_orchestra_nodes_see_the_same_private_relative_and_searched_params(
        side, master):
    _seed_params(master.params)
    argv = ("--name", "talker", "params", "_speed:=2.5", "__ns:=/interop/ns")
    real = side.rospy(*argv).ready()
    ours_proc = side.orch(*argv[:3], "_speed:=2.5", "__name:=talker2", "__ns:=/interop/ns")
    ours = ours_proc.ready()
    assert real["params"] == {
        "name": "/interop/ns/talker", "namespace": "/interop/ns/",
        "~speed": 2.5, "~gains": {"p": 1.5, "i": [0, 1]}, "relative": "in ns",
        "/absolute": 42, "~missing": "<default>", "search": "/interop/shared",
        "written": {"by": "rospy", "n": [1, 2]}, "has_written": True,
        "has_after_delete": False,
        "names": ["/interop/ns/relative", "/interop/ns/talker/gains/i",
                  "/interop/ns/talker/gains/p", "/interop/ns/talker/speed",
                  "/interop/shared"]}
    # the orchestra node (named talker2: a second /interop/ns/talker would evict the first)
    expected = dict(real["params"], name="/interop/ns/talker2", written={"by": "orchestra",
                    "n": [1, 2]}, **{"~gains": "<default>"})
    expected["names"] = sorted(real["params"]["names"] + ["/interop/ns/talker2/speed"])
    assert ours["params"] == expected
    assert master.params.get("/interop/ns/talker/speed") == 2.5


def test_rospy_subscriber_connects_when_an_orchestra_publisher_starts_later(side):
    listener = side.rospy("--name", "listener", "sub", "chatter", "std_msgs/String")
    listener.ready()
    side.orch("--name", "talker", "pub", "chatter", "std_msgs/String", "data: late $N").ready()
    got = listener.expect(lambda d: "msg" in d)
    assert got["msg"]["data"].startswith("late ") and got["callerid"] == "/talker"


def test_orchestra_subscriber_connects_when_a_rospy_publisher_starts_later(side):
    listener = side.orch("--name", "listener", "sub", "chatter", "std_msgs/String")
    listener.ready()
    side.rospy("--name", "talker", "pub", "chatter", "std_msgs/String", "data: late").ready()
    assert listener.expect(lambda d: "msg" in d)["callerid"] == "/talker"


def test_rospy_cached_param_follows_orchestra_param_set_and_delete(side, master):
    # subscribed before it exists: the set still reaches rospy's cache
    watcher = side.rospy("--name", "watcher", "watch", "/interop/gain")
    assert watcher.ready()["value"] is None
    result = side.orchestra("param", "set", "/interop/gain", "7")
    assert result.returncode == 0, result.stderr
    assert watcher.expect(lambda d: d.get("value") == 7, timeout=5)
    result = side.orchestra("param", "set", "/interop", "{gain: 8, other: x}")
    assert result.returncode == 0, result.stderr
    assert watcher.expect(lambda d: d.get("value") == 8, timeout=5)
    result = side.orchestra("param", "delete", "/interop")
    assert result.returncode == 0, result.stderr
    assert watcher.expect(lambda d: "value" in d and d["value"] is None, timeout=5)


# --- 2. topics both ways --------------------------------------------------------------------

TOPIC_CASES = {
    "std_msgs/String": ("data: 'hello $N'", lambda m: m["data"].startswith("hello ")),
    "geometry_msgs/Twist": ("{linear: {x: 0.5, y: -1.25}, angular: {z: 2.0}}",
                            lambda m: m == {"linear": {"x": 0.5, "y": -1.25, "z": 0.0},
                                            "angular": {"x": 0.0, "y": 0.0, "z": 2.0}}),
    "geometry_msgs/PoseArray": (
        "{header: {frame_id: map, stamp: {secs: 12, nsecs: 34}}, poses: ["
        "{position: {x: 1.0}, orientation: {w: 1.0}}, {position: {y: 2.0}, "
        "orientation: {z: 0.5, w: 0.5}}]}",
        lambda m: m["header"]["frame_id"] == "map"
        and m["header"]["stamp"] == {"secs": 12, "nsecs": 34}
        and len(m["poses"]) == 2 and m["poses"][1]["orientation"]["z"] == 0.5
        and m["poses"][0]["position"] == {"x": 1.0, "y": 0.0, "z": 0.0}),
    "std_msgs/Float64MultiArray": (
        "{layout: {dim: [{label: rows, size: 2, stride: 4}, {label: cols, size: 2, stride: 2}],"
        " data_offset: 1}, data: [0.5, -1.0, 1.0e+300, 3.25]}",
        lambda m: m == {"layout": {"dim": [{"label": "rows", "size": 2, "stride": 4},
                                           {"label": "cols", "size": 2, "stride": 2}],
                                   "data_offset": 1},
                        "data": [0.5, -1.0, 1e300, 3.25]}),
    "std_msgs/UInt8MultiArray": ("{data: [0, 1, 254, 255]}",
                                 lambda m: m["data"] == [0, 1, 254, 255]),
}


@pytest.mark.parametrize("direction", ["rospy_to_orchestra", "orchestra_to_rospy"])
def test_messages_cross_between_rospy_and_orchestra(side, direction):
    publish, subscribe = ((side.rospy, side.orch) if direction == "rospy_to_orchestra"
                          else (side.orch, side.rospy))
    subs = {}
    for i, type_name in enumerate(TOPIC_CASES):
        subs[type_name] = subscribe("--name", f"sub{i}", "sub", f"topic{i}", type_name)
        publish("--name", f"pub{i}", "pub", f"topic{i}", type_name, TOPIC_CASES[type_name][0])
    for type_name, sub in subs.items():
        got = messages(sub, 2)
        assert all(TOPIC_CASES[type_name][1](g["msg"]) for g in got), got
    # a header's seq is set per publisher, counting up
    seqs = [g["msg"]["header"]["seq"] for g in messages(subs["geometry_msgs/PoseArray"], 2)]
    assert seqs[1] == seqs[0] + 1


@pytest.mark.parametrize("direction", ["rospy_to_orchestra", "orchestra_to_rospy"])
def test_latched_message_reaches_a_late_subscriber_across_implementations(side, direction):
    publish, subscribe = ((side.rospy, side.orch) if direction == "rospy_to_orchestra"
                          else (side.orch, side.rospy))
    pub = publish("--name", "latcher", "pub", "/map_name", "std_msgs/String", "data: once",
                  "--latch", "--count", "1")
    pub.expect(lambda d: "sent" in d)
    sub = subscribe("--name", "late", "sub", "/map_name", "std_msgs/String")
    got = sub.expect(lambda d: "msg" in d)
    assert got["msg"] == {"data": "once"} and got["latching"] == "1"


@pytest.mark.parametrize("direction", ["rospy_to_orchestra", "orchestra_to_rospy"])
def test_md5_mismatch_is_refused_and_both_nodes_keep_working(side, direction):
    publish, subscribe = ((side.rospy, side.orch) if direction == "rospy_to_orchestra"
                          else (side.orch, side.rospy))
    pub = publish("--name", "talker", "pub", "chatter", "std_msgs/String", "data: text")
    wrong = subscribe("--name", "wrong", "sub", "chatter", "geometry_msgs/Twist")
    right = subscribe("--name", "right", "sub", "chatter", "std_msgs/String")
    pub.ready()
    wrong.ready()
    assert right.expect(lambda d: "msg" in d)["msg"] == {"data": "text"}
    time.sleep(0.5)
    assert not [d for d in wrong.seen + _drain(wrong) if "msg" in d]
    assert pub.proc.poll() is None and wrong.proc.poll() is None
    # orchestra's side says why, whichever end it is
    ours = wrong if direction == "rospy_to_orchestra" else pub
    wait_for(lambda: any("refused" in line and "geometry_msgs/Twist" in line
                         for line in ours.stderr_lines), timeout=5)
    # the refused subscriber's node still answers its slave API
    _, _, uri = side.master().lookupNode("/probe", "/wrong")
    assert OneShotProxy(uri).getPid("/probe")[0] == 1


def _drain(proc: NodeProcess) -> list[dict]:
    items = []
    while not proc.lines.empty():
        items.append(proc.lines.get())
    return items


# --- 3. services both ways ------------------------------------------------------------------

@pytest.mark.parametrize("direction", ["rospy_serves", "orchestra_serves"])
def test_service_calls_cross_between_rospy_and_orchestra(side, direction):
    serve, call = ((side.rospy, side.orch) if direction == "rospy_serves"
                   else (side.orch, side.rospy))
    server_impl = "rospy" if direction == "rospy_serves" else "orchestra"
    serve("--name", "server", "serve", "set_bool", "std_srvs/SetBool")
    serve("--name", "emptyserver", "serve", "empty", "std_srvs/Empty")
    requests = ("{data: true}", "{data: false}", "{data: true}")
    callers = [call("--name", f"caller{i}", "call", "/set_bool", "std_srvs/SetBool",
                    *requests, *extra) for i, extra in enumerate([(), ("--persistent",)])]
    empty = call("--name", "ecaller", "call", "/empty", "std_srvs/Empty", "{}", "{}")
    ok = re.compile(f"{server_impl} call [1-6]")
    for caller in callers:  # one plain proxy, one persistent (all calls on one connection)
        results = caller.expect(lambda d: "results" in d, timeout=15)["results"]
        assert results[0]["ok"]["success"] and ok.fullmatch(results[0]["ok"]["message"])
        # the handler's exception reaches the caller as ServiceException with its text
        assert "refused by " + server_impl in results[1]["error"]
        # the server survived the exception (persistent: on the same connection)
        assert results[2]["ok"]["success"] and ok.fullmatch(results[2]["ok"]["message"])
    assert empty.expect(lambda d: "results" in d, timeout=15)["results"] == [{"ok": {}}] * 2


@pytest.mark.parametrize("direction", ["rospy_serves", "orchestra_serves"])
def test_a_handler_returning_none_is_the_same_error_for_the_caller_as_in_rospy(side, direction):
    serve, call = ((side.rospy, side.orch) if direction == "rospy_serves"
                   else (side.orch, side.rospy))
    serve("--name", "server", "serve", "none", "std_srvs/Trigger")
    caller = call("--name", "caller", "call", "/none", "std_srvs/Trigger", "{}", "{}")
    # the same words whichever side serves (Debian's rospy client shows them as a bytes
    # repr); both calls: the server keeps serving
    results = caller.expect(lambda d: "results" in d, timeout=15)["results"]
    assert len(results) == 2
    for result in results:
        assert result["error"].startswith("service [/none] responded with an error: ")
        assert "service cannot process request: service handler returned None" in \
            result["error"]


# --- 4. the tools crossed -------------------------------------------------------------------

def test_real_rostopic_lists_inspects_echoes_and_publishes_with_orchestra_nodes(side):
    side.orch("--name", "talker", "pub", "chatter", "std_msgs/String",
              "data: 'two words: here'").ready()
    listener = side.orch("--name", "listener", "sub", "chatter", "std_msgs/String")
    cmd = side.orch("--name", "driver", "sub", "cmd", "geometry_msgs/Twist")
    listener.ready()
    cmd.ready()
    pub = side.background_tool("rostopic", "pub", "-r", "10", "/cmd", "geometry_msgs/Twist",
                               "{linear: {x: 0.25}}")
    # rostopic hz subscribes with rospy.AnyMsg (type "*"): orchestra serves it too
    hz = side.background_tool("rostopic", "hz", "/chatter")
    listed, info, echo = side.run_all(
        ("rostopic", "list"), ("rostopic", "info", "/chatter"),
        ("rostopic", "echo", "-n", "2", "/chatter"))
    assert listed.returncode == 0, listed.stderr
    assert {"/chatter", "/cmd"} <= set(listed.stdout.split())
    assert info.returncode == 0, info.stderr
    assert "Type: std_msgs/String" in info.stdout
    pubs, subs = info.stdout.split("Subscribers:")
    assert " * /talker (http://" in pubs and " * /listener (http://" in subs
    assert echo.returncode == 0, echo.stderr
    assert echo.stdout == 'data: "two words: here"\n---\n' * 2
    got = cmd.expect(lambda d: "msg" in d and d["callerid"].startswith("/rostopic_"))
    assert got["msg"]["linear"]["x"] == 0.25
    pub.signal(signal.SIGINT)
    rate = hz.expect(lambda d: d.get("text", "").startswith("average rate:"), timeout=10)
    assert 10 < float(rate["text"].split(":")[1]) < 30
    hz.signal(signal.SIGINT)


def test_real_rostopic_echo_prints_what_orchestra_topic_echo_prints(side):
    side.orch("--name", "poser", "pub", "poses", "geometry_msgs/PoseArray",
              TOPIC_CASES["geometry_msgs/PoseArray"][0]).ready()

    def without_seq(text: str) -> str:
        return "\n".join(line for line in text.splitlines() if "seq:" not in line)
    echoes = [["/poses"], ["--noarr", "/poses"]]
    results = side.run_all(*[(*tool, "-n", "1", *words) for words in echoes
                             for tool in (("rostopic", "echo"), ("orchestra", "topic", "echo"))])
    for real, ours in zip(results[::2], results[1::2], strict=False):
        assert real.returncode == 0 and ours.returncode == 0, real.stderr + ours.stderr
        assert without_seq(ours.stdout) == without_seq(real.stdout)


def test_real_rosparam_sets_gets_dumps_and_loads_on_orchestra_master(side, master, tmp_path):
    master.params.set("/robot/limits", {"speed": 1.5, "names": ["a", "b"]})
    assert side.tool("rosparam", "set", "/robot/mode", "fast").returncode == 0
    assert master.params.get("/robot/mode") == "fast"
    got = side.tool("rosparam", "get", "/robot/limits/speed")
    assert (got.returncode, got.stdout) == (0, "1.5\n")
    dump = tmp_path / "robot.yaml"
    assert side.tool("rosparam", "dump", str(dump), "/robot").returncode == 0
    assert yaml.safe_load(dump.read_text()) == {"limits": {"speed": 1.5, "names": ["a", "b"]},
                                                "mode": "fast"}
    assert side.tool("rosparam", "load", str(dump), "/copy").returncode == 0
    assert master.params.get("/copy") == master.params.get("/robot")
    listed = side.tool("rosparam", "list", "/copy")
    assert listed.stdout.split() == ["/copy/limits/names", "/copy/limits/speed", "/copy/mode"]
    assert side.tool("rosparam", "delete", "/copy/mode").returncode == 0
    assert not master.params.has("/copy/mode")


PARAM_VALUES = {"/f": 1.5, "/big": 2**31 - 1, "/neg": -3, "/s": "a: b", "/t": True, "/e": {},
                "/l": [1, 2.0, True, "x"], "/ld": [{"a": 1}, {"b": [1, 2]}],
                "/d": {"z": 1, "a": {"c": "multi\nline", "b": 0.1}}, "/num_str": "123",
                "/empty_s": "", "/fl": 1e-7, "/inf": float("inf"), "/yes": "yes", "/null": "~",
                "/unicode": "h\u00e9llo"}


def test_orchestra_param_get_and_dump_print_what_real_rosparam_prints(side, master, tmp_path):
    for name, value in PARAM_VALUES.items():
        master.params.set(name, value)
    words = [("get", "/"), ("get", "/s"), ("get", "/num_str"), ("list",)]
    commands = [(tool, *verb, *w) for w in words
                for tool, verb in (("rosparam", ()), ("orchestra", ("param",)))]
    commands += [("rosparam", "dump", str(tmp_path / "real.yaml"), "/d"),
                 ("orchestra", "param", "dump", str(tmp_path / "ours.yaml"), "/d")]
    results = side.run_all(*commands)
    for real, ours in zip(results[::2], results[1::2], strict=False):
        assert real.returncode == ours.returncode == 0, real.stderr + ours.stderr
        # one deliberate difference: orchestra writes non-ASCII text as UTF-8, rosparam as
        # YAML escapes ("h\xE9llo"); both load back to the same value
        assert ours.stdout == real.stdout.replace('"h\\xE9llo"', "h\u00e9llo"), ours.args
    assert (tmp_path / "ours.yaml").read_text() == (tmp_path / "real.yaml").read_text()
    assert yaml.safe_load(results[0].stdout) == yaml.safe_load(results[1].stdout)
    # loading: rosparam's YAML tags (!degrees, !radians, !!binary) give the same values
    source = tmp_path / "load.yaml"
    source.write_text("angle: !degrees 180\nrad: !radians pi/2\nbin: !!binary aGVsbG8=\n"
                      "nested: {a: 1, b: [x, {c: 2}]}\nflt: 1e3\nstr_num: '007'\n"
                      "empty: []\n")
    for loaded in side.run_all(("rosparam", "load", str(source), "/by_real"),
                               ("orchestra", "param", "load", str(source), "/by_ours")):
        assert loaded.returncode == 0, loaded.stderr
    assert master.params.get("/by_ours") == master.params.get("/by_real")
    assert master.params.get("/by_ours/angle") == pytest.approx(3.141592653589793)


def test_real_rosservice_lists_and_calls_orchestra_services(side):
    side.orch("--name", "server", "serve", "set_bool", "std_srvs/SetBool").ready()
    listed, typ, call, info, failed = side.run_all(
        ("rosservice", "list"), ("rosservice", "type", "/set_bool"),
        ("rosservice", "call", "/set_bool", "data: true"), ("rosservice", "info", "/set_bool"),
        ("rosservice", "call", "/set_bool", "data: false"))
    assert listed.returncode == 0, listed.stderr
    assert "/set_bool" in listed.stdout.split()
    # every node offers the logger services, as rospy's do (tests/test_node_loggers.py)
    assert {"/server/get_loggers", "/server/set_logger_level"} <= set(listed.stdout.split())
    assert typ.stdout == "std_srvs/SetBool\n"
    assert call.returncode == 0, call.stderr
    assert re.fullmatch(r'success: True\nmessage: "orchestra call [12]"\n', call.stdout)
    assert "Node: /server\n" in info.stdout and "Type: std_srvs/SetBool\n" in info.stdout
    assert "Args: data\n" in info.stdout
    assert failed.returncode != 0
    assert "refused by orchestra" in failed.stderr + failed.stdout


def test_real_rosnode_lists_inspects_and_kills_orchestra_nodes(side):
    talker = side.orch("--name", "talker", "pub", "chatter", "std_msgs/String", "data: x")
    listener = side.orch("--name", "listener", "sub", "chatter", "std_msgs/String")
    listener.expect(lambda d: "msg" in d)
    talker.ready()
    listed, info = side.run_all(("rosnode", "list"), ("rosnode", "info", "/talker"))
    assert {"/talker", "/listener"} <= set(listed.stdout.split()), listed
    assert info.returncode == 0, info.stderr
    assert "Publications: \n * /chatter [std_msgs/String]" in info.stdout
    assert f"Pid: {talker.proc.pid}" in info.stdout
    assert "topic: /chatter\n    * to: /listener\n    * direction: outbound (" in info.stdout
    kill = side.tool("rosnode", "kill", "/talker")
    assert kill.returncode == 0, kill.stderr
    assert talker.wait(10) == 0
    assert "/talker" not in side.tool("rosnode", "list").stdout.split()
    # a node that died without unregistering: rosnode cleanup purges it from our master
    listener.signal(signal.SIGKILL)
    listener.wait(5)
    cleanup = subprocess.run([ROS_PYTHON, "/usr/bin/rosnode", "cleanup"], input="y\n",
                             env=side.ros_env, capture_output=True, text=True, timeout=20)
    assert cleanup.returncode == 0 and "Unregistering /listener" in cleanup.stdout, cleanup
    assert side.master().getSystemState("/probe")[2] == [[], [], []]


def test_orchestra_node_info_prints_what_real_rosnode_info_prints(real_side):
    side = real_side
    side.rospy("--name", "talker", "pub", "chatter", "std_msgs/String", "data: x").ready()
    side.orch("--name", "ours", "sub", "chatter", "std_msgs/String").expect(
        lambda d: "msg" in d)
    side.rospy("--name", "theirs", "sub", "chatter", "std_msgs/String").expect(
        lambda d: "msg" in d)
    names = ("/talker", "/ours", "/theirs")
    results = side.run_all(*[cmd for name in names for cmd in
                             (("rosnode", "info", name), ("orchestra", "node", "info", name))])
    for name, real, ours in zip(names, results[::2], results[1::2], strict=False):
        assert real.returncode == ours.returncode == 0, real.stderr + ours.stderr
        assert ours.stdout == real.stdout, name
    # inbound connections name the publisher as rosnode does: "/node (uri)"
    assert "    * to: /talker (http://" in results[3].stdout


REAL_TOOL = {"topic": "rostopic", "service": "rosservice", "node": "rosnode", "param": "rosparam"}
# read-only questions whose answers must be byte-for-byte the real tools' answers
# (topic type, service type/args/uri are lines of topic info and service info)
PARITY = [("topic", "list"), ("topic", "list", "/ns"), ("topic", "info", "/chatter"),
          ("topic", "info", "/ns/pose"), ("topic", "find", "geometry_msgs/Twist"),
          ("service", "list"), ("service", "info", "/set_bool"), ("service", "info", "/empty"),
          ("node", "list"), ("param", "list"), ("param", "get", "/robot")]
# these are run after the ones above: `rosservice call` registers a node of its own
PARITY_CALLS = [("service", "call", "/empty", "{}"),
                # roscpp/GetLoggers from rospy: a response with an array of nested messages
                ("service", "call", "/server/get_loggers")]


def test_orchestra_tools_against_a_real_rosmaster_answer_as_the_real_tools_do(
        real_side, tmp_path):
    side = real_side
    talker = side.rospy("--name", "talker", "pub", "chatter", "geometry_msgs/Twist",
                        "{linear: {x: 1.5}}")
    server = side.rospy("--name", "server", "serve", "set_bool", "std_srvs/SetBool")
    listener = side.rospy("--name", "listener", "sub", "cmd", "std_msgs/String")
    ours = [side.orch("--name", "oserver", "serve", "empty", "std_srvs/Empty"),
            side.orch("--name", "opub", "pub", "/ns/pose", "geometry_msgs/Pose2D", "{x: 1}"),
            side.orch("--name", "osub", "sub", "chatter", "geometry_msgs/Twist")]
    for proc in (talker, server, listener, *ours):
        proc.ready()
    dump = tmp_path / "dump.yaml"
    setting = side.orchestra("param", "set", "/robot/gains", "{p: 2, d: [1, 2]}")
    assert setting.returncode == 0, setting.stderr
    parity = [cmd for words in PARITY
              for cmd in ((REAL_TOOL[words[0]], *words[1:]), ("orchestra", *words))]
    results = side.run_all(*parity)
    for words, real, ours in zip(PARITY, results[::2], results[1::2], strict=False):
        assert (ours.returncode, ours.stdout) == (real.returncode, real.stdout), \
            (words, real.stderr, ours.stderr)
    # then what adds nodes to the graph (echo, pub and rosservice call are nodes; node list
    # must not see them)
    calls = [cmd for words in PARITY_CALLS
             for cmd in ((REAL_TOOL[words[0]], *words[1:]), ("orchestra", *words))]
    *results, echo, pub, dumped, call, refused = side.run_all(
        *calls,
        ("orchestra", "topic", "echo", "/chatter/linear/x", "-n", "1"),
        ("orchestra", "topic", "pub", "-1", "/cmd", "std_msgs/String", "data: from us"),
        ("orchestra", "param", "dump", str(dump), "/robot"),
        ("orchestra", "service", "call", "/set_bool", "data: true"),
        ("orchestra", "service", "call", "/set_bool", "data: false"))
    for words, real, ours in zip(PARITY_CALLS, results[::2], results[1::2], strict=False):
        assert (ours.returncode, ours.stdout) == (real.returncode, real.stdout), \
            (words, real.stderr, ours.stderr)
    assert (echo.returncode, echo.stdout) == (0, "1.5\n---\n"), echo.stderr
    assert pub.returncode == 0, pub.stderr
    assert listener.expect(lambda d: "msg" in d)["msg"] == {"data": "from us"}
    assert dumped.returncode == 0, dumped.stderr
    assert yaml.safe_load(dump.read_text()) == {"gains": {"p": 2, "d": [1, 2]}}
    assert call.returncode == 0, call.stderr
    assert re.fullmatch(r'success: True\nmessage: "rospy call [12]"\n', call.stdout)
    assert refused.returncode == 1 and "refused by rospy" in refused.stderr

    kill = side.orchestra("node", "kill", "/talker")
    assert kill.returncode == 0, kill.stderr
    talker.wait(10)
    assert "/talker" not in side.orchestra("node", "list").stdout.split()


# --- 5. orchestra launch running a real rospy node ------------------------------------------

ROS1_PACKAGES = str(HERE / "ros1_nodes")
REPORT_LAUNCH = HERE / "ros1_nodes" / "interop_pkg" / "launch" / "report.launch"


def _wait_for_file(path: Path, proc: subprocess.Popen, log: Path, timeout: float = 20) -> dict:
    def ready():
        if proc.poll() is not None:
            raise AssertionError(f"{proc.args[:3]} exited {proc.returncode}: "
                                 f"{log.read_text()[-2000:]}")
        return path.exists()
    try:
        wait_for(ready, timeout=timeout)
    except AssertionError as exc:
        raise AssertionError(f"{exc}\n{log.read_text()[-2000:]}") from None
    return json.loads(path.read_text())


def _stop(proc: subprocess.Popen, timeout: float = 10) -> int:
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        return proc.wait(timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.wait()


def test_rospy_node_sees_the_same_names_remaps_and_params_under_orchestra_and_roslaunch(
        real_master, tmp_path):
    ros_out, orch_out = tmp_path / "roslaunch.json", tmp_path / "orchestra.json"
    ros_log, orch_log = tmp_path / "roslaunch.log", tmp_path / "orchestra.log"
    home = {"ROS_HOME": str(tmp_path / "ros_home"), "ROS_PACKAGE_PATH": ROS1_PACKAGES}
    orch_port = free_port()
    with open(ros_log, "w") as rlog, open(orch_log, "w") as olog:
        roslaunch = subprocess.Popen(
            [ROS_PYTHON, "/usr/bin/roslaunch", str(REPORT_LAUNCH), f"out:={ros_out}"],
            env=_ros_env(dict(home, ROS_MASTER_URI=real_master)),
            stdout=rlog, stderr=subprocess.STDOUT)
        ours = subprocess.Popen(
            [sys.executable, "-m", "orchestra", "launch", "-p", str(orch_port), "--no-status",
             str(REPORT_LAUNCH), f"out:={orch_out}"],
            env=dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{orch_port}/", **home),
            stdout=olog, stderr=subprocess.STDOUT)
    try:
        expected = _wait_for_file(ros_out, roslaunch, ros_log)
        got = _wait_for_file(orch_out, ours, orch_log)
    finally:
        ros_code, orch_code = _stop(roslaunch), _stop(ours)
    assert expected == {
        "name": "/robot/reporter", "namespace": "/robot/", "ROS_NAMESPACE": "/robot",
        "chatter": "/robot/speech", "published": ["/robot/speech", "/rosout"],
        "private": {"rate": 5.5, "label": "007", "config": {"a": 1, "b": ["x", "y"]}},
        "global": "g", "argv": ["extra", "word"]}
    assert got == expected
    assert (ros_code, orch_code) == (0, 0), orch_log.read_text()[-2000:]


def test_orchestra_launch_waits_for_an_external_rosmaster_and_uploads_params(tmp_path):
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    out, log = tmp_path / "report.json", tmp_path / "orchestra.log"
    env = dict(os.environ, ROS_MASTER_URI=uri, ROS_HOME=str(tmp_path / "ros_home"),
               ROS_PACKAGE_PATH=ROS1_PACKAGES)
    with open(log, "w") as olog:
        ours = subprocess.Popen([sys.executable, "-m", "orchestra", "launch", "--wait",
                                 "--no-status", str(REPORT_LAUNCH), f"out:={out}"],
                                env=env, stdout=olog, stderr=subprocess.STDOUT)
    rosmaster = None
    try:
        wait_for(lambda: "waiting for the master" in log.read_text(), timeout=15)
        assert ours.poll() is None
        rosmaster = subprocess.Popen(
            [ROS_PYTHON, "/usr/bin/rosmaster", "--core", "-p", str(port)],
            env=_ros_env({"ROS_MASTER_URI": uri, "ROS_HOME": str(tmp_path / "ros_home")}),
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        report = _wait_for_file(out, ours, log)
        assert report["private"] == {"rate": 5.5, "label": "007",
                                     "config": {"a": 1, "b": ["x", "y"]}}
        real = OneShotProxy(uri)
        assert real.getParam("/probe", "/robot/reporter/rate")[2] == 5.5
        assert real.getParam("/probe", "/interop/global")[2] == "g"
        assert real.getParam("/probe", "/run_id")[0] == 1
        code, _, state = real.getSystemState("/probe")
        assert ["/robot/speech", ["/robot/reporter"]] in state[0]
        # the run leaves the external master running and its node unregistered
        assert _stop(ours) == 0, log.read_text()[-2000:]
        assert real.getPid("/probe")[0] == 1
        state = real.getSystemState("/probe")[2]
        assert not [t for t, nodes in state[0] if "/robot/reporter" in nodes]
    finally:
        _stop(ours)
        if rosmaster is not None:
            rosmaster.terminate()
            try:
                rosmaster.wait(5)
            except subprocess.TimeoutExpired:
                rosmaster.kill()
                rosmaster.wait()


def test_real_roslaunch_runs_a_launch_file_against_orchestra_core(tmp_path):
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    out, log, core_log = tmp_path / "report.json", tmp_path / "roslaunch.log", \
        tmp_path / "core.log"
    home = {"ROS_HOME": str(tmp_path / "ros_home"), "ROS_PACKAGE_PATH": ROS1_PACKAGES,
            "ROS_MASTER_URI": uri}
    with open(core_log, "w") as clog:
        core = subprocess.Popen([sys.executable, "-m", "orchestra", "core", "-p", str(port)],
                                env=dict(os.environ, **home), stdout=clog,
                                stderr=subprocess.STDOUT)
    roslaunch = None
    try:
        wait_for(lambda: "master ready" in core_log.read_text(), timeout=15)
        with open(log, "w") as rlog:
            roslaunch = subprocess.Popen(
                [ROS_PYTHON, "/usr/bin/roslaunch", str(REPORT_LAUNCH), f"out:={out}"],
                env=_ros_env(home), stdout=rlog, stderr=subprocess.STDOUT)
        report = _wait_for_file(out, roslaunch, log)
        assert report["private"] == {"rate": 5.5, "label": "007",
                                     "config": {"a": 1, "b": ["x", "y"]}}
        assert report["published"] == ["/robot/speech", "/rosout"]
        master = OneShotProxy(uri)
        # roslaunch found orchestra core's /run_id and registered its own server node
        run_id = master.getParam("/probe", "/run_id")[2]
        assert run_id in log.read_text()
        # orchestra's /rosout collects the rospy node's log messages
        rosout_log = tmp_path / "ros_home" / "log" / run_id / "rosout.log"
        wait_for(lambda: rosout_log.exists() and " INFO /robot/reporter [" in
                 rosout_log.read_text(), timeout=10)
        assert f"report written to {out}" in rosout_log.read_text()
        assert _stop(roslaunch) == 0, log.read_text()[-2000:]
        pubs = master.getSystemState("/probe")[2][0]
        assert not [t for t, nodes in pubs if "/robot/reporter" in nodes]
    finally:
        if roslaunch is not None:
            _stop(roslaunch)
        _stop(core)


# --- 6. real roslaunch resolving orchestra's bundled demos ----------------------------------

DEMOS = sorted(f"{p.parent.parent.name} {p.name}"
               for p in (REPO / "packages").glob("*/launch/*.launch"))
# the URI every node gets; set in both environments so roslaunch's --args prints no
# ROS_MASTER_URI=... prefix (it prefixes variables that differ from the caller's)
DUMP_ENV = {"ROS_PACKAGE_PATH": str(REPO / "packages"),
            "ROS_MASTER_URI": "http://localhost:11311/"}


def _start_resolving(interpreter: str, script: str, env: dict[str, str]) -> subprocess.Popen:
    return subprocess.Popen([interpreter, str(HERE / "ros1_nodes" / script), *DEMOS], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.fixture(scope="module", autouse=True)
def _resolving(tmp_path_factory):
    """Real roslaunch and orchestra resolving every demo, started with the module's first test.

    Real roslaunch takes seconds (it re-runs xacro and every substitution per option), so
    both run in the background while the other tests do; ``dumps`` collects the answers.
    """
    home = str(tmp_path_factory.mktemp("ros_home"))
    procs = {"roslaunch": _start_resolving(ROS_PYTHON, "roslaunch_resolve.py",
                                           _ros_env(dict(DUMP_ENV, ROS_HOME=home))),
             "orchestra": _start_resolving(sys.executable, "orchestra_resolve.py",
                                           dict(os.environ, ROS_HOME=home, **DUMP_ENV))}
    yield procs
    for proc in procs.values():
        if proc.poll() is None:
            proc.kill()
        proc.communicate()


@pytest.fixture(scope="module")
def dumps(_resolving) -> dict:
    """{"roslaunch"|"orchestra": {demo: {"nodes", "params", "files", "args": {node: text}}}}."""
    answers = {}
    for name, proc in _resolving.items():
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err
        answers[name] = json.loads(out)
    return answers


@pytest.mark.timeout(90)
@pytest.mark.parametrize("demo", DEMOS)
def test_real_roslaunch_resolves_bundled_demo_to_the_same_nodes_params_and_argv(dumps, demo):
    real, ours = dumps["roslaunch"][demo], dumps["orchestra"][demo]
    assert isinstance(real["nodes"], str), real["nodes"]
    assert ours["nodes"] == real["nodes"]
    assert yaml.safe_load(ours["params"]) == yaml.safe_load(real["params"])
    # roslaunch prints the files read from a set (any order); orchestra in reading order
    assert sorted(ours["files"].split()) == sorted(real["files"].split())
    # roslaunch writes env prefixes as K="v", orchestra shell-quotes only when needed
    # (K=v): compared as the words a shell makes of them, which is what `| bash` runs
    assert set(ours["args"]) == set(real["args"])
    for node, argv in real["args"].items():
        assert shlex.split(ours["args"][node]) == shlex.split(argv), node
