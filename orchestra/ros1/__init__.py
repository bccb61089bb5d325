"""The ROS 1 Python layer: what unmodified rospy nodes import, backed by orchestra.

``site/`` is a directory put on a node's PYTHONPATH (``activation``); it holds the top-level
``rospy``, ``roslib``, ``tf``... modules and a ``sitecustomize`` that switches the layer on
only when no real rospy is importable. ``finder`` makes ``<pkg>.msg``/``<pkg>.srv`` modules
for every package with definitions, from ``orchestra.node.msg``'s classes.
See docs/rospy-layer.md.
"""
