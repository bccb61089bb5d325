"""Package discovery: search roots, rospack crawl rules, shadowing, and the on-disk cache."""
from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest

from orchestra.packages import cache
from orchestra.packages.crawl import crawl
from orchestra.packages.discovery import BUNDLED_PACKAGES, catkin_workspace, search_roots
from orchestra.packages.index import PackageIndex, PackageNotFound, find_package, reset_index

OLD = time.time() - 3600  # an mtime safely outside the "racily clean" window


def make_pkg(directory, name=None, manifest="package.xml"):
    directory.mkdir(parents=True, exist_ok=True)
    if manifest == "package.xml":
        (directory / manifest).write_text(
            f'<?xml version="1.0"?>\n<!-- <name>decoy</name> -->\n<package format="2">\n'
            f"  <name>{name or directory.name}</name>\n  <version>1.0.0</version>\n"
            f"  <description>d</description>\n  <maintainer email='a@b.cc'>A</maintainer>\n"
            f"  <license>BSD</license>\n</package>\n")
    else:
        (directory / manifest).write_text("<package><description>legacy</description></package>\n")
    return directory


def age(root):
    """Backdate every mtime below ``root`` so the cache may trust it."""
    for directory, dirs, files in os.walk(root):
        for entry in dirs + files:
            os.utime(os.path.join(directory, entry), (OLD, OLD))
    os.utime(root, (OLD, OLD))


@pytest.fixture(autouse=True)
def fresh_index():
    reset_index()
    yield
    reset_index()


def test_crawl_stops_descending_at_a_package(tmp_path):
    make_pkg(tmp_path / "outer")
    make_pkg(tmp_path / "outer" / "inner")
    assert [name for name, _ in crawl(str(tmp_path)).packages] == ["outer"]


def test_catkin_ignore_prunes_the_whole_subtree(tmp_path):
    make_pkg(tmp_path / "kept")
    make_pkg(tmp_path / "ignored" / "deep" / "hidden_pkg")
    (tmp_path / "ignored" / "CATKIN_IGNORE").write_text("")
    assert [name for name, _ in crawl(str(tmp_path)).packages] == ["kept"]


def test_package_name_comes_from_manifest_not_directory_and_ignores_comments(tmp_path):
    make_pkg(tmp_path / "dir_name", name="real_name")
    make_pkg(tmp_path / "legacy_pkg", manifest="manifest.xml")
    found = dict(crawl(str(tmp_path)).packages)
    assert found == {"real_name": str(tmp_path / "dir_name"), "legacy_pkg": str(tmp_path / "legacy_pkg")}


def test_hidden_directories_are_skipped_and_symlink_loops_terminate(tmp_path):
    make_pkg(tmp_path / ".git" / "not_a_pkg")
    make_pkg(tmp_path / "a" / "real")
    os.symlink(tmp_path / "a", tmp_path / "a" / "loop")
    assert [name for name, _ in crawl(str(tmp_path)).packages] == ["real"]


def test_first_root_wins_and_duplicates_are_remembered(tmp_path):
    first = make_pkg(tmp_path / "one" / "dup")
    second = make_pkg(tmp_path / "two" / "dup")
    make_pkg(tmp_path / "two" / "only_two")
    index = PackageIndex.build([str(tmp_path / "one"), str(tmp_path / "two")], cache_dir=None)
    assert index.find("dup") == str(first)
    assert index.duplicates == {"dup": [str(second)]}
    assert index.find("only_two") == str(tmp_path / "two" / "only_two")


def test_unknown_package_raises_package_not_found_naming_it(tmp_path):
    index = PackageIndex.build([str(tmp_path)], cache_dir=None)
    with pytest.raises(PackageNotFound, match="'nope'"):
        index.find("nope")


