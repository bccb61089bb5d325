"""turtlesim_node as a process: its services, topics, walls, pens and PNG snapshots, driven by
a client process through the topic/service API against a master on a free port."""
from __future__ import annotations

import contextlib
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from test_turtlesim_world import read_png

# orchestra's bundled packages, whatever ROS workspace the developer's shell points at
BUNDLED_ENV = {k: v for k, v in os.environ.items()
               if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH")}

SIM = Path(__file__).resolve().parent.parent / "packages" / "turtlesim" / "scripts" / \
    "turtlesim_node"

CLIENT = r'''
import json, sys, time
import orchestra.node as node
from orchestra.node.msg import get_message_class, get_service_class
node.init_node("turtlesim_test_client")
Pose = get_message_class("turtlesim/Pose")
Twist = get_message_class("geometry_msgs/Twist")
srv = lambda t: get_service_class(t)
out = {}
def call(service, kind, **fields):
    node.wait_for_service(service, timeout=20)
    try:
        return node.ServiceProxy(service, srv(kind))(**fields)
    except node.ServiceException as exc:
        return "error: " + str(exc)
def pose(turtle):
    time.sleep(0.1)  # a tick or two after the request
    m = node.wait_for_message(f"/{turtle}/pose", Pose, timeout=10)
    return [round(m.x, 3), round(m.y, 3), round(m.theta, 3)]
out["start"] = pose("turtle1")
out["spawn"] = call("/spawn", "turtlesim/Spawn", x=1.0, y=1.0, theta=0.0, name="").name
out["spawn_dup"] = call("/spawn", "turtlesim/Spawn", x=1.0, y=1.0, theta=0.0, name="turtle2")
call("/turtle2/teleport_absolute", "turtlesim/TeleportAbsolute", x=3.0, y=4.0, theta=1.0)
out["abs"] = pose("turtle2")
call("/turtle2/teleport_relative", "turtlesim/TeleportRelative", linear=1.0, angular=0.5)
out["rel"] = pose("turtle2")
out["kill"] = str(call("/kill", "turtlesim/Kill", name="turtle2"))
out["kill_again"] = call("/kill", "turtlesim/Kill", name="turtle2")
call("/turtle1/set_pen", "turtlesim/SetPen", r=255, g=0, b=0, width=4, off=0)
call("/turtle1/teleport_absolute", "turtlesim/TeleportAbsolute", x=8.0, y=8.0, theta=0.0)
node.set_param("/sim/snapshot_path", sys.argv[1] + "/pen.png")
call("/sim/snapshot", "std_srvs/Empty")
pub = node.Publisher("/turtle1/cmd_vel", Twist, queue_size=1)
for _ in range(15):
    t = Twist(); t.linear.x = 20.0; pub.publish(t); time.sleep(0.05)
out["wall"] = pose("turtle1")
for c in "rgb":
    node.set_param("/sim/background_" + c, 0)
call("/reset", "std_srvs/Empty")
out["reset"] = pose("turtle1")
node.set_param("/sim/snapshot_path", sys.argv[1] + "/reset.png")
call("/sim/snapshot", "std_srvs/Empty")
print(json.dumps(out), flush=True)
'''


@pytest.fixture
def master():
    from orchestra.master import start_master
    handle = start_master(port=0)
    yield handle.uri
    handle.shutdown()


@pytest.mark.timeout(90)
def test_turtlesim_node_services_topics_walls_and_snapshots(master, tmp_path):
    env = dict(BUNDLED_ENV, ROS_MASTER_URI=master, PYTHONUNBUFFERED="1")
    env.pop("DISPLAY", None)
    sim = subprocess.Popen([str(SIM), "__name:=sim"], env=env, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    try:
        client = subprocess.run([sys.executable, "-c", CLIENT, str(tmp_path)], env=env,
                                capture_output=True, text=True, timeout=80)
        assert client.returncode == 0, client.stderr
        out = json.loads(client.stdout.strip().splitlines()[-1])
    finally:
        sim.send_signal(signal.SIGINT)
        try:
            sim.wait(15)
        except subprocess.TimeoutExpired:
            sim.kill()
            sim.wait()
    assert sim.returncode == 0
    assert out["start"] == pytest.approx([5.544, 5.544, 0.0], abs=1e-3)
    assert out["spawn"] == "turtle2"
    assert "A turtle named [turtle2] already exists" in out["spawn_dup"]
    assert out["abs"] == pytest.approx([3.0, 4.0, 1.0], abs=1e-3)
    # turn by 0.5 first, then 1 m along the new heading 1.5 rad
    assert out["rel"] == pytest.approx([3.071, 4.997, 1.5], abs=2e-3)
    assert "does not exist" in out["kill_again"]
    assert out["wall"][0] == pytest.approx(11.089, abs=1e-3)  # clamped at the east wall
    assert out["reset"] == pytest.approx([5.544, 5.544, 0.0], abs=1e-3)

    width, _, pen = read_png((tmp_path / "pen.png").read_bytes())
    px, py = int(6.5 * 45), int((11.0889 - 6.5) * 45)  # on the red line (5.5,5.5)->(8,8)
    i = (py * width + px) * 3
    assert tuple(pen[i:i + 3]) == (255, 0, 0)
    _, _, reset = read_png((tmp_path / "reset.png").read_bytes())
    assert tuple(reset[0:3]) == (0, 0, 0)  # cleared with the new background params
    assert tuple(reset[i:i + 3]) == (0, 0, 0)  # and the old trail is gone


READ_POSE = r'''
import orchestra.node as node
from orchestra.node.msg import get_message_class
node.init_node("gui_test_reader", anonymous=True)
m = node.wait_for_message("/turtle1/pose", get_message_class("turtlesim/Pose"), timeout=20)
print(m.x)
'''


def _interrupt(sim: subprocess.Popen) -> str:
    """Ctrl-C the node (SIGKILL if it hangs) and return everything it printed."""
    sim.send_signal(signal.SIGINT)
    try:
        output, _ = sim.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        sim.kill()
        output, _ = sim.communicate()
    return output


@pytest.mark.timeout(60)
def test_gui_requested_on_an_unusable_display_falls_back_to_headless(master):
    env = dict(BUNDLED_ENV, ROS_MASTER_URI=master, DISPLAY=":987", PYTHONUNBUFFERED="1")
    sim = subprocess.Popen([str(SIM), "_gui:=true"], env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
    try:
        reader = subprocess.run([sys.executable, "-c", READ_POSE], env=env, capture_output=True,
                                text=True, timeout=40)
        assert reader.returncode == 0, reader.stderr
        assert float(reader.stdout.split()[-1]) == pytest.approx(5.544, abs=1e-3)
    finally:
        output = _interrupt(sim)
    assert sim.returncode == 0
    assert "cannot open a window" in output and "running headless" in output
    assert "Traceback" not in output


@pytest.mark.timeout(60)
def test_headless_simulator_says_so_and_how_to_get_a_picture(master):
    env = {k: v for k, v in BUNDLED_ENV.items() if k != "DISPLAY"}
    env.update(ROS_MASTER_URI=master, PYTHONUNBUFFERED="1")
    sim = subprocess.Popen([str(SIM)], env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
    try:
        reader = subprocess.run([sys.executable, "-c", READ_POSE], env=env, capture_output=True,
                                text=True, timeout=40)
        assert reader.returncode == 0, reader.stderr
    finally:
        output = _interrupt(sim)
    assert "runs headless" in output and "snapshot:=" in output


@contextlib.contextmanager
def _virtual_screen():
    """Start Xvfb on a display it picks itself and yield ":N" once it accepts clients.

    `-displayfd` makes Xvfb choose a free display and write its number only when the server
    is ready, so the node under test never races a half-started X server (a Tk that cannot
    connect falls back to headless, and the window would never appear).
    """
    read_end, write_end = os.pipe()
    log = tempfile.TemporaryFile()
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write_end), "-screen", "0", "800x600x24",
                             "-nolisten", "tcp"], pass_fds=(write_end,),
                            stdout=subprocess.DEVNULL, stderr=log)
    os.close(write_end)
    try:
        ready, _, _ = select.select([read_end], [], [], 60)
        number = os.read(read_end, 32).decode().strip() if ready else ""
        if not number:
            xvfb.kill()
            xvfb.wait()
            log.seek(0)
            pytest.fail(f"Xvfb did not start: {log.read().decode(errors='replace')[-2000:]}")
        yield f":{number}"
    finally:
        os.close(read_end)
        log.close()
        if xvfb.poll() is None:
            xvfb.terminate()
            try:
                xvfb.wait(timeout=10)
            except subprocess.TimeoutExpired:
                xvfb.kill()
                xvfb.wait()


@pytest.mark.timeout(120)
@pytest.mark.skipif(not (shutil.which("Xvfb") and shutil.which("xwd")),
                    reason="Xvfb and xwd (Debian xvfb, x11-apps) are not installed")
def test_gui_window_shows_the_canvas_on_a_real_x_server(master, tmp_path):
    """On a desktop (DISPLAY set) turtlesim opens its Tk window: dump it and find the canvas."""
    with _virtual_screen() as display:
        _check_turtlesim_window(master, tmp_path, display)


def _check_turtlesim_window(master: str, tmp_path, display: str) -> None:
    import time

    env = dict(BUNDLED_ENV, ROS_MASTER_URI=master, DISPLAY=display, PYTHONUNBUFFERED="1")
    sim = subprocess.Popen([str(SIM)], env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
    dump = tmp_path / "window.xwd"
    appeared = False
    try:
        deadline = time.monotonic() + 40
        while time.monotonic() < deadline and sim.poll() is None:
            grabbed = subprocess.run(["xwd", "-silent", "-name", "TurtleSim", "-out", str(dump)],
                                     env=env, capture_output=True, timeout=20)
            if grabbed.returncode == 0 and dump.stat().st_size > 500 * 500 * 3:
                appeared = True
                break
            time.sleep(0.3)
    finally:
        output = _interrupt(sim)
    assert appeared, f"no TurtleSim window appeared on {display}; turtlesim said:\n{output}"
    # 24/32-bit TrueColor dumps store pixels as B, G, R, pad: the default background
    # (69, 86, 255) must fill most of the window
    assert dump.read_bytes().count(bytes((255, 86, 69))) > 200_000
    assert sim.returncode == 0, output
    assert "running headless" not in output and "Traceback" not in output
