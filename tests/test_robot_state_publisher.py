"""robot_state_publisher's URDF handling: parsing, errors, joint transforms, mimic joints."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

PACKAGES = Path(__file__).resolve().parent.parent / "packages"
sys.path.insert(0, str(PACKAGES / "robot_state_publisher" / "src"))

from robot_state_publisher.urdf import (  # noqa: E402
    URDFError,
    fixed_joints,
    joint_positions,
    joint_transform,
    moving_joints,
    parse_urdf,
    quaternion_from_rpy,
    rotate,
)

ARM = """<robot name="arm">
  <link name="base"/><link name="upper"/><link name="slider"/><link name="twin"/>
  <link name="floating_thing"/>
  <joint name="shoulder" type="revolute">
    <origin xyz="0 0 1" rpy="0 0 0"/><parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/>
  </joint>
  <joint name="slide" type="prismatic">
    <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/><parent link="upper"/><child link="slider"/>
    <axis xyz="1 0 0"/>
  </joint>
  <joint name="mirror" type="continuous">
    <parent link="upper"/><child link="twin"/><axis xyz="0 0 1"/>
    <mimic joint="shoulder" multiplier="-2" offset="0.1"/>
  </joint>
  <joint name="float" type="floating"><parent link="base"/><child link="floating_thing"/></joint>
</robot>"""


def test_parse_links_joints_and_root():
    robot = parse_urdf(ARM)
    assert robot.name == "arm" and robot.root == "base"
    assert [j.name for j in moving_joints(robot)] == ["shoulder", "slide", "mirror"]
    assert fixed_joints(robot) == []   # floating joints are not published


def test_turtlebot_description_has_fixed_tree_and_two_wheels():
    robot = parse_urdf((PACKAGES / "turtlebot_description" / "robots"
                        / "kobuki_hexagons_asus_xtion_pro.urdf").read_text())
    assert robot.root == "base_footprint"
    assert {j.name for j in moving_joints(robot)} == {"wheel_left_joint", "wheel_right_joint"}
    fixed = {j.child: j for j in fixed_joints(robot)}
    assert fixed["base_link"].xyz == (0.0, 0.0, 0.0102)


def test_rpy_quaternion_matches_known_rotations():
    assert quaternion_from_rpy(0, 0, math.pi / 2) == pytest.approx(
        (0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)))
    # roll then yaw, fixed axes: x axis maps to y
    q = quaternion_from_rpy(math.pi / 2, 0, math.pi / 2)
    assert rotate(q, (1, 0, 0)) == pytest.approx((0, 1, 0), abs=1e-12)
    assert rotate(q, (0, 1, 0)) == pytest.approx((0, 0, 1), abs=1e-12)


def test_revolute_joint_rotates_about_its_axis():
    shoulder = parse_urdf(ARM).joints[0]
    xyz, q = joint_transform(shoulder, math.pi / 2)
    assert xyz == (0, 0, 1)
    assert rotate(q, (1, 0, 0)) == pytest.approx((0, 1, 0), abs=1e-12)


def test_prismatic_joint_moves_along_axis_in_joint_frame():
    slide = parse_urdf(ARM).joints[1]
    xyz, _ = joint_transform(slide, 0.5)
    assert xyz == pytest.approx((1.0, 0.5, 0.0), abs=1e-12)   # joint frame is yawed 90 deg


def test_mimic_joint_position_follows_its_master():
    positions = joint_positions(parse_urdf(ARM), {"shoulder": 0.3})
    assert positions == pytest.approx({"shoulder": 0.3, "mirror": -0.5})


@pytest.mark.parametrize("text, message", [
    ("<robot><link name='a'/>", "not valid XML"),
    ("<model/>", "not <robot>"),
    ("<robot><link name='a'/><joint name='j' type='hinge'><parent link='a'/><child link='a'/>"
     "</joint></robot>", "unknown type 'hinge'"),
    ("<robot><link name='a'/><joint name='j' type='fixed'><parent link='a'/><child link='b'/>"
     "</joint></robot>", "unknown link 'b'"),
    ("<robot><link name='a'/><link name='b'/><link name='c'/>"
     "<joint name='j1' type='fixed'><parent link='a'/><child link='c'/></joint>"
     "<joint name='j2' type='fixed'><parent link='b'/><child link='c'/></joint></robot>",
     "two parents"),
    ("<robot><link name='a'/><link name='b'/><joint name='j' type='fixed'>"
     "<origin xyz='1 2'/><parent link='a'/><child link='b'/></joint></robot>",
     "three numbers"),
])
def test_invalid_descriptions_are_rejected_with_reason(text, message):
    with pytest.raises(URDFError, match=message):
        parse_urdf(text)