def test_search_roots_order_rpp_then_catkin_prefix_then_workspace_then_bundled(tmp_path):
    rpp = tmp_path / "rpp"
    prefix = tmp_path / "opt"
    (prefix / "share").mkdir(parents=True)
    (prefix / ".catkin").write_text("")
    not_catkin = tmp_path / "usr_local"
    (not_catkin / "share").mkdir(parents=True)
    ws = tmp_path / "ws"
    (ws / "src" / "pkg").mkdir(parents=True)
    (ws / ".catkin_workspace").write_text("")
    env = {"ROS_PACKAGE_PATH": f"{rpp}{os.pathsep}{rpp}",
           "CMAKE_PREFIX_PATH": f"{not_catkin}{os.pathsep}{prefix}"}
    roots = search_roots(env, cwd=str(ws / "src" / "pkg"))
    assert [(r.path, r.origin) for r in roots] == [
        (str(rpp), "ROS_PACKAGE_PATH"), (str(prefix / "share"), "CMAKE_PREFIX_PATH"),
        (str(ws / "src"), "workspace"), (BUNDLED_PACKAGES, "bundled")]


def test_devel_space_marker_lists_source_spaces(tmp_path):
    devel = tmp_path / "ws" / "devel"
    devel.mkdir(parents=True)
    (devel / ".catkin").write_text(str(tmp_path / "ws" / "src"))
    roots = search_roots({"CMAKE_PREFIX_PATH": str(devel)}, cwd="/")
    assert [r.path for r in roots][:2] == [str(tmp_path / "ws" / "src"), str(devel / "share")]


def test_workspace_is_found_from_a_bare_src_directory_without_markers(tmp_path):
    (tmp_path / "ws" / "src" / "a" / "b").mkdir(parents=True)
    assert catkin_workspace(str(tmp_path / "ws" / "src" / "a" / "b")) == str(tmp_path / "ws")
    assert catkin_workspace(str(tmp_path / "ws")) is None  # src/ below the cwd does not count


def test_bundled_demo_packages_are_found_with_an_empty_environment(monkeypatch, tmp_path):
    bundled = sorted(os.listdir(BUNDLED_PACKAGES)) if os.path.isdir(BUNDLED_PACKAGES) else []
    bundled = [d for d in bundled if os.path.isfile(os.path.join(BUNDLED_PACKAGES, d, "package.xml"))]
    assert bundled, "the repository's packages/ holds the demo packages"
    for var in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "HOME"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "rh"))
    monkeypatch.chdir(tmp_path)
    assert find_package(bundled[0]).startswith(BUNDLED_PACKAGES)


def test_ros_package_path_shadows_bundled_package(monkeypatch, tmp_path):
    names = [d for d in os.listdir(BUNDLED_PACKAGES)
             if os.path.isfile(os.path.join(BUNDLED_PACKAGES, d, "package.xml"))]
    bundled_name = None
    for d in names:
        text = Path(BUNDLED_PACKAGES, d, "package.xml").read_text()
        if f"<name>{d}</name>" in text:
            bundled_name = d
            break
    assert bundled_name
    mine = make_pkg(tmp_path / "rpp" / bundled_name)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "rpp"))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "rh"))
    monkeypatch.chdir(tmp_path)
    assert find_package(bundled_name) == str(mine)


def test_compat_workspace_has_all_118_packages(compat_dir, tmp_path):
    index = PackageIndex.build([str(compat_dir / "ws")], cache_dir=str(tmp_path))
    # like rospack, the 16 metapackages among them are not findable packages
    assert len(index.packages) + len(index.metapackages) == 118
    assert len(index.metapackages) == 16
    assert index.find("turtlesim") == str(compat_dir / "ws" / "turtlesim")


