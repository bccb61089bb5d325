"""orchestra's imports form no cycle: not between modules, not between subpackages.

Data flows one way (file -> entities -> interpreter -> plan -> app -> master + processes), so
a lower layer never imports an upper one. A cycle is how that rule erodes, and a
function-level import hides one from the reader and from `python -c "import x"`; so the
graph here is read from the source (every ``import`` statement, at any depth) rather than
from what importing happens to load. Imports under ``if TYPE_CHECKING:`` are left out: they
never run, they only name types for the checker.

Every module counts in its subpackage, the command modules (``<subpackage>/cli.py``...)
included: a command that needs a layer above its subject is composed in app/ (see
docs/architecture.md). The layering itself is checked by the import-linter contract in
pyproject.toml.
"""
from __future__ import annotations

import ast
import functools
from pathlib import Path

import networkx as nx

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "orchestra"


def _modules() -> dict[str, Path]:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(ROOT).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _runtime_nodes(tree: ast.AST):
    """Every node of ``tree`` except those under ``if TYPE_CHECKING:``."""
    for child in ast.iter_child_nodes(tree):
        if isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test):
            for other in child.orelse:
                yield other
                yield from _runtime_nodes(other)
            continue
        yield child
        yield from _runtime_nodes(child)


@functools.cache
def import_graph() -> nx.DiGraph:
    """Module -> imported module, for every import statement of orchestra's own modules
    (``from a import b`` is an edge to ``a.b`` when that is a module, else to ``a``)."""
    modules = _modules()

    def owner(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph = nx.DiGraph()
    for name, path in modules.items():
        graph.add_node(name)
        is_package = path.name == "__init__.py"
        for node in _runtime_nodes(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    here = name if is_package else name.rpartition(".")[0]
                    for _ in range(node.level - 1):
                        here = here.rpartition(".")[0]
                    base = f"{here}.{base}" if base else here
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                           for a in node.names]
            else:
                continue
            for target in targets:
                found = owner(target) if target.startswith("orchestra") else None
                if found is not None and found != name:
                    graph.add_edge(name, found)
    return graph


def subpackage(module: str) -> str:
    """The subpackage a module belongs to (a top-level module is its own)."""
    return ".".join(module.split(".")[:2])


def _cycles(graph: nx.DiGraph) -> list[list[str]]:
    return sorted(sorted(c) for c in nx.strongly_connected_components(graph) if len(c) > 1)


def _explain(graph: nx.DiGraph, cycle: list[str], detail: nx.DiGraph | None = None) -> str:
    members = set(cycle)
    edges = [(a, b) for a, b in graph.edges if a in members and b in members]
    if detail is not None:
        edges = [(a, b) for a, b in detail.edges
                 if subpackage(a) in members and subpackage(b) in members
                 and subpackage(a) != subpackage(b)]
    return "\n".join(f"  {a} -> {b}" for a, b in sorted(edges))


def test_the_graph_sees_function_level_imports():
    graph = import_graph()
    # orchestra/launch/check.py imports the package index inside a method
    assert graph.has_edge("orchestra.launch.check", "orchestra.packages")
    assert len(graph) > 100


def test_no_module_imports_itself_back_through_others():
    graph = import_graph()
    cycles = _cycles(graph)
    assert cycles == [], "\n".join(_explain(graph, c) for c in cycles)


def test_no_subpackage_imports_itself_back_through_others():
    modules = import_graph()
    graph = nx.DiGraph()
    graph.add_nodes_from({subpackage(m) for m in modules})
    for a, b in modules.edges:
        if subpackage(a) != subpackage(b):
            graph.add_edge(subpackage(a), subpackage(b))
    cycles = _cycles(graph)
    assert cycles == [], "\n".join(_explain(graph, c, modules) for c in cycles)


def test_the_bottom_modules_import_nothing_above_them():
    graph = import_graph()
    bottom = {"orchestra.names", "orchestra.errors", "orchestra.rpc", "orchestra.rosdirs",
              "orchestra.expression", "orchestra.xmlrpc_codec"}
    for module in bottom:
        assert set(graph.successors(module)) <= bottom, module
