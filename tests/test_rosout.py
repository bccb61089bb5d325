"""rosout without processes: rosout.log lines, rotation, log directory, aggregation, and which
core nodes ``orchestra launch`` / ``orchestra core`` add."""
from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "packages" / "rosout" / "src"))

from rosout_core.aggregator import Aggregator  # noqa: E402
from rosout_core.logfile import (  # noqa: E402
    RosoutLog,
    format_line,
    format_stamp,
    level_name,
    log_directory,
    plan_rotation,
    startup_banner,
)

from orchestra.app.options import RunOptions  # noqa: E402
from orchestra.launch.plan import Node  # noqa: E402
from orchestra.supervise.rosout import ROSOUT, core_nodes, resolve_core_executables  # noqa: E402
from orchestra.supervise.specs import run_specs  # noqa: E402


def log_msg(level=2, name="/talker", text="hello", topics=("/rosout", "/chatter"),
            secs=1700000000, nsecs=5):
    return SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(secs=secs, nsecs=nsecs)),
                           level=level, name=name, msg=text, file="talker.py",
                           function="main", line=12, topics=list(topics))


def test_line_has_rosout_layout_stamp_level_node_location_topics_text():
    assert format_line(log_msg()) == (
        "1700000000.000000005 INFO /talker [talker.py:12(main)] "
        "[topics: /rosout, /chatter] hello\n")


def test_omit_topics_leaves_the_topics_bracket_out():
    assert format_line(log_msg(), omit_topics=True) == (
        "1700000000.000000005 INFO /talker [talker.py:12(main)] hello\n")


def test_line_of_a_real_rosgraph_log_message():
    from orchestra.node.msg import get_message_class
    from orchestra.node.rostime import Time

    msg = get_message_class("rosgraph_msgs/Log")(level=8, name="/n", msg="bad", file="f.py",
                                                 function="g", line=3, topics=[])
    msg.header.stamp = Time(12, 345)
    assert format_line(msg) == "12.000000345 ERROR /n [f.py:3(g)] [topics: ] bad\n"


@pytest.mark.parametrize("level,word", [(1, "DEBUG"), (2, "INFO"), (4, "WARN"), (8, "ERROR"),
                                        (16, "FATAL"), (3, "3")])
def test_level_words_and_unknown_level_as_number(level, word):
    assert level_name(level) == word


def test_stamp_nanoseconds_are_zero_padded_to_nine_digits():
    assert format_stamp(5, 120) == "5.000000120"
    assert startup_banner(5, 0) == "\n\n5.000000000  Node Startup\n"


def test_log_directory_is_the_directory_of_the_log_argument():
    argv = ["rosout", "__name:=rosout", "__log:=/logs/run1/rosout-1.log"]
    assert log_directory(argv, {"ROS_LOG_DIR": "/elsewhere"}) == "/logs/run1"


def test_log_directory_without_log_argument_follows_roscpp_roots():
    assert log_directory(["rosout"], {"ROS_LOG_DIR": "/l", "ROS_HOME": "/h"}) == "/l"
    assert log_directory(["rosout"], {"ROS_HOME": "/h"}) == "/h/log"
    assert log_directory(["rosout"], {"HOME": "/home/u"}) == "/home/u/.ros/log"


def test_rotation_plan_shifts_oldest_first_and_drops_past_the_limit():
    first = plan_rotation("r.log", 0, 3)
    assert first.delete is None and first.renames == (("r.log", "r.log.1"),)
    full = plan_rotation("r.log", 3, 3)
    assert full.delete == "r.log.3"
    assert full.renames == (("r.log.2", "r.log.3"), ("r.log.1", "r.log.2"), ("r.log", "r.log.1"))
    assert full.backups == 3
    assert plan_rotation("r.log", 0, 0).renames == ()


def test_log_file_rotates_past_max_size_keeping_max_backups(tmp_path):
    path = tmp_path / "run" / "rosout.log"
    log = RosoutLog(str(path), max_bytes=100, max_backups=2)
    log.open(startup_banner(1, 0))
    for i in range(20):
        log.write(f"line {i:02d} " + "x" * 30 + "\n")
    log.close()
    names = sorted(p.name for p in path.parent.iterdir())
    assert names == ["rosout.log", "rosout.log.1", "rosout.log.2"]
    # banner 27 bytes, then 39-byte lines: every third one passes 100 bytes, a new file
    assert [line[:7] for line in (path.parent / "rosout.log.1").read_text().splitlines()] == [
        "line 17", "line 18", "line 19"]
    assert (path.parent / "rosout.log.2").read_text().startswith("line 14")
    assert path.read_text() == ""


