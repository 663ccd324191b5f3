"""Smallest sets of objects to send to buffers so that a dependency graph can be resolved.

Two problems share one exact search:

* **feedback vertex set** (``allow_swaps=False``): remove vertices until no directed cycle is
  left. With free buffer space a single arm needs exactly ``n + |minimum FVS|`` pick-and-places:
  the objects never buffered go start -> goal once, in an order that needs their induced graph
  to be acyclic.
* **buffer set for synchronous dual arms** (``allow_swaps=True``): remove vertices until every
  strongly connected component has at most two objects. A 2-cycle ``i <-> j`` is resolved by a
  dual-arm swap, and objects resolved in one synchronous step form at most a pair, so
  ``n + |minimum buffer set|`` is the fewest actions of two synchronous arms.
* **buffer set for k synchronous arms** (``arms=k``): remove vertices until every strongly
  connected component has at most ``k`` objects: ``k`` arms lift every object of such a
  component at once and place each at its goal (a rotation, which generalises the swap).
  ``arms=1`` is the feedback vertex set, ``arms=2`` the dual-arm buffer set.

Search: iterative deepening on the set size. A vertex set is split into its bad components
(more than ``k`` objects), solved one by one; inside a component it branches on the vertices of
a small obstruction, one of which every solution contains: for ``k <= 2`` a shortest cycle (of
length >= 3 with swaps; when all cycles are 2-cycles, a path ``a <-> b <-> c``); for ``k >= 3`` a
strongly connected set of more than ``k`` objects grown from a shortest cycle by shortest ears
(a path out of the set and back). A packing of disjoint obstructions bounds from below; failed
(set, size) pairs are memoised. ``node_budget`` caps the search nodes; past it the component
falls back to a greedy set and ``exact`` is ``False``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph, strongly_connected_components


@dataclass(frozen=True)
class FeedbackSet:
    """Objects to buffer (by name); ``exact`` is ``False`` when the greedy fallback was used."""

    members: frozenset[str]
    exact: bool


class _OutOfBudget(Exception):
    pass


def _largest(allow_swaps: bool, arms: int | None) -> int:
    """The largest component a solution may leave: ``arms``, else 2 with swaps, else 1."""
    if arms is None:
        return 2 if allow_swaps else 1
    if arms < 1:
        raise ParameterError(f"arms must be None or >= 1, got {arms}")
    return arms


class _Search:
    def __init__(self, graph: DependencyGraph, largest: int, budget: int | None) -> None:
        self.succ: list[set[int]] = [set() for _ in range(graph.n)]
        for i, j in graph.edges:
            if i != j:
                self.succ[i].add(j)
        self.min_size = largest + 1
        self.budget = budget
        self.nodes = 0
        self.lower: dict[frozenset[int], int] = {}
        self.best: dict[frozenset[int], frozenset[int]] = {}
        self.bounds: dict[frozenset[int], int] = {}

    def bad_components(self, vs: frozenset[int]) -> list[frozenset[int]]:
        order = sorted(vs)
        local = {v: k for k, v in enumerate(order)}
        edges = tuple((local[v], local[w]) for v in order for w in self.succ[v] if w in vs)
        comps = strongly_connected_components(len(order), edges)
        return [frozenset(order[k] for k in c) for c in comps if len(c) >= self.min_size]

    def optimum(self, comp: frozenset[int]) -> frozenset[int]:
        """A minimum solution for one component (deepening from the lower bound)."""
        if comp in self.best:
            return self.best[comp]
        k = max(self.lower.get(comp, 0), self.bound(comp))
        while (found := self.solve(comp, k)) is None:
            k += 1
        self.best[comp] = found
        return found

    def solve(self, vs: frozenset[int], k: int) -> frozenset[int] | None:
        """A solution of at most ``k`` vertices for the graph induced on ``vs``, or None."""
        self.nodes += 1
        if self.budget is not None and self.nodes > self.budget:
            raise _OutOfBudget
        if vs in self.best:
            return self.best[vs] if len(self.best[vs]) <= k else None
        if self.lower.get(vs, 0) > k:
            return None
        comps = self.bad_components(vs)
        found: frozenset[int] | None = frozenset()
        if len(comps) > 1:
            bounds = [self.bound(c) for c in comps]
            used: set[int] = set()
            for idx, comp in enumerate(comps):
                allowance = k - len(used) - sum(bounds[idx + 1 :])
                part = None
                for size in range(bounds[idx], allowance + 1):
                    if (part := self.solve(comp, size)) is not None:
                        break
                if part is None:
                    found = None
                    break
                used |= part
            found = frozenset(used) if found is not None else None
        elif comps:
            comp = comps[0]
            found = None
            if k > 0 and self.bound(comp) <= k:
                for w in self.obstruction(comp):
                    if (rest := self.solve(comp - {w}, k - 1)) is not None:
                        found = rest | {w}
                        break
        if found is None:
            self.lower[vs] = max(self.lower.get(vs, 0), k + 1)
        return found

    def bound(self, comp: frozenset[int]) -> int:
        """Vertex-disjoint obstructions packed greedily: a lower bound on any solution."""
        if comp not in self.bounds:
            rest, count = comp, 0
            while comps := self.bad_components(rest):
                rest = rest - frozenset(self.obstruction(comps[0]))
                count += 1
            self.bounds[comp] = count
        return self.bounds[comp]

    def obstruction(self, comp: frozenset[int]) -> list[int]:
        """Vertices of which every solution holds one, most connected first."""
        if self.min_size > 3:
            return self.grown(comp)
        cycle = self.short_cycle(comp)
        if cycle is None:  # swaps allowed and only 2-cycles: a path a <-> b <-> c
            b = min(comp, key=lambda v: (-len(self.succ[v] & comp), v))
            a, c = sorted(self.succ[b] & comp)[:2]
            cycle = [b, a, c]
        return sorted(cycle, key=lambda v: (-len(self.succ[v] & comp), v))

    def grown(self, comp: frozenset[int]) -> list[int]:
        """A strongly connected set of at least ``min_size`` vertices of ``comp`` (a bad
        component): a shortest cycle, then shortest ears (out of the set and back) until it
        is large enough. A solution that kept all of it would keep a component too large."""
        found: list[int] | None = None
        for v in sorted(comp):
            for u in sorted(self.succ[v] & comp):
                path = self.path(u, v, comp, None)
                if path is not None and (found is None or len(path) < len(found)):
                    found = [v, *path[:-1]]
        assert found is not None  # a bad component holds a cycle
        members = set(found)
        while len(members) < self.min_size:
            best: list[int] | None = None
            for v in sorted(members):
                for w in sorted((self.succ[v] & comp) - members):
                    back = self._path_to(w, members, comp)
                    if back is not None and (best is None or len(back) < len(best)):
                        best = back
            assert best is not None  # comp is strongly connected and larger than members
            members |= set(best)
        return sorted(members, key=lambda v: (-len(self.succ[v] & comp), v))

    def _path_to(self, src: int, targets: set[int], comp: frozenset[int]) -> list[int] | None:
        """The vertices of a shortest path from ``src`` into ``targets`` (before entering)."""
        parent = {src: src}
        queue = deque([src])
        while queue:
            v = queue.popleft()
            for w in sorted(self.succ[v] & comp):
                if w in targets:
                    out = [v]
                    while out[-1] != src:
                        out.append(parent[out[-1]])
                    return out
                if w not in parent:
                    parent[w] = v
                    queue.append(w)
        return None

    def short_cycle(self, comp: frozenset[int]) -> list[int] | None:
        best: list[int] | None = None
        for v in sorted(comp):
            for u in sorted(self.succ[v] & comp):
                skip = v if self.min_size == 3 else None
                path = self.path(u, v, comp, skip)
                if path is not None and (best is None or len(path) < len(best)):
                    best = [v, *path[:-1]]
                    if len(best) == self.min_size:
                        return best
        return best

    def path(self, src: int, dst: int, comp: frozenset[int], skip: int | None) -> list[int] | None:
        """Shortest path src -> dst inside comp (not using the edge src -> skip)."""
        parent = {src: src}
        queue = deque([src])
        while queue:
            v = queue.popleft()
            for w in sorted(self.succ[v] & comp):
                if w in parent or (v == src and w == skip):
                    continue
                parent[w] = v
                if w == dst:
                    out = [w]
                    while out[-1] != src:
                        out.append(parent[out[-1]])
                    return out[::-1]
                queue.append(w)
        return None

    def greedy(self, comp: frozenset[int]) -> frozenset[int]:
        """Remove the vertex of largest in x out degree until no bad component is left."""
        chosen: list[int] = []
        rest = comp
        while comps := self.bad_components(rest):
            c = comps[0]
            pred = {v: sum(1 for w in c if v in self.succ[w]) for v in c}
            v = min(c, key=lambda x: (-pred[x] * len(self.succ[x] & c), x))
            chosen.append(v)
            rest = rest - {v}
        for v in reversed(chosen):  # drop the ones that turned out unnecessary
            if not self.bad_components(rest | {v}):
                rest = rest | {v}
        return comp - rest


def feedback_vertex_set(
    graph: DependencyGraph,
    *,
    allow_swaps: bool = False,
    node_budget: int | None = None,
    arms: int | None = None,
) -> FeedbackSet:
    """A minimum FVS (or buffer set with ``allow_swaps``, or for ``arms`` arms); greedy per
    component past the budget."""
    if node_budget is not None and node_budget < 1:
        raise ParameterError(f"node_budget must be None or >= 1, got {node_budget}")
    search = _Search(graph, _largest(allow_swaps, arms), node_budget)
    members: set[int] = set()
    exact = True
    for comp in search.bad_components(frozenset(range(graph.n))):
        search.nodes = 0
        try:
            members |= search.optimum(comp)
        except _OutOfBudget:
            members |= search.greedy(comp)
            exact = False
    return FeedbackSet(frozenset(graph.names[v] for v in members), exact)


def minimum_feedback_vertex_set(graph: DependencyGraph) -> frozenset[str]:
    """The exact minimum feedback vertex set (ties broken deterministically)."""
    return feedback_vertex_set(graph).members


def minimum_buffer_set(graph: DependencyGraph, arms: int = 2) -> frozenset[str]:
    """The fewest objects to buffer when cycles of up to ``arms`` objects are rotated by that
    many synchronous arms (two: 2-cycles swapped)."""
    return feedback_vertex_set(graph, arms=arms).members


def breaks_cycles(
    graph: DependencyGraph, members: frozenset[str], allow_swaps: bool, arms: int | None = None
) -> bool:
    """Removing ``members`` leaves no cycle (no component above two objects with swaps, above
    ``arms`` objects when given)."""
    search = _Search(graph, _largest(allow_swaps, arms), None)
    keep = frozenset(i for i, name in enumerate(graph.names) if name not in members)
    return not search.bad_components(keep)


def optimal_choices(
    graph: DependencyGraph,
    *,
    allow_swaps: bool,
    node_budget: int | None = None,
    arms: int | None = None,
) -> frozenset[str] | None:
    """The objects that belong to some minimum set; ``None`` when the budget ran out.

    Buffering any of them first keeps the total optimal: the rest of the graph then needs one
    object fewer. ``arms`` replaces ``allow_swaps`` (see the module docstring).
    """
    search = _Search(graph, _largest(allow_swaps, arms), node_budget)
    good: set[int] = set()
    try:
        for comp in search.bad_components(frozenset(range(graph.n))):
            k = len(search.optimum(comp))
            good |= {v for v in comp if search.solve(comp - {v}, k - 1) is not None}
    except _OutOfBudget:
        return None
    return frozenset(graph.names[v] for v in good)


def extending_minimum(
    graph: DependencyGraph,
    options: list[frozenset[str]],
    *,
    allow_swaps: bool,
    node_budget: int | None = None,
    arms: int | None = None,
) -> list[frozenset[str]] | None:
    """The ``options`` that some minimum set contains; ``None`` when the budget ran out."""
    search = _Search(graph, _largest(allow_swaps, arms), node_budget)
    everything = frozenset(range(graph.n))
    out: list[frozenset[str]] = []
    try:
        k = sum(len(search.optimum(c)) for c in search.bad_components(everything))
        for chosen in options:
            rest = frozenset(i for i in everything if graph.names[i] not in chosen)
            if k >= len(chosen) and search.solve(rest, k - len(chosen)) is not None:
                out.append(chosen)
    except _OutOfBudget:
        return None
    return out
