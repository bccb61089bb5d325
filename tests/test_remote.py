"""orchestra/remote without a network: ssh command lines, the agent's rules, locality.

The real thing (sshd, two network namespaces) is tests/test_remote_netns.py.
"""
from __future__ import annotations

import json
import os
import shlex
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from orchestra.launch.plan import Machine, Node
from orchestra.remote import agent, payload, ssh
from orchestra.remote.locality import UnresolvableAddress, is_local_machine
from orchestra.remote.session import (
    CLIENT,
    agent_command,
    check_machine_config,
    reachable_master_uri,
)
from orchestra.supervise.command import node_env

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(60)


def target(**kw) -> ssh.SshTarget:
    values = dict(machine="base", address="10.0.0.2", port=2222, user="robot", timeout=2.5,
                  control_path="/tmp/x/c0", config=None)
    values.update(kw)
    return ssh.SshTarget(**values)


def test_master_forwards_the_agent_socket_and_fails_if_it_cannot():
    argv = ssh.master_argv(target(), forward=("/tmp/x/a0", "/tmp/orchestra-agent-1/s"))
    assert ["-L", "/tmp/x/a0:/tmp/orchestra-agent-1/s"] == argv[argv.index("-L"):][:2]
    assert "ExitOnForwardFailure=yes" in argv


def test_session_argv_is_batch_mode_multiplexed_and_never_reads_the_terminal():
    argv = ssh.session_argv(target(), "true", program="ssh")
    assert argv[0] == "ssh" and argv[-2:] == ["10.0.0.2", "true"]
    words = " ".join(argv)
    for option in ("BatchMode=yes", "ConnectTimeout=3", "ControlPath=/tmp/x/c0",
                   "ControlMaster=no", "-p 2222", "-l robot", " -n ", " -T "):
        assert option in words
    assert "-F" not in argv                       # the user's own ~/.ssh/config applies


def test_ssh_config_from_the_environment_is_passed_with_dash_f():
    machine = Machine("base", address="h", ssh_port=22)
    tgt = ssh.target_for(machine, "/tmp/c", {ssh.CONFIG_VARIABLE: "/tmp/cfg"})
    assert ssh.master_argv(tgt)[1:3] == ["-F", "/tmp/cfg"]
    assert "-M" in ssh.master_argv(tgt) and "-N" in ssh.master_argv(tgt)


def test_ssh_error_is_its_last_line_without_warnings():
    err = "Warning: Permanently added 'x' (ED25519) to the list of known hosts.\n" \
          "root@x: Permission denied (publickey).\n"
    assert ssh.explain(err) == "ssh: root@x: Permission denied (publickey)."
    assert ssh.explain("ssh: connect to host x port 2: Connection refused\n") == \
        "ssh: connect to host x port 2: Connection refused"


