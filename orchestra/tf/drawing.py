"""Pictures of a transform tree for ``view_frames``: Graphviz DOT text and a self-drawn SVG.

roslaunch's view_frames needs the graphviz binary to make its PDF; here the DOT file is
still written (for anyone who has graphviz) and the SVG is laid out by a small tidy-tree rule
(leaves on consecutive slots, each parent centred over its children, one row per depth), so
the picture needs nothing but a browser.
"""
from __future__ import annotations

from collections.abc import Mapping
from html import escape

BOX_W, BOX_H, GAP_X, GAP_Y, MARGIN = 150, 40, 30, 70, 20


def roots_and_children(parents: Mapping[str, str]) -> tuple[list[str], dict[str, list[str]]]:
    """Tree roots (frames that are nobody's child) and each frame's sorted children."""
    children: dict[str, list[str]] = {}
    frames = set(parents) | set(parents.values())
    for child, parent in parents.items():
        children.setdefault(parent, []).append(child)
    for kids in children.values():
        kids.sort()
    roots = sorted(f for f in frames if f not in parents)
    return roots, children


def layout(parents: Mapping[str, str]) -> dict[str, tuple[float, int]]:
    """frame -> (slot x, depth); a cycle (impossible in a tf tree) is simply not drawn."""
    roots, children = roots_and_children(parents)
    pos: dict[str, tuple[float, int]] = {}
    next_slot = [0.0]

    def place(frame: str, depth: int) -> float:
        kids = [k for k in children.get(frame, []) if k not in pos]
        pos[frame] = (0.0, depth)  # mark visited before recursing
        if not kids:
            x = next_slot[0]
            next_slot[0] += 1.0
        else:
            xs = [place(k, depth + 1) for k in kids]
            x = (xs[0] + xs[-1]) / 2.0
        pos[frame] = (x, depth)
        return x

    for root in roots:
        place(root, 0)
    return pos


def _label(child: str, info: Mapping[str, dict]) -> str:
    edge = info.get(child)
    if not edge:
        return ""
    if edge.get("static"):
        return "static"
    span = edge["newest"] - edge["oldest"]
    rate = (edge["samples"] - 1) / span if span > 0 else 0.0
    return f"{rate:.1f} Hz"


def tree_dot(parents: Mapping[str, str], info: Mapping[str, dict] | None = None) -> str:
    """Graphviz text of the tree, edges labelled with their average rate (or 'static')."""
    info = info or {}
    lines = ["digraph G {", '  node [shape=box, style="rounded"];']
    for child, parent in sorted(parents.items()):
        label = _label(child, info)
        lines.append(f'  "{parent}" -> "{child}" [label="{label}"];')
    lines.append("}")
    return "\n".join(lines) + "\n"


def tree_svg(parents: Mapping[str, str], info: Mapping[str, dict] | None = None,
             title: str = "tf frames") -> str:
    """An SVG drawing of the tree: rounded boxes, parent above child, edge rate labels."""
    info = info or {}
    pos = layout(parents)
    slots = max((x for x, _ in pos.values()), default=0.0) + 1.0
    depth = max((d for _, d in pos.values()), default=0) + 1
    width = int(2 * MARGIN + slots * BOX_W + (slots - 1) * GAP_X)
    height = int(2 * MARGIN + 30 + depth * BOX_H + (depth - 1) * GAP_Y)

    def box(frame: str) -> tuple[float, float]:
        x, d = pos[frame]
        return MARGIN + x * (BOX_W + GAP_X), MARGIN + 30 + d * (BOX_H + GAP_Y)

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'font-family="sans-serif" font-size="13">',
           f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{MARGIN}" y="{MARGIN + 12}" font-weight="bold">{escape(title)}</text>']
    for child, parent in sorted(parents.items()):
        if child not in pos or parent not in pos:
            continue
        (px, py), (cx, cy) = box(parent), box(child)
        x1, y1, x2, y2 = px + BOX_W / 2, py + BOX_H, cx + BOX_W / 2, cy
        out.append(f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" '
                   'stroke="#555" stroke-width="1.5"/>')
        label = _label(child, info)
        if label:
            out.append(f'<text x="{(x1 + x2) / 2 + 4:.1f}" y="{(y1 + y2) / 2:.1f}" '
                       f'fill="#555" font-size="11">{escape(label)}</text>')
    for frame in sorted(pos):
        x, y = box(frame)
        out.append(f'<rect x="{x:.1f}" y="{y:.1f}" width="{BOX_W}" height="{BOX_H}" rx="8" '
                   'fill="#e8f0ff" stroke="#3060c0" stroke-width="1.5"/>')
        out.append(f'<text x="{x + BOX_W / 2:.1f}" y="{y + BOX_H / 2 + 4:.1f}" '
                   f'text-anchor="middle">{escape(frame)}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"
