"""`orchestra create-pkg` makes the same package as the real catkin_create_pkg.

"Same" (issue 2): the same file tree; package.xml parsed by catkin_pkg's own parser gives the
same name, version, description, maintainers, authors, licenses, every dependency kind and
exports; CMakeLists.txt has the same non-comment lines.
"""
from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from catkin_pkg.package import parse_package

from orchestra.packages.cli import parse_create_args
from orchestra.packages.create import InvalidPackageRequest, PackageRequest, create_package
from orchestra.packages.manifest import parse_manifest

#: the real tool: the catkin_create_pkg script catkin_pkg (a test dependency) installs, or the
#: same entry point run with this interpreter when the script is not on PATH
CATKIN_CREATE_PKG = ([shutil.which("catkin_create_pkg")] if shutil.which("catkin_create_pkg")
                     else [sys.executable, "-m", "catkin_pkg.cli.create_pkg"])
ORCHESTRA = [sys.executable, "-m", "orchestra"]
ENV = {**os.environ, "ROS_DISTRO": "noetic", "USER": "tester", "LOGNAME": "tester"}

CASES = {
    "no_deps": ["plain"],
    "roscpp_only": ["cpp_pkg", "roscpp"],
    "rospy_std_msgs": ["py_pkg", "rospy", "std_msgs"],
    "messages": ["msg_pkg", "message_generation", "message_runtime", "std_msgs", "geometry_msgs"],
    "people_and_meta": ["people_pkg", "roscpp", "tf2_ros", "-a", "Zed Author", "-a", "Amy Author",
                        "-m", "Mia Maintainer", "-m", "Bob Builder", "-l", "MIT", "-l", "BSD",
                        "-V", "1.4.2", "-D", "Does things with turtles"],
    "system_deps": ["sys_pkg", "roscpp", "sensor_msgs", "-s", "eigen", "python-yaml",
                    "-b", "thread", "system", "-l", "Apache-2.0"],
    "boost_only": ["boost_pkg", "-b", "filesystem", "-V", "0.1.0"],
    "genmsg": ["old_msgs", "genmsg", "rospy", "-m", "Old Timer"],
    "metapackage": ["--meta", "meta_pkg", "-D", "Groups things", "-a", "A Person"],
}


