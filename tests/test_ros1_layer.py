"""orchestra's ROS 1 layer (orchestra/ros1/site): rospy, tf, tf2_ros, message_filters,
actionlib, roslib, rospkg, rosgraph as unmodified ROS code sees them.

- API shape: every public name of Debian's real modules exists in the layer with the same
  parameter names and kinds (tests/ros1_layer/api_shape.py run under both interpreters);
- behaviour: tests/ros1_layer/rospy_behaviours.py gives the same answers on the layer as on
  real rospy (topics made before init_node, SubscribeListener, a Service's error_handler,
  log_level=rospy.DEBUG, *_once/*_throttle, get_master, names, time, shutdown hooks);
- tf.transformations against real tf's numbers in all 24 Euler conventions;
- message_filters' synchronizers and cache on plain messages;
- importing rospy is cheap: no runtime is loaded until a name is used.
Tests that need Debian's ROS 1 skip with the reason when it is absent.
"""
from __future__ import annotations

import importlib
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
SITE = REPO / "orchestra" / "ros1" / "site"
HERE = Path(__file__).resolve().parent / "ros1_layer"
ROS_PYTHON = "/usr/bin/python3"

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
import harness  # noqa: E402


def layer_env(**extra: str) -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(SITE), str(REPO)]), **extra)
    env.pop("ROS_NAMESPACE", None)
    return env


def real_env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "ROS_NAMESPACE")}
    env.update(extra)
    return env


def real_ros_has(*modules: str) -> bool:
    if not os.path.exists(ROS_PYTHON):
        return False
    probe = subprocess.run([ROS_PYTHON, "-c", "import " + ", ".join(modules)],
                           env=real_env(), capture_output=True, timeout=60)
    return probe.returncode == 0


def need_real(*modules: str) -> None:
    if not real_ros_has(*modules):
        pytest.skip(f"Debian's ROS 1 ({', '.join(modules)} under {ROS_PYTHON}) is not installed")


# --- API shape --------------------------------------------------------------------------------

#: methods compared for the classes code uses most (the rest of a real class is internals)
METHODS = {
    "Publisher": ["publish", "get_num_connections", "unregister"],
    "Subscriber": ["get_num_connections", "unregister"],
    "ServiceProxy": ["call", "close", "wait_for_service"],
    "Service": ["shutdown", "spin"],
    "Rate": ["sleep", "remaining"],
    "Time": ["now", "from_sec", "to_sec", "to_nsec", "is_zero", "set", "canon"],
    "Duration": ["from_sec", "to_sec", "to_nsec", "is_zero"],
    "Timer": ["shutdown"],
    "TransformListener": ["lookupTransform", "waitForTransform", "canTransform",
                          "transformPoint", "transformPose", "getLatestCommonTime",
                          "lookupTransformFull", "frameExists", "getFrameStrings"],
    "TransformBroadcaster": ["sendTransform", "sendTransformMessage"],
    "Buffer": ["lookup_transform", "can_transform", "lookup_transform_full",
               "can_transform_full"],
    "SimpleActionServer": ["start", "accept_new_goal", "is_new_goal_available",
                           "is_preempt_requested", "is_active", "set_succeeded", "set_aborted",
                           "set_preempted", "publish_feedback", "register_goal_callback",
                           "register_preempt_callback", "get_default_result"],
    "SimpleActionClient": ["wait_for_server", "send_goal", "send_goal_and_wait",
                           "wait_for_result", "get_result", "get_state",
                           "get_goal_status_text", "cancel_goal", "cancel_all_goals",
                           "cancel_goals_at_and_before_time", "stop_tracking_goal"],
    "Cache": ["add", "getElemAfterTime", "getElemBeforeTime", "getInterval",
              "getLastestTime", "getOldestTime", "getLast"],
    "TimeSynchronizer": ["add", "connectInput", "registerCallback", "signalMessage"],
    "ApproximateTimeSynchronizer": ["add", "registerCallback"],
    "RosPack": ["get_path", "list", "get_depends", "get_depends_on"],
}

