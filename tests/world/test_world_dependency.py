from __future__ import annotations

import itertools

import numpy as np
import pytest

from sdar_tamp.world.dependency import (
    dependency_graph,
    instance_dependency_graph,
    strongly_connected_components,
)
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import parse_instance

S = np.array([[0.08, 0.04]])


def _overlap(p: tuple[float, float, float], q: tuple[float, float, float]) -> bool:
    return bool(overlap_matrix(corners(np.array([p]), S), corners(np.array([q]), S))[0, 0])


def test_overlap_cases() -> None:
    assert _overlap((0, 0, 0), (0.079, 0, 0))
    assert not _overlap((0, 0, 0), (0.08, 0, 0))  # touching edges
    assert not _overlap((0, 0, 0), (0.08, 0.04, 0))  # touching corners
    assert _overlap((0, 0, 0), (0, 0, np.pi / 2))
    # a diamond whose corner just misses / just enters the rectangle's right edge
    r = 0.02 * np.sqrt(2)  # half-diagonal of a 0.04 x 0.04 square
    sq = np.array([[0.04, 0.04]])
    rect = corners(np.array([[0, 0, 0]]), S)
    for dx, expect in ((0.04 + r + 1e-6, False), (0.04 + r - 1e-4, True)):
        diamond = corners(np.array([[dx, 0.0, np.pi / 4]]), sq)
        assert overlap_matrix(rect, diamond)[0, 0] == expect


def _monte_carlo(p: np.ndarray, q: np.ndarray, rng: np.random.Generator) -> float:
    """Fraction of samples of p's rectangle inside q's rectangle."""
    u = rng.uniform(-0.5, 0.5, (4000, 2)) * S[0]
    c, s = np.cos(p[2]), np.sin(p[2])
    pts = u @ np.array([[c, s], [-s, c]]) + p[:2]
    c, s = np.cos(q[2]), np.sin(q[2])
    local = (pts - q[:2]) @ np.array([[c, -s], [s, c]])
    return float(np.mean(np.all(np.abs(local) < S[0] / 2, axis=1)))


def test_overlap_agrees_with_sampling() -> None:
    rng = np.random.default_rng(0)
    a = np.column_stack([rng.uniform(-0.1, 0.1, (60, 2)), rng.uniform(-np.pi, np.pi, 60)])
    b = np.column_stack([rng.uniform(-0.1, 0.1, (60, 2)), rng.uniform(-np.pi, np.pi, 60)])
    m = overlap_matrix(corners(a, np.tile(S, (60, 1))), corners(b, np.tile(S, (60, 1))))
    for i in range(60):
        frac = _monte_carlo(a[i], b[i], rng)
        if frac > 0.0:
            assert m[i, i]  # a sample strictly inside both: they overlap
        if not m[i, i]:
            assert frac == 0.0


def test_overlap_agrees_with_shapely() -> None:
    shapely = pytest.importorskip("shapely.geometry")
    rng = np.random.default_rng(1)
    poses = np.column_stack([rng.uniform(-0.1, 0.1, (80, 2)), rng.uniform(-np.pi, np.pi, 80)])
    rect = corners(poses, np.tile(S, (80, 1)))
    m = overlap_matrix(rect, rect)
    polys = [shapely.Polygon(r) for r in rect]
    for i, j in itertools.combinations(range(80), 2):
        assert m[i, j] == (polys[i].intersection(polys[j]).area > 1e-12)


def test_edge_direction_goal_of_i_on_start_of_j() -> None:
    # a's goal lies on b's start: a cannot be placed until b moves -> edge a -> b
    text = """name: T
workspace: {x: [-0.25, 0.25], y: [-0.3, 0.3]}
objects:
  - {name: a, size: [0.08, 0.04, 0.05], start: [-0.1, 0, 0], goal: [0.1, 0, 0]}
  - {name: b, size: [0.08, 0.04, 0.05], start: [0.1, 0, 0], goal: [0, 0.2, 0]}
  - {name: c, size: [0.08, 0.04, 0.05], start: [0, -0.2, 0], goal: [0, -0.15, 0]}
"""
    g = instance_dependency_graph(parse_instance(text))
    assert g.named_edges() == (("a", "b"),)  # c overlapping its own start is no edge
    s = g.structure()
    assert s.chains == (("b", "a"),)  # b is moved first
    assert s.independent == ("c",) and s.cycles == ()


def test_cycle_chain_and_independent() -> None:
    # 0 -> 1 -> 2 -> 0 cycle, 3 -> 4 chain, 5 independent, 6 -> 0 hangs off the cycle
    names = tuple(f"o{i}" for i in range(7))
    start = np.array([[x, 0.0, 0.0] for x in np.arange(7) * 0.1])
    goal = start.copy()
    goal[0], goal[1], goal[2], goal[3] = start[1], start[2], start[0], start[4]
    goal[4] = [0.2, 0.2, 0.0]
    goal[6] = [0.0, 0.0, 0.3]
    goal[5] = [0.5, 0.3, 0.0]
    g = dependency_graph(names, start, goal, np.tile(S, (7, 1)))
    assert set(g.named_edges()) == {
        ("o0", "o1"),
        ("o1", "o2"),
        ("o2", "o0"),
        ("o3", "o4"),
        ("o6", "o0"),
    }
    s = g.structure()
    assert s.cycles == (("o0", "o1", "o2"),)
    assert s.chains == (("o4", "o3"),)
    assert s.independent == ("o5", "o6")
    assert g.is_simple_cycle(g.cycle_components()[0])


def _reachable(n: int, edges: list[tuple[int, int]]) -> np.ndarray:
    r = np.eye(n, dtype=bool)
    for i, j in edges:
        r[i, j] = True
    for k in range(n):
        r |= r[:, [k]] & r[[k], :]
    return r


def test_tarjan_matches_transitive_closure() -> None:
    rng = np.random.default_rng(2)
    for _ in range(40):
        n = int(rng.integers(1, 25))
        edges = [
            (int(i), int(j))
            for i, j in rng.integers(0, n, (int(rng.integers(0, 3 * n)), 2))
            if i != j
        ]
        comps = strongly_connected_components(n, tuple(edges))
        r = _reachable(n, edges)
        mutual = r & r.T
        label = {v: k for k, c in enumerate(comps) for v in c}
        assert sorted(label) == list(range(n))
        for i in range(n):
            for j in range(n):
                assert (label[i] == label[j]) == mutual[i, j]


def test_tarjan_handles_a_long_cycle_without_recursion() -> None:
    n = 5000
    edges = tuple((i, (i + 1) % n) for i in range(n))
    assert [len(c) for c in strongly_connected_components(n, edges)] == [n]
