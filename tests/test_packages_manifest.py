"""package.xml formats 1-3, invalid manifests with file:line, and the dependency graph."""
from __future__ import annotations

import glob

import pytest
from catkin_pkg.package import parse_package

from orchestra.packages.deps import build_graph
from orchestra.packages.index import PackageIndex
from orchestra.packages.manifest import InvalidManifest, evaluate_condition, parse_manifest

FORMAT1 = """<?xml version="1.0"?>
<package>
  <name>one</name>
  <version>0.1.0</version>
  <description>Format one</description>
  <maintainer email="m@x.org">M</maintainer>
  <author>A</author>
  <license>BSD</license>
  <buildtool_depend>catkin</buildtool_depend>
  <build_depend>roscpp</build_depend>
  <run_depend>roscpp</run_depend>
  <run_depend>std_msgs</run_depend>
  <test_depend>rostest</test_depend>
  <export><nodelet plugin="${prefix}/plugins.xml"/></export>
</package>
"""

FORMAT3 = """<?xml version="1.0"?>
<package format="3">
  <name>three</name>
  <version>3.0.0</version>
  <description>Format <b>three</b></description>
  <maintainer email="m@x.org">M</maintainer>
  <license>Apache-2.0</license>
  <license>MIT</license>
  <url type="website">https://x.org</url>
  <buildtool_depend condition="$ROS_VERSION == 1">catkin</buildtool_depend>
  <buildtool_depend condition="$ROS_VERSION == 2">ament_cmake</buildtool_depend>
  <depend version_gte="1.2.0">roscpp</depend>
  <exec_depend condition="$ROS_PYTHON_VERSION == 3">python3-yaml</exec_depend>
  <doc_depend>doxygen</doc_depend>
  <group_depend>plugins</group_depend>
  <member_of_group>things</member_of_group>
  <conflict>old_three</conflict>
  <export><metapackage/><build_type>catkin</build_type></export>
</package>
"""


