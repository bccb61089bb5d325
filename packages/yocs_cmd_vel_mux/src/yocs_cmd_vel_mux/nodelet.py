"""``yocs_cmd_vel_mux/CmdVelMuxNodelet``: the mux on the graph.

Reads the YAML named by ``~yaml_cfg_file``; subscribes each input's topic in the nodelet's
private namespace (``/cmd_vel_mux/input/teleop`` for ``input/teleop``, global names stay
global); forwards on ``~output`` (default) and reports the active input's name, or
``idle``, on the latched ``~active``.
"""
from __future__ import annotations

import threading
import time

from nodelet import Nodelet

from yocs_cmd_vel_mux.mux import CmdVelMux, load_config

EXPIRY_CHECK_PERIOD = 0.05  # s; how late an input's timeout may be noticed


def _private(topic: str) -> str:
    return topic if topic.startswith(("/", "~")) else "~" + topic


class CmdVelMuxNodelet(Nodelet):
    def on_init(self) -> None:
        from orchestra.node.msg import get_message_class

        path = self.get_private_param("yaml_cfg_file", "")
        if not path:
            raise RuntimeError(f"parameter {self.resolve('~yaml_cfg_file')} is not set")
        config = load_config(str(path))
        self.mux = CmdVelMux(config)
        self._lock = threading.Lock()
        twist, string = get_message_class("geometry_msgs/Twist"), get_message_class("std_msgs/String")
        self._string = string
        self.output = self.advertise(_private(config.output), twist)
        self.active_pub = self.advertise("~active", string, latch=True)
        self.active_pub.publish(string(data=self.mux.active_name))
        for index, item in enumerate(config.inputs):
            self.subscribe(_private(item.topic), twist,
                           lambda msg, index=index: self._on_input(index, msg))
        self.create_timer(EXPIRY_CHECK_PERIOD, self._check_expiry)
        self.log.info("cmd_vel_mux: %d inputs -> %s", len(config.inputs),
                      self.resolve(_private(config.output)))

    def _on_input(self, index: int, msg) -> None:
        with self._lock:
            forward, changed = self.mux.on_message(index, time.monotonic())
            name = self.mux.active_name
        if changed:
            self.active_pub.publish(self._string(data=name))
        if forward:
            self.output.publish(msg)

    def _check_expiry(self, _now: float) -> None:
        with self._lock:
            changed = self.mux.expire(time.monotonic())
            name = self.mux.active_name
        if changed:
            self.active_pub.publish(self._string(data=name))
