"""``orchestra export --to systemd``: one unit per node, grouped per machine."""
from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys

import pytest
import yaml

from orchestra.export.systemd import ExportOptions, nested_params, quote_word, units
from orchestra.launch.plan import LaunchPlan, Machine, Node

pytestmark = pytest.mark.timeout(60)

OPTIONS = ExportOptions(prefix="orchestra-bot", master_uri="http://localhost:11311/",
                        params_path="/srv/bot/local/orchestra-bot-params.yaml",
                        public_master=True)


def plan() -> LaunchPlan:
    return LaunchPlan(
        params={"/arm/gain": 2.5, "/name": "bot"},
        nodes=(Node("drive", "base", "base", respawn=True, respawn_delay=2.0),
               Node("drive", "safety", "safety", required=True),
               Node("cam", "driver", "cam", namespace="/sensors/", machine_name="head",
                    args="--fps 30", remap_args=(("image", "raw"),),
                    env_args=(("CAM_ID", "$1 50%"),))),
        machines={"": Machine(""), "head": Machine("head", address="10.0.0.7",
                                                   env_loader="/opt/ros/env.sh")})


def test_one_service_per_node_grouped_per_machine_with_master_and_params_locally():
    files = units(plan(), OPTIONS, {"head": True}, {"head": "http://10.0.0.1:11311/"})
    assert sorted(files) == [
        "head/orchestra-bot-sensors-cam.service", "head/orchestra-bot.target",
        "local/orchestra-bot-base.service", "local/orchestra-bot-master.service",
        "local/orchestra-bot-params.service", "local/orchestra-bot-safety.service",
        "local/orchestra-bot.target"]
    assert '"core" "-p" "11311" "--host" "0.0.0.0"' in files["local/orchestra-bot-master.service"]


def test_respawn_is_restart_always_and_required_binds_the_machines_other_nodes():
    files = units(plan(), OPTIONS, {"head": True}, {"head": "http://10.0.0.1:11311/"})
    base = files["local/orchestra-bot-base.service"]
    assert "Restart=always" in base and "RestartSec=2" in base
    assert "BindsTo=orchestra-bot-safety.service" in base
    assert re.search(r"^After=.*orchestra-bot-safety.service", base, re.M)
    safety = files["local/orchestra-bot-safety.service"]
    assert "Restart=no" in safety and "BindsTo" not in safety


def test_remote_node_runs_through_its_env_loader_with_the_reachable_master():
    cam = units(plan(), OPTIONS, {"head": True},
                {"head": "http://10.0.0.1:11311/"})["head/orchestra-bot-sensors-cam.service"]
    start = [line for line in cam.splitlines() if line.startswith("ExecStart=")][0]
    assert shlex.split(start[len("ExecStart="):]) == [
        "/opt/ros/env.sh", "orchestra", "run", "cam", "driver", "--fps", "30", "image:=raw",
        "__name:=cam"]
    assert 'Environment="ROS_MASTER_URI=http://10.0.0.1:11311/"' in cam
    assert 'Environment="ROS_NAMESPACE=/sensors"' in cam
    assert 'Environment="CAM_ID=$1 50%%"' in cam          # systemd specifiers escaped
    assert "orchestra-bot-master" not in cam               # no master on that machine


def test_words_are_quoted_for_systemd():
    assert quote_word('a "b" $HOME 100%') == '"a \\"b\\" $$HOME 100%%"'
    assert nested_params({"/arm/gain": 2.5, "/name": "bot"}) == {"arm": {"gain": 2.5},
                                                                  "name": "bot"}


PROBE = r'''#!PYTHON
import json, os, sys
with open(os.environ["PROBE_OUT"], "w") as fh:
    json.dump({"argv": sys.argv[1:], "ns": os.environ.get("ROS_NAMESPACE"),
               "uri": os.environ.get("ROS_MASTER_URI")}, fh)
'''


def test_cli_writes_units_whose_command_runs_the_node(tmp_path, monkeypatch):
    pkg = tmp_path / "ws" / "demo"
    pkg.mkdir(parents=True)
    (pkg / "package.xml").write_text(
        "<package format='2'><name>demo</name><version>0.0.0</version><description>d"
        "</description><maintainer email='a@b.c'>a</maintainer><license>BSD</license>"
        "</package>")
    (pkg / "probe").write_text(PROBE.replace("PYTHON", sys.executable))
    (pkg / "probe").chmod(0o755)
    launch = tmp_path / "bot.launch"
    launch.write_text('<launch><param name="p" value="7"/><group ns="g">'
                      '<node pkg="demo" type="probe" name="n" args="x y" respawn="true">'
                      f'<env name="PROBE_OUT" value="{tmp_path / "out.json"}"/></node>'
                      '</group></launch>')
    env = {**os.environ, "ROS_PACKAGE_PATH": str(tmp_path / "ws"),
           "ROS_HOME": str(tmp_path / "home"), "ROS_MASTER_URI": "http://localhost:11411/"}
    command = f"{sys.executable} -m orchestra"
    out = subprocess.run([sys.executable, "-m", "orchestra", "export", "--to", "systemd",
                          str(tmp_path / "units"), str(launch), "--orchestra-command", command],
                         env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    local = tmp_path / "units" / "local"
    unit = (local / "orchestra-bot-g-n.service").read_text()
    assert yaml.safe_load((local / "orchestra-bot-params.yaml").read_text()) == {"p": 7}
    start = [line for line in unit.splitlines() if line.startswith("ExecStart=")][0]
    unit_env = dict(re.findall(r'^Environment="([^=]+)=(.*)"$', unit, re.M))
    ran = subprocess.run(shlex.split(start[len("ExecStart="):]), env={**env, **unit_env},
                         capture_output=True, text=True, timeout=60)
    assert ran.returncode == 0, ran.stderr
    record = json.loads((tmp_path / "out.json").read_text())
    assert record == {"argv": ["x", "y", "__name:=n"], "ns": "/g",
                      "uri": "http://localhost:11411/"}
    if shutil.which("systemd-analyze"):
        verify = subprocess.run(["systemd-analyze", "verify", "--man=no",
                                 *sorted(str(p) for p in local.glob("*.service"))],
                                capture_output=True, text=True, timeout=60, cwd=local)
        assert verify.returncode == 0, verify.stderr     # systemd's own parser accepts them
