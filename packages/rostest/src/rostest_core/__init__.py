"""Shared parts of the bundled rostest helpers (see ``unitrun``)."""