def catkin_make(args: list[str], where) -> None:
    proc = subprocess.run([*CATKIN_CREATE_PKG, *args], cwd=where, env=ENV,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr


def orchestra_make(args: list[str], where) -> subprocess.CompletedProcess:
    return subprocess.run([*ORCHESTRA, "create-pkg", *args], cwd=where, env=ENV,
                          capture_output=True, text=True, timeout=60)


def tree(root) -> list[str]:
    entries = []
    for directory, dirs, files in os.walk(root):
        rel = os.path.relpath(directory, root)
        entries += [os.path.normpath(os.path.join(rel, d)) + "/" for d in dirs]
        entries += [os.path.normpath(os.path.join(rel, f)) for f in files]
    return sorted(entries)


def manifest_facts(path) -> dict:
    pkg = parse_package(path, warnings=[])
    people = lambda persons: sorted((p.name, p.email) for p in persons)  # noqa: E731
    deps = lambda ds: sorted(d.name for d in ds)  # noqa: E731
    return {
        "name": pkg.name, "version": pkg.version, "description": pkg.description,
        "format": pkg.package_format,
        "maintainers": people(pkg.maintainers), "authors": people(pkg.authors),
        "licenses": sorted(pkg.licenses),
        "buildtool": deps(pkg.buildtool_depends), "build": deps(pkg.build_depends),
        "build_export": deps(pkg.build_export_depends),
        "buildtool_export": deps(pkg.buildtool_export_depends),
        "exec": deps(pkg.exec_depends), "test": deps(pkg.test_depends),
        "doc": deps(pkg.doc_depends), "conflicts": deps(pkg.conflicts),
        "replaces": deps(pkg.replaces),
        "exports": sorted((e.tagname, sorted(e.attributes.items()), e.content) for e in pkg.exports),
    }


def code_lines(path) -> list[str]:
    with open(path) as fh:
        lines = [line.rstrip() for line in fh]
    return [line for line in lines if line.strip() and not line.lstrip().startswith("#")]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("case", sorted(CASES))
def test_create_pkg_equals_catkin_create_pkg(case, tmp_path):
    args = CASES[case]
    name = next(a for a in args if not a.startswith("-"))
    (tmp_path / "catkin").mkdir()
    (tmp_path / "orchestra").mkdir()
    catkin_make(args, tmp_path / "catkin")
    proc = orchestra_make(args, tmp_path / "orchestra")
    assert proc.returncode == 0, proc.stderr
    theirs, ours = tmp_path / "catkin" / name, tmp_path / "orchestra" / name
    assert tree(ours) == tree(theirs)
    assert manifest_facts(ours / "package.xml") == manifest_facts(theirs / "package.xml")
    assert code_lines(ours / "CMakeLists.txt") == code_lines(theirs / "CMakeLists.txt")


def test_create_pkg_manifest_is_readable_by_orchestra_parser(tmp_path):
    request = PackageRequest("reader_pkg", dependencies=("rospy", "std_msgs"), sys_deps=("python-yaml",),
                             maintainers=("Ann Other",), version="2.0.1")
    created = create_package(request, str(tmp_path))
    manifest = parse_manifest(created.path)
    assert manifest.format == 2 and manifest.version == "2.0.1"
    assert manifest.depends(("exec",)) == ["python-yaml", "rospy", "std_msgs"]
    assert manifest.depends(("build",)) == ["rospy", "std_msgs"]
    assert manifest.maintainers[0].email == "Other@todo.todo"


def test_create_pkg_escapes_xml_special_characters_in_description(tmp_path):
    created = create_package(PackageRequest("esc_pkg", description='Fish & <chips> "now"'), str(tmp_path))
    # catkin_pkg keeps the description as inner XML (it may hold XHTML), so read the text back
    assert parse_manifest(created.path).description == 'Fish & <chips> "now"'


@pytest.mark.parametrize("bad", ["1-bad!", "with space", "_leading", "na/me", ""])
def test_create_pkg_refuses_names_catkin_rejects(bad, tmp_path):
    with pytest.raises(InvalidPackageRequest, match="invalid package name"):
        create_package(PackageRequest(bad), str(tmp_path))
    assert os.listdir(tmp_path) == []


def test_create_pkg_refuses_existing_directory_without_touching_it(tmp_path):
    (tmp_path / "taken").mkdir()
    (tmp_path / "taken" / "keep.txt").write_text("mine")
    proc = orchestra_make(["taken", "rospy"], tmp_path)
    assert proc.returncode == 2
    assert "already exists" in proc.stderr and "Traceback" not in proc.stderr
    assert os.listdir(tmp_path / "taken") == ["keep.txt"]
    assert sorted(os.listdir(tmp_path)) == ["taken"]  # no staging directory left behind


def test_create_pkg_refuses_bad_version_and_self_dependency(tmp_path):
    with pytest.raises(InvalidPackageRequest, match="invalid version"):
        create_package(PackageRequest("v_pkg", version="1.0"), str(tmp_path))
    with pytest.raises(InvalidPackageRequest, match="must not depend on itself"):
        create_package(PackageRequest("self_pkg", dependencies=("self_pkg",)), str(tmp_path))
    assert os.listdir(tmp_path) == []


def test_create_pkg_cli_reports_invalid_name_as_one_line_error(tmp_path):
    proc = orchestra_make(["Bad!Name"], tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.startswith("orchestra: error:") and "Traceback" not in proc.stderr


def test_sys_deps_option_takes_every_following_word_like_argparse():
    fields, directory = parse_create_args(["p", "roscpp", "-s", "eigen", "opencv", "-b", "thread",
                                           "-l", "MIT", "--license=BSD", "-V", "1.0.0", "-C", "/x"])
    assert fields["dependencies"] == ("roscpp",)
    assert fields["sys_deps"] == ("eigen", "opencv")
    assert fields["boost_comps"] == ("thread",)
    assert fields["licenses"] == ("MIT", "BSD")
    assert fields["version"] == "1.0.0" and directory == "/x"


def test_python_node_option_writes_executable_node_and_launch_file(tmp_path):
    created = create_package(PackageRequest("talker_pkg", dependencies=("rospy", "std_msgs"),
                                            python_node="talker"), str(tmp_path))
    node = os.path.join(created.path, "scripts", "talker")
    launch = os.path.join(created.path, "launch", "talker_pkg.launch")
    assert os.stat(node).st_mode & stat.S_IXUSR
    source = Path(node).read_text()
    compile(source, node, "exec")
    assert "import orchestra.node as on" in source and 'get_message_class("std_msgs/String")' in source
    from lxml import etree
    node_el = etree.parse(launch).getroot().find("node")
    assert (node_el.get("pkg"), node_el.get("type"), node_el.get("name")) == (
        "talker_pkg", "talker", "talker")
    cmake = Path(created.path, "CMakeLists.txt").read_text()
    assert "catkin_install_python(PROGRAMS scripts/talker" in cmake


def test_python_node_is_found_as_the_launch_files_executable(tmp_path, monkeypatch):
    """In a workspace src/ the new package is discoverable and its node resolvable at once."""
    from orchestra.packages import find_executable
    from orchestra.packages.index import reset_index

    src = tmp_path / "ws" / "src"
    src.mkdir(parents=True)
    proc = orchestra_make(["hello_pkg", "rospy", "--python-node", "hello"], src)
    assert proc.returncode == 0, proc.stderr
    assert "not on the package search path" not in proc.stderr
    monkeypatch.chdir(src)
    monkeypatch.setenv("ROS_PACKAGE_PATH", "")
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "rh"))
    reset_index()
    try:
        assert find_executable("hello_pkg", "hello") == str(src / "hello_pkg" / "scripts" / "hello")
    finally:
        reset_index()


