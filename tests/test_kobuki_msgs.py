"""The bundled kobuki_msgs are wire-compatible with the real ones (same md5 as genmsg's)."""
from orchestra.node.msg import get_message_class


def test_sensor_state_md5_matches_real_kobuki_msgs():
    cls = get_message_class("kobuki_msgs/SensorState")
    assert cls._md5sum == "430a4bfd78449c8740bfef32b26613a6"
    assert cls.DB25_TEST_BOARD_CONNECTED == 64