def test_launch_file_text_reaches_the_remote_shell_only_as_base64():
    node = Node("pkg", "exe", "n", args="$(rm -rf /); `boom` 'q'", env_args=(("A", "$HOME;x"),))
    machine = Machine("m", address="h", env_loader="/opt/ros/env with space.sh")
    command = agent_command(machine, "http://10.0.0.1:11311/", "run",
                            {"node": payload.node_to_data(node)})
    words = shlex.split(command)
    assert words[:3] == ["env", "ROS_MASTER_URI=http://10.0.0.1:11311/",
                         "/opt/ros/env with space.sh"]
    assert words[3:7] == ["python3", "-m", "orchestra.remote.agent", "run"]
    assert set(words[7]) <= set("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                "0123456789-_=")
    assert payload.node_from_data(payload.decode(words[7])["node"]) == node


def test_password_machines_are_refused_before_connecting():
    node = Node("p", "t", "n", machine_name="m", filename="a.launch", line=4)
    with pytest.raises(Exception) as info:
        check_machine_config(Machine("m", address="h", password="secret"), node)
    assert str(info.value).startswith("a.launch:4: machine 'm': password= is not supported")


def test_loopback_master_uri_becomes_this_hosts_address_on_the_route():
    assert reachable_master_uri("http://master.example:11311/", "127.0.0.1") == \
        "http://master.example:11311/"
    assert reachable_master_uri("http://localhost:11311/", "127.0.0.5") == \
        "http://127.0.0.1:11311/"


def test_remote_env_is_setup_env_plus_the_machine_address_as_ros_hostname():
    node = Node("p", "t", "n", namespace="/arm/", env_args=(("X", "1"),))
    base = {"PATH": "/usr/bin", "ROS_NAMESPACE": "/stale", "KEEP": "k"}
    env = agent.node_environment(base, node, "http://10.0.0.1:11311/", "10.0.0.2", "mk",
                                 "/venv/bin/python3")
    expected = {**base, **node_env(node, "http://10.0.0.1:11311/")}
    for key in ("ROS_MASTER_URI", "ROS_NAMESPACE", "X", "KEEP"):
        assert env[key] == expected[key]
    assert env["ROS_HOSTNAME"] == "10.0.0.2"
    assert env["PATH"] == "/venv/bin:/usr/bin"
    with_ip = agent.node_environment({**base, "ROS_IP": "10.0.0.9"}, node, "u", "a", None, "/p")
    assert "ROS_HOSTNAME" not in with_ip and with_ip["ROS_IP"] == "10.0.0.9"


def test_exit_status_reports_signals_as_a_shell_does():
    assert agent.exit_status(3) == 3
    assert agent.exit_status(-signal.SIGSEGV) == 128 + signal.SIGSEGV


def test_locality_follows_roslaunch(monkeypatch):
    assert is_local_machine("localhost", None)
    assert is_local_machine("127.0.0.1", None)
    assert not is_local_machine("127.0.0.1", "someone-else-" + os.urandom(3).hex())

    def unresolvable(*args, **kwargs):
        raise socket.gaierror("no such host")

    monkeypatch.setattr(socket, "getaddrinfo", unresolvable)
    with pytest.raises(UnresolvableAddress):
        is_local_machine("robot-base", None)


SLOW_STOPPER = r"""
import signal, sys, time
signal.signal(signal.SIGINT, lambda *a: (print("got SIGINT", flush=True), sys.exit(0)))
print("up", flush=True)
time.sleep(60)
"""


@pytest.fixture
def package(tmp_path, monkeypatch):
    pkg = tmp_path / "ws" / "adem"
    pkg.mkdir(parents=True)
    (pkg / "package.xml").write_text(
        "<package format='2'><name>adem</name><version>0.0.0</version><description>d"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license>"
        "</package>")
    exe = pkg / "stopper"
    exe.write_text(f"#!{sys.executable}\n{SLOW_STOPPER}")
    exe.chmod(0o755)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws"))
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "log"))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "home"))
    return tmp_path


