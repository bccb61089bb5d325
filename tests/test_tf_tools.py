"""The tf package's tools: static_transform_publisher's argument forms, view_frames' drawing,
and the three tools run against a master on a free port."""
from __future__ import annotations

import importlib.machinery
import importlib.util
import math
import os
import re
import shutil
import signal
import subprocess
import threading
from pathlib import Path

import pytest

from orchestra.tf.drawing import layout, tree_dot, tree_svg
from orchestra.tf.transformations import euler_from_quaternion

# orchestra's bundled packages, whatever ROS workspace the developer's shell points at
BUNDLED_ENV = {k: v for k, v in os.environ.items()
               if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH")}

SCRIPTS = Path(__file__).resolve().parent.parent / "packages" / "tf" / "scripts"


def load_script(path: Path):
    loader = importlib.machinery.SourceFileLoader(path.name.replace(".", "_"), str(path))
    spec = importlib.util.spec_from_loader(loader.name, loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def stp():
    return load_script(SCRIPTS / "static_transform_publisher")


def test_static_publisher_euler_form_is_yaw_pitch_roll(stp):
    trans, rot, parent, child, period = stp.parse_args(
        "1 2 3 0.5 0.2 0.1 base_link laser".split())
    assert (trans, parent, child, period) == ((1, 2, 3), "base_link", "laser", None)
    assert euler_from_quaternion(rot) == pytest.approx((0.1, 0.2, 0.5))


def test_static_publisher_nine_args_with_period_is_tf1_euler_form(stp):
    *_, parent, child, period = stp.parse_args("0 0 0 0 0 0 map odom 100".split())
    assert (parent, child, period) == ("map", "odom", 0.1)


def test_static_publisher_nine_args_with_numbers_is_quaternion_form(stp):
    _, rot, parent, child, period = stp.parse_args("0 0 0 0 0 1 1 map odom".split())
    assert rot == pytest.approx((0, 0, math.sqrt(0.5), math.sqrt(0.5)))
    assert (parent, child, period) == ("map", "odom", None)


def test_static_publisher_ten_args_is_quaternion_with_period(stp):
    *_, period = stp.parse_args("0 0 0 0 0 0 1 map odom 50".split())
    assert period == 0.05


@pytest.mark.parametrize("args", ["1 2 3", "0 0 0 0 0 0 map map", "0 0 0 x 0 0 a b",
                                  "0 0 0 0 0 0 a b -5"])
def test_static_publisher_rejects_bad_arguments(stp, args):
    with pytest.raises(ValueError):
        stp.parse_args(args.split())


def test_static_publisher_bad_arguments_exit_1_with_usage_and_no_traceback():
    proc = subprocess.run([str(SCRIPTS / "static_transform_publisher"), "1", "2"],
                          capture_output=True, text=True, timeout=30,
                          env=dict(BUNDLED_ENV, ROS_MASTER_URI="http://127.0.0.1:1/"))
    assert proc.returncode == 1
    assert "usage" in proc.stderr and "Traceback" not in proc.stderr


TREE = {"odom": "map", "base_link": "odom", "laser": "base_link", "camera": "base_link",
        "turtle1": "world"}


def test_layout_puts_children_one_row_below_and_parent_centred_over_them():
    pos = layout(TREE)
    assert pos["map"][1] == 0 and pos["laser"][1] == 3
    assert pos["base_link"][0] == (pos["camera"][0] + pos["laser"][0]) / 2
    xs = [pos[leaf][0] for leaf in ("camera", "laser", "turtle1")]
    assert len(set(xs)) == 3  # leaves never overlap


def test_dot_and_svg_name_every_frame_and_edge():
    info = {"odom": {"parent": "map", "static": False, "samples": 11, "oldest": 0.0,
                     "newest": 1.0}}
    dot = tree_dot(TREE, info)
    assert '"map" -> "odom" [label="10.0 Hz"]' in dot
    svg = tree_svg(TREE, info)
    for frame in ("map", "odom", "base_link", "laser", "camera", "world", "turtle1"):
        assert f">{frame}</text>" in svg
    assert svg.count("<line ") == len(TREE)


@pytest.fixture
def master():
    from orchestra.master import start_master
    handle = start_master(port=0)
    yield handle.uri
    handle.shutdown()


@pytest.mark.timeout(120)
def test_static_transform_reaches_tf_echo_and_view_frames(master, tmp_path):
    env = dict(BUNDLED_ENV, ROS_MASTER_URI=master, PYTHONUNBUFFERED="1")
    procs = []
    readers: list[threading.Thread] = []
    echo_err = open(tmp_path / "tf_echo.err", "w+")
    try:
        procs.append(subprocess.Popen(
            [str(SCRIPTS / "static_transform_publisher"), "1", "2", "0", "1.5707963", "0", "0",
             "base_link", "laser"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        procs.append(subprocess.Popen(
            [str(SCRIPTS / "static_transform_publisher"), "0", "0", "0", "0", "0", "0", "1",
             "odom", "base_link", "20"], env=env, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL))
        echo = subprocess.Popen([str(SCRIPTS / "tf_echo"), "odom", "laser", "10"], env=env,
                                stdout=subprocess.PIPE, stderr=echo_err, text=True)
        procs.append(echo)
        lines: list[str] = []
        complete = threading.Event()

        def read_echo() -> None:
            for line in echo.stdout:
                lines.append(line)
                if line.startswith("            in RPY (degree)"):
                    complete.set()
                    return
        reader = threading.Thread(target=read_echo, daemon=True)
        readers.append(reader)
        reader.start()
        view = subprocess.run([str(SCRIPTS / "view_frames"), "2", str(tmp_path / "frames")],
                              env=env, capture_output=True, text=True, timeout=40)
        assert view.returncode == 0, view.stderr
        if not complete.wait(30):
            echo_err.seek(0)
            pytest.fail("tf_echo printed no full transform; stdout:\n" + "".join(lines)[-3000:]
                        + "\nstderr:\n" + echo_err.read()[-3000:])
        text = "".join(lines)
        assert "- Translation: [1.000, 2.000, 0.000]" in text
        assert re.search(r"in RPY \(degree\) \[0\.000, -?0\.000, 90\.000\]", text)
        dot = (tmp_path / "frames.gv").read_text()
        assert '"odom" -> "base_link"' in dot and '"base_link" -> "laser" [label="static"]' in dot
        assert ">laser</text>" in (tmp_path / "frames.svg").read_text()
        if shutil.which("dot"):  # like ROS's view_frames: frames.pdf through graphviz
            assert (tmp_path / "frames.pdf").read_bytes().startswith(b"%PDF")
    finally:
        for p in procs:
            p.send_signal(signal.SIGINT)
        for p in procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        echo_err.close()
        for reader in readers:          # up to the end of the pipe (or the line it wanted)
            reader.join(10)
        for p in procs:
            if p.stdout is not None:
                p.stdout.close()
