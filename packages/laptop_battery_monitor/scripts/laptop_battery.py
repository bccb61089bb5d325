#!/usr/bin/env python3
"""Laptop battery monitor: ``~acpi_path`` (default /sys/class/power_supply/BAT0) read every
``~rate`` seconds (default 5); publishes /diagnostics ("Laptop Battery") and
``laptop_charge`` (sensor_msgs/BatteryState). A missing battery is reported as an Error
diagnostic, not a crash: a netbook without a battery is a state, not a configuration bug.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "src"))

from laptop_battery_monitor.battery import diagnostic, read  # noqa: E402

STATUS = {"Charging": 1, "Discharging": 2, "Not charging": 3, "Full": 4}


def main() -> int:
    from orchestra import node
    from orchestra.node.msg import get_message_class as M

    node.init_node("laptop_battery")
    path = str(node.get_param("~acpi_path", "/sys/class/power_supply/BAT0"))
    period = float(node.get_param("~rate", 5.0))
    if period <= 0:
        node.logerr("%s must be > 0 seconds", node.resolve_name("~rate"))
        return 1
    array, status_cls, kv = (M("diagnostic_msgs/DiagnosticArray"),
                             M("diagnostic_msgs/DiagnosticStatus"), M("diagnostic_msgs/KeyValue"))
    state_cls = M("sensor_msgs/BatteryState")
    diag_pub = node.Publisher("/diagnostics", array, queue_size=1)
    charge_pub = node.Publisher("laptop_charge", state_cls, queue_size=1, latch=True)
    while not node.is_shutdown():
        reading = read(path)
        level, message, values = diagnostic(reading, path)
        out = array(status=[status_cls(level=level, name="Laptop Battery", message=message,
                                       hardware_id=path,
                                       values=[kv(key=k, value=v) for k, v in values])])
        out.header.stamp = node.Time.now()
        diag_pub.publish(out)
        state = state_cls(present=reading.present,
                          power_supply_status=STATUS.get(reading.status, 0))
        state.header.stamp = out.header.stamp
        nan = float("nan")
        state.voltage = reading.voltage if reading.voltage is not None else nan
        state.current = reading.current if reading.current is not None else nan
        state.charge = reading.charge if reading.charge is not None else nan
        state.capacity = reading.capacity if reading.capacity is not None else nan
        state.percentage = reading.percent / 100.0 if reading.percent is not None else nan
        state.location = path
        charge_pub.publish(state)
        try:
            node.sleep(period)
        except node.ROSInterruptException:
            break
    return 0


if __name__ == "__main__":
    from orchestra.node.entry import run_main
    run_main(main)
