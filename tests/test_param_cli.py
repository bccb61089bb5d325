"""``orchestra param`` behaves like rosparam against a live master."""
from __future__ import annotations

import math
import xmlrpc.client

import pytest

from orchestra.cli import main
from orchestra.master import start_master

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def master(monkeypatch):
    handle = start_master(port=0)
    monkeypatch.setenv("ROS_MASTER_URI", handle.uri)
    monkeypatch.delenv("ROS_NAMESPACE", raising=False)
    yield handle
    handle.shutdown()


@pytest.fixture
def run(capsys):
    """Run ``orchestra param ...`` in-process; returns (exit code, stdout, stderr)."""
    def invoke(*args: str) -> tuple[int, str, str]:
        with pytest.raises(SystemExit) as info:
            main(["param", *args])
        out, err = capsys.readouterr()
        return info.value.code, out, err
    return invoke


def test_list_is_sorted_and_filters_by_namespace(master, run):
    for name in ("/b/x", "/a/z", "/a/y", "/ab"):
        master.params.set(name, 1)
    assert run("list") == (0, "/a/y\n/a/z\n/ab\n/b/x\n", "")
    # a namespace filter matches whole segments: /a does not list /ab
    assert run("list", "/a")[1] == "/a/y\n/a/z\n"


def test_get_prints_yaml_like_rosparam(master, run):
    master.params.set("/n", 42)
    master.params.set("/s", "hello")
    master.params.set("/d", {"k": [1, 2], "j": {"x": 1.5}})
    assert run("get", "/n")[1] == "42\n"
    assert run("get", "/s")[1] == "hello\n"
    # dictionaries: block YAML with sorted keys, then rosparam's extra newline
    assert run("get", "/d")[1] == "j:\n  x: 1.5\nk:\n- 1\n- 2\n\n"


def test_get_pretty_prints_nested_keys_and_multiline_strings(master, run):
    master.params.set("/d", {"b": "two\nlines", "a": {"c": True}})
    assert run("get", "-p", "/d")[1] == "a:\n  c: true\nb: |\n  two\n  lines\n"


def test_get_missing_param_fails_with_rosmaster_message(master, run):
    code, out, err = run("get", "/missing")
    assert code == 1 and out == ""
    assert "Parameter [/missing] is not set" in err


def test_set_reads_value_as_yaml(master, run):
    assert run("set", "/i", "7")[0] == 0
    run("set", "/neg", "-3")
    run("set", "/f", "0.5")
    run("set", "/b", "true")
    run("set", "/l", "[1, a]")
    run("set", "/str", "'7'")
    run("set", "/empty", "")
    run("set", "/angle", "deg(180)")
    p = master.params
    assert (p.get("/i"), p.get("/neg"), p.get("/f"), p.get("/b")) == (7, -3, 0.5, True)
    assert p.get("/l") == [1, "a"] and p.get("/str") == "7" and p.get("/empty") == ""
    assert math.isclose(p.get("/angle"), math.pi)


def test_set_dict_updates_keys_instead_of_replacing(master, run):
    master.params.set("/cfg", {"keep": 1, "change": 1})
    run("set", "/cfg", "{change: 2, new: {deep: 3}}")
    assert master.params.get("/cfg") == {"keep": 1, "change": 2, "new": {"deep": 3}}


def test_set_from_text_and_binary_files(master, run, tmp_path):
    text = tmp_path / "robot.urdf"
    text.write_text("<robot/>\n")
    blob = tmp_path / "blob.bin"
    blob.write_bytes(b"\x00\x01\xff")
    run("set", "-t", str(text), "/robot_description")
    run("set", "--binfile", str(blob), "/blob")
    assert master.params.get("/robot_description") == "<robot/>\n"
    assert master.params.get("/blob").data == b"\x00\x01\xff"


def test_set_out_of_range_int_is_refused_naming_param(master, run):
    code, _, err = run("set", "/big", "4294967296")
    assert code == 2 and "/big" in err and "32 bits" in err
    assert not master.params.has("/big")