#: the message classes' own shape is orchestra.node.msg's business (genpy compatibility)
NOT_HERE = {"Header", "Message", "AnyMsg", "GoalStatus"}

LAYER_API = {
    "tf": ["TransformListener", "TransformBroadcaster", "Transformer", "Exception",
           "LookupException", "ConnectivityException", "ExtrapolationException"],
    "tf.transformations": [
        "quaternion_from_euler", "euler_from_quaternion", "quaternion_multiply",
        "quaternion_inverse", "quaternion_conjugate", "quaternion_slerp", "quaternion_matrix",
        "quaternion_from_matrix", "quaternion_about_axis", "euler_matrix", "euler_from_matrix",
        "translation_matrix", "translation_from_matrix", "rotation_matrix",
        "concatenate_matrices", "inverse_matrix", "identity_matrix", "unit_vector",
        "vector_norm", "random_quaternion", "random_rotation_matrix", "compose_matrix",
        "decompose_matrix", "is_same_transform", "scale_matrix"],
    "tf2_ros": ["Buffer", "TransformListener", "LookupException", "ConnectivityException",
                "ExtrapolationException", "TransformException", "InvalidArgumentException",
                "TimeoutException"],
    "message_filters": ["Subscriber", "Cache", "TimeSynchronizer",
                        "ApproximateTimeSynchronizer", "SimpleFilter"],
    "actionlib": ["SimpleActionServer", "SimpleActionClient", "SimpleGoalState"],
    "roslib": ["load_manifest"],
    "roslib.packages": ["get_pkg_dir", "find_node", "InvalidROSPkgException"],
    "roslib.message": ["get_message_class", "get_service_class"],
    "rospkg": ["RosPack", "ResourceNotFound", "get_ros_home", "get_log_dir",
               "get_ros_package_path"],
    "rosgraph": ["Master", "get_master_uri", "is_master_online", "myargv", "MasterError",
                 "MasterFailure", "MasterException"],
    "rosgraph.names": ["ns_join", "resolve_name", "get_ros_namespace", "make_global_ns",
                       "is_global", "is_private", "namespace", "canonicalize_name",
                       "anonymous_name", "load_mappings", "script_resolve_name",
                       "make_caller_id", "is_legal_name", "is_legal_base_name"],
}


