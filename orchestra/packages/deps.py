"""The package dependency graph (``orchestra pkg deps``, rospack depends/depends1).

Only packages reachable from the one asked about are parsed, so asking about a leaf package on
a 2,000-package path reads one manifest. Names that no package on the path answers to are
kept as leaf nodes marked missing: they are usually system dependencies (rosdep keys such as
``boost``), which rospack would look up with rosdep — orchestra reports them instead.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx

from orchestra.errors import OrchestraError
from orchestra.packages.index import PackageIndex, get_index
from orchestra.packages.manifest import KINDS, Manifest, parse_manifest

#: what rospack follows by default: everything needed to build and run, not tests or docs
DEFAULT_KINDS = ("buildtool", "buildtool_export", "build", "build_export", "exec")


@dataclass
class DependencyGraph:
    """Edges point from a package to what it depends on."""

    graph: nx.DiGraph = field(default_factory=nx.DiGraph)
    manifests: dict[str, Manifest] = field(default_factory=dict)

    @property
    def missing(self) -> list[str]:
        return sorted(n for n in self.graph if n not in self.manifests)

    def direct(self, name: str) -> list[str]:
        return sorted(self.graph.successors(name))

    def transitive(self, name: str) -> list[str]:
        """All dependencies of ``name``, each after everything it depends on (build order)."""
        reachable = nx.descendants(self.graph, name)
        sub = self.graph.subgraph(reachable | {name})
        try:
            order = list(nx.lexicographical_topological_sort(sub.reverse(copy=True)))
            return [n for n in order if n != name]
        except nx.NetworkXUnfeasible:
            cycle = nx.find_cycle(sub)
            chain = " -> ".join([edge[0] for edge in cycle] + [cycle[0][0]])
            raise OrchestraError(f"dependency cycle: {chain}") from None

    def dependents(self, name: str) -> list[str]:
        """Packages that depend on ``name``, directly or not (rospack depends-on)."""
        return sorted(nx.ancestors(self.graph, name))


def build_graph(roots: list[str], kinds: tuple[str, ...] = DEFAULT_KINDS,
                index: PackageIndex | None = None) -> DependencyGraph:
    """Parse ``roots`` and everything they reach through ``kinds`` dependencies."""
    unknown = set(kinds) - set(KINDS)
    if unknown:
        raise OrchestraError(f"unknown dependency kind(s): {', '.join(sorted(unknown))} "
                             f"(known: {', '.join(KINDS)})")
    index = get_index() if index is None else index
    result = DependencyGraph()
    todo = list(roots)
    for name in roots:
        index.find(name)  # PackageNotFound for the packages asked about
    while todo:
        name = todo.pop()
        if name in result.graph and (name in result.manifests or name not in index):
            continue
        result.graph.add_node(name)
        if name not in index:
            continue
        manifest = parse_manifest(index.find(name))
        result.manifests[name] = manifest
        for dep in manifest.depends(kinds):
            result.graph.add_edge(name, dep)
            if dep not in result.manifests:
                todo.append(dep)
    return result


def all_packages_graph(kinds: tuple[str, ...] = DEFAULT_KINDS,
                       index: PackageIndex | None = None) -> DependencyGraph:
    """The graph of every package on the path (for ``depends-on`` questions)."""
    index = get_index() if index is None else index
    return build_graph(index.names(), kinds, index)
