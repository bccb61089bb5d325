"""Wire compatibility with REAL roscpp: Debian's C++ topic_tools, rosout and tf2_ros nodes.

``tests/test_interop_ros1.py`` covers rospy; this module puts Debian's compiled roscpp
programs against orchestra: ``topic_tools/relay`` and ``mux`` between orchestra publishers and
subscribers (TCPROS both ways: headers, md5, message_definition, latching, a subscriber that
asks for UDPROS first), mux's services called by orchestra's ``ServiceProxy``, the C++
``rosout`` aggregating an orchestra node's log (and writing the same ``rosout.log`` lines as
orchestra's Python rosout), tf2_ros' ``static_transform_publisher`` heard by ``orchestra.tf``,
and ``orchestra launch`` starting ``pkg="topic_tools" type="relay"`` from Debian's layout
(``/usr/share/topic_tools/package.xml``, ``/usr/lib/topic_tools/relay``) the way roslaunch
there does. The orchestra side is ``ros1_nodes/peer.py --orchestra``.

Everything runs on loopback against an orchestra master on a free port; every process is
killed by a finalizer. Skipped when the Debian packages are absent (``.ci/run`` installs them).
"""
from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import ROS_PYTHON, NodeProcess, OneShotProxy, ProcessGroup, free_port, wait_for  # noqa: E402

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
PEER = HERE / "ros1_nodes" / "peer.py"
PY_ROSOUT = REPO / "packages" / "rosout" / "scripts" / "rosout"

RELAY = "/usr/lib/topic_tools/relay"            # Debian: topic-tools
MUX = "/usr/lib/topic_tools/mux"
ROSOUT = "/usr/lib/rosout/rosout"               # Debian: rosout
STATIC_TF = "/usr/lib/tf2_ros/static_transform_publisher"  # Debian: tf2-tools
TOPIC_TOOLS = Path("/usr/share/topic_tools")    # package.xml: libtopic-tools-dev
MUX_SRV = TOPIC_TOOLS / "srv" / "MuxSelect.srv"  # ros-topic-tools-srvs


def _absent(*paths: str | Path) -> str | None:
    missing = [str(p) for p in paths if not os.path.exists(p)]
    if missing:
        return f"Debian's roscpp programs/files are not installed: {', '.join(missing)}"
    return None


_NO_TOPIC_TOOLS = _absent(RELAY, MUX)
pytestmark = [pytest.mark.skipif(_NO_TOPIC_TOOLS is not None, reason=_NO_TOPIC_TOOLS or ""),
              pytest.mark.timeout(30)]


def _real_tools(*modules: str) -> bool:
    """Whether Debian's Python ROS tools (rosnode, rosservice, ...) can be compared with."""
    return os.access(ROS_PYTHON, os.X_OK) and subprocess.run(
        [ROS_PYTHON, "-c", "import " + ", ".join(modules)], capture_output=True).returncode == 0


def _skip_unless(*paths: str | Path) -> None:
    reason = _absent(*paths)
    if reason:
        pytest.skip(reason)


@pytest.fixture(scope="module")
def ros_home(tmp_path_factory) -> Path:
    """One ROS_HOME for the module: orchestra's package cache of /usr/share is crawled once."""
    return tmp_path_factory.mktemp("ros_home")


