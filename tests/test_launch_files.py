"""Reading the files a launch file names: regular files only, bounded, symlink stubs followed."""
import os
import threading

import pytest

from orchestra.launch import files
from orchestra.launch.files import read_bytes, read_text


def test_regular_file_is_read_whole_with_universal_newlines(tmp_path):
    path = tmp_path / "a.yaml"
    path.write_bytes(b"a: 1\r\nb: 2\rc: 3\n" * 5000)
    assert read_bytes(str(path)) == path.read_bytes()
    assert read_text(str(path)) == "a: 1\nb: 2\nc: 3\n" * 5000


def test_empty_file_is_empty(tmp_path):
    (tmp_path / "e").write_bytes(b"")
    assert read_bytes(str(tmp_path / "e")) == b""


def test_fifo_is_refused_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    result: list = []
    reader = threading.Thread(target=lambda: result.append(_error_of(str(fifo))), daemon=True)
    reader.start()
    reader.join(timeout=30)
    assert not reader.is_alive(), "reading a FIFO blocked"
    assert "not a regular file" in result[0]


def test_device_is_refused():
    assert "not a regular file" in _error_of("/dev/zero")


def test_file_over_the_limit_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(files, "MAX_FILE_BYTES", 1000)
    (tmp_path / "big").write_bytes(b"x" * 1001)
    (tmp_path / "fits").write_bytes(b"x" * 1000)
    assert "larger than" in _error_of(str(tmp_path / "big"))
    assert read_bytes(str(tmp_path / "fits")) == b"x" * 1000


def test_file_whose_size_the_stat_does_not_tell_is_read_to_its_end():
    """/proc files stat as empty: they are read on, up to the limit."""
    data = read_bytes("/proc/self/status")
    assert data.startswith(b"Name:") and data.endswith(b"\n")


def test_symlink_stub_is_followed_to_its_target(tmp_path):
    (tmp_path / "real.yaml").write_text("a: 1\n")
    (tmp_path / "link.yaml").write_text("real.yaml")
    assert read_text(str(tmp_path / "link.yaml")) == "a: 1\n"


def _error_of(path: str) -> str:
    with pytest.raises(OSError) as info:
        read_bytes(path)
    return str(info.value)
