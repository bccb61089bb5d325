"""The logger services of every node (``~get_loggers``, ``~set_logger_level``) and
``orchestra node loggers`` / ``set-logger-level``, with real node processes on loopback.

The node under test (node_fixtures/logger_node.py) logs one round per line on its stdin:
debug, info, warn, then a fatal "end" marker. Its stdout report of the round comes after
its DEBUG/INFO console lines, and the marker closes the round on stderr and on /rosout, so
what a round printed and published is known exactly, without waiting for silence.
"""
from __future__ import annotations

import logging
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
import harness  # noqa: E402
from harness import wait_for  # noqa: E402
from test_node_simtime import Driven  # noqa: E402  (a NodeProcess with a stdin pipe)

from orchestra.node import loggers  # noqa: E402

pytestmark = pytest.mark.timeout(60)

FIXTURE = Path(__file__).resolve().parent / "node_fixtures" / "logger_node.py"
KINDS = ("debug", "info", "warn", "end")


def start_talker(group, env: dict[str, str], *args: str) -> Driven:
    """logger_node.py as a process of ``group`` (stopped by its close())."""
    proc = Driven([sys.executable, str(FIXTURE), *args], dict(env))
    group.procs.append(proc)
    return proc


def run_all(env: dict[str, str], *commands: tuple[str, ...], timeout: float = 30
            ) -> list[subprocess.CompletedProcess]:
    """``orchestra ...`` commands run concurrently (each is an interpreter start-up)."""
    return harness.run_all([(argv, [sys.executable, "-m", "orchestra", *argv], env)
                            for argv in commands], timeout)


def orchestra(env: dict[str, str], *args: str) -> subprocess.CompletedProcess:
    return run_all(env, args)[0]


def run_round(talker: Driven, r: int, reader=None) -> tuple[set[str], set[str] | None]:
    """Make the talker log round ``r``: (kinds printed on its console, kinds it published
    on /rosout as ``reader`` received them; None without a reader)."""
    talker.send(str(r))
    talker.expect(lambda d: d.get("round") == str(r))
    prefix = f"round {r} "
    console = {item["text"].rsplit(" ", 1)[-1] for item in talker.seen
               if prefix in item.get("text", "")}
    wait_for(lambda: any(prefix + "end" in line for line in talker.stderr_lines), timeout=10)
    console |= {line.rsplit(" ", 1)[-1] for line in talker.stderr_lines if prefix in line}
    if reader is None:
        return console, None
    reader.expect(lambda d: d.get("msg", {}).get("msg") == prefix + "end")
    published = {item["msg"]["msg"].rsplit(" ", 1)[-1] for item in reader.seen
                 if item.get("msg", {}).get("msg", "").startswith(prefix)}
    return console, published


def level_table(text: str) -> dict[str, str]:
    return dict(line.split() for line in text.splitlines())


# --- in-process: level names ------------------------------------------------------------------

def test_level_names_are_roscpps_and_python_levels_in_between_round_down():
    assert [loggers.level_name(v) for v in (5, 10, 20, 25, 30, 40, 50, 60)] == \
        ["debug", "debug", "info", "info", "warn", "error", "fatal", "fatal"]
    assert [loggers.python_level(n) for n in ("DEBUG", "info", "Warn", "error", "FATAL")] == \
        [logging.DEBUG, logging.INFO, logging.WARNING, logging.ERROR, logging.CRITICAL]
    with pytest.raises(ValueError, match=r"unknown logger level \[loud\]"):
        loggers.python_level("loud")


def test_library_console_shows_debug_lines_only_of_loggers_whose_level_was_lowered():
    from orchestra.node.runtime import _explicitly_lowered

    name = "orchestra.node.test_loggers_probe"
    probe, parent = logging.getLogger(name), logging.getLogger("orchestra.node")

    def record(level):
        return logging.LogRecord(name, level, __file__, 1, "x", None, None)
    try:
        assert _explicitly_lowered(record(logging.WARNING))
        assert not _explicitly_lowered(record(logging.DEBUG))  # only the root's level: hidden
        probe.setLevel(logging.DEBUG)
        assert _explicitly_lowered(record(logging.DEBUG))
        probe.setLevel(logging.NOTSET)
        parent.setLevel(logging.INFO)  # set on an ancestor below the root counts too
        assert _explicitly_lowered(record(logging.INFO))
    finally:
        probe.setLevel(logging.NOTSET)
        parent.setLevel(logging.NOTSET)


# --- real processes -----------------------------------------------------------------------------

def test_every_node_offers_the_logger_services_listing_its_python_loggers(nodes):
    start_talker(nodes, nodes.env, "--name", "talk").ready()
    # rospy offers them whatever init_node's flags: so does orchestra
    start_talker(nodes, nodes.env, "--name", "quiet", "--disable-rosout").ready()
    services = {name: providers for name, providers in nodes.master().getSystemState("/t")[2][2]}
    for node in ("/talk", "/quiet"):
        assert services.get(f"{node}/get_loggers") == [node]
        assert services.get(f"{node}/set_logger_level") == [node]
    table, names, one, raw = run_all(nodes.env, ("node", "loggers", "-l", "/talk"),
                                     ("node", "loggers", "talk"),
                                     ("node", "loggers", "/talk", "rosout"),
                                     ("service", "call", "/quiet/get_loggers"))
    for result in (table, names, one, raw):
        assert result.returncode == 0, (result.args, result.stderr)
    levels = level_table(table.stdout)
    # the node's own messages go through "rosout" (as in rospy), the library's through
    # orchestra.node.*, which shows warnings and worse unless told otherwise
    assert levels["rosout"] == "info"
    assert levels["orchestra.node"] == levels["orchestra.node.topics"] == "warn"
    assert set(levels.values()) <= set(loggers.LEVEL_NAMES)
    # rosconsole list's shape: one name per line, here sorted
    assert names.stdout.splitlines() == list(levels) == sorted(levels)
    assert one.stdout == "info\n"
    answer = yaml.safe_load(raw.stdout)["loggers"]
    assert {"name": "rosout", "level": "info"} in answer


