"""The local process of a remote node: relays it from the machine's agent. Standard library only.

Run by the supervisor as ``python3 -I -S client.py SOCKET PAYLOAD`` (no site, no orchestra
import: it costs a bare interpreter start, less than the node itself). ``SOCKET`` is this
host's end of a Unix-socket forwarding on the machine's ssh connection, so every node is one
forwarded channel on one connection -- no remote shell, no ssh session per node. The client
sends the node's payload, then copies the agent's frames to its own stdout/stderr (which the
supervisor prefixes and logs, as for a local node) and exits with the node's exit status.

Frames: one byte (1 stdout, 2 stderr, 0 end), four bytes big-endian (length, or the exit
status for 0), the data. When the client dies -- the supervisor's SIGINT, a kill, orchestra
killed -- its socket closes, the channel closes, and the agent stops the node. 255 means the
agent could not be reached or the connection was lost (as ssh's own failures).
"""
import os
import signal
import socket
import struct
import sys


def _write(fd: int, data: bytes) -> None:
    while data:
        data = data[os.write(fd, data):]


def main(path: str, word: str) -> int:
    signal.signal(signal.SIGINT, signal.SIG_DFL)       # die at once: the agent takes over
    sock = socket.socket(socket.AF_UNIX)
    try:
        sock.connect(path)
        sock.sendall(word.encode() + b"\n")
    except OSError as exc:
        _write(2, f"orchestra: remote agent unreachable: {exc}\n".encode())
        return 255
    stream = sock.makefile("rb")
    while True:
        head = stream.read(5)
        if len(head) < 5:
            _write(2, b"orchestra: connection to the remote machine lost\n")
            return 255
        kind, size = head[0], struct.unpack(">I", head[1:])[0]
        if kind == 0:
            return size
        data = stream.read(size)
        try:
            _write(kind if kind in (1, 2) else 2, data)
        except OSError:
            pass


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
