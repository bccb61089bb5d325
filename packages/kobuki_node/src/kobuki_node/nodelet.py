"""``kobuki_node/KobukiNodelet``: the simulated base on the real driver's topics.

Names are the real driver's, private to the nodelet (``/mobile_base/...`` when loaded as
``mobile_base``): ``~commands/velocity`` in; ``~odom``, ``~joint_states``,
``~sensors/imu_data``, ``~sensors/core`` out, ``/diagnostics`` and the odom -> base_footprint
transform on ``/tf``; ``~enable``/``~disable`` (std_msgs/String) switch the motors;
``~set_digital_outputs`` (kobuki_msgs/SetDigitalOutputs) is what the kinect breaker enabler
calls.
"""
from __future__ import annotations

import threading
import time

from nodelet import Nodelet

from kobuki_node.base import BatteryModel, KobukiBase, yaw_to_quaternion


class KobukiNodelet(Nodelet):
    def on_init(self) -> None:
        from orchestra import node
        from orchestra.node.msg import get_message_class, get_service_class

        self._node = node
        self.msgs = {n: get_message_class(n) for n in (
            "geometry_msgs/Twist", "nav_msgs/Odometry", "sensor_msgs/Imu",
            "sensor_msgs/JointState", "kobuki_msgs/SensorState", "std_msgs/String",
            "diagnostic_msgs/DiagnosticArray", "diagnostic_msgs/DiagnosticStatus",
            "diagnostic_msgs/KeyValue", "tf2_msgs/TFMessage",
            "geometry_msgs/TransformStamped")}
        p = self.get_private_param
        self.odom_frame = str(p("odom_frame", "odom"))
        self.base_frame = str(p("base_frame", "base_footprint"))
        self.publish_tf = bool(p("publish_tf", True))
        self.joint_names = (str(p("wheel_left_joint_name", "wheel_left_joint")),
                            str(p("wheel_right_joint_name", "wheel_right_joint")))
        rate = float(p("update_rate", 20.0))
        self.base = KobukiBase(
            cmd_vel_timeout=float(p("cmd_vel_timeout", 0.6)),
            use_imu_heading=bool(p("use_imu_heading", True)),
            gyro_noise=float(p("gyro_noise", 0.002)),
            battery=BatteryModel(capacity=float(p("battery_capacity", 16.5)),
                                 low=float(p("battery_low", 14.0)),
                                 dangerous=float(p("battery_dangerous", 13.2)),
                                 voltage=float(p("battery_capacity", 16.5))))
        # the C++ diagnostic updater names tasks after the process's node: the manager
        self.diag_prefix = node.get_name().lstrip("/")
        self._lock = threading.Lock()
        self._last = time.time()
        self._boot = self._last

        self.odom_pub = self.advertise("~odom", self.msgs["nav_msgs/Odometry"], queue_size=20)
        self.joint_pub = self.advertise("~joint_states", self.msgs["sensor_msgs/JointState"])
        self.imu_pub = self.advertise("~sensors/imu_data", self.msgs["sensor_msgs/Imu"])
        self.core_pub = self.advertise("~sensors/core", self.msgs["kobuki_msgs/SensorState"])
        self.diag_pub = self.advertise("/diagnostics", self.msgs["diagnostic_msgs/DiagnosticArray"])
        self.tf_pub = self.advertise("/tf", self.msgs["tf2_msgs/TFMessage"], queue_size=50) \
            if self.publish_tf else None
        self.subscribe("~commands/velocity", self.msgs["geometry_msgs/Twist"], self._on_cmd_vel)
        self.subscribe("~enable", self.msgs["std_msgs/String"], lambda _m: self._motors(True))
        self.subscribe("~disable", self.msgs["std_msgs/String"], lambda _m: self._motors(False))
        self.advertise_service("~set_digital_outputs",
                               get_service_class("kobuki_msgs/SetDigitalOutputs"),
                               self._on_digital_outputs)
        self.create_timer(1.0 / rate, self._tick)
        self.create_timer(1.0, self._publish_diagnostics)
        self.log.info("simulated kobuki base up (%s -> %s)", self.odom_frame, self.base_frame)

    # ---- inputs ------------------------------------------------------------------------
    def _on_cmd_vel(self, msg) -> None:
        with self._lock:
            self.base.command(float(msg.linear.x), float(msg.angular.z), time.time())

    def _motors(self, enabled: bool) -> None:
        with self._lock:
            self.base.motors_enabled = enabled
        self.log.info("motors %s", "enabled" if enabled else "disabled")

    def _on_digital_outputs(self, req):
        from orchestra.node.msg import get_service_class
        outputs = tuple(1 if getattr(req, f"digital_out_{i}") else 0 for i in range(4))
        with self._lock:
            self.base.digital_outputs = outputs
        self.log.info("digital outputs set to %s", list(outputs))
        return get_service_class("kobuki_msgs/SetDigitalOutputs").Response(
            success=True, message=f"outputs {list(outputs)}")

    # ---- outputs -----------------------------------------------------------------------
    def _tick(self, now: float) -> None:
        with self._lock:
            self.base.step(now, now - self._last)
            self._last = now
            b = self.base
            pose, v, w, rate = b.odom_pose, b.v, b.w, b.gyro_rate
            heading = b.gyro_heading
            wheels = (b.left_wheel, b.right_wheel)
            encoders = (b.left_encoder, b.right_encoder)
            voltage = b.battery.voltage
        stamp = self._node.Time.from_sec(now)
        qx, qy, qz, qw = yaw_to_quaternion(pose.theta)

        odom = self.msgs["nav_msgs/Odometry"]()
        odom.header.stamp, odom.header.frame_id = stamp, self.odom_frame
        odom.child_frame_id = self.base_frame
        odom.pose.pose.position.x, odom.pose.pose.position.y = pose.x, pose.y
        o = odom.pose.pose.orientation
        o.x, o.y, o.z, o.w = qx, qy, qz, qw
        odom.twist.twist.linear.x, odom.twist.twist.angular.z = v, w
        big = 1e6  # z, roll, pitch are not observed by a planar base
        yaw_var = 0.05 if self.base.use_imu_heading else 0.2
        odom.pose.covariance = [0.1, 0, 0, 0, 0, 0, 0, 0.1, 0, 0, 0, 0, 0, 0, big, 0, 0, 0,
                                0, 0, 0, big, 0, 0, 0, 0, 0, 0, big, 0, 0, 0, 0, 0, 0, yaw_var]
        odom.twist.covariance = list(odom.pose.covariance)
        self.odom_pub.publish(odom)

        if self.tf_pub is not None:
            t = self.msgs["geometry_msgs/TransformStamped"]()
            t.header.stamp, t.header.frame_id = stamp, self.odom_frame
            t.child_frame_id = self.base_frame
            t.transform.translation.x, t.transform.translation.y = pose.x, pose.y
            r = t.transform.rotation
            r.x, r.y, r.z, r.w = qx, qy, qz, qw
            self.tf_pub.publish(self.msgs["tf2_msgs/TFMessage"](transforms=[t]))

        js = self.msgs["sensor_msgs/JointState"]()
        js.header.stamp = stamp
        js.name = list(self.joint_names)
        js.position = list(wheels)
        js.velocity = [0.0, 0.0]
        js.effort = [0.0, 0.0]
        self.joint_pub.publish(js)

        imu = self.msgs["sensor_msgs/Imu"]()
        imu.header.stamp, imu.header.frame_id = stamp, "gyro_link"
        iq = yaw_to_quaternion(heading)
        imu.orientation.x, imu.orientation.y, imu.orientation.z, imu.orientation.w = iq
        imu.orientation_covariance = [big, 0, 0, 0, big, 0, 0, 0, 0.05]
        imu.angular_velocity.z = rate
        imu.angular_velocity_covariance = [big, 0, 0, 0, big, 0, 0, 0, 0.02]
        imu.linear_acceleration_covariance = [-1.0, 0, 0, 0, 0, 0, 0, 0, 0]
        self.imu_pub.publish(imu)

        core = self.msgs["kobuki_msgs/SensorState"]()
        core.header.stamp = stamp
        core.time_stamp = int((now - self._boot) * 1000) % 65536
        core.left_encoder, core.right_encoder = encoders
        core.battery = max(0, min(255, int(round(voltage * 10))))
        core.bottom = [0, 0, 0]
        core.current = [0, 0]
        core.analog_input = [0, 0, 0, 0]
        self.core_pub.publish(core)

    def _publish_diagnostics(self, now: float) -> None:
        with self._lock:
            items = self.base.diagnostics(self.diag_prefix)
        status_cls, kv_cls = (self.msgs["diagnostic_msgs/DiagnosticStatus"],
                              self.msgs["diagnostic_msgs/KeyValue"])
        array = self.msgs["diagnostic_msgs/DiagnosticArray"]()
        array.header.stamp = self._node.Time.from_sec(now)
        array.status = [status_cls(level=item.level, name=item.name, message=item.message,
                                   hardware_id=item.hardware_id,
                                   values=[kv_cls(key=k, value=v) for k, v in item.values])
                        for item in items]
        self.diag_pub.publish(array)

