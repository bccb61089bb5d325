"""The tutorial's logic, shared by the C++-style and Python-style executables of learning_tf
and turtle_tf: the follower's control law and the pose-to-transform rule (``follow``), and
the two node bodies (``nodes``)."""
