"""diagnostic_aggregator's analyzers: matching, renaming, staleness, levels, config errors."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest
import yaml

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "diagnostic_aggregator" / "src"))

from diagnostic_aggregator.analyzers import (  # noqa: E402
    ERROR,
    OK,
    STALE,
    WARN,
    Aggregator,
    AnalyzerConfigError,
    GenericAnalyzer,
    Status,
    build_analyzers,
    remove_leading_chaff,
)


def test_remove_prefix_strips_node_name_colon_and_spaces():
    assert remove_leading_chaff("mobile_base_nodelet_manager: Battery",
                                "mobile_base_nodelet_manager") == "Battery"
    assert remove_leading_chaff("other: Battery", "mobile_base_nodelet_manager") == "other: Battery"
    assert remove_leading_chaff("/a/mgr: X", "mgr") == "/a/X"


def test_generic_analyzer_matching_rules():
    a = GenericAnalyzer("P", contains=["Batt"], startswith="Motor", name="Exact", regex="^r[0-9]$")
    assert a.match("mgr: Battery")
    assert a.match("Motor State") and not a.match("The Motor")
    assert a.match("Exact") and not a.match("Exactly")
    assert a.match("r7") and not a.match("r77")


def test_items_are_renamed_under_base_path_and_path():
    a = GenericAnalyzer("Power System", "robot", contains="Battery", remove_prefix="mgr")
    a.analyze(Status(OK, "mgr: Battery", "Normal"), now=0.0)
    header, item = a.report(now=1.0)
    assert header.name == "/robot/Power System"
    assert item.name == "/robot/Power System/Battery"
    assert item.message == "Normal"


def test_header_level_is_worst_item_level():
    a = GenericAnalyzer("K", contains=["A", "B"])
    a.analyze(Status(OK, "A"), 0.0)
    a.analyze(Status(WARN, "B", "hot"), 0.0)
    header = a.report(1.0)[0]
    assert (header.level, header.message) == (WARN, "Warning")


def test_stale_item_among_fresh_ones_makes_header_error():
    a = GenericAnalyzer("K", contains=["A", "B"], timeout=5.0)
    a.analyze(Status(OK, "A"), 0.0)
    a.analyze(Status(OK, "B"), 4.0)
    header, first, second = a.report(6.0)
    assert first.level == STALE and second.level == OK
    assert header.level == ERROR


def test_all_stale_header_is_stale():
    a = GenericAnalyzer("K", contains="A", timeout=1.0)
    a.analyze(Status(OK, "A"), 0.0)
    header = a.report(10.0)[0]
    assert (header.level, header.message) == (STALE, "Stale")


def test_analyzer_without_items_is_stale():
    assert GenericAnalyzer("K", contains="A").report(0.0)[0].level == STALE


def test_discard_stale_drops_old_items():
    a = GenericAnalyzer("K", contains="A", timeout=1.0, discard_stale=True)
    a.analyze(Status(OK, "A"), 0.0)
    assert len(a.report(10.0)) == 1


def test_expected_item_is_listed_missing_until_it_reports():
    a = GenericAnalyzer("K", expected=["Watchdog"])
    header, item = a.report(0.0)
    assert (item.name, item.level, item.message) == ("/K/Watchdog", STALE, "Missing")
    assert header.level == STALE
    a.analyze(Status(OK, "Watchdog", "Alive"), 1.0)
    header, item = a.report(2.0)
    assert (header.level, item.level, item.message) == (OK, OK, "Alive")


def test_expected_item_dropped_as_stale_makes_header_error():
    a = GenericAnalyzer("K", expected=["Watchdog"], contains="Motor", timeout=1.0,
                        discard_stale=True)
    a.analyze(Status(OK, "Watchdog"), 0.0)
    a.analyze(Status(OK, "Motor"), 9.5)
    header, *items = a.report(10.0)
    assert (header.level, header.message) == (ERROR, "Error")
    assert ("/K/Watchdog", STALE, "Missing") in [(i.name, i.level, i.message) for i in items]


def test_num_items_mismatch_is_an_error():
    a = GenericAnalyzer("K", contains="M", num_items=2)
    a.analyze(Status(OK, "M1"), 0.0)
    header = a.report(1.0)[0]
    assert (header.level, header.message) == (ERROR, "Expected 2, found 1")


def test_slashes_in_item_names_do_not_deepen_the_tree():
    a = GenericAnalyzer("Motors", contains="motor")
    a.analyze(Status(OK, "left/motor"), 0.0)
    assert a.report(1.0)[1].name == "/Motors/left motor"


def test_header_values_list_raw_names_and_messages():
    a = GenericAnalyzer("P", contains="Battery", remove_prefix="mgr")
    a.analyze(Status(OK, "mgr: Battery", "Normal"), 0.0)
    assert a.report(1.0)[0].values == [("mgr: Battery", "Normal")]


def test_every_matching_analyzer_gets_the_item_and_unmatched_go_to_other():
    analyzers = build_analyzers({
        "a_power": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "Power",
                    "contains": "Battery"},
        "b_all": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "All",
                  "startswith": "B"},
    })
    agg = Aggregator(analyzers)
    agg.add(Status(OK, "Battery"), 0.0)
    agg.add(Status(OK, "Gyro"), 0.0)
    names = [s.name for s in agg.report(1.0)[0]]
    assert "/Power/Battery" in names and "/All/Battery" in names
    assert "/Other/Gyro" in names


def test_unclaimed_items_appear_under_other_until_stale():
    agg = Aggregator(build_analyzers({"p": {"type": "diagnostic_aggregator/GenericAnalyzer",
                                            "path": "Power", "contains": "Battery"}}))
    agg.add(Status(WARN, "Mystery"), 0.0)
    statuses, top = agg.report(1.0)
    assert "/Other/Mystery" in [s.name for s in statuses]
    assert "/Other" not in [s.name for s in agg.report(100.0)[0]]


def test_toplevel_state_counts_stale_as_error_unless_all_stale():
    agg = Aggregator(build_analyzers({
        "a": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "A", "contains": "x",
              "timeout": 1.0},
        "b": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "B", "contains": "y",
              "timeout": 100.0}}))
    agg.add(Status(OK, "x"), 0.0)
    agg.add(Status(OK, "y"), 0.0)
    assert agg.report(0.5)[1].level == OK
    assert agg.report(5.0)[1].level == ERROR     # x went stale, y is fine
    assert agg.report(500.0)[1].level == STALE   # everything stale


def test_group_without_analyzers_is_an_error():
    group = build_analyzers({"g": {"type": "diagnostic_aggregator/AnalyzerGroup",
                                   "path": "G", "analyzers": {}}})[0]
    header, = group.report(0.0)
    assert (header.name, header.level, header.message) == ("/G", ERROR, "No analyzers")


def test_toplevel_state_is_worst_analyzer():
    agg = Aggregator(build_analyzers({
        "a": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "A", "contains": "x"},
        "b": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "B", "contains": "y"}}))
    agg.add(Status(OK, "x"), 0.0)
    agg.add(Status(ERROR, "y", "broken"), 0.0)
    assert agg.report(1.0)[1].level == ERROR


def test_analyzer_group_nests_paths():
    analyzers = build_analyzers({"base": {
        "type": "diagnostic_aggregator/AnalyzerGroup", "path": "Base",
        "analyzers": {"motors": {"type": "diagnostic_aggregator/GenericAnalyzer",
                                 "path": "Motors", "contains": "Motor"}}}})
    agg = Aggregator(analyzers)
    agg.add(Status(WARN, "Motor State"), 0.0)
    statuses, _ = agg.report(1.0)
    by_name = {s.name: s for s in statuses}
    assert by_name["/Base"].level == WARN
    assert by_name["/Base/Motors/Motor State"].level == WARN


@pytest.mark.parametrize("spec, message", [
    ({"x": {"type": "diagnostic_aggregator/Nope", "path": "X"}}, "unsupported type"),
    ({"x": {"type": "diagnostic_aggregator/GenericAnalyzer", "contains": "a"}}, "needs a 'path'"),
    ({"x": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "X", "contain": "a"}},
     "unknown option"),
    ({"x": "not a dict"}, "not a dictionary"),
    ({"x": {"type": "diagnostic_aggregator/GenericAnalyzer", "path": "X"}}, "no way to match"),
])
def test_bad_analyzer_configs_are_rejected(spec, message):
    with pytest.raises(AnalyzerConfigError, match=message):
        build_analyzers(spec)


@pytest.mark.parametrize("config_file", ["turtlebot_bringup/param/kobuki/diagnostics.yaml",
                                         "kobuki_node/param/diagnostics.yaml"])
def test_kobuki_diagnostics_configs_sort_every_base_diagnostic(config_file):
    sys.path.insert(0, str(PACKAGES / "kobuki_node" / "src"))
    from kobuki_node.base import KobukiBase

    config = yaml.safe_load((PACKAGES / config_file).read_text())
    agg = Aggregator(build_analyzers(config["analyzers"], config["base_path"]))
    for item in KobukiBase().diagnostics("mobile_base_nodelet_manager"):
        agg.add(Status(item.level, item.name, item.message), 0.0)
    statuses, top = agg.report(1.0)
    names = {s.name for s in statuses}
    assert {"/Power System/Battery", "/Kobuki/Watchdog", "/Sensors/Gyro Sensor",
            "/Input Ports/Analog Input"} <= names
    assert not any(n.startswith("/Other") for n in names)
    assert top.level == OK
