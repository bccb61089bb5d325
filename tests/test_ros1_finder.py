"""The ROS 1 layer's imports: <pkg>.msg / <pkg>.srv modules, package modules, activation."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from orchestra.ros1 import activation, finder

REPO = Path(__file__).resolve().parent.parent
SYSTEM_PYTHON = "/usr/bin/python3"


def _package(root: Path, name: str, files: dict[str, str]) -> Path:
    pkg = root / name
    pkg.mkdir(parents=True)
    (pkg / "package.xml").write_text(f"<package><name>{name}</name></package>")
    for rel, text in files.items():
        path = pkg / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    return pkg


FIBONACCI = """\
#goal definition
int32 order
---
#result definition
int32[] sequence
---
#feedback
int32[] sequence
"""


@pytest.fixture
def layer(tmp_path, monkeypatch):
    """The finders on sys.meta_path, the package path at tmp_path; imported modules of the
    test's packages are forgotten afterwards."""
    from orchestra.packages.index import reset_index

    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path))
    reset_index()
    before = set(sys.modules)
    finder.install()
    yield tmp_path
    finder.uninstall()
    for name in set(sys.modules) - before:
        if name.split(".")[0].startswith("l10_"):
            del sys.modules[name]
    reset_index()


def test_standard_message_and_service_modules_import_like_genpy(layer):
    from actionlib_msgs.msg import GoalStatus
    from std_msgs.msg import String
    from std_srvs.srv import SetBool, SetBoolRequest, SetBoolResponse

    assert String._type == "std_msgs/String" and String(data="x").data == "x"
    assert GoalStatus.SUCCEEDED == 3
    assert SetBool._request_class is SetBoolRequest and SetBool._response_class is SetBoolResponse


def test_custom_package_msg_srv_and_action_types_need_no_build(layer):
    _package(layer, "l10_pkg", {
        "msg/Person.msg": "string name\nuint8 age\n",
        "srv/AddTwoInts.srv": "int64 a\nint64 b\n---\nint64 sum\n",
        "action/Fibonacci.action": FIBONACCI,
    })
    import l10_pkg.srv
    from l10_pkg.msg import FibonacciAction, FibonacciActionGoal, FibonacciGoal, Person

    assert Person(name="ann", age=3).age == 3
    assert l10_pkg.srv.AddTwoInts._md5sum == "6a2e34150c00229791cc89ff309fff21"
    assert l10_pkg.srv.AddTwoIntsResponse(sum=3).sum == 3
    # genaction's derived types: the md5 sums of actionlib_tutorials' Fibonacci
    assert FibonacciAction._md5sum == "f59df5767bf7634684781c92598b2406"
    assert FibonacciActionGoal._md5sum == "006871c7fa1d0e3d5fe2226bf17b2a94"
    assert FibonacciActionGoal._slot_types == ["std_msgs/Header", "actionlib_msgs/GoalID",
                                               "l10_pkg/FibonacciGoal"]
    assert FibonacciGoal(order=5).order == 5


def test_star_import_of_a_srv_module_gives_services_and_their_halves(layer):
    _package(layer, "l10_star", {"srv/AddTwoInts.srv": "int64 a\nint64 b\n---\nint64 sum\n"})
    scope: dict = {}
    exec("from l10_star.srv import *", scope)  # noqa: S102 - the statement under test
    assert {"AddTwoInts", "AddTwoIntsRequest", "AddTwoIntsResponse"} <= set(scope)


def test_package_module_exposes_the_packages_own_python_code(layer):
    _package(layer, "l10_py", {
        "msg/Num.msg": "int64 num\n",
        "src/l10_py/__init__.py": "FLAVOUR = 'catkin_python_setup'\n",
        "src/l10_py/utils.py": "def double(x):\n    return 2 * x\n",
    })
    import l10_py
    from l10_py.msg import Num
    from l10_py.utils import double

    assert l10_py.FLAVOUR == "catkin_python_setup"
    assert double(Num(num=2).num) == 4


def test_msg_syntax_error_fails_the_import_naming_file_and_line(layer):
    pkg = _package(layer, "l10_bad", {"msg/Broken.msg": "int32 ok\nfloat64\n"})
    with pytest.raises(ImportError) as err:
        from l10_bad.msg import Broken  # noqa: F401
    assert str(err.value).startswith(f"{pkg / 'msg' / 'Broken.msg'}:2: ")
    assert isinstance(err.value, finder.DefinitionImportError)