def cpp_env(master_uri: str, ros_home: Path) -> dict[str, str]:
    """For a roscpp program: loopback addresses, line-buffered ROS_INFO on stdout."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env.update(ROS_MASTER_URI=master_uri, ROS_HOME=str(ros_home), ROS_IP="127.0.0.1",
               ROSCONSOLE_STDOUT_LINE_BUFFERED="1")
    return env


def orch_env(master_uri: str, ros_home: Path) -> dict[str, str]:
    """For orchestra: Debian's /usr/share on the package path (topic_tools' srv files)."""
    env = dict(os.environ, ROS_MASTER_URI=master_uri, ROS_HOME=str(ros_home),
               ROS_PACKAGE_PATH="/usr/share", PYTHONUNBUFFERED="1")
    env.pop("ROS_NAMESPACE", None)
    env.pop("CMAKE_PREFIX_PATH", None)
    return env


class Graph(ProcessGroup):
    """roscpp programs and orchestra nodes against one master; ``close()`` kills what is left."""

    def __init__(self, master_uri: str, ros_home: Path):
        super().__init__(master_uri)
        self.cpp_env = cpp_env(master_uri, ros_home)
        self.orch_env = orch_env(master_uri, ros_home)
        # Debian's Python tools (rosnode, rosservice ...) beside the C++ programs
        self.ros_env = {k: v for k, v in self.cpp_env.items()
                        if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}

    def cpp(self, exe: str, *args: str) -> NodeProcess:
        return self._start([exe, *args], self.cpp_env)

    def orch(self, *args: str) -> NodeProcess:
        """``peer.py`` as an orchestra.node node."""
        return self._start([sys.executable, str(PEER), "--orchestra", *args], self.orch_env)

    def orchestra(self, *args: str, timeout: float = 20) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "orchestra", *args], env=self.orch_env,
                              capture_output=True, text=True, timeout=timeout)

    def registered(self, node: str) -> bool:
        return self.master().lookupNode("/probe", node)[0] == 1

    def state(self) -> tuple[dict, dict, dict]:
        """getSystemState as {name: set(nodes)} for publishers, subscribers, services."""
        lists = self.master().getSystemState("/probe")[2]
        return tuple({name: set(nodes) for name, nodes in rows} for rows in lists)


@pytest.fixture
def graph(master, ros_home):
    group = Graph(master.uri, ros_home)
    yield group
    group.close()


def _text(proc: NodeProcess, fragment: str, timeout: float = 10.0) -> dict:
    """The roscpp program's next stdout line containing ``fragment`` (ROS_INFO output)."""
    return proc.expect(lambda d: fragment in d.get("text", ""), timeout)


def _orchestra_class(type_name: str):
    from orchestra.node.msg import get_message_class
    return get_message_class(type_name)


# --- 1. TCPROS both ways through topic_tools/relay ------------------------------------------

RELAYED = {
    "std_msgs/String": ("data: 'hello $N'", None),
    "geometry_msgs/Twist": ("{linear: {x: 0.5, y: -1.25}, angular: {z: 2.0}}",
                            {"linear": {"x": 0.5, "y": -1.25, "z": 0.0},
                             "angular": {"x": 0.0, "y": 0.0, "z": 2.0}}),
}


def test_orchestra_messages_cross_a_roscpp_relay_intact(graph):
    """orchestra publisher -> C++ relay (subscriber, then publisher) -> orchestra subscriber.

    relay is generic (ShapeShifter): it republishes the bytes, type, md5 and
    message_definition it got from orchestra's publisher, so what arrives must be exactly what
    orchestra's own classes say; the second relay asks for UDPROS first (``_unreliable``) and
    must fall back to TCPROS, which is all orchestra's publisher offers."""
    subs, relays = {}, {}
    for i, (type_name, (text, _)) in enumerate(RELAYED.items()):
        extra = ["_unreliable:=true"] if i == 1 else []
        relays[type_name] = graph.cpp(RELAY, f"in{i}", f"out{i}", f"__name:=relay{i}", *extra)
        subs[type_name] = graph.orch("--name", f"sub{i}", "sub", f"out{i}", type_name)
        graph.orch("--name", f"pub{i}", "pub", f"in{i}", type_name, text)
    for i, (type_name, (_, expected)) in enumerate(RELAYED.items()):
        cls = _orchestra_class(type_name)
        got = [subs[type_name].expect(lambda d: "msg" in d) for _ in range(3)]
        for item in got:
            assert item["callerid"] == f"/relay{i}"
            assert (item["type"], item["md5sum"]) == (type_name, cls._md5sum)
            assert item["definition"] == cls._full_text
            assert item["latching"] == "0"
        if expected is None:  # String: consecutive messages, in order, none mangled
            numbers = [int(re.fullmatch(r"hello (\d+)", g["msg"]["data"]).group(1)) for g in got]
            assert numbers == sorted(numbers) and len(set(numbers)) == 3, numbers
        else:
            assert all(g["msg"] == expected for g in got)
        _text(relays[type_name], f"advertised as out{i}")
    pubs, subscribed, _ = graph.state()
    assert pubs["/out0"] == {"/relay0"} and subscribed["/in0"] == {"/relay0"}
    assert pubs["/in1"] == {"/pub1"} and subscribed["/out1"] == {"/sub1"}
    # the roscpp node's slave API, found through orchestra's master
    uri = graph.master().lookupNode("/probe", "/relay0")[2]
    assert OneShotProxy(uri).getPid("/probe")[2] == relays["std_msgs/String"].proc.pid


