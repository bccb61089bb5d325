"""The node/topic graph (what rqt_graph shows) as a networkx graph, DOT text, or SVG.

No graphviz binary is assumed: DOT is written by hand, and the SVG uses a small layered
layout of our own (layer = longest path from a source over the graph's strongly connected
components, so cycles such as a request/response pair stay readable). PNG is not produced:
it would need a rasteriser and a font, i.e. a new dependency.
"""
from __future__ import annotations

from html import escape

import networkx as nx

from orchestra.node.introspect import SystemState

HIDDEN_TOPICS = ("/rosout", "/rosout_agg")
HIDDEN_NODES = ("/rosout",)


def build_graph(state: SystemState, show_all: bool = False) -> nx.DiGraph:
    """Nodes and topics as vertices (``kind`` = node/topic); publisher -> topic -> subscriber."""
    graph = nx.DiGraph()

    def hidden(topic: str) -> bool:
        return not show_all and topic in HIDDEN_TOPICS

    for node in state.nodes:
        if show_all or node not in HIDDEN_NODES:
            graph.add_node(node, kind="node", label=node)
    for topic in state.topics:
        if hidden(topic):
            continue
        key = "t:" + topic
        graph.add_node(key, kind="topic", label=topic, type=state.types.get(topic, ""))
        for node in state.publishers.get(topic, []):
            if node in graph:
                graph.add_edge(node, key)
        for node in state.subscribers.get(topic, []):
            if node in graph:
                graph.add_edge(key, node)
    return graph


def _dot_id(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def to_dot(graph: nx.DiGraph) -> str:
    lines = ["digraph rosgraph {", "  rankdir=LR;", "  node [fontname=\"sans-serif\"];"]
    for vertex, data in sorted(graph.nodes(data=True)):
        shape = "ellipse" if data["kind"] == "node" else "box"
        lines.append(f"  {_dot_id(vertex)} [label={_dot_id(data['label'])}, shape={shape}];")
    for a, b in sorted(graph.edges()):
        lines.append(f"  {_dot_id(a)} -> {_dot_id(b)};")
    lines.append("}")
    return "\n".join(lines) + "\n"


def layers(graph: nx.DiGraph) -> dict[str, int]:
    """Column of each vertex: longest path from a source in the condensed (acyclic) graph."""
    dag = nx.condensation(graph)
    depth: dict[int, int] = {}
    for comp in nx.topological_sort(dag):
        preds = list(dag.predecessors(comp))
        depth[comp] = max((depth[p] + 1 for p in preds), default=0)
    mapping = dag.graph["mapping"]
    return {v: depth[mapping[v]] for v in graph.nodes}


CHAR_W, BOX_H, COL_GAP, ROW_GAP, MARGIN = 7.2, 30, 60, 24, 20


def to_svg(graph: nx.DiGraph) -> str:
    """A self-contained SVG: ellipses for nodes, boxes for topics, arrows for data flow."""
    if graph.number_of_nodes() == 0:
        return ('<svg xmlns="http://www.w3.org/2000/svg" width="200" height="40">'
                '<text x="10" y="25" font-family="sans-serif" font-size="12">'
                '(empty graph)</text></svg>\n')
    col_of = layers(graph)
    columns: dict[int, list[str]] = {}
    for v in sorted(graph.nodes, key=lambda v: graph.nodes[v]["label"]):
        columns.setdefault(col_of[v], []).append(v)
    width_of = {v: max(60.0, len(graph.nodes[v]["label"]) * CHAR_W + 24) for v in graph.nodes}
    col_x: dict[int, float] = {}
    x: float = MARGIN
    for col in sorted(columns):
        col_x[col] = x
        x += max(width_of[v] for v in columns[col]) + COL_GAP
    pos: dict[str, tuple[float, float]] = {}
    height = 0.0
    for col, members in columns.items():
        colw = max(width_of[v] for v in members)
        for row, v in enumerate(members):
            cx = col_x[col] + colw / 2
            cy = MARGIN + BOX_H / 2 + row * (BOX_H + ROW_GAP)
            pos[v] = (cx, cy)
            height = max(height, cy + BOX_H / 2 + MARGIN)
    total_w = x - COL_GAP + MARGIN
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{total_w:.0f}" '
           f'height="{height:.0f}" viewBox="0 0 {total_w:.0f} {height:.0f}">',
           '<defs><marker id="arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="8" '
           'markerHeight="8" orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" '
           'fill="#444"/></marker></defs>',
           '<g font-family="sans-serif" font-size="12">']
    for a, b in graph.edges():
        (ax, ay), (bx, by) = pos[a], pos[b]
        x1 = ax + width_of[a] / 2 if bx >= ax else ax - width_of[a] / 2
        x2 = bx - width_of[b] / 2 if bx >= ax else bx + width_of[b] / 2
        out.append(f'<line x1="{x1:.1f}" y1="{ay:.1f}" x2="{x2:.1f}" y2="{by:.1f}" '
                   'stroke="#444" stroke-width="1.2" marker-end="url(#arrow)"/>')
    for v, data in graph.nodes(data=True):
        cx, cy = pos[v]
        w = width_of[v]
        label = escape(data["label"])
        if data["kind"] == "node":
            out.append(f'<ellipse cx="{cx:.1f}" cy="{cy:.1f}" rx="{w / 2:.1f}" ry="{BOX_H / 2}" '
                       'fill="#dbe9ff" stroke="#335"/>')
        else:
            tip = escape(data.get("type", ""))
            out.append(f'<rect x="{cx - w / 2:.1f}" y="{cy - BOX_H / 2:.1f}" width="{w:.1f}" '
                       f'height="{BOX_H}" fill="#fff4d6" stroke="#553"><title>{tip}</title></rect>')
        out.append(f'<text x="{cx:.1f}" y="{cy + 4:.1f}" text-anchor="middle">{label}</text>')
    out.append("</g></svg>")
    return "\n".join(out) + "\n"


#: formats graphviz's ``dot`` renders for us (a raster or PDF needs fonts and a rasteriser)
GRAPHVIZ_FORMATS = ("png", "pdf")


def render_with_graphviz(dot_text: str, fmt: str, out: str, dot: str = "dot") -> None:
    """Render DOT text to ``out`` with graphviz's ``dot`` program, as rqt_graph users expect.

    Raises OrchestraError when graphviz is not installed or ``dot`` fails, naming what to do.
    """
    import shutil
    import subprocess

    from orchestra.errors import OrchestraError

    program = shutil.which(dot)
    if program is None:
        raise OrchestraError(f"{fmt.upper()} output needs graphviz's 'dot' program "
                             "(e.g. apt install graphviz); or use --out graph.svg / graph.dot")
    try:
        result = subprocess.run([program, f"-T{fmt}", "-o", out], input=dot_text.encode(),
                                capture_output=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise OrchestraError(f"graphviz 'dot' failed: {exc}") from None
    if result.returncode != 0:
        raise OrchestraError(f"graphviz 'dot' could not write {out}: "
                             f"{result.stderr.decode(errors='replace').strip()}")
