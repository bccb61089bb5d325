"""Is a ``<machine>`` this host? roslaunch's rule, so the same launch file splits the same way.

A machine is local when its address resolves to a loopback address or to an address of one
of this host's interfaces -- and, as roslaunch (#491), its ``user`` (if given) is the user
running the launch: another account on this host is reached over ssh. An address that does
not resolve is an error, as in roslaunch ("cannot resolve host address for machine").
"""
from __future__ import annotations

import getpass
import socket

import psutil

LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1", "localhost.localdomain",
                            "ip6-localhost"})


class UnresolvableAddress(Exception):
    """The address of a machine has no IP address (roslaunch refuses such a launch too)."""


def local_addresses() -> set[str]:
    return {a.address.split("%")[0] for addrs in psutil.net_if_addrs().values()
            for a in addrs if a.family in (socket.AF_INET, socket.AF_INET6)}


def is_local_address(address: str) -> bool:
    """True when ``address`` names this host; UnresolvableAddress when it names nothing."""
    if not address or address in LOOPBACK_NAMES or address.startswith("127."):
        return True
    try:
        resolved = {info[4][0] for info in socket.getaddrinfo(address, 0, 0, 0, socket.SOL_TCP)
                    if isinstance(info[4][0], str)}
    except socket.gaierror:
        raise UnresolvableAddress(address) from None
    if any(ip.startswith("127.") or ip == "::1" for ip in resolved):
        return True
    return bool(resolved & local_addresses())


def is_local_machine(address: str, user: str | None) -> bool:
    """roslaunch's is_machine_local: a local address, and no other user to log in as."""
    if not is_local_address(address):
        return False
    return not user or user == getpass.getuser()
