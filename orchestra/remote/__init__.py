"""Nodes on other machines (``<machine>``): started through the system's OpenSSH client.

See docs/remote.md for the design: each remote node is a local supervised ``ssh`` client
(multiplexed over one connection per machine) running ``orchestra.remote.agent`` there.
"""
