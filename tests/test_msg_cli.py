"""``orchestra msg|srv`` against Debian's rosmsg/rossrv, byte for byte.

Both sides see the same package path (/usr/share, where Debian's ros-*-msgs packages put
their .msg/.srv files). rosmsg's texts for every type it lists come from one
/usr/bin/python3 run of ``msg_fixtures/rosmsg_side.py`` (what ``rosmsg show`` prints); a few
commands are also compared as whole processes. Skipped where rosmsg is not installed.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from orchestra.node.msgcli import msg, srv

FIXTURES = Path(__file__).resolve().parent / "msg_fixtures"
REPO = Path(__file__).resolve().parent.parent
SHARE = "/usr/share"
SYSTEM_PYTHON = "/usr/bin/python3"


def _rosmsg_present() -> bool:
    return shutil.which("rosmsg") is not None and os.path.isfile(
        os.path.join(SHARE, "std_msgs", "msg", "String.msg"))


needs_rosmsg = pytest.mark.skipif(not _rosmsg_present(),
                                  reason="Debian's rosmsg (python3-rosmsg, ros-std-msgs) absent")


@pytest.fixture(scope="module")
def reference() -> dict:
    if not _rosmsg_present():
        pytest.skip("Debian's rosmsg (python3-rosmsg, ros-std-msgs) absent")
    out = subprocess.run([SYSTEM_PYTHON, str(FIXTURES / "rosmsg_side.py")], capture_output=True,
                         text=True, timeout=300,
                         env={"PATH": "/usr/bin:/bin", "ROS_PACKAGE_PATH": SHARE,
                              "HOME": os.environ.get("HOME", "/tmp")})
    assert out.returncode == 0, out.stderr[-500:]
    return json.loads(out.stdout)


@pytest.fixture
def same_path(monkeypatch):
    from orchestra.packages.index import reset_index

    monkeypatch.setenv("ROS_PACKAGE_PATH", SHARE)
    reset_index()
    yield
    reset_index()


def _ours(group, *args: str) -> str:
    result = CliRunner().invoke(group, list(args), catch_exceptions=False)
    assert result.exit_code == 0, result.output
    return result.output


def _compared(reference: dict, kind: str) -> list[str]:
    return sorted(t for t, v in reference[kind].items() if "error" not in v)


def test_every_message_type_shows_and_hashes_as_rosmsg(reference, same_path):
    types = _compared(reference, "msg")
    assert len(types) >= 30
    wrong = []
    for type_name in types:
        ref = reference["msg"][type_name]
        if (_ours(msg, "show", type_name) != ref["show"] + "\n"
                or _ours(msg, "show", "-r", type_name) != ref["raw"] + "\n"
                or _ours(msg, "md5", type_name) != ref["md5"] + "\n"):
            wrong.append(type_name)
    assert wrong == []


def test_every_service_type_shows_and_hashes_as_rossrv(reference, same_path):
    types = _compared(reference, "srv")
    assert len(types) >= 10
    wrong = []
    for type_name in types:
        ref = reference["srv"][type_name]
        if (_ours(srv, "show", type_name) != ref["show"] + "\n"
                or _ours(srv, "show", "-r", type_name) != ref["raw"] + "\n"
                or _ours(srv, "md5", type_name) != ref["md5"] + "\n"):
            wrong.append(type_name)
    assert wrong == []


@pytest.mark.parametrize("kind", ["msg", "srv"])
def test_package_listings_match(reference, same_path, kind):
    group = msg if kind == "msg" else srv
    for pkg, types in reference["packages"][kind].items():
        assert _ours(group, "package", pkg) == "\n".join(types) + "\n", pkg
        assert _ours(group, "package", "-s", pkg) == " ".join(types) + "\n", pkg


@needs_rosmsg
@pytest.mark.parametrize("argv", [
    ["msg", "show", "Header"],
    ["msg", "show", "geometry_msgs/PoseStamped"],
    ["msg", "show", "-r", "sensor_msgs/NavSatStatus"],
    ["msg", "md5", "Twist"],
    ["srv", "show", "nav_msgs/GetPlan"],
    ["srv", "show", "-r", "std_srvs/SetBool"],
    ["msg", "package", "-s", "std_msgs"],
])
def test_commands_print_what_the_ros_tools_print(argv):
    env = dict(os.environ, ROS_PACKAGE_PATH=SHARE, PYTHONPATH=str(REPO))
    ours = subprocess.run([sys.executable, "-m", "orchestra", *argv], env=env,
                          capture_output=True, text=True, timeout=60)
    theirs = subprocess.run([f"ros{argv[0]}", *argv[1:]], env=env, capture_output=True,
                            text=True, timeout=60)
    assert ours.returncode == theirs.returncode == 0, ours.stderr + theirs.stderr
    assert ours.stdout == theirs.stdout


def _orchestra(*argv: str, **env: str) -> subprocess.CompletedProcess:
    full = dict(os.environ, PYTHONPATH=str(REPO), **env)
    return subprocess.run([sys.executable, "-m", "orchestra", *argv], env=full,
                          capture_output=True, text=True, timeout=60)


def test_unknown_type_is_a_one_line_error_with_exit_2():
    out = _orchestra("msg", "show", "nosuch_msgs/Thing")
    assert out.returncode == 2 and out.stdout == ""
    assert out.stderr.startswith("orchestra: error: cannot find message type nosuch_msgs/Thing")
    assert len(out.stderr.splitlines()) == 1


def test_broken_definition_is_reported_at_its_file_and_line(tmp_path):
    pkg = tmp_path / "broken_pkg"
    (pkg / "msg").mkdir(parents=True)
    (pkg / "package.xml").write_text("<package><name>broken_pkg</name></package>")
    (pkg / "msg" / "Outer.msg").write_text("int32 a\n\nbroken_pkg/Missing inner\n")
    out = _orchestra("msg", "show", "broken_pkg/Outer", ROS_PACKAGE_PATH=str(tmp_path))
    assert out.returncode == 2
    assert f"{pkg / 'msg' / 'Outer.msg'}:3: unknown type 'broken_pkg/Missing'" in out.stderr
    assert "Traceback" not in out.stderr


def test_bare_name_not_found_says_so_like_rosmsg():
    out = _orchestra("msg", "show", "NoSuchTypeAnywhere")
    assert out.returncode == 1 and out.stderr == "Could not find msg 'NoSuchTypeAnywhere'\n"


def test_type_can_be_piped_in_as_from_topic_type():
    result = CliRunner().invoke(msg, ["show"], input="\ngeometry_msgs/Vector3\n")
    assert result.exit_code == 0, result.output
    assert result.output == "float64 x\nfloat64 y\nfloat64 z\n\n"
    result = CliRunner().invoke(srv, ["md5"], input="std_srvs/Trigger\n")
    assert result.output == "937c9679a518e3a18d831e57125ea522\n"