def test_latched_orchestra_topic_stays_latched_through_a_roscpp_relay(graph):
    """relay latches its output when the input connection says ``latching: 1``: orchestra's
    latched publisher must say so, and a late orchestra subscriber then gets roscpp's latched
    copy."""
    graph.orch("--name", "once", "pub", "in", "std_msgs/String", "data: only once",
               "--latch", "--count", "1").ready()
    relay = graph.cpp(RELAY, "in", "out", "__name:=relay")
    _text(relay, "advertised as out")
    late = graph.orch("--name", "late", "sub", "out", "std_msgs/String")
    got = late.expect(lambda d: "msg" in d)
    assert got["msg"] == {"data": "only once"}
    assert (got["callerid"], got["latching"]) == ("/relay", "1")


def test_orchestra_node_info_and_topic_info_describe_a_roscpp_node(graph):
    """roscpp's slave API (getBusInfo, getPid) read by orchestra's tools: the same text as
    rosnode/rostopic print for it, byte for byte, when those are installed."""
    relay = graph.cpp(RELAY, "in", "out", "__name:=relay")
    graph.orch("--name", "talker", "pub", "in", "std_msgs/String", "data: x")
    listener = graph.orch("--name", "listener", "sub", "out", "std_msgs/String")
    listener.expect(lambda d: "msg" in d)
    commands = [("orchestra", "node", "info", "/relay"), ("orchestra", "topic", "info", "/out")]
    real = _real_tools("rosnode", "rostopic")
    if real:
        commands += [("rosnode", "info", "/relay"), ("rostopic", "info", "/out")]
    info, topic, *reference = graph.run_all(*commands)
    assert info.returncode == 0, info.stderr
    text = info.stdout
    assert f"Pid: {relay.proc.pid}" in text
    assert re.search(r"Publications: \n(.*\n)* \* /out \[std_msgs/String\]", text), text
    assert re.search(r"Subscriptions: \n(.*\n)* \* /in \[std_msgs/String\]", text), text
    # roscpp's getBusInfo rows: one inbound from /talker, one outbound to /listener
    assert re.search(r" \* topic: /in\n    \* to: /talker \(http://127\.0\.0\.1:\d+/\)\n"
                     r"    \* direction: inbound \(\d+ - 127\.0\.0\.1:\d+\) \[\d+\]\n"
                     r"    \* transport: TCPROS\n", text), text
    assert re.search(r" \* topic: /out\n    \* to: /listener\n    \* direction: outbound "
                     r"\(\d+ - 127\.0\.0\.1:\d+\) \[\d+\]\n", text), text
    assert topic.returncode == 0, topic.stderr
    assert "Type: std_msgs/String" in topic.stdout and " * /relay (http://127.0.0.1:" \
        in topic.stdout
    if real:
        assert [r.returncode for r in reference] == [0, 0], [r.stderr for r in reference]
        assert (info.stdout, topic.stdout) == (reference[0].stdout, reference[1].stdout)


# --- 2. a roscpp service server called by orchestra's ServiceProxy --------------------------

