"""orchestra's ROS 1 layer: switched on or off as this interpreter starts.

This directory is on PYTHONPATH of nodes started by orchestra (see
orchestra/ros1/activation.py and docs/rospy-layer.md). With ``ORCHESTRA_ROS1`` unset or
``auto``, the layer is used only when no real ``rospy`` is importable; otherwise (or with
``ORCHESTRA_ROS1=real``) this directory takes itself off ``sys.path`` so that nothing here
shadows a real ROS install. Any other ``sitecustomize`` on the path (Debian ships one) still
runs afterwards.
"""
import importlib.util
import os
import sys


def _load_file(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None, path
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _activate():
    here = os.path.dirname(os.path.abspath(__file__))
    # activation.py imports nothing of orchestra: load it by path, so that deciding costs
    # nothing and "real" leaves no trace of orchestra in the process
    activation = _load_file("_orchestra_ros1_activation",
                            os.path.join(os.path.dirname(here), "activation.py"))
    warning = activation.bad_mode(os.environ)
    if warning:
        sys.stderr.write(warning + "\n")
    if not activation.decide(os.environ, sys.path, here):
        sys.path[:] = activation.without_site(sys.path, here)
        return
    if importlib.util.find_spec("orchestra") is None:
        sys.path.append(activation.SOURCE_ROOT)
    from orchestra.ros1 import finder
    finder.install()


def _chain():
    """Run the next ``sitecustomize`` on the path, which this module hides."""
    here = os.path.dirname(os.path.abspath(__file__))
    for entry in sys.path:
        if os.path.abspath(entry or ".") == here:
            continue
        candidate = os.path.join(entry or ".", "sitecustomize.py")
        if os.path.isfile(candidate):
            _load_file("_orchestra_chained_sitecustomize", candidate)
            return


_activate()
_chain()
