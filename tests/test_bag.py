"""orchestra's bag tools without real ROS: the file format (write, read, reindex after a
kill, a full disk), the one-line errors of the CLI, the safe filter expressions, and
record/play through orchestra's own nodes (nothing lost at 1 kHz, latched topics)."""
from __future__ import annotations

import errno
import os
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from orchestra.bag import writer as writer_mod
from orchestra.bag.expression import ExpressionError, compile_expression
from orchestra.bag.reader import BagReader, BagUnindexed
from orchestra.bag.reindex import reindex
from orchestra.bag.writer import BagWriteError, BagWriter

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import NodeProcess, wait_for  # noqa: E402

FIXTURES = Path(__file__).resolve().parent / "bag_fixtures"
STRING = {"type": "std_msgs/String", "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1",
          "message_definition": "string data\n", "callerid": "/talker", "latching": "1"}
T0 = 1_700_000_000 * 10**9


def _string(text: str) -> bytes:
    raw = text.encode()
    return struct.pack("<I", len(raw)) + raw


def _write(path: Path, count: int, compression: str = "none", chunk_size: int = 1000,
           close: bool = True) -> BagWriter:
    w = BagWriter(str(path), compression, chunk_size).open()
    a = w.add_connection("/chatter", STRING)
    b = w.add_connection("/other", dict(STRING, callerid="/second", latching="0"))
    for i in range(count):
        w.write(a if i % 3 else b, T0 + i * 10_000_000, _string(f"n {i}"))
    if close:
        w.close()
    return w


def _orchestra(*args: str, env: dict | None = None, timeout: float = 60
               ) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "orchestra", *args], capture_output=True,
                          text=True, timeout=timeout, env=env)


@pytest.mark.parametrize("compression", ["none", "bz2", "lz4"])
def test_written_bag_reads_back_in_time_order_with_full_connection_headers(tmp_path,
                                                                            compression):
    path = tmp_path / "x.bag"
    _write(path, 500, compression)
    with BagReader(str(path)) as r:
        msgs = list(r.messages())
        assert r.message_count == 500 and len(r.chunk_infos) > 3
        assert {h.compression for h in r.chunk_headers} == {compression}
    assert [m[2] for m in msgs] == [_string(f"n {i}") for i in range(500)]
    assert [m[1] for m in msgs] == sorted(m[1] for m in msgs)
    other = next(c for c, _, _ in msgs if c.topic == "/other")
    assert other.header == dict(STRING, callerid="/second", latching="0", topic="/other")


def test_reader_filters_topics_and_time_window(tmp_path):
    path = tmp_path / "x.bag"
    _write(path, 300)
    with BagReader(str(path)) as r:
        got = list(r.messages(["/other"], T0 + 100 * 10_000_000, T0 + 200 * 10_000_000))
    assert [d for _, _, d in got] == [_string(f"n {i}") for i in range(102, 201, 3)]


def test_killed_recording_loses_at_most_the_open_chunk_and_reindex_repairs_it(tmp_path):
    path = tmp_path / "killed.bag"
    w = _write(path, 400, close=False)          # as after kill -9: no index, open chunk lost
    on_disk = sum(sum(i.counts.values()) for i in w._infos)
    assert 400 - on_disk < 1000 // 20            # at most one chunk's worth missing
    with pytest.raises(BagUnindexed):
        BagReader(str(path))
    result = reindex(str(path))
    assert (tmp_path / "killed.orig.bag").exists()
    with BagReader(str(path)) as r:
        got = [d for _, _, d in r.messages()]
    assert result.messages == on_disk == len(got)
    assert got == [_string(f"n {i}") for i in range(on_disk)]


def test_blocks_reserved_ahead_neither_show_in_the_size_nor_stay_after_close(tmp_path):
    """The writer reserves disk blocks past the end (fallocate, size kept): a killed
    recording ends where its last chunk ends, and closing gives the reserve back."""
    path = tmp_path / "reserved.bag"
    w = _write(path, 400, close=False)
    assert os.path.getsize(path) == w._good_end   # what a kill -9 leaves: no zeros after
    w.close()
    st = os.stat(path)
    assert st.st_blocks * 512 < st.st_size + writer_mod.RESERVE_AHEAD // 4


