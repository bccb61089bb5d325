"""laptop_battery_monitor: reading Linux power_supply batteries and judging their level."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "laptop_battery_monitor" / "src"))

from laptop_battery_monitor.battery import ERROR, OK, WARN, diagnostic, parse, read  # noqa: E402


def test_charge_counters_in_micro_units():
    r = parse({"present": "1", "status": "Discharging", "voltage_now": "11100000",
               "current_now": "1500000", "charge_now": "2000000", "charge_full": "4000000"})
    assert r.present and r.status == "Discharging"
    assert (r.voltage, r.current, r.charge, r.capacity) == pytest.approx((11.1, 1.5, 2.0, 4.0))
    assert r.percent == pytest.approx(50.0)


def test_energy_counters_are_converted_with_voltage():
    r = parse({"present": "1", "voltage_now": "10000000", "energy_now": "20000000",
               "energy_full": "40000000", "power_now": "5000000", "capacity": "49"})
    assert (r.charge, r.capacity, r.current) == pytest.approx((2.0, 4.0, 0.5))
    assert r.percent == 49.0   # the firmware's own figure wins


def test_absent_battery():
    assert parse({"present": "0"}).present is False
    assert parse({}).present is False


def test_read_from_a_sysfs_like_directory(tmp_path):
    bat = tmp_path / "BAT0"
    bat.mkdir()
    for name, value in {"present": "1", "status": "Full", "capacity": "100"}.items():
        (bat / name).write_text(value + "\n")
    r = read(str(bat))
    assert (r.present, r.status, r.percent) == (True, "Full", 100.0)
    assert read(str(tmp_path / "BAT9")).present is False


@pytest.mark.parametrize("fields, level", [
    ({"status": "Discharging", "capacity": "50"}, OK),
    ({"status": "Discharging", "capacity": "10"}, WARN),
    ({"status": "Discharging", "capacity": "3"}, ERROR),
    ({"status": "Charging", "capacity": "3"}, OK),
])
def test_diagnostic_level_follows_charge_unless_charging(fields, level):
    assert diagnostic(parse({"present": "1", **fields}), "/bat")[0] == level


def test_missing_battery_is_an_error_naming_the_path():
    level, message, _ = diagnostic(parse({"present": "0"}), "/sys/class/power_supply/BAT0")
    assert level == ERROR and "/sys/class/power_supply/BAT0" in message