def test_unknown_field_type_fails_the_import_naming_the_line_that_uses_it(layer):
    pkg = _package(layer, "l10_unk", {"msg/Uses.msg": "# header\nint32 ok\nNoSuchType thing\n"})
    with pytest.raises(ImportError, match=r"Uses\.msg:3: unknown type 'l10_unk/NoSuchType'") as err:
        from l10_unk.msg import Uses  # noqa: F401
    assert str(pkg) in str(err.value)


def test_service_error_lines_count_from_the_top_of_the_srv_file(layer):
    _package(layer, "l10_srvbad", {"srv/S.srv": "int32 a\n---\nint32 b\nbad[x] c\n"})
    with pytest.raises(ImportError, match=r"S\.srv:4: bad type"):
        from l10_srvbad.srv import S  # noqa: F401


def test_unknown_message_package_names_the_package_and_where_it_looked(layer):
    with pytest.raises(ImportError, match=r"no ROS package l10_nothing_msgs .*looked in .*"
                                          + str(layer).replace("/", ".")):
        import l10_nothing_msgs.msg  # noqa: F401


def test_layer_is_chosen_only_without_a_real_rospy(tmp_path):
    real = tmp_path / "real"
    (real / "rospy").mkdir(parents=True)
    (real / "rospy" / "__init__.py").write_text("")
    site = str(tmp_path / "site")
    assert activation.decide({}, [site], site) is True
    assert activation.decide({}, [site, str(real)], site) is False
    assert activation.decide({"ORCHESTRA_ROS1": "layer"}, [site, str(real)], site) is True
    assert activation.decide({"ORCHESTRA_ROS1": "real"}, [site], site) is False


def test_layer_env_puts_the_site_dir_first_once():
    env = activation.layer_env({"PYTHONPATH": f"/a{os.pathsep}{activation.SITE_DIR}"})
    assert env["PYTHONPATH"].split(os.pathsep) == [activation.SITE_DIR, "/a"]


def _run(python: str, code: str, **env: str) -> subprocess.CompletedProcess:
    full = dict(os.environ)
    full.update(activation.layer_env({"PYTHONPATH": str(REPO)}))
    full.update(env)
    return subprocess.run([python, "-c", code], env=full, capture_output=True, text=True,
                          timeout=60, cwd="/")


def test_a_python_without_ros_gets_the_layer_at_startup():
    out = _run(sys.executable, "from std_msgs.msg import String; print(String._type)")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "std_msgs/String"


def test_orchestra_ros1_real_turns_the_layer_off():
    out = _run(sys.executable, "import sys; print(any(p.endswith('site') and 'ros1' in p "
                               "for p in sys.path)); import std_msgs.msg",
               ORCHESTRA_ROS1="real")
    assert out.stdout.startswith("False") and "No module named 'std_msgs'" in out.stderr


def test_a_real_ros_install_is_never_shadowed():
    if not os.path.exists(SYSTEM_PYTHON) or subprocess.run(
            [SYSTEM_PYTHON, "-c", "import rospy, std_msgs.msg"],
            capture_output=True).returncode != 0:
        pytest.skip("no real rospy/std_msgs under /usr/bin/python3 (python3-rospy, -std-msgs)")
    out = _run(SYSTEM_PYTHON, "import rospy, std_msgs.msg, sys; print(rospy.__file__); "
                              "print(std_msgs.msg.String.__module__); "
                              f"print({activation.SITE_DIR!r} in sys.path)")
    assert out.returncode == 0, out.stderr
    rospy_file, module, on_path = out.stdout.split()
    assert rospy_file.startswith("/usr/lib/python3/") and module == "std_msgs.msg._String"
    assert on_path == "False"