def test_roscpp_mux_services_called_by_orchestra_service_proxy(graph):
    _skip_unless(TOPIC_TOOLS / "package.xml", MUX_SRV)
    mux = graph.cpp(MUX, "out", "a", "b", "__name:=mux")
    graph.orch("--name", "pa", "pub", "a", "std_msgs/String", "data: from a")
    graph.orch("--name", "pb", "pub", "b", "std_msgs/String", "data: from b")
    out = graph.orch("--name", "out", "sub", "out", "std_msgs/String")
    # roscpp's latched /mux/selected reaches a late orchestra subscriber
    selected = graph.orch("--name", "selected", "sub", "/mux/selected", "std_msgs/String")
    first = selected.expect(lambda d: "msg" in d)
    assert (first["msg"], first["latching"], first["callerid"]) == ({"data": "/a"}, "1", "/mux")
    assert out.expect(lambda d: "msg" in d)["msg"] == {"data": "from a"}
    _text(mux, "advertising")

    select = graph.orch("--name", "caller", "call", "/mux/select", "topic_tools/MuxSelect",
                        "{topic: b}", "{topic: /nowhere}")
    selecting = select.expect(lambda d: "results" in d, 15)["results"]
    assert selecting[0] == {"ok": {"prev_topic": "/a"}}
    # a handler returning false: roscpp answers ok=0 with an empty error string
    assert "error" in selecting[1] and "/mux/select" in selecting[1]["error"], selecting
    assert out.expect(lambda d: d.get("msg") == {"data": "from b"}, 10)
    assert selected.expect(lambda d: "msg" in d)["msg"] == {"data": "b"}

    # persistent connection to a roscpp server: three calls on one socket, one refused
    listing = graph.orch("--name", "lister", "call", "/mux/list", "topic_tools/MuxList",
                         "{}", "{}", "--persistent")
    assert listing.expect(lambda d: "results" in d, 15)["results"] == [
        {"ok": {"topics": ["/a", "/b"]}}] * 2
    adding = graph.orch("--name", "adder", "call", "/mux/add", "topic_tools/MuxAdd",
                        "{topic: c}", "{topic: c}", "--persistent")
    added = adding.expect(lambda d: "results" in d, 15)["results"]
    assert added[0] == {"ok": {}} and "error" in added[1], added
    # a string[] response printed as rosservice (genpy) prints it
    commands = [("orchestra", "service", "call", "/mux/list"),
                ("orchestra", "service", "type", "/mux/select")]
    real = _real_tools("rosservice", "topic_tools.srv")
    if real:
        commands.append(("rosservice", "call", "/mux/list"))
    call, kind, *reference = graph.run_all(*commands)
    assert (call.returncode, call.stdout) == (0, "topics: \n  - /a\n  - /b\n  - /c\n"), call.stderr
    assert kind.stdout == "topic_tools/MuxSelect\n"
    if real:
        assert (reference[0].returncode, reference[0].stdout) == (0, call.stdout)


# --- 3. the C++ rosout against orchestra's master -------------------------------------------

def test_cpp_rosout_aggregates_an_orchestra_nodes_log_like_orchestras_rosout(graph, tmp_path):
    """The real /rosout subscribes to the orchestra node's /rosout (orchestra publishes,
    roscpp subscribes) and republishes on /rosout_agg (roscpp publishes rosgraph_msgs/Log with
    a Header and a string[], orchestra subscribes). orchestra's Python rosout runs beside it
    under another name and writes its rosout.log from the same messages: the lines must be
    the same, byte for byte."""
    _skip_unless(ROSOUT)
    cpp_dir, py_dir = tmp_path / "cpp", tmp_path / "py"
    cpp_dir.mkdir()  # roslaunch makes the run's log directory; the C++ rosout does not
    rosout = graph.cpp(ROSOUT, f"__log:={cpp_dir}/rosout-1-stdout.log")
    ours = graph._start([sys.executable, str(PY_ROSOUT), "__name:=rosout_py",
                         "rosout_agg:=/rosout_agg_py", f"__log:={py_dir}/rosout-2-stdout.log"],
                        graph.orch_env)
    agg = graph.orch("--name", "console", "sub", "/rosout_agg", "rosgraph_msgs/Log")
    agg.ready()
    wait_for(lambda: graph.state()[1].get("/rosout", set()) >= {"/rosout", "/rosout_py"}, 15)
    logger = graph.orch("--name", "logger", "log", "hello from orchestra")
    info = agg.expect(lambda d: d.get("msg", {}).get("name") == "/logger"
                      and d["msg"]["level"] == 2, 15)
    warn = agg.expect(lambda d: d.get("msg", {}).get("name") == "/logger"
                      and d["msg"]["level"] == 4, 10)
    assert info["callerid"] == "/rosout" and info["type"] == "rosgraph_msgs/Log"
    assert info["md5sum"] == _orchestra_class("rosgraph_msgs/Log")._md5sum
    assert re.fullmatch(r"hello from orchestra \d+", info["msg"]["msg"])
    assert re.fullmatch(r"hello from orchestra warn \d+", warn["msg"]["msg"])
    assert info["msg"]["topics"] == ["/rosout"] and info["msg"]["function"] == "run_log"
    assert info["msg"]["file"] == str(PEER) and info["msg"]["header"]["stamp"]["secs"] > 0
    # only the real rosout publishes /rosout_agg; ours is on its remapped topic
    pubs = graph.state()[0]
    assert pubs["/rosout_agg"] == {"/rosout"} and pubs["/rosout_agg_py"] == {"/rosout_py"}

    def lines(directory: Path) -> list[str]:
        path = directory / "rosout.log"
        return [ln for ln in path.read_text().splitlines() if " /logger " in ln] \
            if path.exists() else []
    # both have written several of the logger's lines (rosout flushes per message)
    wait_for(lambda: len(set(lines(cpp_dir)) & set(lines(py_dir))) >= 6, 10)
    logger.signal(signal.SIGINT)
    logger.wait(10)
    cpp_lines, py_lines = lines(cpp_dir), lines(py_dir)
    common = set(cpp_lines) & set(py_lines)
    # each rosout may miss the logger's first lines (it connects asynchronously) and may not
    # have written its last ones yet; between the first and the last line both have, the
    # files are identical: same stamps, levels, locations, topics and text
    spans = []
    for got in (cpp_lines, py_lines):
        shared = [i for i, line in enumerate(got) if line in common]
        spans.append(got[shared[0]:shared[-1] + 1])
    assert spans[0] == spans[1], (cpp_lines[:4], py_lines[:4])
    info_line = next(line for line in spans[0] if " INFO " in line)
    assert re.fullmatch(r"\d+\.\d{9} INFO /logger \[" + re.escape(str(PEER)) +
                        r":\d+\(run_log\)\] \[topics: /rosout\] hello from orchestra \d+",
                        info_line), info_line
    for directory in (cpp_dir, py_dir):
        assert re.search(r"\n\n\n\d+\.\d{9}  Node Startup\n",
                         "\n" + (directory / "rosout.log").read_text())
    assert rosout.proc.poll() is None and ours.proc.poll() is None


