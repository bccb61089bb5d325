"""The app layer: the composition of one run (master, parameters, rosout, supervisor, UI).

``launch`` turns files into a plan, ``supervise`` runs ProcessSpecs, ``master`` serves the
graph; only this layer knows all three. ``orchestra launch``, ``orchestra core``,
``orchestra test`` and the Python API (``orchestra.launch_file``) are built on it, so a run
is composed in one place (``run.LaunchRun``).
"""