def test_other_sitecustomize_still_runs(tmp_path):
    (tmp_path / "sitecustomize.py").write_text("import builtins; builtins.CHAINED = 1\n")
    full = dict(os.environ)
    full["PYTHONPATH"] = os.pathsep.join([activation.SITE_DIR, str(tmp_path), str(REPO)])
    out = subprocess.run([sys.executable, "-c", "print(CHAINED)"], env=full,
                         capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == "1", out.stderr



def test_orchestra_env_prints_lines_a_shell_can_eval(tmp_path):
    full = dict(os.environ, PYTHONPATH=str(REPO))
    out = subprocess.run([sys.executable, "-m", "orchestra", "env", "--mode", "layer"],
                         env=full, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    shell = subprocess.run(["sh", "-c", out.stdout + 'echo "$ORCHESTRA_ROS1 $PYTHONPATH"'],
                           capture_output=True, text=True, timeout=60)
    assert shell.stdout.split() == ["layer",
                                    os.pathsep.join([activation.SITE_DIR, str(REPO)])]


def test_a_node_importing_orchestra_directly_is_not_disturbed_by_the_layer():
    # orchestra.node's own imports probe optional modules (copy.py's "org") half-way through
    out = _run(sys.executable, "import orchestra.node, copy; print('ok')")
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr


def test_layer_genpy_module_is_the_message_system_in_use():
    out = _run(sys.executable, "import genpy, genpy.message; from std_msgs.msg import Header; "
                               "h = Header(); print(isinstance(h, genpy.Message), "
                               "isinstance(h.stamp, genpy.Time), "
                               "genpy.message.strify_message(h) == str(h))")
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "True", "True"]


def test_action_types_have_genactions_text_for_debians_actionlib_actions():
    from orchestra.node import msgspec

    share = Path("/usr/share/actionlib")
    actions = sorted((share / "action").glob("*.action")) if share.is_dir() else []
    if not actions or not (share / "msg").is_dir():
        pytest.skip("Debian's actionlib .action/.msg files are absent (python3-actionlib)")
    for action in actions:
        texts = msgspec.action_message_texts(action.read_text(), f"actionlib/{action.stem}")
        for type_name, (text, _line) in texts.items():
            generated = share / "msg" / (type_name.split("/")[1] + ".msg")
            assert text == generated.read_text(), type_name


def test_orchestra_run_gives_a_python_script_the_layer(tmp_path):
    pkg = _package(tmp_path, "l10_run", {
        "msg/Person.msg": "string name\n",
        "scripts/hello.py": ("#!/usr/bin/env python3\n"
                             "from l10_run.msg import Person\n"
                             "from std_msgs.msg import String\n"
                             "print(Person(name='ann').name, String._type)\n"),
    })
    (pkg / "scripts" / "hello.py").chmod(0o755)
    env = dict(os.environ, PYTHONPATH=str(REPO), ROS_PACKAGE_PATH=str(tmp_path),
               PATH=os.pathsep.join([os.path.dirname(sys.executable), os.environ["PATH"]]))
    out = subprocess.run([sys.executable, "-m", "orchestra", "run", "l10_run", "hello.py"],
                         env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["ann", "std_msgs/String"]


def test_service_without_separator_is_located(layer):
    pkg = _package(layer, "l10_nosep", {"srv/S.srv": "int32 a\nint32 b\n"})
    with pytest.raises(ImportError, match=rf"^{pkg / 'srv' / 'S.srv'}:2: a service definition "
                                          r"has 1 '---' line between its parts, found 0"):
        from l10_nosep.srv import S  # noqa: F401


def test_unknown_package_of_any_name_is_explained_only_for_msg_imports(layer):
    import importlib.util

    with pytest.raises(ImportError, match="no ROS package l10_nowhere with msg/"):
        from l10_nowhere.srv import Thing  # noqa: F401
    with pytest.raises(ModuleNotFoundError) as plain:
        import l10_nowhere  # noqa: F401
    assert "no ROS package" not in str(plain.value)
    assert importlib.util.find_spec("l10_nowhere") is None


def test_dir_of_a_message_module_lists_its_types_before_any_is_built(layer):
    _package(layer, "l10_dir", {"msg/A.msg": "int8 a\n", "srv/S.srv": "---\n"})
    import l10_dir.msg
    import l10_dir.srv

    assert "A" in dir(l10_dir.msg)
    assert {"S", "SRequest", "SResponse"} <= set(dir(l10_dir.srv))


def test_unknown_mode_warns_once_and_means_auto():
    out = _run(sys.executable, "from std_msgs.msg import String; print(String._type)",
               ORCHESTRA_ROS1="yes")
    assert out.returncode == 0 and out.stdout.strip() == "std_msgs/String"
    assert out.stderr.strip() == ("orchestra: warning: ORCHESTRA_ROS1='yes' is not one of "
                                  "auto, layer, real; using auto")