def test_restarted_rosout_appends_after_a_new_banner(tmp_path):
    path = tmp_path / "rosout.log"
    path.write_text("1.000000000 INFO /a [f:1(g)] [topics: ] before the respawn\n")
    log = RosoutLog(str(path))
    log.open(startup_banner(2, 0))
    log.close()
    assert path.read_text() == ("1.000000000 INFO /a [f:1(g)] [topics: ] before the respawn\n"
                                "\n\n2.000000000  Node Startup\n")


def test_appending_counts_the_existing_size_towards_rotation(tmp_path):
    path = tmp_path / "rosout.log"
    path.write_text("x" * 90 + "\n")
    log = RosoutLog(str(path), max_bytes=100, max_backups=1)
    log.open()
    log.write("0123456789\n")
    log.close()
    assert path.read_text() == "" and (tmp_path / "rosout.log.1").stat().st_size == 102


def test_aggregator_republishes_then_writes_each_message(tmp_path):
    events = []
    log = RosoutLog(str(tmp_path / "rosout.log"))
    log.open()
    agg = Aggregator(lambda m: events.append(("pub", m.msg, log.size)), log)
    agg.on_message(log_msg(text="one"))
    agg.on_message(log_msg(text="two", level=4))
    log.close()
    assert [e[:2] for e in events] == [("pub", "one"), ("pub", "two")]
    assert events[0][2] == 0                      # published before anything was written
    lines = (tmp_path / "rosout.log").read_text().splitlines()
    assert [line.split(" ")[1] for line in lines] == ["INFO", "WARN"]
    assert agg.count == 2


def test_rosout_is_added_first_only_with_the_embedded_master():
    talker = Node("demo", "talker", "talker")
    assert core_nodes([talker], embedded_master=True) == [ROSOUT]
    assert ROSOUT.full_name == "/rosout" and ROSOUT.respawn
    assert core_nodes([talker], embedded_master=False) == []
    assert core_nodes([talker], embedded_master=True, enabled=False) == []


def test_a_plan_declaring_its_own_rosout_keeps_it():
    own = Node("rosout", "rosout", "rosout", respawn=False)
    assert core_nodes([own], embedded_master=True) == []


def test_missing_rosout_package_is_a_warning_not_an_error(monkeypatch, tmp_path):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path))
    warnings = []
    missing = Node("no_such_pkg_xyz", "rosout", "rosout")
    assert resolve_core_executables([missing], warnings.append) == {}
    assert "not starting /rosout" in warnings[0]


def test_bundled_rosout_is_found_and_counts_first_like_roslaunch(tmp_path):
    exes = resolve_core_executables([ROSOUT], pytest.fail)
    assert exes["/rosout"].endswith("rosout")
    talker = Node("demo", "talker", "talker")
    specs = run_specs([ROSOUT], [talker], {**exes, "/talker": "/bin/true"},
                      "http://127.0.0.1:1/", str(tmp_path), RunOptions())
    assert [s.log_name for s in specs] == ["rosout-1", "talker-2"]
    assert specs[0].respawn and f"__log:={tmp_path}/rosout-1.log" in specs[0].argv


def test_required_flag_leaves_rosout_respawning_instead_of_ending_the_launch(tmp_path):
    talker = Node("demo", "talker", "talker")
    specs = run_specs([ROSOUT], [talker], {"/rosout": "/bin/true", "/talker": "/bin/true"},
                      "http://127.0.0.1:1/", str(tmp_path), RunOptions(all_required=True))
    assert [(s.name, s.required, s.respawn) for s in specs] == [
        ("/rosout", False, True), ("/talker", True, False)]


def test_no_rosout_option_reaches_the_run_options():
    assert RunOptions.from_kwargs({"no_rosout": True}).no_rosout
    assert not RunOptions.from_kwargs({}).no_rosout
