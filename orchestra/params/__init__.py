"""Parameters: the hierarchical parameter tree and the rosparam YAML rules.

Public entry points (import them from their modules; this package imports nothing eagerly so
that ``orchestra launch`` start-up stays fast):

- ``orchestra.params.yaml.load_rosparam_yaml(text, filename)`` -> the Python value rosparam
  would load (``!degrees``, ``!radians``, ``!!binary`` understood, safe loading only).
- ``orchestra.params.yaml.flatten(name, value)`` -> ``[(full_name, leaf_value), ...]`` as
  roslaunch stores a ``<rosparam>`` dictionary on the parameter server.
"""