def test_reindex_drops_a_half_written_chunk(tmp_path):
    path = tmp_path / "cut.bag"
    _write(path, 400)
    with BagReader(str(path)) as r:
        last = r.chunk_headers[-1]
        before_last = r.message_count - sum(r.chunk_infos[-1].counts.values())
    with open(path, "r+b") as fh:
        fh.truncate(last.data_pos + last.data_len // 2)
    result = reindex(str(path), backup=False)
    assert "stopped at byte" in result.problem
    with BagReader(str(path)) as r:
        assert len(list(r.messages())) == before_last == result.messages


def test_full_disk_stops_with_an_error_and_leaves_a_valid_bag(tmp_path, monkeypatch):
    path = tmp_path / "full.bag"
    budget = {"left": 12_000}
    real_write = os.write

    def write(fd, data):  # the disk fills up after 12 kB (injected at the file layer)
        if budget["left"] == 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        n = min(len(data), budget["left"])  # a short write first, as a filling disk does
        budget["left"] -= n
        return real_write(fd, bytes(data)[:n])

    def writev(fd, parts):
        return write(fd, b"".join(bytes(p) for p in parts))

    monkeypatch.setattr(writer_mod.os, "write", write)
    monkeypatch.setattr(writer_mod.os, "writev", writev)
    w = BagWriter(str(path), "none", 1000).open()
    conn = w.add_connection("/chatter", STRING)
    with pytest.raises(BagWriteError, match="No space left"):
        for i in range(10_000):
            w.write(conn, T0 + i, _string(f"n {i}"))
    budget["left"] = 10**9  # the cut-off partial chunk freed room for the index
    with pytest.raises(BagWriteError, match="messages written before"):
        w.close()
    monkeypatch.undo()
    with BagReader(str(path)) as r:
        got = [d for _, _, d in r.messages()]
    assert 0 < len(got) < 10_000
    assert got == [_string(f"n {i}") for i in range(len(got))]


def test_full_tmpfs_keeps_what_was_recorded_as_a_valid_bag(tmp_path):
    mnt = tmp_path / "small"
    mnt.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs",
                                            str(mnt)], capture_output=True).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    try:
        w = BagWriter(str(mnt / "x.bag"), "none", 16 * 1024).open()
        conn = w.add_connection("/chatter", STRING)
        with pytest.raises(BagWriteError):
            for i in range(100_000):
                w.write(conn, T0 + i, _string(f"message number {i}"))
        with pytest.raises(BagWriteError):
            w.close()
        with BagReader(str(mnt / "x.bag")) as r:
            assert r.message_count > 1000
            assert len(list(r.messages())) == r.message_count
    finally:
        subprocess.run(["umount", str(mnt)], capture_output=True)


