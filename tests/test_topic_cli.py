"""``orchestra node|topic|service|graph`` against a live master and node processes."""
from __future__ import annotations

import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from lxml import etree

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import Nodes, wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(90)


def orchestra(nodes: Nodes, *args: str, timeout: float = 30) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "orchestra", *args], env=nodes.env,
                          capture_output=True, text=True, timeout=timeout)


def test_topic_echo_prints_yaml_documents_each_followed_by_dashes(nodes):
    nodes.start("pub.py", "chatter", "std_msgs/String", "data: hello").ready()
    result = orchestra(nodes, "topic", "echo", "chatter", "-n", "2")
    assert result.returncode == 0, result.stderr
    assert result.stdout == 'data: "hello"\n---\ndata: "hello"\n---\n'


def test_topic_echo_of_a_field_path_prints_just_that_field(nodes):
    nodes.start("pub.py", "turtle1/pose", "geometry_msgs/Pose2D", "{x: 5.5, y: 1, theta: 0}"
                ).ready()
    result = orchestra(nodes, "topic", "echo", "/turtle1/pose/x", "-n", "1")
    assert result.returncode == 0, result.stderr
    assert result.stdout == "5.5\n---\n"


def test_topic_echo_of_a_field_path_waits_for_the_topic_to_be_published(nodes):
    echo = subprocess.Popen([sys.executable, "-m", "orchestra", "topic", "echo",
                             "/late/linear/x", "-n", "1"], env=nodes.env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert "does not appear to be published yet" in echo.stderr.readline()
        nodes.start("pub.py", "late", "geometry_msgs/Twist", "{linear: {x: 0.5}}",
                    "--rate", "20").ready()
        out, _ = echo.communicate(timeout=30)
        assert out == "0.5\n---\n"
    finally:
        echo.kill()
        echo.wait()


def test_topic_echo_decodes_a_type_it_has_no_definition_for(nodes, package_path):
    nodes.start("pub.py", "nums", "test_msgs/Num", "{num: 4, label: four}").ready()
    env_without_pkg = dict(nodes.env, ROS_PACKAGE_PATH="")
    result = subprocess.run([sys.executable, "-m", "orchestra", "topic", "echo", "/nums",
                             "-n", "1"], env=env_without_pkg, capture_output=True, text=True,
                            timeout=30)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith('num: 4\nlabel: "four"\nstamp: \n  secs: 0\n')


def test_topic_pub_once_reaches_a_running_subscriber(nodes):
    sub = nodes.start("sub.py", "cmd_vel", "geometry_msgs/Twist")
    sub.ready()
    result = orchestra(nodes, "topic", "pub", "-1", "/cmd_vel", "geometry_msgs/Twist",
                       "{linear: {x: 0.5}, angular: {z: 1.0}}")
    assert result.returncode == 0, result.stderr
    assert sub.messages() == {"linear": {"x": 0.5, "y": 0.0, "z": 0.0},
                              "angular": {"x": 0.0, "y": 0.0, "z": 1.0}}


def test_topic_pub_without_rate_latches_and_stays_up_for_late_subscribers(nodes):
    pub = nodes.start_orchestra("topic", "pub", "/greeting", "std_msgs/String", "hello")
    pub.expect(lambda d: "publishing and latching" in d.get("text", ""))
    sub = nodes.start("sub.py", "greeting", "std_msgs/String")
    assert sub.expect(lambda d: "msg" in d) == {"msg": {"data": "hello"}, "latching": "1"}
    assert pub.proc.poll() is None
    pub.signal(2)
    assert pub.wait() == 0


def test_topic_pub_at_a_rate_streams_messages(nodes):
    sub = nodes.start("sub.py", "ticks", "std_msgs/Int32")
    sub.ready()
    pub = nodes.start_orchestra("topic", "pub", "-r", "50", "/ticks",
                      "std_msgs/Int32", "7")
    for _ in range(3):
        assert sub.messages() == {"data": 7}
    pub.kill()


def stamps_seen(sub, stamp, count: int = 4) -> list[float]:
    """The stamps (seconds) of the next ``count`` messages ``sub`` prints."""
    def seconds(msg):
        t = stamp(msg)
        return t["secs"] + t["nsecs"] / 1e9
    return [seconds(sub.messages(timeout=20)) for _ in range(count)]


@pytest.mark.parametrize("type_name,yaml_text,stamp", [
    ("rosgraph_msgs/Clock", "clock: now", lambda m: m["clock"]),
    ("std_msgs/Header", "auto", lambda m: m["stamp"]),
    ("geometry_msgs/PoseStamped", "{header: auto, pose: {position: {x: 1.5}}}",
     lambda m: m["header"]["stamp"]),
])
def test_topic_pub_substitute_keywords_stamps_each_message_now(nodes, type_name, yaml_text,
                                                                stamp):
    """rostopic pub -s -r: 'now' / 'auto' evaluated again for every message, on wall time
    (``rostopic pub -s -r 10 /clock rosgraph_msgs/Clock "clock: now"`` drives /clock)."""
    sub = nodes.start("sub.py", "stamped", type_name)
    sub.ready()
    started = time.time()
    nodes.start_orchestra("topic", "pub", "-s", "-r", "20", "/stamped", type_name, yaml_text)
    stamps = stamps_seen(sub, stamp)
    assert all(a < b for a, b in zip(stamps, stamps[1:], strict=False)), stamps
    assert started - 5 < stamps[0] and stamps[-1] < time.time() + 5, (started, stamps)
    last = sub.messages(timeout=20)
    if type_name == "geometry_msgs/PoseStamped":
        assert last["header"]["frame_id"] == "" and last["header"]["seq"] > 0
        assert last["pose"]["position"]["x"] == 1.5
    elif type_name == "std_msgs/Header":
        assert last["frame_id"] == ""


def test_topic_pub_without_substitute_keywords_stamps_once_at_start(nodes):
    """As rostopic: without -s, 'now' and 'auto' are evaluated once, so every message of
    ``-r`` carries the same (start) time."""
    sub = nodes.start("sub.py", "stamped", "geometry_msgs/PoseStamped")
    sub.ready()
    started = time.time()
    nodes.start_orchestra("topic", "pub", "-r", "20", "/stamped", "geometry_msgs/PoseStamped",
                          "{header: auto}")
    stamps = stamps_seen(sub, lambda m: m["header"]["stamp"])
    assert len(set(stamps)) == 1 and abs(stamps[0] - started) < 10, (started, stamps)


@pytest.mark.parametrize("args,message", [
    (["/x", "std_msgs/String", "{data: [}"], "malformed YAML for std_msgs/String"),
    (["/c", "rosgraph_msgs/Clock", "clock: later"],
     "field clock must be {secs, nsecs}, a number or 'now', not 'later'"),
    (["/c", "rosgraph_msgs/Clock", "-s", "clock: {secs: now}"],
     "field clock.secs must be an integer, not 'now'"),
    (["/h", "std_msgs/Header", "now"], "give a mapping of its fields (or 'auto')"),
    (["/p", "geometry_msgs/PoseStamped", "{header: {stamp: auto}}"],
     "field header.stamp must be {secs, nsecs}, a number or 'now'"),
    (["/x", "std_msgs/String", "{dat: 1}"], "has no field dat"),
    (["/x", "geometry_msgs/Twist", "{linear: {x: fast}}"], "must be a number"),
    (["/x", "nope_msgs/Nothing", "{}"], "cannot find message type nope_msgs/Nothing"),
])
def test_topic_pub_rejects_bad_input_with_a_clear_error(nodes, args, message):
    result = orchestra(nodes, "topic", "pub", "-1", *args)
    assert result.returncode == 2
    assert message in result.stderr
    assert "Traceback" not in result.stderr


def test_topic_list_info_and_type(nodes):
    nodes.start("pub.py", "chatter", "std_msgs/String", "data: a", "--name", "talker").ready()
    nodes.start("sub.py", "chatter", "std_msgs/String", "--name", "listener").ready()
    listed = orchestra(nodes, "topic", "list").stdout.split()
    assert "/chatter" in listed and "/rosout" in listed
    info = orchestra(nodes, "topic", "info", "/chatter").stdout
    assert info.startswith("Type: std_msgs/String\n\nPublishers: \n * /talker (http://")
    assert "Subscribers: \n * /listener (http://" in info
    assert orchestra(nodes, "topic", "type", "chatter").stdout == "std_msgs/String\n"
    missing = orchestra(nodes, "topic", "type", "/nothing")
    assert missing.returncode == 2 and "unknown topic /nothing" in missing.stderr


def test_topic_hz_reports_the_average_rate(nodes):
    nodes.start("pub.py", "fast", "std_msgs/Empty", "{}", "--rate", "50").ready()
    result = orchestra(nodes, "topic", "hz", "/fast", "-n", "2")
    assert result.returncode == 0, result.stderr
    rates = [float(line.split(":")[1]) for line in result.stdout.splitlines()
             if line.startswith("average rate")]
    assert rates and 30 < rates[-1] < 70
    assert "\tmin: " in result.stdout and "window: " in result.stdout


def test_topic_hz_with_a_window_keeps_reporting_the_rate(nodes):
    nodes.start("pub.py", "fast", "std_msgs/Empty", "{}", "--rate", "50").ready()
    result = orchestra(nodes, "topic", "hz", "/fast", "-w", "5", "-n", "3")
    assert result.returncode == 0, result.stderr
    assert "no new messages" not in result.stdout
    assert result.stdout.count("window: 6") == 3


def test_topic_hz_piped_prints_its_reports_and_ends_quietly_on_ctrl_c(nodes):
    import signal

    nodes.start("pub.py", "fast", "std_msgs/Empty", "{}", "--rate", "50").ready()
    hz = subprocess.Popen([sys.executable, "-m", "orchestra", "topic", "hz", "/fast"],
                          env=nodes.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)
    try:       # a report read through the pipe while it runs: nothing held back
        assert hz.stdout.readline() == "subscribed to [/fast]\n"
        assert hz.stdout.readline().startswith("average rate: ")
    finally:
        hz.send_signal(signal.SIGINT)
        _, err = hz.communicate(timeout=30)
    assert hz.returncode == 0 and err == ""


def test_ctrl_c_while_a_command_waits_for_the_master_is_quiet(nodes):
    import signal
    import socket

    with socket.socket() as silent:      # accepts connections, never answers
        silent.bind(("127.0.0.1", 0))
        silent.listen(4)
        env = dict(nodes.env, ROS_MASTER_URI=f"http://127.0.0.1:{silent.getsockname()[1]}/")
        hz = subprocess.Popen([sys.executable, "-m", "orchestra", "topic", "hz", "/fast"],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True)
        conn, _ = silent.accept()        # hz is now inside the command, asking the master
        hz.send_signal(signal.SIGINT)
        _, err = hz.communicate(timeout=30)
        conn.close()
    assert hz.returncode == 130
    assert "Aborted" not in err and "Traceback" not in err


def test_service_list_type_info_and_call(nodes):
    nodes.start("adder.py", "add").ready()
    # with the logger services every node offers (tests/test_node_loggers.py)
    assert orchestra(nodes, "service", "list").stdout.split() == [
        "/add", "/adder/get_loggers", "/adder/set_logger_level"]
    assert orchestra(nodes, "service", "type", "/add").stdout == "test_msgs/AddTwoInts\n"
    info = orchestra(nodes, "service", "info", "add").stdout
    assert "Node: /adder\nURI: rosrpc://127.0.0.1:" in info and "Args: a b" in info
    result = orchestra(nodes, "service", "call", "/add", "{a: 20, b: 22}")
    assert (result.returncode, result.stdout) == (0, "sum: 42\n")
    positional = orchestra(nodes, "service", "call", "/add", "1", "2")
    assert positional.stdout == "sum: 3\n"
    failed = orchestra(nodes, "service", "call", "/add", "{a: -3, b: 0}")
    assert failed.returncode == 1 and "responded with an error" in failed.stderr
    assert "negative a: -3" in failed.stderr
    bad = orchestra(nodes, "service", "call", "/add", "{a: [}")
    assert bad.returncode == 2 and "malformed YAML" in bad.stderr
    unknown = orchestra(nodes, "service", "call", "/nope", "{}")
    assert unknown.returncode == 2 and "service [/nope] is not available" in unknown.stderr


def test_node_list_info_and_kill(nodes):
    pub = nodes.start("pub.py", "chatter", "std_msgs/String", "data: a", "--name", "talker")
    pub.ready()
    nodes.start("sub.py", "chatter", "std_msgs/String", "--name", "listener").ready()
    assert orchestra(nodes, "node", "list").stdout.split() == ["/listener", "/talker"]
    wait_for(lambda: "* to: /listener" in orchestra(nodes, "node", "info", "/talker").stdout)
    info = orchestra(nodes, "node", "info", "/talker").stdout
    assert "Publications: \n * /chatter [std_msgs/String]" in info
    assert f"Pid: {pub.proc.pid}" in info
    killed = orchestra(nodes, "node", "kill", "/talker")
    assert killed.returncode == 0 and "killing /talker" in killed.stdout
    assert pub.wait() == 0
    assert orchestra(nodes, "node", "list").stdout.split() == ["/listener"]
    unknown = orchestra(nodes, "node", "kill", "/ghost")
    assert unknown.returncode == 1 and "unknown node [/ghost]" in unknown.stderr


def test_node_stop_falls_back_to_the_slave_api_for_nodes_not_launched_by_orchestra(
        nodes, tmp_path):
    pub = nodes.start("pub.py", "chatter", "std_msgs/String", "data: a", "--name", "talker")
    pub.ready()
    env = dict(nodes.env, XDG_RUNTIME_DIR=str(tmp_path))     # no orchestra launch here
    stop = subprocess.run([sys.executable, "-m", "orchestra", "node", "stop", "/talker"],
                          env=env, capture_output=True, text=True, timeout=60)
    assert stop.returncode == 0, stop.stderr
    assert "killing /talker (not started by orchestra" in stop.stdout
    assert pub.wait() == 0
    ghost = subprocess.run([sys.executable, "-m", "orchestra", "node", "restart", "/talker"],
                           env=env, capture_output=True, text=True, timeout=60)
    assert ghost.returncode == 2 and "no node /talker in any orchestra launch" in ghost.stderr


def test_graph_writes_dot_and_svg_with_nodes_and_topics(nodes, tmp_path):
    nodes.start("pub.py", "chatter", "std_msgs/String", "data: a", "--name", "talker").ready()
    nodes.start("sub.py", "chatter", "std_msgs/String", "--name", "listener").ready()
    dot = orchestra(nodes, "graph").stdout
    assert '"/talker" -> "t:/chatter";' in dot and '"t:/chatter" -> "/listener";' in dot
    assert "/rosout" not in dot
    out = tmp_path / "g.svg"
    result = orchestra(nodes, "graph", "--out", str(out))
    assert result.returncode == 0, result.stderr
    svg = etree.parse(str(out)).getroot()
    ns = {"s": "http://www.w3.org/2000/svg"}
    labels = [t.text for t in svg.iterfind(".//s:text", ns)]
    assert sorted(labels) == ["/chatter", "/listener", "/talker"]
    assert len(svg.findall(".//s:line", ns)) == 2
    png = orchestra(nodes, "graph", "--out", str(tmp_path / "g.png"))
    if shutil.which("dot"):
        assert png.returncode == 0, png.stderr
        assert (tmp_path / "g.png").read_bytes().startswith(b"\x89PNG")
    else:
        assert png.returncode == 2 and "needs graphviz" in png.stderr
    bad = orchestra(nodes, "graph", "--out", str(tmp_path / "g.bmp"))
    assert bad.returncode == 2 and "unknown graph format" in bad.stderr


def test_commands_fail_cleanly_without_a_master(nodes):
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(nodes.env, ROS_MASTER_URI=f"http://127.0.0.1:{port}/")
    started = time.monotonic()
    result = subprocess.run([sys.executable, "-m", "orchestra", "topic", "echo", "/x"],
                            env=env, capture_output=True, text=True, timeout=30)
    assert result.returncode == 1
    assert "cannot contact the master" in result.stderr and "Traceback" not in result.stderr
    assert time.monotonic() - started < 10
    listing = subprocess.run([sys.executable, "-m", "orchestra", "node", "list"], env=env,
                             capture_output=True, text=True, timeout=30)
    assert listing.returncode == 1 and "cannot contact the master" in listing.stderr


def test_node_ping_and_cleanup_of_a_node_that_died_without_unregistering(nodes):
    alive = nodes.start("sub.py", "chatter", "std_msgs/String", "--name", "alive")
    alive.ready()
    ghost = nodes.start("pub.py", "chatter", "std_msgs/String", "data: x", "--name", "ghost")
    ghost.ready()
    ping = orchestra(nodes, "node", "ping", "/ghost")
    assert ping.returncode == 0 and ping.stdout.startswith("xmlrpc reply from http://")
    ghost.signal(9)
    ghost.wait()
    dead = orchestra(nodes, "node", "ping", "/ghost")
    assert dead.returncode == 1 and "does not answer" in dead.stderr
    cleanup = orchestra(nodes, "node", "cleanup", "--yes")
    assert cleanup.returncode == 0, cleanup.stderr
    assert " * /ghost" in cleanup.stdout and "/alive" not in cleanup.stdout
    assert orchestra(nodes, "node", "list").stdout.split() == ["/alive"]
    assert orchestra(nodes, "topic", "find", "std_msgs/String").stdout == "/chatter\n"
    assert orchestra(nodes, "topic", "find", "std_msgs/Int8").stdout == ""


def test_service_uri_and_args(nodes):
    nodes.start("adder.py", "add").ready()
    assert orchestra(nodes, "service", "uri", "/add").stdout.startswith("rosrpc://127.0.0.1:")
    assert orchestra(nodes, "service", "args", "/add").stdout == "a b\n"
