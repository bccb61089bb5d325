"""Remote ``<machine>`` nodes for real: two network namespaces, a real sshd, real ssh.

The launching orchestra runs in one namespace, sshd in the other (tests/node_fixtures/
netns_ssh.py builds both on a private 10.213.N.0/24 subnet that exists only inside them).
Where a node really ran is read from ``/proc/PID/ns/net``. Skipped with the reason where
namespaces or sshd are not available (not root, no iproute2/openssh-server).
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
import netns_ssh  # noqa: E402
from harness import wait_for  # noqa: E402

pytestmark = [pytest.mark.timeout(120)]

_WHY = netns_ssh.unavailable()
if _WHY:
    pytestmark.append(pytest.mark.skip(reason=_WHY))

PROBE = r'''#!PYTHON
"""Records how it was started and where (its network namespace), then behaves as asked."""
import json, os, sys, time
name = [a[8:] for a in sys.argv if a.startswith("__name:=")][0]
out = os.environ["PROBE_OUT"]
record = {"argv": sys.argv, "pid": os.getpid(), "cwd": os.getcwd(),
          "env": {k: os.environ.get(k) for k in ("ROS_MASTER_URI", "ROS_NAMESPACE",
                                                 "ROS_HOSTNAME", "ROS_IP", "NODE_ENV")}}
with open(os.path.join(out, f"{name}-{os.getpid()}.json"), "w") as fh:
    json.dump(record, fh)
print(f"hello from {name}", flush=True)
mode = os.environ.get("PROBE_MODE", "sleep")
if mode == "crash":
    time.sleep(0.3)
    sys.exit(3)
while not (mode == "die_on_file" and os.path.exists(os.path.join(out, name + ".die"))):
    time.sleep(0.05)
print(f"{name} dying", flush=True)
sys.exit(1)
'''

LAUNCH = '''<launch>
  <machine name="far" address="{address}" ssh-port="{port}" env-loader="{loader}"
           timeout="{timeout}"/>
  <env name="PROBE_OUT" value="{out}"/>
  <node pkg="rdemo" type="probe" name="here" output="screen"/>
  <node pkg="rdemo" type="probe" name="talker" machine="far" output="screen" args="a 'b c'">
    <remap from="chatter" to="/news"/><env name="NODE_ENV" value="v1"/>
  </node>
  <node pkg="rdemo" type="probe" name="crashy" machine="far" respawn="true">
    <env name="PROBE_MODE" value="crash"/>
  </node>
  <group ns="arm">
    <node pkg="rdemo" type="probe" name="boss" machine="far" required="true" output="screen">
      <env name="PROBE_MODE" value="die_on_file"/>
    </node>
  </group>
</launch>
'''


@pytest.fixture(scope="module")
def bed(tmp_path_factory):
    root = tmp_path_factory.mktemp("netns")
    with netns_ssh.Testbed(root) as testbed:
        ws = root / "ws" / "rdemo"
        ws.mkdir(parents=True)
        (ws / "package.xml").write_text(
            "<package format='2'><name>rdemo</name><version>0.0.0</version><description>d"
            "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license>"
            "</package>")
        (ws / "probe").write_text(PROBE.replace("PYTHON", sys.executable))
        (ws / "probe").chmod(0o755)
        testbed.workspace = root / "ws"
        testbed.loader = testbed.env_loader(root / "loader.sh", {
            "ROS_PACKAGE_PATH": str(root / "ws"), "ROS_LOG_DIR": str(root / "remote_log"),
            "ROS_HOME": str(root / "remote_home")})
        yield testbed


@pytest.fixture
def run(bed, tmp_path):
    """Writes the launch file; ``start(**launch_values)`` runs orchestra in the local netns."""
    out = tmp_path / "out"
    out.mkdir()
    procs: list[subprocess.Popen] = []

    class Run:
        def __init__(self) -> None:
            self.out = out
            self.env = {**os.environ, "ROS_PACKAGE_PATH": str(bed.workspace),
                        "ROS_HOME": str(tmp_path / "home"), "XDG_RUNTIME_DIR": str(tmp_path),
                        "ROS_MASTER_URI": "http://localhost:11311/",
                        "ORCHESTRA_SSH_CONFIG": str(bed.ssh_config)}
            self.env.pop("ROS_LOG_DIR", None)

        def launch_file(self, **values) -> Path:
            fields = {"address": bed.remote_ip, "port": bed.port, "loader": bed.loader,
                      "out": out, "timeout": 3, **values}
            path = tmp_path / "two.launch"
            path.write_text(LAUNCH.format(**fields))
            return path

        def start(self, **values) -> subprocess.Popen:
            proc = bed.popen_local(
                [sys.executable, "-m", "orchestra", "launch", str(self.launch_file(**values)),
                 "--no-status", "--disable-title"],
                env=self.env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
            procs.append(proc)
            return proc

        def records(self, name: str) -> list[dict]:
            return [json.loads(p.read_text()) for p in sorted(out.glob(f"{name}-*.json"))
                    if p.stat().st_size]

    yield Run()
    for proc in procs:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def leftovers(bed) -> list[int]:
    """Processes still in either namespace, apart from sshd listening in the remote one."""
    return [pid for ns in (bed.local_ns, bed.remote_ns) for pid in bed.pids_in(ns)
            if pid != bed.sshd.pid]


def assert_nothing_left(bed, within: float = 5.0) -> None:
    """After a run has ended: nothing of it left in either namespace. The launch asks its
    remote agent to end and waits for that before it exits, so no agent may be left at
    all; the remote sshd's own processes for the connection end a moment after it closes,
    so those are waited for briefly."""
    agents = [pid for pid in bed.pids_in(bed.remote_ns)
              if b"orchestra.remote.agent" in cmdline(pid)]
    assert [cmdline(pid) for pid in agents] == []
    deadline = time.monotonic() + within
    while leftovers(bed) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert [cmdline(pid) for pid in leftovers(bed)] == []


def cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


def netns_of(pid: int) -> int:
    return os.stat(f"/proc/{pid}/ns/net").st_ino


def wait_started(run) -> dict[str, list[dict]]:
    names = ("here", "talker", "crashy", "boss")
    return wait_for(lambda: all(run.records(n) for n in names)
                    and {n: run.records(n) for n in names}, timeout=30)


def test_remote_nodes_run_remotely_respawn_and_a_required_death_stops_both_sides(bed, run):
    proc = run.start()
    found = wait_started(run)
    remote_ns, local_ns = bed.netns_inode(bed.remote_ns), bed.netns_inode(bed.local_ns)
    assert netns_of(found["talker"][0]["pid"]) == remote_ns
    assert netns_of(found["boss"][0]["pid"]) == remote_ns
    assert netns_of(found["here"][0]["pid"]) == local_ns
    wait_for(lambda: len(run.records("crashy")) >= 2, timeout=20)     # crashed, respawned
    status = bed.in_local([sys.executable, "-m", "orchestra", "status", "--json"],
                          env=run.env, capture_output=True, text=True, timeout=30)
    assert status.returncode == 0, status.stderr
    launches = json.loads(status.stdout)
    assert len(launches) == 1, status.stdout
    nodes = {n["name"]: n for n in launches[0]["nodes"]}
    talker = nodes["/talker"]            # its pid/memory on ITS machine, not the local relay's
    assert (talker["machine"], talker["pid"]) == ("far", found["talker"][0]["pid"]), talker
    assert talker["rss"] and talker["rss"] > 0
    assert "machine" not in nodes["/here"]
    (run.out / "boss.die").write_text("")
    output, _ = proc.communicate(timeout=40)
    text = output.decode(errors="replace")
    assert proc.returncode == 1, text
    assert "required process /arm/boss died (exit code 1)" in text
    assert "[/talker] hello from talker" in text                     # remote output, prefixed
    assert "[/arm/boss] boss dying" in text
    assert "process[/crashy]: died (exit code 3), respawning" in text
    assert_nothing_left(bed)


def test_remote_argv_env_are_roslaunchs_and_sigint_stops_both_sides(bed, run):
    proc = run.start()
    found = wait_started(run)
    first = found["talker"][0]["pid"]
    restart = bed.in_local([sys.executable, "-m", "orchestra", "node", "restart", "/talker"],
                           env=run.env, capture_output=True, text=True, timeout=60)
    assert restart.returncode == 0, restart.stdout + restart.stderr   # live control works too
    again = wait_for(lambda: [r for r in run.records("talker") if r["pid"] != first])
    assert not os.path.exists(f"/proc/{first}")
    assert netns_of(again[0]["pid"]) == bed.netns_inode(bed.remote_ns)
    proc.send_signal(signal.SIGINT)
    output, _ = proc.communicate(timeout=30)
    assert proc.returncode == 0, output.decode(errors="replace")
    assert_nothing_left(bed)
    talker, boss = found["talker"][0], found["boss"][0]
    exe = str(bed.workspace / "rdemo" / "probe")
    # roslaunch's remote child: create_local_process_args + setup_env on the remote side,
    # __log in the REMOTE log directory (its ROS_LOG_DIR, from the env-loader)
    assert talker["argv"][:5] == [exe, "a", "b c", "chatter:=/news", "__name:=talker"]
    log_arg = talker["argv"][5]
    # (counted per machine from 1, as by roslaunch's child on that machine)
    assert log_arg.startswith(f"__log:={bed.root / 'remote_log'}/")
    assert log_arg.endswith("/talker-1.log")
    assert len(talker["argv"]) == 6
    # the master as the remote machine reaches it: this host's address on that route
    assert talker["env"]["ROS_MASTER_URI"] == f"http://{bed.local_ip}:11311/"
    assert talker["env"]["ROS_NAMESPACE"] is None and talker["env"]["NODE_ENV"] == "v1"
    assert boss["env"]["ROS_NAMESPACE"] == "/arm"
    assert talker["env"]["ROS_HOSTNAME"] == bed.remote_ip     # per machine: its address
    assert talker["cwd"] == str(bed.root / "remote_home")      # ROS_HOME there
    remote_logs = list((bed.root / "remote_log").glob("*/talker-*-stdout.log"))
    assert any(b"hello from talker" in p.read_bytes() for p in remote_logs)
    if not compare_with_real_roslaunch(bed, run, found):
        pytest.skip("the rules above hold; Debian's roslaunch (python3-roslaunch) is not "
                    "installed to compare with it directly")


def test_sigkilled_orchestra_leaves_no_remote_process(bed, run):
    proc = run.start()
    found = wait_started(run)
    remote = [found[n][-1]["pid"] for n in ("talker", "boss")]
    proc.kill()
    proc.wait()
    wait_for(lambda: leftovers(bed) == [], timeout=5.0)
    assert not any(os.path.exists(f"/proc/{pid}") for pid in remote)


BAD = {
    "unknown host key": ({"known_hosts": "empty"}, {}, "Host key verification failed"),
    "refused key": ({"key": "other"}, {}, "Permission denied"),
    "wrong port": ({}, {"port": 2222}, "Connection refused"),
    "env-loader missing": ({}, {"loader": "/nonexistent/env.sh"}, "No such file"),
    "env-loader not executable": ({}, {"loader": "NOEXEC"}, "Permission denied"),
    "orchestra missing remotely": ({}, {"loader": "NOORCH"}, "orchestra is not installed"),
    "package missing remotely": ({}, {"loader": "NOPKG"}, "rdemo"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_remote_setup_is_one_line_exit_2_and_nothing_started(bed, run, tmp_path, case):
    client, launch, expected = BAD[case]
    key = known = None
    if client.get("known_hosts") == "empty":
        known = tmp_path / "known_hosts"
        known.write_text("")
    if client.get("key") == "other":
        key = tmp_path / "other_key"
        subprocess.run(["ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", str(key)],
                       check=True)
    run.env["ORCHESTRA_SSH_CONFIG"] = str(bed.write_client_config(key, known))
    loader = launch.get("loader")
    if loader == "NOEXEC":
        launch["loader"] = tmp_path / "noexec.sh"
        launch["loader"].write_text("#!/bin/sh\nexec \"$@\"\n")
    elif loader == "NOORCH":     # a python3 without orchestra (Debian's, or nothing at all)
        launch["loader"] = tmp_path / "noorch.sh"
        launch["loader"].write_text("#!/bin/sh\nexport PATH=/usr/bin:/bin PYTHONPATH=\n"
                                    f"export ROS_PACKAGE_PATH={bed.workspace}\nexec \"$@\"\n")
        launch["loader"].chmod(0o755)
    elif loader == "NOPKG":
        launch["loader"] = bed.env_loader(tmp_path / "nopkg.sh",
                                          {"ROS_PACKAGE_PATH": str(tmp_path)})
    try:
        proc = run.start(**launch)
        output, _ = proc.communicate(timeout=40)
    finally:
        bed.write_client_config()
    lines = output.decode(errors="replace").strip().splitlines()
    assert proc.returncode == 2, lines
    assert len(lines) == 1, lines
    address = bed.remote_ip
    assert "machine 'far'" in lines[0] and address in lines[0], lines
    assert expected in lines[0], lines
    assert "two.launch:" in lines[0], lines
    assert run.records("here") == []
    assert leftovers(bed) == []


def test_unreachable_machine_fails_fast_with_nothing_started(bed, run):
    silent = bed.remote_ip.rsplit(".", 1)[0] + ".3"     # in our private subnet; nobody there
    proc = run.start(address=silent, timeout=1)
    output, _ = proc.communicate(timeout=30)
    text = output.decode(errors="replace").strip()
    assert proc.returncode == 2, text
    assert len(text.splitlines()) == 1 and f"machine 'far' ({silent}:22)" in text, text
    assert run.records("here") == []
    assert leftovers(bed) == []


def test_check_machines_warns_about_a_machine_it_cannot_reach(bed, run):
    def check(**values) -> subprocess.CompletedProcess:
        return bed.in_local([sys.executable, "-m", "orchestra", "check", "--check-machines",
                             str(run.launch_file(**values))], env=run.env,
                            capture_output=True, text=True, timeout=60)

    good = check()
    assert good.returncode == 0 and "[machine]" not in good.stdout, good.stdout + good.stderr
    bad = check(port=2222)
    assert bad.returncode == 0, bad.stdout + bad.stderr               # a warning, not an error
    warnings = [line for line in bad.stdout.splitlines() if "[machine]" in line]
    assert len(warnings) == 1, bad.stdout
    assert "warning: machine 'far'" in warnings[0] and "Connection refused" in warnings[0]
    assert "two.launch:" in warnings[0]
    assert leftovers(bed) == []


def test_lost_connection_stops_the_remote_nodes_and_the_launch_sees_them_die(bed, run):
    proc = run.start()
    found = wait_started(run)
    masters = [pid for pid in bed.pids_in(bed.local_ns) if b"\0-M\0" in cmdline(pid)]
    assert len(masters) == 1                            # one connection for three nodes
    os.kill(masters[0], signal.SIGKILL)                 # the network connection is gone
    output, _ = proc.communicate(timeout=40)
    text = output.decode(errors="replace")
    assert proc.returncode == 1, text                   # the required remote node "died"
    assert "required process /arm/boss died (exit code 255)" in text
    remote = [found[n][-1]["pid"] for n in ("talker", "boss")]
    assert not any(os.path.exists(f"/proc/{pid}") for pid in remote)
    assert leftovers(bed) == []


ROSLAUNCH_SIDE = r'''
import json, sys
from roslaunch.core import Machine, Node, setup_env
from roslaunch.node_args import create_local_process_args
spec = json.loads(sys.argv[1])
node = Node("rdemo", "probe", name=spec["name"], namespace=spec["namespace"],
            args=spec["args"], remap_args=spec["remaps"], env_args=spec["env"])
machine = Machine("far", spec["address"], env_loader=spec["loader"])
node.machine = machine
env = setup_env(node, machine, spec["master_uri"])
print(json.dumps({"argv": create_local_process_args(node, machine),
                  "env": {k: env.get(k) for k in ("ROS_MASTER_URI", "ROS_NAMESPACE",
                                                  "NODE_ENV")}}))
'''


def compare_with_real_roslaunch(bed, run, found) -> bool:
    """roslaunch's remote child builds a node's process with create_local_process_args and
    setup_env, on the remote machine, after the env-loader: run exactly that there and
    compare. False when Debian's roslaunch is not installed."""
    probe = subprocess.run(["/usr/bin/python3", "-c", "import roslaunch.node_args"],
                           capture_output=True)
    if probe.returncode != 0:
        return False
    for name, namespace, args, remaps, env in (
            ("talker", "/", "a 'b c'", [["chatter", "/news"]], [["NODE_ENV", "v1"]]),
            ("boss", "/arm/", "", [], [["PROBE_OUT", str(run.out)],
                                       ["PROBE_MODE", "die_on_file"]])):
        record = found[name][0]
        spec = {"name": name, "namespace": namespace, "args": args, "remaps": remaps,
                "env": env, "address": bed.remote_ip, "loader": str(bed.loader),
                "master_uri": record["env"]["ROS_MASTER_URI"]}
        ros = subprocess.run(["ip", "netns", "exec", bed.remote_ns, str(bed.loader),
                              "/usr/bin/python3", "-c", ROSLAUNCH_SIDE, json.dumps(spec)],
                             capture_output=True, text=True, timeout=60,
                             env={"PATH": "/usr/bin:/bin"})
        assert ros.returncode == 0, ros.stderr
        expected = json.loads(ros.stdout)
        # roslaunch adds __log:= itself when it spawns (LocalProcess); the rest is equal
        assert record["argv"][:-1] == expected["argv"]
        assert record["argv"][-1].startswith("__log:=")
        for key, value in expected["env"].items():
            assert record["env"].get(key) == value, key
    return True