def start_agent(nodes, tmp_path):
    """The agent as ssh would run it (stdout = its channel); returns (process, its report)."""
    sock = f"/tmp/orchestra-agent-test-{os.getpid()}-{os.urandom(3).hex()}/s"
    data = {"machine": "m", "address": "10.0.0.2", "mark": None, "socket": sock,
            "nodes": [payload.node_to_data(n) for n in nodes]}
    proc = subprocess.Popen([sys.executable, "-m", "orchestra.remote.agent", "serve",
                             payload.encode(data)], stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    return proc, json.loads(proc.stdout.readline()), sock


def test_agent_runs_the_node_through_the_client_and_stops_it_when_the_client_dies(package):
    node = Node("adem", "stopper", "s", args="x")
    agent_proc, report, sock = start_agent([node], package)
    assert report["missing"] == []
    data = {"node": payload.node_to_data(node), "master_uri": "http://10.0.0.1:11311/",
            "run_id": "r1", "log_name": "s-1", "sigint_timeout": 5, "sigterm_timeout": 1}
    client = subprocess.Popen([sys.executable, "-I", "-S", CLIENT, sock, payload.encode(data)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert client.stdout.readline() == b"up\n"              # relayed by the agent
        log = package / "log" / "r1" / "s-1-stdout.log"
        client.send_signal(signal.SIGINT)                       # the supervisor's stop
        assert client.wait(timeout=10) == -signal.SIGINT
        wait_for(lambda: b"got SIGINT" in log.read_bytes())     # the node stopped in order,
        assert log.read_bytes().startswith(b"up\n")             # ...its output kept there
    finally:
        client.kill()
        client.communicate()
        agent_proc.stdout.close()                               # the agent's session ends
        assert agent_proc.wait(timeout=10) == 0
        agent_proc.stderr.close()
    assert not os.path.exists(os.path.dirname(sock))


def test_release_request_stops_the_agents_nodes_and_ends_the_agent(package):
    node = Node("adem", "stopper", "s", args="x")
    agent_proc, _, sock = start_agent([node], package)
    data = {"node": payload.node_to_data(node), "master_uri": "http://10.0.0.1:11311/",
            "run_id": "r3", "log_name": "s-1", "sigint_timeout": 5, "sigterm_timeout": 1}
    client = subprocess.Popen([sys.executable, "-I", "-S", CLIENT, sock, payload.encode(data)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert client.stdout.readline() == b"up\n"
        with socket.socket(socket.AF_UNIX) as conn:            # what the session's close() sends
            conn.connect(sock)
            conn.sendall(agent.RELEASE_REQUEST)
        assert agent_proc.wait(timeout=10) == 0                 # ended on its own, channel open
        assert client.wait(timeout=10) == 0                     # the node stopped in order
        log = package / "log" / "r3" / "s-1-stdout.log"
        assert b"got SIGINT" in log.read_bytes()
    finally:
        client.kill()
        client.communicate()
        agent_proc.kill()
        agent_proc.communicate()
    assert not os.path.exists(os.path.dirname(sock))


def test_node_exit_status_reaches_the_client(package):
    node = Node("adem", "stopper", "s")
    (package / "ws" / "adem" / "three").write_text(f"#!{sys.executable}\nimport sys\n"
                                                    "print('bye'); sys.exit(3)\n")
    (package / "ws" / "adem" / "three").chmod(0o755)
    three = Node("adem", "three", "t")
    agent_proc, _, sock = start_agent([node, three], package)
    data = {"node": payload.node_to_data(three), "master_uri": "u", "run_id": "r2",
            "log_name": "t-1", "sigint_timeout": 5, "sigterm_timeout": 1}
    try:
        done = subprocess.run([sys.executable, "-I", "-S", CLIENT, sock, payload.encode(data)],
                              capture_output=True, timeout=30)
        assert (done.returncode, done.stdout) == (3, b"bye\n")
    finally:
        agent_proc.stdout.close()
        agent_proc.wait(timeout=10)
        agent_proc.stderr.close()


def test_agent_reports_missing_executables_before_anything_runs(package):
    proc, report, _ = start_agent([Node("adem", "stopper", "a"),
                                   Node("adem", "nothere", "b", filename="f", line=2)], package)
    proc.communicate(timeout=10)
    assert proc.returncode == 0
    assert len(report["missing"]) == 1 and "nothere" in report["missing"][0]


def test_agent_reap_kills_what_is_left_of_the_run(package):
    mark = "test-" + os.urandom(4).hex()
    left = subprocess.Popen(["sleep", "30"], env={**os.environ, "ORCHESTRA_RUN_MARK": mark})
    out = subprocess.run([sys.executable, "-m", "orchestra.remote.agent", "reap",
                          payload.encode({"mark": mark, "timeout": 0.2})],
                         capture_output=True, text=True, timeout=30)
    assert json.loads(out.stdout)["killed"] == [left.pid]
    assert left.wait(timeout=5) == -signal.SIGKILL


def test_an_external_loopback_master_is_a_warning_for_remote_nodes():
    from orchestra.app.machines import master_warnings

    assert master_warnings("http://localhost:11311/", embedded=True) == []
    assert master_warnings("http://base.local:11311/", embedded=False) == []
    (warning,) = master_warnings("http://127.0.0.1:11311/", embedded=False)
    assert "external" in warning and "ROS_MASTER_URI" in warning
