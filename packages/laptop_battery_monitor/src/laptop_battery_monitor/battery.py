"""Reading a Linux battery from /sys/class/power_supply/<BAT> (pure parsing + the read).

The kernel reports either charge (uAh) or energy (uWh) counters depending on the battery's
firmware; both are handled, and ``capacity`` (percent) wins when present because it is what
the firmware itself computed.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

OK, WARN, ERROR = 0, 1, 2


@dataclass(frozen=True)
class BatteryReading:
    present: bool
    status: str = "Unknown"          # Charging / Discharging / Full / Not charging
    percent: float | None = None
    voltage: float | None = None     # V
    current: float | None = None     # A
    charge: float | None = None      # Ah
    capacity: float | None = None    # Ah (design or last full)


def _number(fields: dict[str, str], key: str, scale: float) -> float | None:
    try:
        return float(fields[key]) * scale
    except (KeyError, ValueError):
        return None


def parse(fields: dict[str, str]) -> BatteryReading:
    """A reading from the sysfs files' contents (name -> stripped text)."""
    if fields.get("present", "1") != "1" or not fields:
        return BatteryReading(False)
    voltage = _number(fields, "voltage_now", 1e-6)
    current = _number(fields, "current_now", 1e-6)
    charge = _number(fields, "charge_now", 1e-6)
    full = _number(fields, "charge_full", 1e-6)
    if charge is None and voltage:  # energy counters: convert with the present voltage
        energy, energy_full = _number(fields, "energy_now", 1e-6), _number(fields, "energy_full", 1e-6)
        charge = energy / voltage if energy is not None else None
        full = energy_full / voltage if energy_full is not None else None
        if current is None:
            power = _number(fields, "power_now", 1e-6)
            current = power / voltage if power is not None else None
    percent = _number(fields, "capacity", 1.0)
    if percent is None and charge is not None and full:
        percent = 100.0 * charge / full
    return BatteryReading(True, fields.get("status", "Unknown"), percent, voltage, current,
                          charge, full)


def read(path: str) -> BatteryReading:
    """Read every small file of the battery directory; missing directory -> not present."""
    if not os.path.isdir(path):
        return BatteryReading(False)
    fields = {}
    for name in os.listdir(path):
        full = os.path.join(path, name)
        if os.path.isfile(full):
            try:
                with open(full, encoding="utf-8", errors="replace") as fh:
                    fields[name] = fh.read(256).strip()
            except OSError:
                continue
    return parse(fields)


def diagnostic(reading: BatteryReading, path: str, low_percent: float = 15.0,
               critical_percent: float = 5.0) -> tuple[int, str, list[tuple[str, str]]]:
    """(level, message, key/values) of the "Laptop Battery" diagnostic status."""
    if not reading.present:
        return ERROR, f"Battery not present at {path}", []
    values = [("Status", reading.status)]
    for key, value, unit in (("Percentage", reading.percent, "%"), ("Voltage", reading.voltage, "V"),
                             ("Current", reading.current, "A"), ("Charge", reading.charge, "Ah"),
                             ("Capacity", reading.capacity, "Ah")):
        if value is not None:
            values.append((f"{key} ({unit})", f"{value:.2f}"))
    charging = reading.status in ("Charging", "Full")
    if reading.percent is not None and not charging:
        if reading.percent <= critical_percent:
            return ERROR, "Critical battery", values
        if reading.percent <= low_percent:
            return WARN, "Low battery", values
    return OK, reading.status, values
