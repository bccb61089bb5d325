"""Two network namespaces joined by a veth pair, a real sshd in one: a two-machine testbed.

Used by tests/test_remote_netns.py and bench/bench_remote.py. Everything is private and
temporary: the namespaces and their addresses (a 10.213.N.0/24 subnet that exists only inside
them), sshd's host key and config, the client key pair, known_hosts and an ssh config file
that orchestra reads through ORCHESTRA_SSH_CONFIG. The machine's own ssh configuration,
~/.ssh and the host's network are never touched; no traffic leaves the two namespaces.

``unavailable()`` says why the testbed cannot be built here (not root, no ``ip netns``, no
sshd), so callers skip with that reason.
"""
from __future__ import annotations

import os
import secrets
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

SSHD = "/usr/sbin/sshd"


def unavailable() -> str | None:
    """Why namespaces + sshd cannot be used here, or None."""
    if sys.platform != "linux":
        return "network namespaces are Linux only"
    if os.geteuid() != 0:
        return "creating network namespaces needs root"
    for program in ("ip", "ssh", "ssh-keygen", "ssh-keyscan"):
        if shutil.which(program) is None:
            return f"'{program}' is not installed (Debian: iproute2 / openssh-client)"
    if not os.access(SSHD, os.X_OK):
        return "sshd is not installed (Debian: openssh-server)"
    name = f"orchprobe{os.getpid()}"
    probe = subprocess.run(["ip", "netns", "add", name], capture_output=True, text=True)
    if probe.returncode != 0:
        return f"cannot create a network namespace: {probe.stderr.strip()}"
    try:
        inside = subprocess.run(["ip", "netns", "exec", name, "true"], capture_output=True,
                                text=True)
    finally:
        subprocess.run(["ip", "netns", "del", name], capture_output=True)
    if inside.returncode != 0:
        return f"cannot run a program in a network namespace: {inside.stderr.strip()}"
    return None


def _run(*argv: str) -> None:
    subprocess.run(argv, check=True, capture_output=True, text=True)