def _bad_inputs(tmp_path: Path) -> dict[str, Path]:
    good = tmp_path / "good.bag"
    _write(good, 300)
    cases = {"text": tmp_path / "notes.bag", "empty": tmp_path / "empty.bag",
             "truncated": tmp_path / "truncated.bag", "corrupt": tmp_path / "corrupt.bag",
             "directory": tmp_path / "dir.bag", "missing": tmp_path / "missing.bag",
             "unindexed": tmp_path / "unindexed.bag"}
    cases["text"].write_text("hello\n")
    cases["empty"].write_bytes(b"")
    data = good.read_bytes()
    cases["truncated"].write_bytes(data[:len(data) // 2])
    cases["corrupt"].write_bytes(data[:5000] + b"\xff" * 64 + data[5064:])
    cases["directory"].mkdir()
    _write(cases["unindexed"], 300, close=False)
    return cases


@pytest.mark.parametrize("command", ["info", "play", "filter", "compress"])
def test_bad_bag_is_one_line_exit_2_never_a_traceback(tmp_path, command):
    cases = _bad_inputs(tmp_path)
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:1")
    for kind, path in cases.items():
        if command == "play" and kind not in ("text", "truncated", "missing"):
            continue
        argv = {"info": ["bag", "info", str(path)],
                "play": ["bag", "play", str(path)],
                "filter": ["bag", "filter", str(path), str(tmp_path / "o.bag"), "True"],
                "compress": ["bag", "compress", "--output-dir", str(tmp_path), str(path)]
                }[command]
        if (command == "compress" and kind == "missing") or (command == "info"
                                                              and kind == "corrupt"):
            continue  # info reads the index only, as rosbag info
        proc = _orchestra(*argv, env=env)
        assert proc.returncode == 2, (kind, proc.stderr)
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in proc.stderr, (kind, proc.stderr)
        assert str(path) in lines[0], (kind, lines)
        if kind in ("text", "empty", "directory"):
            assert "not a ROS 1 bag" in lines[0], lines
        if kind in ("truncated", "corrupt", "unindexed") and command != "play":
            assert "bag reindex" in lines[0], (kind, lines)


def test_corrupt_bag_says_reindex_and_reindex_repairs_it(tmp_path):
    cases = _bad_inputs(tmp_path)
    proc = _orchestra("bag", "reindex", str(cases["unindexed"]))
    assert proc.returncode == 0, proc.stderr
    proc = _orchestra("bag", "info", "--yaml", str(cases["unindexed"]))
    assert proc.returncode == 0 and "indexed: True" in proc.stdout


@pytest.mark.parametrize("text", [
    "__import__('os').system('true')", "m.__class__", "(lambda: 1)()", "open('x')",
    "[x for x in m.data]", "m.data.format(m)", "topic; 1", "exec('1')", "x" * 3000,
])
def test_filter_expression_refuses_anything_but_the_whitelist(text):
    with pytest.raises(ExpressionError):
        compile_expression(text, frozenset({"topic", "m", "t"}))


def test_filter_keeps_the_messages_the_expression_selects(tmp_path):
    src, dst = tmp_path / "in.bag", tmp_path / "out.bag"
    _write(src, 300)
    proc = _orchestra("bag", "filter", str(src), str(dst),
                      "topic == '/other' and int(m.data.split()[1]) % 2 == 0 "
                      f"and t.to_sec() < {T0 / 1e9 + 1.5}")
    assert "split" in proc.stderr and proc.returncode == 2  # split is not whitelisted
    proc = _orchestra("bag", "filter", str(src), str(dst),
                      "topic == '/other' and m.data.endswith('0') "
                      f"and t.to_sec() < {T0 / 1e9 + 1.5}")
    assert proc.returncode == 0, proc.stderr
    with BagReader(str(dst)) as r:
        got = [d for _, _, d in r.messages()]
        assert [c.header for c in r.connections] == [dict(STRING, callerid="/second",
                                                          latching="0", topic="/other")]
    assert got == [_string(f"n {i}") for i in range(0, 150, 3) if str(i).endswith("0")]


def test_compress_then_decompress_keeps_every_message(tmp_path):
    path = tmp_path / "x.bag"
    _write(path, 300)
    original = BagReader(str(path))
    before = [(c.topic, s, d) for c, s, d in original.messages()]
    original.close()
    for args, expect in ((["--lz4"], "lz4"), ([], "bz2"), (None, "none")):
        cmd = ["bag", "decompress", "-f", str(path)] if args is None else \
            ["bag", "compress", "-f", *args, str(path)]
        proc = _orchestra(*cmd)
        assert proc.returncode == 0, proc.stderr
        with BagReader(str(path)) as r:
            assert {h.compression for h in r.chunk_headers} == {expect}
            assert [(c.topic, s, d) for c, s, d in r.messages()] == before
    assert (tmp_path / "x.orig.bag").exists()


def test_record_into_a_missing_folder_is_one_line_exit_2(tmp_path):
    proc = _orchestra("bag", "record", "-O", str(tmp_path / "nope" / "x.bag"), "/chatter")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"orchestra: error: cannot record to {tmp_path / 'nope' / 'x.bag'}: folder "
        f"{tmp_path / 'nope'} does not exist"]


def _env(master) -> dict:
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    env.pop("ROS_NAMESPACE", None)
    return env


@pytest.fixture
def start():
    """Start a process whose JSON lines are collected; at the end of the test it is killed
    if still running and its pipes are closed (left to the garbage collector they are
    unclosed files, reported in whatever test runs then)."""
    started: list[NodeProcess] = []

    def _start(argv: list[str], env: dict) -> NodeProcess:
        proc = NodeProcess(argv, env)
        started.append(proc)
        return proc
    yield _start
    for proc in started:
        proc.kill()
        proc.close_pipes()


def test_record_loses_nothing_of_10000_messages_at_1khz(start, master, tmp_path):
    env = _env(master)
    out = tmp_path / "burst.bag"
    # a relative name, resolved as rosbag resolves it: the limit still ends the recording
    rec = start([sys.executable, "-m", "orchestra", "bag", "record", "-q", "-O", str(out),
                  "--limit", "10000", "numbers"], env)
    procs = [rec]
    try:
        wait_for(lambda: _subscribed(master.uri, "/numbers"), timeout=20)
        pub = start([sys.executable, str(FIXTURES / "burst.py"), "/numbers", "10000", "1000"],
                     env)
        procs.append(pub)
        pub.expect(lambda d: "sent" in d, timeout=60)
        assert rec.wait(timeout=30) == 0, rec.stderr_lines
    finally:
        for p in procs:
            p.kill()
    with BagReader(str(out)) as r:
        got = [d for _, _, d in r.messages()]
    assert len(got) == 10_000
    assert got == [_string(f"n {i}") for i in range(10_000)]


def _subscribed(uri: str, topic: str) -> bool:
    import xmlrpc.client
    with xmlrpc.client.ServerProxy(uri) as proxy:
        _code, _msg, (_pubs, subs, _srvs) = proxy.getSystemState("/t")
    return any(t == topic and nodes for t, nodes in subs)


def test_play_latches_a_topic_that_was_latched_when_recorded(start, master, tmp_path):
    path = tmp_path / "latched.bag"
    w = BagWriter(str(path)).open()
    conn = w.add_connection("/map_name", STRING)  # latching: 1
    w.write(conn, T0, _string("the map"))
    w.close()
    env = _env(master)
    play = start([sys.executable, "-m", "orchestra", "bag", "play", "-q", "-d", "0",
                   "--loop", str(path)], env)
    try:
        wait_for(lambda: _published(master.uri, "/map_name"), timeout=20)
        # a subscriber that comes after the message was sent still gets it
        sub = start([sys.executable, str(FIXTURES / "stamp_sub.py"), "/map_name"], env)
        try:
            got = sub.expect(lambda d: "data" in d, timeout=20)
        finally:
            sub.kill()
    finally:
        play.kill()
    assert got["data"] == "the map" and got["latching"] == "1"


def _published(uri: str, topic: str) -> bool:
    import xmlrpc.client
    with xmlrpc.client.ServerProxy(uri) as proxy:
        _code, _msg, (pubs, _subs, _srvs) = proxy.getSystemState("/t")
    return any(t == topic and nodes for t, nodes in pubs)


def test_record_names_bags_as_rosbag():
    from orchestra.bag.record import RecordOptions, bag_path
    started = 1_700_000_000.0
    import time as _time
    stamp = _time.strftime("%Y-%m-%d-%H-%M-%S", _time.localtime(started))
    assert bag_path(RecordOptions(name="run"), started, None) == "run.bag"
    assert bag_path(RecordOptions(name="run.bag"), started, 2) == "run_2.bag"
    assert bag_path(RecordOptions(prefix="session"), started, None) == f"session_{stamp}.bag"
    assert bag_path(RecordOptions(prefix="out/"), started, 0) == f"out/{stamp}_0.bag"
    assert bag_path(RecordOptions(), started, None) == f"{stamp}.bag"


def test_record_all_picks_up_later_topics_and_splits_by_size(start, master, tmp_path):
    env = _env(master)
    rec = start([sys.executable, "-m", "orchestra", "bag", "record", "-q", "-a", "-x",
                  "/rosout.*", "-O", str(tmp_path / "split"), "--split", "--size", "0.05",
                  "--chunksize", "8"], env)
    pub = None
    try:
        # the topic appears only after the recorder started: -a finds it by polling (the
        # publisher sends once a subscriber is connected)
        pub = start([sys.executable, str(FIXTURES / "burst.py"), "/late", "3000", "1000"],
                     env)
        pub.expect(lambda d: "sent" in d, timeout=60)
        wait_for(lambda: len(list(tmp_path.glob("split_*.bag"))) >= 2, timeout=30)
    finally:
        rec.signal(2)
        assert rec.wait(timeout=30) == 0, rec.stderr_lines
        if pub is not None:
            pub.kill()
    parts = sorted(tmp_path.glob("split_*.bag"), key=lambda p: int(p.stem.split("_")[1]))
    assert len(parts) >= 2 and not list(tmp_path.glob("*.active"))
    got = []
    for part in parts:
        with BagReader(str(part)) as r:
            assert {c.topic for c in r.connections} == {"/late"}
            got += [d for _, _, d in r.messages()]
    # the first messages may precede the subscription, the last may still be in flight
    # when the SIGINT comes (on a loaded machine); in between, nothing is lost
    first = int(got[0][4:].decode().split()[1])
    assert got == [_string(f"n {i}") for i in range(first, first + len(got))]


def _timed_bag(path: Path, hz: int = 10, seconds: int = 3) -> None:
    w = BagWriter(str(path)).open()
    conn = w.add_connection("/timed", dict(STRING, latching="0"))
    for i in range(hz * seconds + 1):
        w.write(conn, T0 + i * 10**9 // hz, _string(f"n {i}"))
    w.close()


def test_play_start_duration_and_rate_pick_and_pace_the_messages(start, master, tmp_path):
    bag = tmp_path / "timed.bag"
    _timed_bag(bag)
    env = _env(master)
    sub = start([sys.executable, str(FIXTURES / "stamp_sub.py"), "/timed"], env)
    try:
        sub.ready(timeout=20)
        wait_for(lambda: _subscribed(master.uri, "/timed"), timeout=20)
        play = start([sys.executable, "-m", "orchestra", "bag", "play", "-q", "-d", "0",
                       "--wait-for-subscribers", "-s", "1", "-u", "1", "-r", "2", str(bag)],
                      env)
        assert play.wait(timeout=30) == 0, play.stderr_lines
        got = [sub.expect(lambda d: "data" in d, timeout=10) for _ in range(11)]
    finally:
        sub.kill()
    assert [g["data"] for g in got] == [f"n {i}" for i in range(10, 21)]
    span = got[-1]["t"] - got[0]["t"]
    assert 0.3 < span < 0.8, span  # 1 s of bag at rate 2 (a loose correctness check)


def test_play_clock_publishes_the_bag_time(start, master, tmp_path):
    bag = tmp_path / "timed.bag"
    _timed_bag(bag)
    env = _env(master)
    play = start([sys.executable, "-m", "orchestra", "bag", "play", "-q", "-d", "0",
                   "--clock", "--hz", "50", "-l", str(bag)], env)
    try:
        echo = subprocess.run([sys.executable, "-m", "orchestra", "topic", "echo", "-n", "1",
                               "/clock"], capture_output=True, text=True, env=env, timeout=30)
    finally:
        play.kill()
    assert echo.returncode == 0, echo.stderr
    secs = int(echo.stdout.split("secs:")[1].split()[0])
    assert T0 // 10**9 <= secs <= T0 // 10**9 + 3, echo.stdout


def test_kill_9_of_the_recorder_leaves_a_bag_that_reindex_repairs(start, master, tmp_path):
    env = _env(master)
    out = tmp_path / "killed.bag"
    active = tmp_path / "killed.bag.active"
    rec = start([sys.executable, "-m", "orchestra", "bag", "record", "-q", "-O", str(out),
                  "--chunksize", "2", "/numbers"], env)
    pub = None
    try:
        wait_for(lambda: _subscribed(master.uri, "/numbers"), timeout=20)
        pub = start([sys.executable, str(FIXTURES / "burst.py"), "/numbers", "100000",
                      "2000"], env)
        wait_for(lambda: active.exists() and active.stat().st_size > 40_000, timeout=30)
        rec.proc.kill()  # SIGKILL: no chance to write the index
        rec.wait(timeout=10)
    finally:
        rec.kill()
        if pub is not None:
            pub.kill()
    info = _orchestra("bag", "info", str(active))
    assert info.returncode == 2 and "bag reindex" in info.stderr, info.stderr
    fixed = _orchestra("bag", "reindex", str(active))
    assert fixed.returncode == 0, fixed.stderr
    with BagReader(str(active)) as r:
        got = [d for _, _, d in r.messages()]
    assert len(got) > 500
    assert got == [_string(f"n {i}") for i in range(len(got))]


def test_play_on_a_terminal_pauses_with_space_and_steps_with_s(start, master, tmp_path):
    import pty
    bag = tmp_path / "timed.bag"
    _timed_bag(bag)
    env = _env(master)
    sub = start([sys.executable, str(FIXTURES / "stamp_sub.py"), "/timed"], env)
    keys, tty = pty.openpty()
    play = subprocess.Popen([sys.executable, "-m", "orchestra", "bag", "play", "--pause",
                             "-d", "0", "--wait-for-subscribers", str(bag)], env=env,
                            stdin=tty, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        sub.ready(timeout=20)
        sub.expect(lambda d: d.get("connected"), timeout=20)
        for expected in ("n 0", "n 1"):
            os.write(keys, b"s")
            assert sub.expect(lambda d: "data" in d, timeout=10)["data"] == expected
        with pytest.raises(AssertionError):  # paused: nothing more comes
            sub.expect(lambda d: "data" in d, timeout=0.6)
        os.write(keys, b" ")
        rest = [sub.expect(lambda d: "data" in d, timeout=10)["data"] for _ in range(29)]
        assert rest == [f"n {i}" for i in range(2, 31)]
        assert play.wait(timeout=20) == 0, play.stderr.read() if play.stderr else ""
    finally:
        play.kill()
        play.wait()
        if play.stderr is not None:
            play.stderr.close()
        sub.kill()
        os.close(keys)
        os.close(tty)



def test_record_onto_a_full_disk_stops_with_one_line_and_a_valid_bag(start, master, tmp_path):
    mnt = tmp_path / "small"
    mnt.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs",
                                            str(mnt)], capture_output=True).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    env = _env(master)
    rec = pub = None
    try:
        rec = start([sys.executable, "-m", "orchestra", "bag", "record", "-q", "-O",
                      str(mnt / "x"), "--chunksize", "8", "/numbers"], env)
        wait_for(lambda: _subscribed(master.uri, "/numbers"), timeout=20)
        pub = start([sys.executable, str(FIXTURES / "burst.py"), "/numbers", "20000",
                      "5000"], env)
        assert rec.wait(timeout=60) == 2
        wait_for(lambda: rec.stderr_lines, timeout=5)
        assert len(rec.stderr_lines) == 1 and "No space left on device" in \
            rec.stderr_lines[0] and "messages written before" in rec.stderr_lines[0], \
            rec.stderr_lines
        with BagReader(str(mnt / "x.bag")) as r:
            got = [d for _, _, d in r.messages()]
        assert len(got) > 100 and got == [_string(f"n {i}") for i in range(len(got))]
    finally:
        for proc in (rec, pub):
            if proc is not None:
                proc.kill()
        subprocess.run(["umount", str(mnt)], capture_output=True)


def test_record_buffer_drops_the_oldest_messages_beyond_buffsize(tmp_path):
    from types import SimpleNamespace

    from orchestra.bag.record import Recorder, RecordOptions
    rec = Recorder(RecordOptions(topics=["/x"], name=str(tmp_path / "b"), buffsize=100))
    rec._write_lock.acquire()  # the writer is busy: messages queue up
    for i in range(5):
        rec._on_message(SimpleNamespace(_buff=bytes([i]) * 40, _connection_header={}), "/x")
    assert rec.dropped == 3
    assert [item[3][0] for item in rec._queue] == [3, 4]


def test_record_and_play_signal_handler_takes_no_lock_the_interrupted_thread_holds():
    """A SIGINT arriving while the main thread is inside ``event.wait`` (holding the event's
    lock): the handler may not wait for that lock; the event is set once it is released."""
    import signal
    import threading

    from orchestra.bag.cli import _stop_on_signals

    event = threading.Event()
    undo = _stop_on_signals(event)
    try:
        handler = signal.getsignal(signal.SIGINT)
        assert callable(handler)
        returned = threading.Event()

        def interrupted_thread() -> None:
            with event._cond:           # what Event.wait holds around its wait
                handler(signal.SIGINT, None)
                handler(signal.SIGINT, None)
                returned.set()

        thread = threading.Thread(target=interrupted_thread, daemon=True)
        thread.start()
        assert returned.wait(10), "the signal handler waited for a lock its thread holds"
        assert event.wait(10)
    finally:
        undo()