def test_names_resolve_in_ros_namespace(master, run, monkeypatch):
    monkeypatch.setenv("ROS_NAMESPACE", "/robot")
    run("set", "rate", "10")
    assert master.params.get("/robot/rate") == 10
    assert run("get", "rate")[1] == "10\n"
    assert run("list")[1] == "/robot/rate\n"


def test_delete_param_and_namespace_and_root(master, run):
    master.params.set("/a/b", 1)
    master.params.set("/c", 2)
    assert run("delete", "/a")[0] == 0
    assert not master.params.has("/a")
    code, _, err = run("delete", "/a")
    assert code == 1 and "parameter [/a] is not set" in err
    run("delete", "/")
    assert master.params.get("/") == {}


def test_load_honours_documents_ns_key_and_rosparam_tags(master, run, tmp_path):
    f = tmp_path / "p.yaml"
    f.write_text("a: 1\nangle: !degrees 90\n---\n_ns: sub\nb: {c: 2}\n")
    assert run("load", str(f), "/base")[0] == 0
    assert master.params.get("/base/a") == 1
    assert math.isclose(master.params.get("/base/angle"), math.pi / 2)
    assert master.params.get("/base/sub/b/c") == 2


def test_load_merges_into_existing_namespace(master, run, tmp_path):
    master.params.set("/ns/old", 1)
    f = tmp_path / "p.yaml"
    f.write_text("new: 2\n")
    run("load", str(f), "/ns")
    assert master.params.get("/ns") == {"old": 1, "new": 2}


def test_load_bad_yaml_names_file_and_line_and_uploads_nothing(master, run, tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text("ok: 1\nlist: [1, 2\n")
    code, _, err = run("load", str(f))
    assert code == 2
    assert f"{f}:" in err and "invalid YAML" in err
    assert "Traceback" not in err
    assert master.params.names() == []


def test_load_value_xmlrpc_cannot_carry_uploads_nothing(master, run, tmp_path):
    f = tmp_path / "big.yaml"
    f.write_text("fine: 1\n---\nnested: {too_big: 3000000000}\n")
    code, _, err = run("load", str(f), "/robot")
    assert code == 2 and "/robot/nested/too_big" in err and str(f) in err
    assert master.params.names() == []


def test_load_missing_file_is_a_clear_error(master, run, tmp_path):
    code, _, err = run("load", str(tmp_path / "nope.yaml"))
    assert code == 2 and "nope.yaml" in err


def test_dump_round_trips_through_load(master, run, tmp_path):
    master.params.set("/ns", {"i": 1, "f": 2.5, "s": "x y", "l": [1, [2]], "b": False,
                              "bin": xmlrpc.client.Binary(b"\x00\x10"), "d": {"e": "f"}})
    out = tmp_path / "dump.yaml"
    assert run("dump", str(out), "/ns")[0] == 0
    text = out.read_text()
    assert "!!binary" in text
    before = master.params.get("/ns")
    master.params.delete("/ns")
    run("load", str(out), "/ns")
    after = master.params.get("/ns")
    assert after.pop("bin").data == before.pop("bin").data
    assert after == before


def test_dump_without_file_writes_stdout(master, run):
    master.params.set("/a", {"b": 1})
    assert run("dump")[1] == "a:\n  b: 1\n"
    assert run("dump", "-", "/a")[1] == "b: 1\n"


def test_unreachable_master_is_an_error_not_a_traceback(run, monkeypatch):
    handle = start_master(port=0)
    handle.shutdown()
    monkeypatch.setenv("ROS_MASTER_URI", handle.uri)
    code, _, err = run("list")
    assert code == 1 and "unable to communicate with master" in err


def test_load_from_stdin(master, run, monkeypatch):
    import io
    monkeypatch.setattr("sys.stdin", io.StringIO("a: {b: 1}\n"))
    assert run("load", "-", "/in")[0] == 0
    assert master.params.get("/in/a/b") == 1


def test_get_binary_prints_yaml_binary_tag(master, run):
    master.params.set("/blob", xmlrpc.client.Binary(b"abc"))
    assert run("get", "/blob")[1] == "!!binary |-\n  YWJj\n\n"