@pytest.mark.timeout(90)
def test_python_node_package_launches_at_once_and_stops_cleanly(tmp_path):
    """create-pkg --python-node, then `orchestra launch NAME NAME.launch` runs the node."""
    import select
    import signal
    import time

    src = tmp_path / "ws" / "src"
    src.mkdir(parents=True)
    assert orchestra_make(["hello_pkg", "rospy", "std_msgs", "--python-node", "hello"], src).returncode == 0
    env = {k: v for k, v in ENV.items() if k not in ("ROS_PACKAGE_PATH", "ROS_MASTER_URI")}
    env["ROS_HOME"] = str(tmp_path / "ros_home")
    proc = subprocess.Popen([*ORCHESTRA, "launch", "-p", "0", "hello_pkg", "hello_pkg.launch"],
                            cwd=src, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True)
    output = []
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            ready, _, _ = select.select([proc.stdout], [], [], 1.0)
            if ready:
                line = proc.stdout.readline()
                if not line:
                    break
                output.append(line)
                if "hello from hello_pkg #0" in line:
                    break
        assert any("hello from hello_pkg #0" in line for line in output), "".join(output)
        proc.send_signal(signal.SIGINT)
        rest, _ = proc.communicate(timeout=30)
        output.append(rest)
        assert "Traceback" not in "".join(output)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_package_made_in_ws_src_is_found_from_the_workspace_root(tmp_path):
    src = tmp_path / "ws" / "src"
    src.mkdir(parents=True)
    assert orchestra_make(["mine", "rospy"], src).returncode == 0
    env = {k: v for k, v in ENV.items() if k not in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH")}
    env["ROS_HOME"] = str(tmp_path / "home")
    for where in (tmp_path / "ws", src):
        found = subprocess.run([*ORCHESTRA, "pkg", "find", "mine"], cwd=where, env=env,
                               capture_output=True, text=True, timeout=60)
        assert found.returncode == 0, (where, found.stderr)
        assert found.stdout.strip() == str(src / "mine")
    # a src/ without packages does not make its parent a workspace
    (tmp_path / "other" / "src").mkdir(parents=True)
    missing = subprocess.run([*ORCHESTRA, "pkg", "find", "mine"], cwd=tmp_path / "other",
                             env=env, capture_output=True, text=True, timeout=60)
    assert missing.returncode == 2
