#!/usr/bin/env python3
"""Switch on the base's power output for the 3D sensor, then exit 0.

Waits for ``~service`` (default ``mobile_base/set_digital_outputs``, kobuki_msgs/
SetDigitalOutputs) up to ``~timeout`` seconds (default 30) and sets output ``~output``
(default 1) on. Exits 1 when the base never offers the service or refuses.
"""


def main() -> int:
    from orchestra import node
    from orchestra.node.msg import get_service_class

    node.init_node("kinect_breaker_enabler")
    service = node.get_param("~service", "mobile_base/set_digital_outputs")
    timeout = float(node.get_param("~timeout", 30.0))
    output = int(node.get_param("~output", 1))
    if not 0 <= output <= 3:
        node.logerr("~output must be 0..3, got %d", output)
        return 1
    resolved = node.resolve_name(service)
    try:
        node.wait_for_service(resolved, timeout=timeout)
    except node.ROSException:
        node.logerr("the base does not offer %s after %.0f s: 3D sensor left unpowered",
                    resolved, timeout)
        return 1
    srv = get_service_class("kobuki_msgs/SetDigitalOutputs")
    request = {f"digital_out_{i}": 1 if i == output else 0 for i in range(4)}
    try:
        response = node.ServiceProxy(resolved, srv)(**request)
    except node.ServiceException as exc:
        node.logerr("%s failed: %s", resolved, exc)
        return 1
    if not response.success:
        node.logerr("%s refused: %s", resolved, response.message)
        return 1
    node.loginfo("3D sensor power on (output %d)", output)
    node.signal_shutdown("done")
    return 0


if __name__ == "__main__":
    from orchestra.node.entry import run_main
    run_main(main)
