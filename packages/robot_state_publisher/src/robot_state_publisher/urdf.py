"""The part of a URDF robot_state_publisher needs: the joint tree and each joint's transform.

Parsed with lxml from the ``robot_description`` string. A fixed joint's transform never
changes, so it is sent once on /tf_static; a moving joint's transform is its origin composed
with the motion along its axis for the position reported on ``joint_states`` (rotation about
the axis for revolute/continuous, translation along it for prismatic).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from lxml import etree

from orchestra.errors import OrchestraError

Quaternion = tuple[float, float, float, float]  # x, y, z, w
Vector = tuple[float, float, float]

MOVING = {"revolute", "continuous", "prismatic"}
KNOWN = MOVING | {"fixed", "floating", "planar"}


class URDFError(OrchestraError):
    """A robot description that cannot be turned into a joint tree."""


@dataclass(frozen=True)
class Joint:
    name: str
    type: str
    parent: str
    child: str
    xyz: Vector = (0.0, 0.0, 0.0)
    rpy: Vector = (0.0, 0.0, 0.0)
    axis: Vector = (1.0, 0.0, 0.0)
    mimic: str | None = None
    multiplier: float = 1.0
    offset: float = 0.0
    line: int = 0


@dataclass(frozen=True)
class Robot:
    name: str
    links: tuple[str, ...]
    joints: tuple[Joint, ...]

    @property
    def root(self) -> str:
        children = {j.child for j in self.joints}
        roots = [link for link in self.links if link not in children]
        return roots[0] if roots else ""


def quaternion_from_rpy(roll: float, pitch: float, yaw: float) -> Quaternion:
    """URDF's fixed-axis roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll)) as a quaternion."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def quaternion_multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def quaternion_about_axis(angle: float, axis: Vector) -> Quaternion:
    norm = math.sqrt(sum(a * a for a in axis)) or 1.0
    s = math.sin(angle / 2) / norm
    return axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2)


def rotate(q: Quaternion, v: Vector) -> Vector:
    """``v`` rotated by unit quaternion ``q``."""
    qv = (v[0], v[1], v[2], 0.0)
    conj = (-q[0], -q[1], -q[2], q[3])
    x, y, z, _ = quaternion_multiply(quaternion_multiply(q, qv), conj)
    return x, y, z


def _vector(text: str | None, default: Vector, what: str, line: int) -> Vector:
    if text is None:
        return default
    parts = text.split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3:
        raise URDFError(f"line {line}: {what}=\"{text}\" must be three numbers")
    return values  # type: ignore[return-value]


def parse_urdf(text: str) -> Robot:
    """The links and joints of a URDF document; raises URDFError on what ROS would reject
    (bad XML, unknown joint type, joints naming links that do not exist, two parents)."""
    try:
        root = etree.fromstring(text.encode("utf-8") if isinstance(text, str) else text)
    except etree.XMLSyntaxError as exc:
        raise URDFError(f"robot_description is not valid XML: {exc}") from None
    if root.tag != "robot":
        raise URDFError(f"robot_description's root element is <{root.tag}>, not <robot>")
    links = tuple(link.get("name", "") for link in root.findall("link"))
    if not links or any(not name for name in links):
        raise URDFError("every <link> needs a name and a robot needs at least one")
    known_links = set(links)
    joints: list[Joint] = []
    parents: dict[str, str] = {}
    for el in root.findall("joint"):
        line = el.sourceline or 0
        name, jtype = el.get("name"), el.get("type")
        if not name or not jtype:
            raise URDFError(f"line {line}: <joint> needs 'name' and 'type'")
        if jtype not in KNOWN:
            raise URDFError(f"line {line}: joint '{name}' has unknown type '{jtype}'")
        parent_el, child_el = el.find("parent"), el.find("child")
        parent = parent_el.get("link") if parent_el is not None else None
        child = child_el.get("link") if child_el is not None else None
        if not parent or not child:
            raise URDFError(f"line {line}: joint '{name}' needs <parent link> and <child link>")
        for link in (parent, child):
            if link not in known_links:
                raise URDFError(f"line {line}: joint '{name}' names unknown link '{link}'")
        if child in parents:
            raise URDFError(f"line {line}: link '{child}' has two parents "
                            f"('{parents[child]}' and '{parent}')")
        parents[child] = parent
        origin = el.find("origin")
        xyz = _vector(origin.get("xyz") if origin is not None else None, (0.0, 0.0, 0.0),
                      "xyz", line)
        rpy = _vector(origin.get("rpy") if origin is not None else None, (0.0, 0.0, 0.0),
                      "rpy", line)
        axis_el = el.find("axis")
        axis = _vector(axis_el.get("xyz") if axis_el is not None else None, (1.0, 0.0, 0.0),
                       "axis", line)
        mimic_el = el.find("mimic")
        mimic = mimic_el.get("joint") if mimic_el is not None else None
        multiplier = float(mimic_el.get("multiplier", 1.0)) if mimic_el is not None else 1.0
        offset = float(mimic_el.get("offset", 0.0)) if mimic_el is not None else 0.0
        joints.append(Joint(name, jtype, parent, child, xyz, rpy, axis, mimic, multiplier,
                            offset, line))
    return Robot(root.get("name", ""), links, tuple(joints))


def joint_transform(joint: Joint, position: float = 0.0) -> tuple[Vector, Quaternion]:
    """(translation, rotation) of the child link in the parent link's frame."""
    origin_q = quaternion_from_rpy(*joint.rpy)
    if joint.type in ("revolute", "continuous"):
        return joint.xyz, quaternion_multiply(origin_q, quaternion_about_axis(position, joint.axis))
    if joint.type == "prismatic":
        norm = math.sqrt(sum(a * a for a in joint.axis)) or 1.0
        along = tuple(a / norm * position for a in joint.axis)
        moved = rotate(origin_q, along)  # the axis is expressed in the joint frame
        return (joint.xyz[0] + moved[0], joint.xyz[1] + moved[1], joint.xyz[2] + moved[2]), origin_q
    return joint.xyz, origin_q


def fixed_joints(robot: Robot) -> list[Joint]:
    """Joints published once on /tf_static (floating and planar ones are not published at
    all: their pose would have to come from elsewhere, e.g. a localisation node)."""
    return [j for j in robot.joints if j.type == "fixed"]


def moving_joints(robot: Robot) -> list[Joint]:
    return [j for j in robot.joints if j.type in MOVING]


def joint_positions(robot: Robot, reported: dict[str, float]) -> dict[str, float]:
    """Positions of every moving joint that can be known: reported ones, plus mimic joints
    of reported ones (``position = multiplier * other + offset``)."""
    positions = dict(reported)
    for joint in moving_joints(robot):
        if joint.name not in positions and joint.mimic in reported:
            positions[joint.name] = joint.multiplier * reported[joint.mimic] + joint.offset
    return {j.name: positions[j.name] for j in moving_joints(robot) if j.name in positions}
