"""The status table, the live footer on a terminal, and the console line prefixes."""
from __future__ import annotations

import io

from orchestra.supervise.output import NodeOutput, Screen
from orchestra.supervise.process import OutputMode
from orchestra.supervise.status import footer_lines, summary_line, table_lines


def node(name, state="RUNNING", pid=10, restarts=0, uptime=5.0, cpu=1.5, rss=2 * 1024 * 1024):
    return {"name": name, "state": state, "pid": pid, "restarts": restarts, "uptime": uptime,
            "cpu_percent": cpu, "rss": rss}


def test_table_has_one_line_per_node_with_state_pid_restarts_uptime_cpu_rss():
    lines = table_lines([node("/talker", uptime=75, restarts=2),
                         node("/crashy", state="BACKOFF", pid=None, cpu=None, rss=None)])
    assert lines[0].split() == ["NODE", "STATE", "PID", "RESTARTS", "UPTIME", "CPU%", "RSS"]
    assert lines[1].split() == ["/talker", "RUNNING", "10", "2", "1m15s", "1.5", "2.0M"]
    assert lines[2].split() == ["/crashy", "BACKOFF", "-", "0", "-", "-", "-"]


def test_footer_shows_summary_and_unhealthy_nodes_when_table_does_not_fit():
    nodes = [node(f"/n{i}") for i in range(50)] + [node("/bad", state="FAILED", pid=None)]
    lines = footer_lines(nodes, max_lines=6)
    assert lines[0] == summary_line(nodes) == "51 nodes: 50 RUNNING, 1 FAILED"
    assert [line.split()[0] for line in lines[1:]] == ["NODE", "/bad"]
    assert len(footer_lines(nodes[:3], max_lines=6)) == 4


def test_footer_is_redrawn_below_new_output_lines():
    out = io.BytesIO()
    screen = Screen(out=out, err=io.BytesIO(), colour=False)
    screen.set_footer(["STATUS 1", "STATUS 2"])
    screen.write_lines(b"[/a] hello\n", "out")
    text = out.getvalue()
    # footer drawn, then erased (cursor up 2 lines, clear), line written, footer again
    assert text == b"STATUS 1\nSTATUS 2\n\x1b[2A\x1b[J[/a] hello\nSTATUS 1\nSTATUS 2\n"
    screen.set_footer([])
    assert out.getvalue().endswith(b"\x1b[2A\x1b[J")


def test_prefix_is_coloured_only_on_a_terminal_and_stable_per_name():
    plain = Screen(out=io.BytesIO(), err=io.BytesIO(), colour=False)
    coloured = Screen(out=io.BytesIO(), err=io.BytesIO(), colour=True)
    assert plain.prefix("/a") == b"[/a] "
    assert coloured.prefix("/a").startswith(b"\x1b[") and b"[/a]" in coloured.prefix("/a")
    assert coloured.prefix("/a") == coloured.prefix("/a")


def test_partial_lines_are_joined_across_reads():
    screen = Screen(out=io.BytesIO(), err=io.BytesIO(), colour=False)
    output = NodeOutput("/n", OutputMode.SCREEN, screen, None, None)
    output.feed("out", b"hel")
    output.feed("out", b"lo\nwor")
    output.feed("out", b"ld\n")
    assert screen.out.getvalue() == b"[/n] hello\n[/n] world\n"


def test_endless_line_is_shown_once_it_passes_the_limit():
    from orchestra.supervise.output import MAX_LINE

    screen = Screen(out=io.BytesIO(), err=io.BytesIO(), colour=False)
    output = NodeOutput("/n", OutputMode.SCREEN, screen, None, None)
    output.feed("out", b"x" * (MAX_LINE + 1))
    assert screen.out.getvalue() == b"[/n] " + b"x" * (MAX_LINE + 1) + b"\n"
