"""Dependency graphs of rearrangements, without geometry (paper, sections III-B and IV-A).

Edge direction: ``i -> j`` iff the goal footprint of ``i`` overlaps the *current* footprint of
``j`` (``i != j``): object ``i`` cannot be placed at its goal until ``j`` has moved away.
Hence objects with no outgoing edge can be moved to their goals right away.

Classification (:meth:`DependencyGraph.structure`):

* **cycles**: strongly connected components with two or more objects (Tarjan, iterative);
* **chains**: among the objects in no cycle, the weakly connected groups of two or more
  (a directed path in the simplest case; resolved leaf first);
* **independent**: the objects in no cycle with no edge to or from another acyclic object.

Edges between a cycle and an acyclic object are kept in ``edges`` but do not join them.
This module imports nothing of the project: planners build graphs from any overlap test
(:mod:`sdar_tamp.world.dependency` builds them from footprints).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Structure:
    """The decomposition of a dependency graph, by object names."""

    independent: tuple[str, ...]
    chains: tuple[tuple[str, ...], ...]
    cycles: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class DependencyGraph:
    """Objects ``names`` and directed edges ``(i, j)`` by index: i's goal blocked by j."""

    names: tuple[str, ...]
    edges: tuple[tuple[int, int], ...]

    @property
    def n(self) -> int:
        return len(self.names)

    def successors(self, i: int) -> tuple[int, ...]:
        return tuple(j for a, j in self.edges if a == i)

    def predecessors(self, j: int) -> tuple[int, ...]:
        return tuple(i for i, b in self.edges if b == j)

    def named_edges(self) -> tuple[tuple[str, str], ...]:
        return tuple((self.names[i], self.names[j]) for i, j in self.edges)

    def components(self) -> list[list[int]]:
        """Strongly connected components, each in discovery order (Tarjan, no recursion)."""
        return strongly_connected_components(self.n, self.edges)

    def cycle_components(self) -> list[list[int]]:
        """The components with two or more objects."""
        return [c for c in self.components() if len(c) >= 2]

    def is_simple_cycle(self, component: list[int]) -> bool:
        """True if the component's internal edges form one directed cycle through all of it."""
        members = set(component)
        inner = [(i, j) for i, j in self.edges if i in members and j in members]
        outs = {i for i, _ in inner}
        return len(inner) == len(component) and outs == members

    def structure(self) -> Structure:
        cycles = self.cycle_components()
        in_cycle = {i for c in cycles for i in c}
        acyclic = [i for i in range(self.n) if i not in in_cycle]
        parent = {i: i for i in acyclic}

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for i, j in self.edges:
            if i in parent and j in parent:
                parent[find(i)] = find(j)
        groups: dict[int, list[int]] = {}
        for i in acyclic:
            groups.setdefault(find(i), []).append(i)
        chains = [g for g in groups.values() if len(g) >= 2]
        independent = [g[0] for g in groups.values() if len(g) == 1]
        return Structure(
            independent=tuple(self.names[i] for i in sorted(independent)),
            chains=tuple(tuple(self.names[i] for i in self._order(g)) for g in chains),
            cycles=tuple(tuple(self.names[i] for i in self._cycle_order(c)) for c in cycles),
        )

    def _order(self, group: list[int]) -> list[int]:
        """Acyclic group in removal order: an object comes after those blocking its goal."""
        members = set(group)
        out_deg = {i: sum(1 for a, b in self.edges if a == i and b in members) for i in group}
        order: list[int] = []
        ready = sorted(i for i in group if out_deg[i] == 0)
        while ready:
            j = ready.pop(0)
            order.append(j)
            for i in sorted(self.predecessors(j)):
                if i in members:
                    out_deg[i] -= 1
                    if out_deg[i] == 0:
                        ready.append(i)
        return order

    def _cycle_order(self, component: list[int]) -> list[int]:
        """Follow edges from the smallest index while they stay new (the whole simple cycle)."""
        members = set(component)
        order = [min(component)]
        while True:
            nxt = [j for j in self.successors(order[-1]) if j in members and j not in order]
            if not nxt:
                break
            order.append(min(nxt))
        return order + sorted(members - set(order))


def strongly_connected_components(n: int, edges: tuple[tuple[int, int], ...]) -> list[list[int]]:
    """Tarjan's algorithm with an explicit stack; components in reverse topological order."""
    succ: list[list[int]] = [[] for _ in range(n)]
    for i, j in edges:
        succ[i].append(j)
    index = [-1] * n
    low = [0] * n
    on_stack = [False] * n
    stack: list[int] = []
    out: list[list[int]] = []
    counter = 0
    for root in range(n):
        if index[root] >= 0:
            continue
        work = [(root, 0)]
        while work:
            v, k = work.pop()
            if k == 0:
                index[v] = low[v] = counter
                counter += 1
                stack.append(v)
                on_stack[v] = True
            if k < len(succ[v]):
                w = succ[v][k]
                work.append((v, k + 1))
                if index[w] < 0:
                    work.append((w, 0))
                elif on_stack[w]:
                    low[v] = min(low[v], index[w])
                continue
            if low[v] == index[v]:
                comp: list[int] = []
                while True:
                    w = stack.pop()
                    on_stack[w] = False
                    comp.append(w)
                    if w == v:
                        break
                out.append(sorted(comp))
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[v])
    return out