def write(tmp_path, text, name="package.xml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_format1_run_depend_means_build_export_and_exec(tmp_path):
    m = parse_manifest(write(tmp_path, FORMAT1))
    assert (m.format, m.name, m.version, m.licenses) == (1, "one", "0.1.0", ("BSD",))
    assert m.depends(("build",)) == ["roscpp"]
    assert m.depends(("exec",)) == ["roscpp", "std_msgs"]
    assert m.depends(("build_export",)) == ["roscpp", "std_msgs"]
    assert m.depends(("test",)) == ["rostest"]
    assert m.exports[0].tag == "nodelet"
    assert dict(m.exports[0].attributes) == {"plugin": "${prefix}/plugins.xml"}


def test_format3_conditions_groups_versions_and_exports(tmp_path):
    m = parse_manifest(write(tmp_path, FORMAT3))
    env = {"ROS_VERSION": "1", "ROS_PYTHON_VERSION": "3"}
    assert m.depends(("buildtool",), env) == ["catkin"]
    assert m.depends(("buildtool",), {"ROS_VERSION": "2"}) == ["ament_cmake"]
    assert m.depends(("exec",), env) == ["roscpp", "python3-yaml"]
    assert m.depends(("exec",), {}) == ["roscpp"]
    assert m.depends(("doc",), env) == ["doxygen"]
    assert [d.versions for d in m.declared if d.name == "roscpp"] == [(("version_gte", "1.2.0"),)]
    assert m.relation("group_depend") == ["plugins"] and m.relation("member_of_group") == ["things"]
    assert m.relation("conflict") == ["old_three"]
    assert m.is_metapackage and m.build_type == "catkin"
    assert m.description == "Format three" and m.urls == (("website", "https://x.org"),)


@pytest.mark.parametrize("text", [
    "$A == 1 and ($B != x or $C == '')",
    "$A == 1 or $B == 2",
])
def test_conditions_follow_rep149(text):
    assert evaluate_condition(text, {"A": "1", "B": "y"}) is True


def test_bad_condition_names_the_manifest(tmp_path):
    with pytest.raises(InvalidManifest, match="invalid condition"):
        evaluate_condition("$A ==", {}, "pkg.xml", 4)


def test_every_compat_manifest_agrees_with_catkin_pkg_on_name_version_and_deps(compat_dir):
    files = sorted(glob.glob(str(compat_dir / "ws" / "**" / "package.xml"), recursive=True))
    assert len(files) == 118
    env = {"ROS_VERSION": "1", "ROS_PYTHON_VERSION": "3", "ROS_DISTRO": "noetic"}
    for path in files:
        ours = parse_manifest(path)
        theirs = parse_package(path, warnings=[])
        theirs.evaluate_conditions(env)
        assert (ours.name, ours.version, ours.format) == (theirs.name, theirs.version, theirs.package_format)
        assert list(ours.licenses) == theirs.licenses
        assert ([(p.name, p.email) for p in ours.maintainers]
                == [(p.name, p.email) for p in theirs.maintainers])
        for kind, attr in [("build", "build_depends"), ("exec", "exec_depends"),
                           ("build_export", "build_export_depends"), ("test", "test_depends"),
                           ("buildtool", "buildtool_depends"), ("doc", "doc_depends")]:
            expected = sorted({d.name for d in getattr(theirs, attr) if d.evaluated_condition is not False})
            assert sorted(ours.depends((kind,), env)) == expected, (path, kind)
        assert [e.tagname for e in theirs.exports] == [e.tag for e in ours.exports]


@pytest.mark.parametrize("text, line, message", [
    ("<package format='2'>\n  <name>x</name>\n  <version>1.0.0\n</package>\n", 4, "invalid XML"),
    ("<manifest/>\n", 1, "root element must be <package>"),
    ("<package format='9'><name>x</name></package>", 1, "unsupported package format"),
    ("<package format='2'>\n<version>1.0.0</version>\n</package>", 1, "missing required <name>"),
    ("<package format='2'>\n<name>x</name>\n<version>1.0</version>\n</package>", 3, "MAJOR.MINOR.PATCH"),
    ("<package format='2'>\n<name>x</name>\n<version>1.0.0</version>\n<run_depend>y</run_depend>\n</package>",
     4, "unknown tag <run_depend> in a format 2"),
    ("<package format='2'>\n<name>x</name>\n<name>y</name>\n"
     "<version>1.0.0</version>\n</package>", 3, "only once"),
    ("<package format='2'>\n<name>x</name>\n<version>1.0.0</version>\n"
     "<depend>x</depend>\n</package>", 4, "itself"),
])
def test_invalid_manifest_error_names_file_and_line(tmp_path, text, line, message):
    path = write(tmp_path, text)
    with pytest.raises(InvalidManifest, match=message) as info:
        parse_manifest(path)
    assert info.value.location.file == path and info.value.location.line == line
    assert str(info.value).startswith(f"{path}:{line}")


def test_entities_are_not_expanded(tmp_path):
    text = ('<?xml version="1.0"?>\n<!DOCTYPE p [<!ENTITY e SYSTEM "file:///etc/passwd">]>\n'
            "<package format='2'><name>x</name><version>1.0.0</version>"
            "<description>&e;</description></package>")
    manifest = parse_manifest(write(tmp_path, text))
    assert "root:" not in manifest.description


def test_rosbuild_manifest_xml_name_is_the_directory(tmp_path):
    pkg = tmp_path / "old_pkg"
    pkg.mkdir()
    (pkg / "manifest.xml").write_text('<package><description>old</description>'
                                      '<depend package="roscpp"/><license>BSD</license></package>')
    m = parse_manifest(str(pkg))
    assert (m.name, m.format, m.depends()) == ("old_pkg", 0, ["roscpp"])


def make(tmp_path, name, deps=(), tag="depend"):
    d = tmp_path / name
    d.mkdir()
    body = "".join(f"<{tag}>{dep}</{tag}>" for dep in deps)
    (d / "package.xml").write_text(f"<package format='2'><name>{name}</name><version>1.0.0</version>"
                                   f"<description>x</description>{body}</package>")


def test_transitive_deps_come_in_build_order_and_missing_ones_are_reported(tmp_path):
    make(tmp_path, "app", ["nav", "base"])
    make(tmp_path, "nav", ["base", "boost"])
    make(tmp_path, "base", ["catkin_like"])
    make(tmp_path, "catkin_like")
    make(tmp_path, "tester", ["app"], tag="test_depend")
    index = PackageIndex.build([str(tmp_path)], cache_dir=None)
    graph = build_graph(["app"], index=index)
    assert graph.transitive("app") == ["boost", "catkin_like", "base", "nav"]
    assert graph.direct("app") == ["base", "nav"]
    assert graph.missing == ["boost"]
    assert build_graph(["tester"], index=index).transitive("tester") == []
    assert build_graph(["tester"], ("test",), index=index).direct("tester") == ["app"]


def test_dependency_cycle_is_an_error_naming_the_cycle(tmp_path):
    make(tmp_path, "a", ["b"])
    make(tmp_path, "b", ["a"])
    index = PackageIndex.build([str(tmp_path)], cache_dir=None)
    with pytest.raises(Exception, match="dependency cycle: (a -> b -> a|b -> a -> b)"):
        build_graph(["a"], index=index).transitive("a")


def test_conditions_default_to_a_ros1_noetic_environment(tmp_path, monkeypatch):
    for var in ("ROS_VERSION", "ROS_PYTHON_VERSION", "ROS_DISTRO"):
        monkeypatch.delenv(var, raising=False)
    m = parse_manifest(write(tmp_path, FORMAT3))
    assert m.depends(("buildtool",)) == ["catkin"]
    assert m.depends(("exec",)) == ["roscpp", "python3-yaml"]
    monkeypatch.setenv("ROS_VERSION", "2")
    assert m.depends(("buildtool",)) == ["ament_cmake"]


def test_every_bundled_demo_package_manifest_is_valid():
    from orchestra.packages.discovery import BUNDLED_PACKAGES

    manifests = sorted(glob.glob(f"{BUNDLED_PACKAGES}/*/package.xml"))
    assert manifests
    for path in manifests:
        manifest = parse_manifest(path)
        assert manifest.name and not manifest.warnings, (path, manifest.warnings)