def test_metapackage_is_not_found_like_rospack_and_the_error_says_why(tmp_path):
    root = tmp_path / "root"
    make_pkg(root / "real_pkg")
    meta = root / "meta_pkg"
    meta.mkdir(parents=True)
    (meta / "package.xml").write_text(
        '<package format="2"><name>meta_pkg</name><version>1.0.0</version>'
        "<description>d</description><maintainer email='a@b.c'>a</maintainer>"
        "<license>BSD</license><buildtool_depend>catkin</buildtool_depend>"
        "<exec_depend>real_pkg</exec_depend><export><metapackage/></export></package>")
    (meta / "inner").mkdir()
    make_pkg(meta / "inner" / "hidden_pkg")  # a metapackage stops the descent like a package
    index = PackageIndex.build([str(root)], cache_dir=str(tmp_path / "cache"))
    assert "real_pkg" in index and "meta_pkg" not in index and "hidden_pkg" not in index
    with pytest.raises(PackageNotFound, match="is a metapackage"):
        index.find("meta_pkg")
    # the warm cache keeps the distinction
    warm = PackageIndex.build([str(root)], cache_dir=str(tmp_path / "cache"))
    assert "meta_pkg" not in warm and warm.metapackages["meta_pkg"] == str(meta)


# -- the disk cache -----------------------------------------------------------------------------

def test_warm_cache_lists_no_directory_and_finds_the_same_packages(tmp_path):
    root = tmp_path / "root"
    for i in range(5):
        make_pkg(root / f"group{i % 2}" / f"pkg{i}")
    age(root)
    cold = PackageIndex.build([str(root)], cache_dir=str(tmp_path / "cache"))
    assert cold.listed > 0
    warm = PackageIndex.build([str(root)], cache_dir=str(tmp_path / "cache"))
    assert warm.listed == 0
    assert warm.packages == cold.packages


def test_cache_notices_added_package_removed_package_and_renamed_manifest(tmp_path):
    root = tmp_path / "root"
    make_pkg(root / "g" / "keep")
    make_pkg(root / "g" / "gone")
    age(root)
    cache_dir = str(tmp_path / "cache")
    PackageIndex.build([str(root)], cache_dir=cache_dir)
    make_pkg(root / "g" / "added")
    import shutil
    shutil.rmtree(root / "g" / "gone")
    make_pkg(root / "g" / "keep", name="renamed")  # same directory, new <name>
    index = PackageIndex.build([str(root)], cache_dir=cache_dir)
    assert sorted(index.packages) == ["added", "renamed"]


def test_cache_notices_catkin_ignore_added_later(tmp_path):
    root = tmp_path / "root"
    make_pkg(root / "sub" / "p")
    age(root)
    cache_dir = str(tmp_path / "cache")
    assert "p" in PackageIndex.build([str(root)], cache_dir=cache_dir).packages
    (root / "sub" / "CATKIN_IGNORE").write_text("")
    assert "p" not in PackageIndex.build([str(root)], cache_dir=cache_dir).packages


def test_records_younger_than_the_racy_window_are_not_trusted(tmp_path):
    make_pkg(tmp_path / "new_pkg")  # just written: its mtime is "now"
    result = crawl(str(tmp_path))
    assert all(record[0] == -1 for record in result.records.values())
    again = crawl(str(tmp_path), result.records)
    assert again.listed == len(result.records)


def test_corrupt_or_foreign_cache_file_is_ignored(tmp_path):
    root = tmp_path / "root"
    make_pkg(root / "p")
    cache_dir = tmp_path / "cache"
    cache_dir.mkdir()
    path = cache.cache_file(str(cache_dir), str(root))
    with open(path, "w") as fh:
        fh.write("{not json")
    assert PackageIndex.build([str(root)], cache_dir=str(cache_dir)).find("p")
    with open(path, "w") as fh:
        json.dump({"format": cache.FORMAT, "root": "/elsewhere", "records": {}}, fh)
    assert cache.load(str(cache_dir), str(root)) == {}


def test_unwritable_cache_directory_never_fails(tmp_path):
    root = tmp_path / "root"
    make_pkg(root / "p")
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    index = PackageIndex.build([str(root)], cache_dir=str(blocker / "orchestra"))
    assert index.find("p") == str(root / "p")