def api_shape(python: str, env: dict[str, str], request: dict[str, list[str]]) -> dict:
    proc = subprocess.run([python, str(HERE / "api_shape.py"), json.dumps(request)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def named(params: list | None) -> list | None:
    """Parameters minus the names of ``*args``/``**kwargs`` (``kwds`` or ``kwargs``)."""
    if params is None:
        return None
    return [(name if kind not in ("VAR_POSITIONAL", "VAR_KEYWORD") else "*", kind)
            for name, kind in params]


def differences(real: dict, ours: dict) -> list[str]:
    found = []
    for module, names in real.items():
        for name, want in names.items():
            have = ours[module].get(name)
            where = f"{module}.{name}"
            if want is None:
                continue
            if have is None:
                found.append(f"{where}: missing")
                continue
            if want["kind"] != have["kind"]:
                found.append(f"{where}: a {have['kind']}, real: a {want['kind']}")
            if name in NOT_HERE:
                continue
            # tf's TransformListener takes (*args, **kwargs) and passes them to Transformer
            if want.get("params") not in (None, [["args", "VAR_POSITIONAL"],
                                                  ["kwargs", "VAR_KEYWORD"]]) \
                    and named(want.get("params")) != named(have.get("params")):
                found.append(f"{where}{want.get('params')} vs ours {have.get('params')}")
            for method in METHODS.get(name, []) if want["kind"] == "class" else []:
                w, h = want["methods"].get(method, "absent"), have["methods"].get(method)
                if w == "absent":
                    continue
                if h is None or named(w) != named(h):
                    found.append(f"{where}.{method}{w} vs ours {h}")
    return found


def test_rospy_has_every_public_name_of_real_rospy_with_its_signature():
    need_real("rospy")
    names = json.loads(subprocess.run(
        [ROS_PYTHON, "-c", "import json, rospy; print(json.dumps(rospy.__all__))"],
        env=real_env(), capture_output=True, text=True, timeout=60).stdout)
    request = {"rospy": sorted(set(names) | {"Timer", "ROSTimeMovedBackwardsException",
                                             "get_time", "wait_for_message"})}
    real = api_shape(ROS_PYTHON, real_env(), request)
    ours = api_shape(sys.executable, layer_env(), request)
    assert differences(real, ours) == []


def test_tf_actionlib_message_filters_and_friends_match_the_real_modules():
    need_real("tf", "tf2_ros", "actionlib", "message_filters", "rospkg", "roslib", "rosgraph")
    real = api_shape(ROS_PYTHON, real_env(), LAYER_API)
    ours = api_shape(sys.executable, layer_env(), LAYER_API)
    assert differences(real, ours) == []


def test_importing_rospy_loads_no_runtime_until_a_name_is_used():
    code = ("import sys, rospy; before = 'orchestra.node.runtime' in sys.modules; "
            "rospy.init_node; print(before, 'orchestra.node.runtime' in sys.modules, "
            "'init_node' in dir(rospy), callable(rospy.loginfo_once))")
    out = subprocess.run([sys.executable, "-c", code], env=layer_env(), capture_output=True,
                         text=True, timeout=60)
    assert out.stdout.split() == ["False", "True", "True", "True"], out.stderr


def test_layer_names_unknown_to_rospy_raise_attribute_error():
    code = "import rospy\ntry:\n    rospy.no_such_thing\nexcept AttributeError as e:\n    print(e)"
    out = subprocess.run([sys.executable, "-c", code], env=layer_env(), capture_output=True,
                         text=True, timeout=60)
    assert "no attribute 'no_such_thing'" in out.stdout


# --- behaviour, the same as real rospy ---------------------------------------------------------

def behaviours(master, python: str, env: dict[str, str]) -> tuple[list[dict], list[str]]:
    group = harness.ProcessGroup(master.uri)
    try:
        node = group._start([python, str(HERE / "rospy_behaviours.py")],
                            dict(env, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1"))
        node.expect(lambda d: "shutdown" in d, timeout=30)
        node.wait(10)
        return [d for d in node.seen if "text" not in d], [d["text"] for d in node.seen
                                                            if "text" in d]
    finally:
        group.close()


EXPECTED_BEHAVIOUR = [
    {"publish_before_init": "refused"},
    {"early_topic": "after init"},
    {"greeting": "welcome 1"},
    {"service_error": True, "error_handler": ["no True"]},
    {"none_handler": True, "error_handler": []},
    {"master_pid_code": 1},
    {"names": ["/behaviours", "/", "/x", "/behaviours/y", "/behaviours"]},
    {"myargv": ["script", "arg"]},
    {"time": [True, True, 1.5, 3000000005]},
    {"shutdown": [True, True]},
]


def test_rospy_behaviours_on_the_layer(master):
    results, console = behaviours(master, sys.executable, layer_env())
    assert results == EXPECTED_BEHAVIOUR
    # log_level=rospy.DEBUG shows debug lines; *_once and *_throttle log once from a loop
    assert [line for line in console if "debug once" in line] == \
        [line for line in console if "debug once 0" in line] != []
    assert len([line for line in console if "throttled" in line]) == 1


def test_rospy_behaviours_are_real_rospys(master):
    need_real("rospy", "std_msgs", "std_srvs")
    results, console = behaviours(master, ROS_PYTHON, real_env())
    assert results == EXPECTED_BEHAVIOUR
    assert len([line for line in console if "throttled" in line]) == 1


# --- tf.transformations -------------------------------------------------------------------------

@pytest.fixture
def layer_modules():
    """Import layer modules into this process, then forget them (and the path) again."""
    before = set(sys.modules)
    sys.path.insert(0, str(SITE))
    try:
        yield importlib.import_module
    finally:
        sys.path.remove(str(SITE))
        for name in set(sys.modules) - before:
            if (getattr(sys.modules[name], "__file__", None) or "").startswith(str(SITE)):
                del sys.modules[name]


AXES = [s + a + b + c for s in "sr" for a in "xyz" for b in "xyz" for c in "xyz"
        if a != b and b != c]


def test_euler_angles_round_trip_in_all_24_conventions(layer_modules):
    t = layer_modules("tf.transformations")
    for axes in AXES:
        angles = (0.3, -0.7, 1.1)
        m = t.euler_matrix(*angles, axes=axes)
        assert t.is_same_transform(t.euler_matrix(*t.euler_from_matrix(m, axes), axes=axes), m)
        q = t.quaternion_from_euler(*angles, axes=axes)
        assert t.is_same_transform(t.quaternion_matrix(q), m)
        back = t.quaternion_from_matrix(m)
        assert min(abs(back - q).max(), abs(back + q).max()) < 1e-9
    # the tutorials' use: a yaw about Z
    assert list(t.quaternion_from_euler(0, 0, math.pi / 2)) == pytest.approx(
        [0, 0, math.sqrt(0.5), math.sqrt(0.5)])


def test_tf_transformations_give_real_tfs_numbers(layer_modules):
    need_real("tf")
    t = layer_modules("tf.transformations")
    cases = []
    for i, axes in enumerate(AXES):
        for angles in ([0.3 + i / 50, -0.7, 1.1], [0.2, 0.0 if axes[1] == axes[3] else math.pi / 2,
                                                    -0.4]):
            m = t.euler_matrix(*angles, axes=axes)
            cases.append({"axes": axes, "angles": angles, "matrix": m.tolist(),
                          "euler": list(t.euler_from_matrix(m, axes)),
                          "q": list(t.quaternion_from_euler(*angles, axes=axes))})
    script = (
        "import json, sys, numpy as np, tf.transformations as t\n"
        "bad = []\n"
        "for c in json.load(sys.stdin):\n"
        "    m = t.euler_matrix(*c['angles'], axes=c['axes'])\n"
        "    q = t.quaternion_from_euler(*c['angles'], axes=c['axes'])\n"
        "    ok = (np.allclose(m, c['matrix']) and np.allclose(t.euler_from_matrix(m, c['axes']),"
        " c['euler']) and (np.allclose(q, c['q']) or np.allclose(q, -np.array(c['q']))))\n"
        "    if not ok: bad.append(c['axes'])\n"
        "print(json.dumps(bad))\n")
    out = subprocess.run([ROS_PYTHON, "-c", script], input=json.dumps(cases), env=real_env(),
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == []


# --- message_filters ---------------------------------------------------------------------------

def stamped(layer_modules, secs: float, frame: str = "") -> object:
    from orchestra.node.msg import get_message_class
    from orchestra.node.rostime import Time

    msg = get_message_class("geometry_msgs/PointStamped")()
    msg.header.stamp = Time.from_sec(secs)
    msg.header.frame_id = frame
    return msg


def test_time_synchronizer_calls_back_with_messages_of_equal_stamps(layer_modules):
    mf = layer_modules("message_filters")
    a, b = mf.SimpleFilter(), mf.SimpleFilter()
    sync = mf.TimeSynchronizer([a, b], 10)
    got = []
    sync.registerCallback(lambda x, y, tag: got.append((x.header.frame_id, y.header.frame_id,
                                                        tag)), "t")
    a.signalMessage(stamped(layer_modules, 1.0, "a1"))
    a.signalMessage(stamped(layer_modules, 2.0, "a2"))
    b.signalMessage(stamped(layer_modules, 1.5, "b1.5"))   # no partner: nothing
    assert got == []
    b.signalMessage(stamped(layer_modules, 2.0, "b2"))
    assert got == [("a2", "b2", "t")]
    b.signalMessage(stamped(layer_modules, 1.0, "b1"))      # older than a match: dropped
    assert got == [("a2", "b2", "t")]


def test_approximate_synchronizer_pairs_stamps_within_the_slop(layer_modules):
    mf = layer_modules("message_filters")
    a, b = mf.SimpleFilter(), mf.SimpleFilter()
    sync = mf.ApproximateTimeSynchronizer([a, b], 10, slop=0.1)
    got = []
    sync.registerCallback(lambda x, y: got.append((x.header.frame_id, y.header.frame_id)))
    a.signalMessage(stamped(layer_modules, 1.00, "a"))
    b.signalMessage(stamped(layer_modules, 1.30, "far"))
    assert got == []
    b.signalMessage(stamped(layer_modules, 1.05, "near"))
    assert got == [("a", "near")]


def test_cache_keeps_the_newest_messages_by_stamp(layer_modules):
    mf = layer_modules("message_filters")
    from orchestra.node.rostime import Time

    source = mf.SimpleFilter()
    cache = mf.Cache(source, cache_size=3)
    passed = []
    cache.registerCallback(lambda m: passed.append(m.header.frame_id))
    for secs in (1, 3, 2, 4):
        source.signalMessage(stamped(layer_modules, secs, str(secs)))
    assert passed == ["1", "3", "2", "4"]
    assert cache.getOldestTime() == Time(2) and cache.getLastestTime() == Time(4)
    assert [m.header.frame_id for m in cache.getInterval(Time(2), Time(3))] == ["2", "3"]
    assert cache.getElemAfterTime(Time(2, 5)).header.frame_id == "3"
    assert cache.getElemBeforeTime(Time(2, 5)).header.frame_id == "2"
    assert cache.getLast().header.frame_id == "4"
    strict = mf.Cache(None, cache_size=2)
    strict.add("no header")  # refused (with a warning), as message_filters does
    assert strict.getLast() is None
    lenient = mf.Cache(None, cache_size=2, allow_headerless=True)
    lenient.add("no header")  # stamped with its arrival time
    assert lenient.getLast() == "no header" and lenient.getLastestTime() > Time(0)


def test_a_script_that_is_no_node_calls_a_remapped_service(master):
    """The tutorials' client never calls init_node; its remapping still applies here (rospy
    ignores it until init_node: docs/compat.md)."""
    scripts = HERE / "beginner_tutorials" / "scripts"
    env = layer_env(ROS_MASTER_URI=master.uri, ROS_PACKAGE_PATH=str(HERE),
                    PYTHONUNBUFFERED="1")
    group = harness.ProcessGroup(master.uri)
    try:
        group._start([sys.executable, str(scripts / "add_two_ints_server.py"),
                      "add_two_ints:=/elsewhere"], env)
        client = group._start([sys.executable, str(scripts / "add_two_ints_client.py"), "2",
                               "3", "add_two_ints:=/elsewhere"], env)
        assert client.expect(lambda d: " = " in d.get("text", ""), 30)["text"] == "2 + 3 = 5"
        assert client.wait(10) == 0
    finally:
        group.close()


# --- actionlib, the same as real actionlib ------------------------------------------------------

EXPECTED_ACTIONS = [
    {"server_found": [True, True]},
    {"succeeded": [True, 3, 5, "added", [[3, 5]], True, 2]},
    {"newer_ran": [True, 3, 9], "preempted_by_newer": [True, 2, -1]},
    {"cancelled": [True, 2, "preempted"]},
    {"states": [0, 3, 2]},
]


def action_run(master, python: str, env: dict[str, str]) -> list[dict]:
    group = harness.ProcessGroup(master.uri)
    try:
        node = group._start([python, str(HERE / "actionlib_behaviours.py")],
                            dict(env, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1"))
        node.expect(lambda d: "states" in d, timeout=60)
        return [d for d in node.seen if "text" not in d]
    finally:
        group.close()


def test_simple_action_server_and_client_semantics_on_the_layer(master):
    assert action_run(master, sys.executable, layer_env()) == EXPECTED_ACTIONS


def test_simple_action_semantics_are_real_actionlibs(master):
    need_real("rospy", "actionlib", "actionlib.msg")
    assert action_run(master, ROS_PYTHON, real_env()) == EXPECTED_ACTIONS
