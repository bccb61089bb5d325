"""TurtleBot minimal bring-up: the launch files resolve like a TurtleBot user expects, and,
run for real with ``orchestra launch``, a Twist on the teleop mux input moves /odom while
/diagnostics_agg reports the base's diagnostics. Headless, a few seconds."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import free_port  # noqa: E402

REPO = Path(__file__).resolve().parent.parent


def clean_env(tmp_path: Path, **extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("TURTLEBOT_", "ROS_"))}
    env["ROS_HOME"] = str(tmp_path / "ros_home")
    env.update(extra)
    return env


def dump_plan(tmp_path: Path, *words: str, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "orchestra", "launch", "turtlebot_bringup",
                           "minimal.launch", "--dump-plan", *words],
                          env=clean_env(tmp_path, **env), capture_output=True, text=True,
                          timeout=60)


# ---- the launch files, resolved without running anything ---------------------------------
def test_minimal_launch_brings_up_the_turtlebot_nodes_in_a_bare_shell(tmp_path):
    result = dump_plan(tmp_path)
    assert result.returncode == 0, result.stderr
    plan = json.loads(result.stdout)
    nodes = {n["name"]: n for n in plan["nodes"]}
    assert set(nodes) == {"robot_state_publisher", "diagnostic_aggregator",
                          "mobile_base_nodelet_manager", "mobile_base", "cmd_vel_mux",
                          "kinect_breaker_enabler", "robot_pose_ekf"}
    assert nodes["mobile_base"]["args"] == "load kobuki_node/KobukiNodelet mobile_base_nodelet_manager"
    assert ["cmd_vel_mux/output", "mobile_base/commands/velocity"] in nodes["cmd_vel_mux"]["remap_args"]
    params = plan["params"]
    assert params["/use_sim_time"] is False
    assert params["/diagnostic_aggregator/analyzers/kobuki/path"] == "Kobuki"
    assert params["/mobile_base/device_port"] == "/dev/kobuki"
    assert "asus_xtion_pro" in params["/robot_description"]


def test_turtlebot_environment_variables_choose_the_defaults(tmp_path):
    result = dump_plan(tmp_path, TURTLEBOT_3D_SENSOR="kinect",
                       TURTLEBOT_SERIAL_PORT="/dev/ttyUSB0")
    assert result.returncode == 0, result.stderr
    params = json.loads(result.stdout)["params"]
    assert "kinect" in params["/robot_description"]
    assert params["/mobile_base/device_port"] == "/dev/ttyUSB0"


def test_battery_arg_adds_the_laptop_battery_monitor(tmp_path):
    result = dump_plan(tmp_path, "battery:=/sys/class/power_supply/BAT1")
    assert result.returncode == 0, result.stderr
    plan = json.loads(result.stdout)
    assert "turtlebot_laptop_battery" in [n["name"] for n in plan["nodes"]]
    assert plan["params"]["/turtlebot_laptop_battery/acpi_path"] == "/sys/class/power_supply/BAT1"


def test_unknown_base_is_a_clear_error_naming_the_missing_file(tmp_path):
    result = dump_plan(tmp_path, "base:=roomba")
    assert result.returncode != 0
    assert "roomba" in result.stderr and "Traceback" not in result.stderr


# ---- the bring-up, running ---------------------------------------------------------------
PROBE = textwrap.dedent('''
    import json, sys, threading, time
    from orchestra import node
    from orchestra.node.msg import get_message_class as M

    node.init_node("turtlebot_probe", anonymous=True)
    lock = threading.Lock()
    seen = {"odom": [], "agg": None, "active": [], "ekf": None, "tf_static": [], "tf": [],
            "core": [], "imu": None}

    def keep(key, value, append=False):
        with lock:
            if append:
                seen[key].append(value)
            else:
                seen[key] = value

    node.Subscriber("/odom", M("nav_msgs/Odometry"), lambda m: keep(
        "odom", [m.pose.pose.position.x, m.pose.pose.position.y, m.child_frame_id], True))
    node.Subscriber("/diagnostics_agg", M("diagnostic_msgs/DiagnosticArray"), lambda m: keep(
        "agg", [[s.name, int(s.level), s.message] for s in m.status]))
    node.Subscriber("/cmd_vel_mux/active", M("std_msgs/String"),
                    lambda m: keep("active", m.data, True))
    node.Subscriber("/robot_pose_ekf/odom_combined",
                    M("geometry_msgs/PoseWithCovarianceStamped"),
                    lambda m: keep("ekf", [m.pose.pose.position.x, m.header.frame_id,
                                           m.pose.covariance[0], m.pose.covariance[35]]))
    node.Subscriber("/mobile_base/sensors/core", M("kobuki_msgs/SensorState"), lambda m: keep(
        "core", [m.left_encoder, m.right_encoder, m.battery], True))
    node.Subscriber("/mobile_base/sensors/imu_data", M("sensor_msgs/Imu"), lambda m: keep(
        "imu", [m.header.frame_id, m.orientation.w]))
    node.Subscriber("/tf_static", M("tf2_msgs/TFMessage"), lambda m: keep(
        "tf_static", [t.child_frame_id for t in m.transforms]))
    def on_tf(m):
        with lock:
            seen["tf"] = sorted(set(seen["tf"]) | {t.child_frame_id for t in m.transforms})
    node.Subscriber("/tf", M("tf2_msgs/TFMessage"), on_tf)
    teleop = node.Publisher("/cmd_vel_mux/input/teleop", M("geometry_msgs/Twist"))

    deadline = time.time() + float(sys.argv[1])
    def wait(pred):
        while time.time() < deadline:
            with lock:
                if pred():
                    return True
            time.sleep(0.05)
        return False

    wait(lambda: seen["odom"] and seen["core"])
    with lock:
        start = seen["odom"][-1] if seen["odom"] else None
        core_start = seen["core"][-1] if seen["core"] else None
    twist = M("geometry_msgs/Twist")()
    twist.linear.x = 0.4
    stop = time.time() + 1.5
    while time.time() < stop:
        teleop.publish(twist)
        time.sleep(0.1)
    time.sleep(1.0)   # the base's 0.6 s command timeout stops it
    # an aggregate sent before the base's first diagnostics has its groups only (stale)
    wait(lambda: seen["agg"] is not None and seen["ekf"] is not None
         and any(s[0] == "/Power System/Battery" for s in seen["agg"]))
    wait(lambda: seen["active"][-1:] == ["idle"])
    with lock:
        seen["start"] = start
        seen["core"] = [core_start, seen["core"][-1]] if seen["core"] else []
        sys.stdout.write(json.dumps(seen) + "\\n")
    node.signal_shutdown("probe done")
''')


@pytest.fixture
def bringup(tmp_path):
    port = free_port()
    env = clean_env(tmp_path, ROS_MASTER_URI=f"http://127.0.0.1:{port}/")
    log = open(tmp_path / "launch.log", "w")  # a file, not a pipe nobody drains
    proc = subprocess.Popen([sys.executable, "-m", "orchestra", "launch", "turtlebot_bringup",
                             "minimal.launch"], env=env, stdout=log, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True)
    yield proc, env
    log.close()
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


@pytest.mark.timeout(90)
def test_teleop_twist_through_the_mux_moves_odom_and_diagnostics_are_aggregated(bringup, tmp_path):
    proc, env = bringup
    probe = tmp_path / "probe.py"
    probe.write_text(PROBE)
    result = subprocess.run([sys.executable, str(probe), "30"], env=env, capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    seen = json.loads(result.stdout.strip().splitlines()[-1])

    # the Twist went teleop -> mux -> base, and the base integrated it into /odom
    start, end = seen["start"], seen["odom"][-1]
    assert start is not None, "no /odom from the base"
    assert end[0] - start[0] > 0.4          # 0.4 m/s for 1.5 s (+ up to 0.6 s timeout)
    assert end[0] - start[0] < 1.2
    assert abs(end[1] - start[1]) < 0.05
    assert end[2] == "base_footprint"
    assert seen["active"][-2:] == ["Teleoperation", "idle"]

    # the aggregator sorted the base's diagnostics, nothing left over, all OK
    agg = {name: level for name, level, _ in seen["agg"]}
    messages = {name: message for name, _, message in seen["agg"]}
    for name in ("/Power System/Battery", "/Kobuki/Watchdog", "/Sensors/Gyro Sensor",
                 "/Input Ports/Digital Input"):
        assert agg.get(name) == 0, (name, agg)
    assert not any(name.startswith("/Other") for name in agg)
    # the kinect breaker enabler switched the sensor rail on through the base's service
    assert messages["/Kobuki/External Power"] == "[0, 1, 0, 0]"

    # the filter followed the odometry; the URDF's fixed frames are on /tf_static
    ekf_x, frame, var_x, var_yaw = seen["ekf"]
    assert frame == "odom_combined"
    assert abs(ekf_x - (end[0] - start[0])) < 0.2
    assert var_x > 0 and var_yaw > 0

    # the base's raw sensors: both wheel encoders counted the drive, battery ~16.5 V, gyro
    (left0, right0, battery), (left1, right1, _) = seen["core"]
    driven = end[0] - start[0]
    ticks = driven / (0.035 * 0.002436916871363930187454)
    for before, after in ((left0, left1), (right0, right1)):
        assert abs((after - before) % 65536 - ticks) < 0.2 * ticks + 50
    assert 160 <= battery <= 165
    assert seen["imu"][0] == "gyro_link"
    assert {"base_link", "gyro_link", "camera_rgb_frame"} <= set(seen["tf_static"])
    # /tf: odom -> base_footprint from the base, the wheels from joint_states via the URDF
    assert {"base_footprint", "wheel_left_link", "wheel_right_link"} <= set(seen["tf"])

    # Ctrl-C stops the whole bring-up cleanly
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=20)
    output = (tmp_path / "launch.log").read_text()
    assert proc.returncode == 0, output
    assert "kinect_breaker_enabler]: has finished cleanly" in output
