"""rosmon's node attributes (stop-timeout, memory-limit, cpu-limit, enable-coredumps): read
into the plan, not warned about, and put into effect when the launch runs."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from orchestra.errors import OrchestraError
from orchestra.launch.interpreter import Interpreter, LoadOptions, load_launch
from orchestra.launch.plan import Node
from orchestra.supervise.specs import SpecOptions, build_specs

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import free_port, wait_for  # noqa: E402

pytestmark = pytest.mark.timeout(90)

NODES = ('<node pkg="p" type="t" name="a" stop-timeout="1.5" memory-limit="15 MB" '
         'cpu-limit="0.5" enable-coredumps="true"/><node pkg="p" type="t" name="b"/>')


def write_launch(tmp_path: Path, body: str) -> str:
    path = tmp_path / "main.launch"
    path.write_text(f"<launch>\n{body}\n</launch>\n")
    return str(path)


def test_rosmon_attributes_reach_the_plan_and_are_not_unknown(tmp_path):
    interp = Interpreter(LoadOptions())
    interp.load_file(write_launch(tmp_path, NODES))
    a, b = interp.plan().nodes
    assert (a.stop_timeout, a.memory_limit, a.cpu_limit, a.enable_coredumps) == \
        (1.5, 15_000_000, 0.5, True)
    assert (b.stop_timeout, b.memory_limit, b.cpu_limit, b.enable_coredumps) == \
        (None, 0, 0.0, False)
    assert not [w for w in interp.warnings if "unknown" in w]
    assert "memory_limit" in a.to_json() and "memory_limit" not in b.to_json()


def test_orchestra_check_does_not_warn_about_rosmon_attributes(tmp_path):
    path = write_launch(tmp_path, NODES.replace('pkg="p" type="t"', 'pkg="rospy" type="x"'))
    cli = subprocess.run([sys.executable, "-m", "orchestra", "check", path, "--json"],
                         capture_output=True, text=True)
    assert "stop-timeout" not in cli.stdout and "memory-limit" not in cli.stdout
    assert "unknown-attribute" not in cli.stdout


@pytest.mark.parametrize("attr, value", [("memory-limit", "lots"), ("stop-timeout", "-1"),
                                         ("enable-coredumps", "yes")])
def test_bad_rosmon_attribute_value_names_file_line_and_attribute(tmp_path, attr, value):
    path = write_launch(tmp_path, f'<node pkg="p" type="t" name="a" {attr}="{value}"/>')
    with pytest.raises(OrchestraError) as err:
        load_launch(path)
    assert str(err.value).startswith(f"{path}:2") and f"'{attr}'" in str(err.value)


def test_stop_timeout_becomes_the_nodes_sigint_timeout_and_limits_its_spec():
    node = Node("p", "t", "a", stop_timeout=1.0, memory_limit=1 << 20, enable_coredumps=True)
    plain = Node("p", "t", "b")
    specs = build_specs([node, plain], {"/a": "/bin/true", "/b": "/bin/true"},
                        "http://localhost:1/", "/tmp", SpecOptions())
    assert (specs[0].sigint_timeout, specs[0].sigterm_timeout) == (1.0, 0.0)
    assert specs[0].limits.memory == 1 << 20 and specs[0].limits.coredumps
    assert (specs[1].sigint_timeout, specs[1].sigterm_timeout) == (15.0, 2.0)
    assert not specs[1].limits


LAUNCH = """<launch>
  <node pkg="demo" type="stubborn" name="stubborn" stop-timeout="1"/>
  <node pkg="demo" type="hog" name="hog" memory-limit="300MiB"/>
  <node pkg="demo" type="calm" name="other"/>
</launch>
"""
STUBBORN = """#!{python}
import signal, time
import os
signal.signal(signal.SIGINT, signal.SIG_IGN)
open(os.path.join(os.environ["READY_DIR"], "ready"), "w").close()
time.sleep(1000)
"""
HOG = """#!{python}
import time
time.sleep(0.5)
blocks = []
while True:
    blocks.append(bytearray(8 << 20))
"""


def test_launch_honours_stop_timeout_and_memory_limit(tmp_path):
    pkg = tmp_path / "ws" / "demo"
    (pkg / "nodes").mkdir(parents=True)
    (pkg / "package.xml").write_text(
        "<package format='2'><name>demo</name><version>0.0.0</version><description>d"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license></package>")
    for name, text in (("stubborn", STUBBORN), ("hog", HOG),
                       ("calm", "#!/bin/sh\nexec sleep 1000\n")):
        (pkg / "nodes" / name).write_text(text.format(python=sys.executable))
        (pkg / "nodes" / name).chmod(0o755)
    (tmp_path / "x.launch").write_text(LAUNCH)
    env = {k: v for k, v in os.environ.items() if k not in ("ROS_LOG_DIR", "ROS_NAMESPACE")}
    env.update(ROS_PACKAGE_PATH=str(tmp_path / "ws"), ROS_HOME=str(tmp_path / "home"),
               ROS_MASTER_URI=f"http://localhost:{free_port()}/", XDG_RUNTIME_DIR=str(tmp_path),
               READY_DIR=str(tmp_path))

    def orchestra(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "orchestra", *args], env=env,
                              capture_output=True, text=True, timeout=60)

    def nodes() -> dict:
        out = orchestra("status", "--json").stdout
        docs = json.loads(out) if out.strip() else []
        return {n["name"]: n for n in docs[0]["nodes"]} if docs else {}

    launch = subprocess.Popen([sys.executable, "-m", "orchestra", "launch", str(tmp_path / "x.launch"),
                               "--no-status", "--no-rosout", "--screen"], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        wait_for(lambda: nodes().get("/hog", {}).get("state") == "EXITED", timeout=30)
        hog = nodes()["/hog"]
        assert "memory-limit of 300 MiB" in hog["reason"]
        wait_for(lambda: (tmp_path / "ready").exists())   # its SIGINT handler is in place
        started = time.monotonic()
        cli = orchestra("node", "stop", "/stubborn")
        took = time.monotonic() - started
        assert cli.returncode == 0 and "/stubborn: STOPPED" in cli.stdout
        assert 1.0 <= took < 10.0      # its 1 s, then killed; the upper bound is a hang guard
        print(f"stop-timeout=1 node stopped by the CLI in {took:.2f} s")
        assert nodes()["/other"]["state"] == "RUNNING"
    finally:
        launch.terminate()
        out, _ = launch.communicate(timeout=30)
    assert "memory-limit of 300 MiB" in out