class Testbed:
    """``local`` and ``remote`` namespaces; sshd listening at ``remote_ip``:``port``."""

    def __init__(self, root: Path, port: int = 22):
        self.root = root
        tag = secrets.token_hex(3)
        self.local_ns = f"orchl{tag}"
        self.remote_ns = f"orchr{tag}"
        subnet = 1 + secrets.randbelow(250)
        self.local_ip = f"10.213.{subnet}.1"
        self.remote_ip = f"10.213.{subnet}.2"
        self.port = port
        self.sshd: subprocess.Popen | None = None
        self.ssh_dir = root / "ssh"
        self.ssh_config = self.ssh_dir / "config"
        self.key = self.ssh_dir / "id_ed25519"
        self.known_hosts = self.ssh_dir / "known_hosts"

    # ------------------------------------------------------------------ setup / teardown

    def __enter__(self) -> Testbed:
        try:
            self._network()
            self._keys()
            self._start_sshd()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _network(self) -> None:
        veth_l, veth_r = f"v{self.local_ns}", f"v{self.remote_ns}"
        _run("ip", "netns", "add", self.local_ns)
        _run("ip", "netns", "add", self.remote_ns)
        _run("ip", "link", "add", veth_l[:15], "type", "veth", "peer", "name", veth_r[:15])
        _run("ip", "link", "set", veth_l[:15], "netns", self.local_ns)
        _run("ip", "link", "set", veth_r[:15], "netns", self.remote_ns)
        for ns, dev, ip in ((self.local_ns, veth_l[:15], self.local_ip),
                            (self.remote_ns, veth_r[:15], self.remote_ip)):
            _run("ip", "-n", ns, "addr", "add", f"{ip}/24", "dev", dev)
            _run("ip", "-n", ns, "link", "set", dev, "up")
            _run("ip", "-n", ns, "link", "set", "lo", "up")

    def _keys(self) -> None:
        self.ssh_dir.mkdir(mode=0o700)
        _run("ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", str(self.ssh_dir / "host"))
        _run("ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", str(self.key))
        (self.ssh_dir / "authorized_keys").write_text((self.ssh_dir / "id_ed25519.pub").read_text())
        host_pub = (self.ssh_dir / "host.pub").read_text().split()
        entry = self.remote_ip if self.port == 22 else f"[{self.remote_ip}]:{self.port}"
        self.known_hosts.write_text(f"{entry} {host_pub[0]} {host_pub[1]}\n")
        (self.ssh_dir / "sshd_config").write_text(
            f"Port {self.port}\nListenAddress {self.remote_ip}\n"
            f"HostKey {self.ssh_dir / 'host'}\n"
            f"AuthorizedKeysFile {self.ssh_dir / 'authorized_keys'}\n"
            "PermitRootLogin prohibit-password\nPasswordAuthentication no\n"
            "KbdInteractiveAuthentication no\nUsePAM no\nStrictModes no\nPidFile none\n"
            "LogLevel ERROR\n")
        self.write_client_config()

    def write_client_config(self, key: Path | None = None,
                            known_hosts: Path | None = None) -> Path:
        self.ssh_config.write_text(
            "Host *\n"
            f"  IdentityFile {key or self.key}\n  IdentitiesOnly yes\n"
            f"  UserKnownHostsFile {known_hosts or self.known_hosts}\n"
            "  GlobalKnownHostsFile /dev/null\n  StrictHostKeyChecking yes\n"
            "  User root\n  LogLevel ERROR\n")
        return self.ssh_config

    def _start_sshd(self) -> None:
        os.makedirs("/run/sshd", exist_ok=True)     # sshd's privilege-separation directory
        log = open(self.root / "sshd.log", "wb")
        self.sshd = subprocess.Popen(
            ["ip", "netns", "exec", self.remote_ns, SSHD, "-D", "-e",
             "-f", str(self.ssh_dir / "sshd_config")],
            stdin=subprocess.DEVNULL, stdout=log, stderr=log, start_new_session=True)
        log.close()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            probe = self.in_local(["ssh", "-F", str(self.ssh_config), "-o", "BatchMode=yes",
                                   "-p", str(self.port), self.remote_ip, "true"],
                                  capture_output=True, timeout=10)
            if probe.returncode == 0:
                return
            if self.sshd.poll() is not None:
                break
            time.sleep(0.1)
        raise RuntimeError("sshd did not come up: "
                           + (self.root / "sshd.log").read_text(errors="replace")[-2000:])

    def close(self) -> None:
        if self.sshd is not None and self.sshd.poll() is None:
            os.killpg(self.sshd.pid, signal.SIGTERM)
            try:
                self.sshd.wait(5)
            except subprocess.TimeoutExpired:
                os.killpg(self.sshd.pid, signal.SIGKILL)
                self.sshd.wait()
        for ns in (self.remote_ns, self.local_ns):
            for pid in self.pids_in(ns):     # nothing of a failed test survives its testbed
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            subprocess.run(["ip", "netns", "del", ns], capture_output=True)

    # ------------------------------------------------------------------ helpers

    def in_local(self, argv: list[str], **kwargs) -> subprocess.CompletedProcess:
        return subprocess.run(["ip", "netns", "exec", self.local_ns, *argv], **kwargs)

    def popen_local(self, argv: list[str], **kwargs) -> subprocess.Popen:
        return subprocess.Popen(["ip", "netns", "exec", self.local_ns, *argv], **kwargs)

    @staticmethod
    def netns_inode(ns: str) -> int:
        return os.stat(f"/run/netns/{ns}").st_ino

    def pids_in(self, ns: str) -> list[int]:
        """Processes whose network namespace is ``ns`` (read from /proc/PID/ns/net)."""
        try:
            inode = self.netns_inode(ns)
        except OSError:
            return []
        found = []
        for entry in os.listdir("/proc"):
            if not entry.isdigit():
                continue
            try:
                if os.stat(f"/proc/{entry}/ns/net").st_ino == inode:
                    found.append(int(entry))
            except OSError:
                continue
        return found

    def env_loader(self, path: Path, extra: dict[str, str] | None = None) -> Path:
        """A roslaunch-style env-loader for the remote machine: set the environment, exec."""
        lines = ["#!/bin/sh",
                 f"export PATH={os.path.dirname(sys.executable)}:/usr/bin:/bin",
                 f"export PYTHONPATH={os.environ.get('PYTHONPATH', '')}"]
        lines += [f"export {key}={value}" for key, value in (extra or {}).items()]
        lines.append('exec "$@"')
        path.write_text("\n".join(lines) + "\n")
        path.chmod(0o755)
        return path
