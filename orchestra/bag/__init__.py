"""ROS 1 bags (format 2.0): the file format, and the record / play / info / filter / reindex /
compress tools behind ``orchestra bag``.

Layers inside: ``records`` (the bytes of one record) <- ``writer`` / ``reader`` (a whole
file) <- ``reindex``, ``info``, ``filter``, ``compress``, ``record``, ``play`` (the tools)
<- ``cli``. Only ``record`` and ``play`` touch the node runtime.
"""
