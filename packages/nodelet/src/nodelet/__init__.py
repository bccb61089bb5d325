"""Python nodelets for orchestra: several nodes sharing one process (see ``base.Nodelet``)."""
from nodelet.base import Nodelet, Timer

__all__ = ["Nodelet", "Timer"]