def test_cache_write_is_atomic_rename_leaving_no_temporary_files(tmp_path):
    root = tmp_path / "root"
    make_pkg(root / "p")
    age(root)
    cache_dir = tmp_path / "cache"
    PackageIndex.build([str(root)], cache_dir=str(cache_dir))
    assert os.listdir(cache_dir) == [os.path.basename(cache.cache_file(str(cache_dir), str(root)))]


def test_cache_location_respects_ros_home_and_survives_unset_home():
    assert cache.default_cache_dir({"ROS_HOME": "/x/ros"}) == "/x/ros/orchestra"
    fallback = cache.default_cache_dir({})
    assert fallback is None or fallback.endswith(os.path.join(".ros", "orchestra"))


def test_process_index_is_built_once_and_rebuilt_when_path_changes(monkeypatch, tmp_path):
    from orchestra.packages.index import get_index

    make_pkg(tmp_path / "a" / "pa")
    make_pkg(tmp_path / "b" / "pb")
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "rh"))
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "a"))
    monkeypatch.chdir(tmp_path)
    first = get_index()
    assert get_index() is first
    assert find_package("pa") == str(tmp_path / "a" / "pa")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "b"))
    assert find_package("pb") == str(tmp_path / "b" / "pb")
    assert get_index() is not first


def test_cache_directory_is_pruned_to_the_most_recent_files(tmp_path, monkeypatch):
    monkeypatch.setattr(cache, "MAX_FILES", 5)
    monkeypatch.setattr(cache, "KEEP_FILES", 3)
    cache_dir = str(tmp_path / "cache")
    for i in range(5):
        assert cache.save(cache_dir, f"/root/{i}", {})
        os.utime(cache.cache_file(cache_dir, f"/root/{i}"), (OLD + i, OLD + i))
    assert cache.save(cache_dir, "/root/new", {})
    left = sorted(os.listdir(cache_dir))
    expected = ["/root/new", "/root/4", "/root/3"]
    assert left == sorted(os.path.basename(cache.cache_file(cache_dir, r)) for r in expected)


def test_deleted_cwd_does_not_break_lookup(tmp_path, monkeypatch):
    make_pkg(tmp_path / "rpp" / "still_here")
    gone = tmp_path / "gone"
    gone.mkdir()
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "rpp"))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "rh"))
    monkeypatch.chdir(gone)
    gone.rmdir()
    assert find_package("still_here") == str(tmp_path / "rpp" / "still_here")


_WRITER = """
import sys
from orchestra.packages import cache
cache_dir, root, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
records = {f"/r/{i}": [i, "dir", [f"c{j}" for j in range(50)]] for i in range(n)}
for _ in range(15):
    assert cache.save(cache_dir, root, records)
    loaded = cache.load(cache_dir, root)
    assert len(loaded) in (300, 400), len(loaded)  # a whole file of one writer or the other
"""


@pytest.mark.timeout(120)
def test_concurrent_writers_and_readers_never_see_a_partial_cache_file(tmp_path):
    import subprocess
    import sys

    cache_dir = str(tmp_path / "cache")
    procs = [subprocess.Popen([sys.executable, "-c", _WRITER, cache_dir, "/shared/root", str(n)],
                              stderr=subprocess.PIPE, text=True)
             for n in (300, 400, 300, 400)]
    for proc in procs:
        _, err = proc.communicate(timeout=100)
        assert proc.returncode == 0, err
    assert [n for n in os.listdir(cache_dir) if n.endswith(".tmp")] == []


def test_package_created_after_the_index_was_built_is_found_on_miss(tmp_path, monkeypatch):
    make_pkg(tmp_path / "rpp" / "early")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "rpp"))
    monkeypatch.setenv("ROS_HOME", str(tmp_path / "rh"))
    monkeypatch.chdir(tmp_path)
    assert find_package("early")
    make_pkg(tmp_path / "rpp" / "late")
    assert find_package("late") == str(tmp_path / "rpp" / "late")
    with pytest.raises(PackageNotFound):
        find_package("never")
