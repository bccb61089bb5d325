"""Copy a bag's messages into a new bag: what compress, decompress and filter share.

Messages are copied in time order with their stamps and full connection headers; the output
is written to ``OUT.active`` and renamed when complete, so a failed copy never leaves a
half-written file under the final name.
"""
from __future__ import annotations

import os
from collections.abc import Callable

from orchestra.bag.reader import BagReader
from orchestra.bag.records import Connection
from orchestra.bag.writer import BagWriter

#: keep(connection, stamp ns, raw bytes) -> whether the message goes to the output
Keep = Callable[[Connection, int, bytes], bool]


def rewrite(src: str, dst: str, compression: str, keep: Keep | None = None) -> int:
    """Write the messages of ``src`` that ``keep`` accepts to ``dst``; return their count."""
    partial = dst + ".active"
    written = 0
    with BagReader(src) as reader:
        writer = BagWriter(partial, compression).open()
        try:
            conns: dict[int, Connection] = {}
            for conn, stamp, data in reader.messages():
                if keep is not None and not keep(conn, stamp, data):
                    continue
                out = conns.get(conn.id)
                if out is None:
                    out = conns[conn.id] = writer.add_connection(conn.topic, conn.header)
                writer.write(out, stamp, data)
                written += 1
            writer.close()
        except BaseException:
            writer.close()
            os.unlink(partial)
            raise
    os.replace(partial, dst)
    return written
