"""The graph drawer: node -> topic -> node edges, layered layout, DOT and SVG text."""
from __future__ import annotations

import shutil

import pytest
from lxml import etree

from orchestra.errors import OrchestraError
from orchestra.node.graph import build_graph, layers, render_with_graphviz, to_dot, to_svg
from orchestra.node.introspect import SystemState

SVG = {"s": "http://www.w3.org/2000/svg"}


def state_with_cycle() -> SystemState:
    return SystemState(
        publishers={"/cmd": ["/planner"], "/odom": ["/base"], "/rosout": ["/planner", "/base"]},
        subscribers={"/cmd": ["/base"], "/odom": ["/planner", "/viz"], "/rosout": ["/rosout"]},
        services={"/planner/plan": ["/planner"]},
        types={"/cmd": "geometry_msgs/Twist", "/odom": "nav_msgs/Odometry"})


def test_edges_go_from_publisher_to_topic_to_subscriber_and_rosout_is_hidden():
    g = build_graph(state_with_cycle())
    assert set(g.edges) == {("/planner", "t:/cmd"), ("t:/cmd", "/base"),
                            ("/base", "t:/odom"), ("t:/odom", "/planner"), ("t:/odom", "/viz")}
    assert "t:/rosout" not in g and "/rosout" not in g
    assert "t:/rosout" in build_graph(state_with_cycle(), show_all=True)


def test_layers_put_a_cycle_in_one_column_and_its_readers_after_it():
    g = build_graph(state_with_cycle())
    col = layers(g)
    assert col["/planner"] == col["/base"] == col["t:/cmd"] == col["t:/odom"]
    assert col["/viz"] == col["/planner"] + 1


def test_dot_and_svg_are_well_formed_and_draw_every_vertex_once():
    g = build_graph(state_with_cycle())
    dot = to_dot(g)
    assert dot.startswith("digraph rosgraph {") and dot.count("->") == 5
    root = etree.fromstring(to_svg(g).encode())
    labels = sorted(t.text for t in root.iterfind(".//s:text", SVG))
    assert labels == ["/base", "/cmd", "/odom", "/planner", "/viz"]
    assert len(root.findall(".//s:ellipse", SVG)) == 3
    assert len(root.findall(".//s:rect", SVG)) == 2
    assert len(root.findall(".//s:line", SVG)) == 5


def test_empty_graph_still_makes_a_valid_svg():
    root = etree.fromstring(to_svg(build_graph(SystemState())).encode())
    assert root.find(".//s:text", SVG).text == "(empty graph)"


@pytest.mark.skipif(shutil.which("dot") is None, reason="graphviz is not installed")
def test_png_and_pdf_are_rendered_by_graphviz(tmp_path):
    dot = to_dot(build_graph(state_with_cycle()))
    render_with_graphviz(dot, "png", str(tmp_path / "g.png"))
    render_with_graphviz(dot, "pdf", str(tmp_path / "g.pdf"))
    assert (tmp_path / "g.png").read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    assert (tmp_path / "g.pdf").read_bytes().startswith(b"%PDF")


def test_png_without_graphviz_is_a_clear_error(tmp_path):
    with pytest.raises(OrchestraError, match="needs graphviz"):
        render_with_graphviz("digraph g {}", "png", str(tmp_path / "g.png"),
                             dot="no-such-graphviz-dot")
    assert not (tmp_path / "g.png").exists()


def test_graphviz_syntax_error_is_reported_not_raised_raw(tmp_path):
    if shutil.which("dot") is None:
        pytest.skip("graphviz is not installed")
    with pytest.raises(OrchestraError, match="could not write"):
        render_with_graphviz("digraph {{{", "png", str(tmp_path / "g.png"))