# --- 4. tf2_ros' C++ static_transform_publisher heard by orchestra.tf ------------------------

LISTEN_TF = """
import json
import orchestra.node as rospy
from orchestra.tf import tf2_ros
rospy.init_node("tf_listener")
buffer = tf2_ros.Buffer()
listener = tf2_ros.TransformListener(buffer)
try:
    t = buffer.lookup_transform("base", "laser", rospy.Time(0), rospy.Duration(15))
except tf2_ros.TransformException as exc:
    print(json.dumps({"error": str(exc)}), flush=True)
    raise SystemExit(1)
q, v = t.transform.rotation, t.transform.translation
print(json.dumps({"translation": [v.x, v.y, v.z], "rotation": [q.x, q.y, q.z, q.w],
                  "parent": t.header.frame_id, "child": t.child_frame_id}), flush=True)
"""


def test_cpp_static_transform_publisher_is_heard_by_orchestra_tf(graph):
    """tf2_ros' latched /tf_static (tf2_msgs/TFMessage: an array of stamped transforms)."""
    _skip_unless(STATIC_TF)
    graph.cpp(STATIC_TF, "0.5", "-1.25", "2", "0", "0", "0.70710678", "0.70710678", "base",
              "laser", "__name:=laser_tf")
    listener = graph._start([sys.executable, "-c", LISTEN_TF], graph.orch_env)
    got = listener.expect(lambda d: "translation" in d or "error" in d, 20)
    assert "error" not in got, got
    assert got["translation"] == [0.5, -1.25, 2.0]
    assert got["rotation"] == pytest.approx([0, 0, 0.70710678, 0.70710678])
    assert (got["parent"], got["child"]) == ("base", "laser")


# --- 5. orchestra launch running Debian's topic_tools the way roslaunch does -----------------

RELAY_LAUNCH = """<launch>
  <node pkg="topic_tools" type="relay" name="relay" ns="robot" args="chatter out">
    <remap from="chatter" to="/remapped/in"/>
    <param name="lazy" value="false"/>
  </node>
</launch>
"""