def test_set_logger_level_takes_effect_at_once_on_console_and_rosout(nodes):
    reader = nodes.start("sub.py", "/rosout", "rosgraph_msgs/Log", "--name", "reader",
                         "--queue", "100")
    talker = start_talker(nodes, nodes.env, "--name", "talk", "--rosout-subscribers", "1")
    reader.ready()
    talker.ready()
    everything = set(KINDS)
    assert run_round(talker, 1, reader) == (everything - {"debug"}, everything - {"debug"})

    lowered = orchestra(nodes.env, "node", "set-logger-level", "/talk", "rosout", "debug")
    assert (lowered.returncode, lowered.stdout) == (0, ""), lowered.stderr  # as rosconsole set
    assert run_round(talker, 2, reader) == (everything, everything)

    # the service itself, as rqt_logger_level calls it: the level in any case
    raised = orchestra(nodes.env, "service", "call", "/talk/set_logger_level",
                       "{logger: rosout, level: WARN}")
    assert raised.returncode == 0, raised.stderr
    assert run_round(talker, 3, reader) == ({"warn", "end"}, {"warn", "end"})
    assert orchestra(nodes.env, "node", "loggers", "/talk", "rosout").stdout == "warn\n"

    orchestra(nodes.env, "node", "set-logger-level", "/talk", "rosout", "FATAL")
    assert run_round(talker, 4, reader) == ({"end"}, {"end"})


def test_an_unknown_level_is_a_service_error_and_changes_nothing(nodes):
    talker = start_talker(nodes, nodes.env, "--name", "talk")
    talker.ready()
    service, cli_level, cli_logger, cli_node = run_all(
        nodes.env,
        ("service", "call", "/talk/set_logger_level", "{logger: rosout, level: loud}"),
        ("node", "set-logger-level", "/talk", "rosout", "loud"),
        ("node", "set-logger-level", "/talk", "no.such.logger", "debug"),
        ("node", "loggers", "/ghost"))
    # the node answers with an error (roscpp does; rospy only logs it) and says so itself
    assert service.returncode == 1
    assert "responded with an error" in service.stderr
    assert "unknown logger level [loud]" in service.stderr
    wait_for(lambda: any("unknown logger level [loud]" in line
                         for line in talker.stderr_lines), timeout=10)
    # the CLI checks level and logger before asking, as rosconsole set does: usage errors
    assert cli_level.returncode == 2 and "'loud' is not one of" in cli_level.stderr
    assert cli_logger.returncode == 2
    assert "node /talk does not contain logger no.such.logger" in cli_logger.stderr
    assert cli_node.returncode == 2
    assert "node [/ghost] does not exist or offers no logger services" in cli_node.stderr
    assert orchestra(nodes.env, "node", "loggers", "/talk", "rosout").stdout == "info\n"
    assert run_round(talker, 1)[0] == {"info", "warn", "end"}


# --- against real ROS 1 (Debian's rospy and ros* tools) -------------------------------------

def _interop():
    import test_interop_ros1
    return test_interop_ros1


@pytest.fixture
def side(master, tmp_path):
    """orchestra's master with room for real rospy and orchestra processes."""
    interop = _interop()
    if interop._MISSING is not None:
        pytest.skip(interop._MISSING)
    group = interop.Side(master.uri, tmp_path / "ros_home")
    yield group
    group.close()


def test_real_rosservice_sets_the_level_of_an_orchestra_node(side):
    talker = start_talker(side, side.orch_env, "--name", "talk")
    talker.ready()
    listed, set_warn, bad = side.run_all(
        ("rosservice", "list"),
        ("rosservice", "call", "/talk/set_logger_level", "rosout", "warn"),
        ("rosservice", "call", "/talk/set_logger_level", "{logger: rosout, level: loud}"))
    assert {"/talk/get_loggers", "/talk/set_logger_level"} <= set(listed.stdout.split())
    assert set_warn.returncode == 0, set_warn.stderr
    assert bad.returncode != 0 and "unknown logger level [loud]" in bad.stdout + bad.stderr
    assert run_round(talker, 1)[0] == {"warn", "end"}
    got = side.tool("rosservice", "call", "/talk/get_loggers")
    assert got.returncode == 0, got.stderr
    assert {"name": "rosout", "level": "warn"} in yaml.safe_load(got.stdout)["loggers"]


def test_orchestra_cli_reads_and_sets_the_levels_of_a_rospy_node(side):
    side.rospy("--name", "peer", "sub", "chatter", "std_msgs/String").ready()
    table, one = side.run_all(("orchestra", "node", "loggers", "-l", "/peer"),
                              ("orchestra", "node", "loggers", "/peer", "rosout"))
    assert table.returncode == 0, table.stderr
    levels = level_table(table.stdout)
    # printed as the node answers: rospy's names are upper-case (roscpp's lower-case)
    assert levels["rosout"] == "INFO" and "rospy.topics" in levels
    assert one.stdout == "INFO\n"
    for logger, level in (("rosout", "warn"), ("rospy.topics", "debug")):
        result = side.orchestra("node", "set-logger-level", "/peer", logger, level)
        assert (result.returncode, result.stdout) == (0, ""), result.stderr
    levels = level_table(side.orchestra("node", "loggers", "-l", "/peer").stdout)
    assert (levels["rosout"], levels["rospy.topics"]) == ("WARN", "DEBUG")
