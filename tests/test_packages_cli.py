"""find_executable (roslaunch/rosrun rules) and the `pkg` / `run` commands."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

import pytest

from orchestra.packages import AmbiguousExecutable, ExecutableNotFound, find_executable
from orchestra.packages.index import reset_index


def script(path, body="#!/bin/sh\necho hi\n", mode=0o755):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(body)
    os.chmod(path, mode)
    return path


def package(root, name, deps=()):
    d = root / name
    d.mkdir(parents=True, exist_ok=True)
    body = "".join(f"<depend>{dep}</depend>" for dep in deps)
    (d / "package.xml").write_text(f"<package format='2'><name>{name}</name><version>1.0.0</version>"
                                   f"<description>x</description>{body}</package>")
    return d


@pytest.fixture
def env(tmp_path, monkeypatch):
    """An isolated package path: tmp/src on ROS_PACKAGE_PATH, cache in tmp, cwd outside it."""
    src = tmp_path / "src"
    src.mkdir()
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(src))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "ros_home"))
    monkeypatch.delenv("CMAKE_PREFIX_PATH", raising=False)
    monkeypatch.chdir(tmp_path)
    reset_index()
    yield src
    reset_index()


def cli(*args, cwd=None, env_extra=None, timeout=60):
    env = {**os.environ, **(env_extra or {})}
    return subprocess.run([sys.executable, "-m", "orchestra", *args], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd, env=env)


def test_executable_found_anywhere_in_package_tree(env):
    pkg = package(env, "talkers")
    exe = script(pkg / "scripts" / "deep" / "talker")
    assert find_executable("talkers", "talker") == str(exe)


def test_non_executable_file_is_not_a_match(env):
    pkg = package(env, "talkers")
    plain = script(pkg / "scripts" / "talker", mode=0o644)
    with pytest.raises(ExecutableNotFound, match="is not executable") as info:
        find_executable("talkers", "talker")
    assert f"chmod +x {plain}" in str(info.value)


def test_two_executables_of_one_name_is_an_error_naming_both(env):
    pkg = package(env, "twins")
    a = script(pkg / "scripts" / "node")
    b = script(pkg / "bin" / "node")
    with pytest.raises(AmbiguousExecutable) as info:
        find_executable("twins", "node")
    assert sorted(info.value.candidates) == sorted([str(a), str(b)])
    assert str(a) in str(info.value) and str(b) in str(info.value)


def test_hidden_directories_are_not_searched(env):
    pkg = package(env, "hid")
    script(pkg / ".git" / "node")
    with pytest.raises(ExecutableNotFound):
        find_executable("hid", "node")


def test_catkin_devel_lib_dir_wins_over_source_script(env, tmp_path, monkeypatch):
    pkg = package(env, "built")
    script(pkg / "scripts" / "node")  # the source a catkin relay script points at
    devel = tmp_path / "devel"
    (devel / ".catkin").parent.mkdir(parents=True, exist_ok=True)
    (devel / ".catkin").write_text("")
    built = script(devel / "lib" / "built" / "node")
    monkeypatch.setenv("CMAKE_PREFIX_PATH", str(devel))
    reset_index()
    assert find_executable("built", "node") == str(built)


def test_unknown_package_is_package_not_found(env):
    from orchestra.packages import PackageNotFound
    with pytest.raises(PackageNotFound):
        find_executable("no_such_pkg", "x")


def test_pkg_find_and_list_and_duplicates(env, tmp_path):
    package(env, "alpha")
    other = tmp_path / "other"
    package(other, "alpha")
    package(other, "beta")
    extra = {"ROS_PACKAGE_PATH": f"{env}{os.pathsep}{other}"}
    proc = cli("pkg", "find", "alpha", cwd=tmp_path, env_extra=extra)
    assert proc.returncode == 0 and proc.stdout.strip() == str(env / "alpha")
    proc = cli("pkg", "list", cwd=tmp_path, env_extra=extra)
    assert f"alpha {env / 'alpha'}" in proc.stdout.splitlines()
    assert f"beta {other / 'beta'}" in proc.stdout.splitlines()
    proc = cli("pkg", "list", "--origins", cwd=tmp_path, env_extra=extra)
    assert f"beta {other / 'beta'} [ROS_PACKAGE_PATH]" in proc.stdout.splitlines()
    proc = cli("pkg", "list", "--duplicates", cwd=tmp_path, env_extra=extra)
    assert proc.stdout.splitlines() == [f"alpha {env / 'alpha'}", f"alpha {other / 'alpha'} (shadowed)"]


def test_pkg_find_unknown_package_is_one_line_error_exit_2(env, tmp_path):
    proc = cli("pkg", "find", "nowhere_pkg", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.startswith("orchestra: error: package 'nowhere_pkg' not found")
    assert "Traceback" not in proc.stderr


def test_pkg_deps_is_transitive_and_direct_with_dash_1(env, tmp_path):
    package(env, "top", ["mid"])
    package(env, "mid", ["low"])
    package(env, "low")
    proc = cli("pkg", "deps", "top", cwd=tmp_path)
    assert proc.stdout.split() == ["low", "mid"]
    assert cli("pkg", "deps", "-1", "top", cwd=tmp_path).stdout.split() == ["mid"]
    assert cli("pkg", "deps", "--on", "low", cwd=tmp_path).stdout.split() == ["mid", "top"]


def test_pkg_deps_invalid_manifest_reports_file_and_line(env, tmp_path):
    bad = env / "broken"
    bad.mkdir()
    (bad / "package.xml").write_text(
        "<package format='2'>\n<name>broken</name>\n<version>1.0.0\n</package>\n")
    proc = cli("pkg", "deps", "broken", cwd=tmp_path)
    assert proc.returncode == 2
    assert f"{bad / 'package.xml'}:4" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.timeout(60)
def test_run_passes_arguments_and_exit_code_through(env, tmp_path):
    pkg = package(env, "runner")
    script(pkg / "scripts" / "exiter", '#!/bin/sh\necho "args:$*"\nexit 7\n')
    proc = cli("run", "runner", "exiter", "a", "--flag", "b:=c", cwd=tmp_path)
    assert proc.returncode == 7
    assert proc.stdout.strip() == "args:a --flag b:=c"


@pytest.mark.timeout(60)
def test_run_with_prefix_runs_under_the_prefix_command(env, tmp_path):
    pkg = package(env, "runner")
    script(pkg / "scripts" / "show", "#!/bin/sh\necho shown\n")
    prefix = """sh -c 'echo "prefix saw $0 $1"; exec "$0" "$@"'"""
    proc = cli("run", "--prefix", prefix, "runner", "show", "x", cwd=tmp_path)
    assert proc.returncode == 0
    assert proc.stdout.splitlines() == [f"prefix saw {pkg / 'scripts' / 'show'} x", "shown"]


@pytest.mark.timeout(60)
def test_run_execs_so_signals_reach_the_node_directly(env, tmp_path):
    """`run` replaces itself with the node: the pid we started IS the node, SIGTERM ends it."""
    pkg = package(env, "runner")
    script(pkg / "scripts" / "sleeper", textwrap.dedent("""\
        #!/bin/sh
        trap 'echo got-term; exit 143' TERM
        echo "pid:$$"
        while true; do sleep 0.1; done
        """))
    proc = subprocess.Popen([sys.executable, "-m", "orchestra", "run", "runner", "sleeper"],
                            stdout=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        line = proc.stdout.readline().strip()
        assert line == f"pid:{proc.pid}"
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=20)
        assert "got-term" in out and proc.returncode == 143
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_run_unknown_executable_is_one_line_error(env, tmp_path):
    package(env, "runner")
    proc = cli("run", "runner", "nope", cwd=tmp_path)
    assert proc.returncode == 2
    assert "cannot find executable 'nope' in package 'runner'" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_pkg_show_prints_manifest_metadata_and_dependencies(env, tmp_path):
    package(env, "shown", ["roscpp"])
    proc = cli("pkg", "show", "shown", cwd=tmp_path)
    assert proc.returncode == 0
    lines = proc.stdout.splitlines()
    assert "name: shown" in lines and "version: 1.0.0" in lines
    assert "build_depends: roscpp" in lines and "exec_depends: roscpp" in lines
    assert "no <maintainer>" in proc.stderr


def only_package_path(monkeypatch, tmp_path, share) -> None:
    """ROS_PACKAGE_PATH=share and nothing else to find packages by (fresh index, cwd, home)."""
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(share))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "rh"))
    monkeypatch.delenv("CMAKE_PREFIX_PATH", raising=False)
    monkeypatch.chdir(tmp_path)
    reset_index()


def test_install_space_package_brings_its_lib_dir_without_cmake_prefix_path(tmp_path, monkeypatch):
    prefix = tmp_path / "opt_ros"
    (prefix / "share").mkdir(parents=True)
    (prefix / ".catkin").write_text("")
    package(prefix / "share", "installed")
    binary = script(prefix / "lib" / "installed" / "tool")
    only_package_path(monkeypatch, tmp_path, prefix / "share")
    try:
        assert find_executable("installed", "tool") == str(binary)
    finally:
        reset_index()


@pytest.mark.parametrize("system", [True, False])
def test_debian_system_package_brings_its_lib_dir_without_a_catkin_marker(
        system, tmp_path, monkeypatch):
    """Debian installs /usr/share/topic_tools/package.xml and /usr/lib/topic_tools/relay, with
    no .catkin in /usr: its catkin counts /usr as a workspace anyway, so roslaunch finds relay.
    Any other unmarked prefix (/usr/local, a conda env) still does not bring its lib/ along."""
    from orchestra.packages import executables

    prefix = tmp_path / "usr"
    package(prefix / "share", "topic_tools")
    binary = script(prefix / "lib" / "topic_tools" / "relay")
    monkeypatch.setattr(executables, "SYSTEM_PREFIXES", (str(prefix),) if system else ())
    only_package_path(monkeypatch, tmp_path, prefix / "share")
    try:
        if system:
            assert find_executable("topic_tools", "relay") == str(binary)
        else:
            with pytest.raises(ExecutableNotFound):
                find_executable("topic_tools", "relay")
    finally:
        reset_index()

def test_pkg_plugins_lists_exports_of_packages_depending_on_the_tool(env, tmp_path):
    package(env, "tool")
    user = package(env, "user", ["tool"])
    (user / "package.xml").write_text(
        "<package format='2'><name>user</name><version>1.0.0</version><description>x</description>"
        "<depend>tool</depend><export><tool plugin='${prefix}/plugins.xml'/></export></package>")
    stranger = package(env, "stranger")
    (stranger / "package.xml").write_text(  # exports for the tool without depending on it
        "<package format='2'><name>stranger</name><version>1.0.0</version><description>x</description>"
        "<export><tool plugin='${prefix}/p.xml'/></export></package>")
    broken = env / "broken"
    broken.mkdir()
    (broken / "package.xml").write_text("<package><name>broken</name><tool")
    proc = cli("pkg", "plugins", "tool", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == [f"user {user}/plugins.xml"]


def test_pkg_roots_and_which_show_search_path_and_resolved_executable(env, tmp_path):
    pkg = package(env, "whiched")
    exe = script(pkg / "nodes" / "thing")
    roots = cli("pkg", "roots", cwd=tmp_path).stdout.splitlines()
    assert roots[0] == f"{env} [ROS_PACKAGE_PATH]"
    assert roots[-1].endswith("[bundled]")
    assert cli("pkg", "which", "whiched", "thing", cwd=tmp_path).stdout.strip() == str(exe)


def test_misspelled_package_and_launch_file_get_a_did_you_mean():
    import subprocess
    import sys

    def launch(*words: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "orchestra", "launch", *words, "--nodes"],
                              capture_output=True, text=True, timeout=60)

    pkg = launch("learnin_tf", "start_tf_demo.launch")
    assert pkg.returncode == 2 and pkg.stderr.rstrip().endswith("(did you mean learning_tf?)")
    file = launch("learning_tf", "start_tf_dem.launch")
    assert file.returncode == 2 and "(did you mean start_tf_demo.launch" in file.stderr


def test_a_package_without_a_launch_file_or_an_unlike_name_lists_its_launch_files():
    import subprocess
    import sys

    def launch(*words: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "orchestra", "launch", *words, "--nodes"],
                              capture_output=True, text=True, timeout=60)

    listing = "(its launch files: start_tf_demo.launch, start_tf_demo_py.launch)"
    alone = launch("learning_tf")
    assert alone.returncode == 2
    assert alone.stderr == ("orchestra: error: [learning_tf] is a package, not a launch file: "
                            f"name a launch file after it {listing}\n")
    unlike = launch("learning_tf", "robot.launch")
    assert unlike.returncode == 2 and unlike.stderr.rstrip().endswith(listing)