def test_orchestra_launch_runs_debian_topic_tools_relay_and_cpp_rosout(tmp_path, ros_home):
    """With Debian's package path (/usr/share, which Debian's rospkg always appends), a
    ``pkg="topic_tools" type="relay"`` node resolves to /usr/lib/topic_tools/relay — Debian
    installs ROS binaries in /usr/lib/<pkg> and its catkin counts /usr as a workspace — and
    the /rosout that ``orchestra launch`` starts is then Debian's C++ rosout, as roscore's
    would be. The relay sees its remap, namespace and private param."""
    _skip_unless(TOPIC_TOOLS / "package.xml", ROSOUT)
    launch = tmp_path / "relay.launch"
    launch.write_text(RELAY_LAUNCH)
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    env = orch_env(uri, ros_home)
    env["ROS_IP"] = "127.0.0.1"
    which = subprocess.run([sys.executable, "-m", "orchestra", "pkg", "which", "topic_tools",
                            "relay"], env=env, capture_output=True, text=True, timeout=20)
    assert (which.returncode, which.stdout) == (0, f"{RELAY}\n"), which.stderr
    log = tmp_path / "launch.log"
    with open(log, "w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "orchestra", "launch", "-p", str(port),
                                 "--no-status", "--screen", str(launch)], env=env,
                                stdout=out, stderr=subprocess.STDOUT)
    group = Graph(uri, ros_home)
    try:
        def up():
            if proc.poll() is not None:
                raise AssertionError(f"orchestra launch exited {proc.returncode}: "
                                     f"{log.read_text()[-2000:]}")
            try:
                return group.registered("/robot/relay") and group.registered("/rosout")
            except OSError:
                return False
        wait_for(up, timeout=20)
        master = group.master()
        assert master.getParam("/probe", "/robot/relay/lazy")[2] is False
        for node, exe in (("/robot/relay", RELAY), ("/rosout", ROSOUT)):
            pid = OneShotProxy(
                master.lookupNode("/probe", node)[2]).getPid("/probe")[2]
            assert os.readlink(f"/proc/{pid}/exe") == exe, node
        # the node is known once its first registration lands; its subscription may follow
        wait_for(lambda: group.state()[1].get("/remapped/in") == {"/robot/relay"}, timeout=10)
        group.orch("--name", "talker", "pub", "/remapped/in", "std_msgs/String", "data: via launch")
        sub = group.orch("--name", "listener", "sub", "/robot/out", "std_msgs/String")
        got = sub.expect(lambda d: "msg" in d, 15)
        assert (got["msg"], got["callerid"]) == ({"data": "via launch"}, "/robot/relay")
        # the C++ rosout logs the relay's ROS_INFO into the run's rosout.log
        run_id = master.getParam("/probe", "/run_id")[2]
        rosout_log = ros_home / "log" / run_id / "rosout.log"
        wait_for(lambda: rosout_log.exists() and " INFO /robot/relay [" in
                 rosout_log.read_text(), timeout=10)
        assert "advertised as out" in rosout_log.read_text()
    finally:
        group.close()
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            code = proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            code = proc.wait()
    assert code == 0, log.read_text()[-2000:]


def test_orchestra_launch_args_of_a_topic_tools_node_equal_real_roslaunch(tmp_path, ros_home):
    """``--args`` prints the command line: the same executable path and words as Debian's
    roslaunch (which finds /usr/share/topic_tools without any environment)."""
    _skip_unless(TOPIC_TOOLS / "package.xml", "/usr/bin/roslaunch")
    probe = subprocess.run([ROS_PYTHON, "-c", "import roslaunch"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("python3-roslaunch is not installed")
    launch = tmp_path / "relay.launch"
    launch.write_text(RELAY_LAUNCH)
    env = orch_env("http://localhost:11311/", ros_home)
    ros_env = {k: v for k, v in env.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV"))}
    ros_env.pop("ROS_PACKAGE_PATH")  # Debian's rospkg always appends /usr/share
    real = subprocess.run([ROS_PYTHON, "/usr/bin/roslaunch", "--args", "/robot/relay",
                           str(launch)], env=ros_env, capture_output=True, text=True,
                          timeout=25)
    ours = subprocess.run([sys.executable, "-m", "orchestra", "launch", "--args",
                           "/robot/relay", str(launch)], env=env, capture_output=True,
                          text=True, timeout=25)
    assert real.returncode == 0, real.stderr
    # roslaunch writes ROS_NAMESPACE="/robot", orchestra ROS_NAMESPACE=/robot: the same words
    # to a shell (docs/interop.md), so they are compared as shell words
    assert ours.returncode == 0, ours.stderr
    assert shlex.split(ours.stdout) == shlex.split(real.stdout)
    assert shlex.split(ours.stdout) == ["ROS_NAMESPACE=/robot", RELAY, "chatter", "out",
                                        "chatter:=/remapped/in", "__name:=relay"]
