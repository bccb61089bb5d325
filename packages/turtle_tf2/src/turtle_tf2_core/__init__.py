"""The turtle_tf2 demo's node bodies (``nodes``), shared by the Python executables and the
C++-named ones, written against the tf2_ros API of ``orchestra.tf.tf2_ros``."""
