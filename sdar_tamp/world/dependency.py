"""The dependency graph of a rearrangement from object footprints (see :mod:`sdar_tamp.graph`)."""

from __future__ import annotations

import numpy as np

from sdar_tamp.graph import DependencyGraph, Structure, strongly_connected_components
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.transforms import FloatArray

__all__ = [
    "DependencyGraph",
    "Structure",
    "dependency_graph",
    "instance_dependency_graph",
    "strongly_connected_components",
]


def dependency_graph(
    names: tuple[str, ...], current: FloatArray, goal: FloatArray, sizes: FloatArray
) -> DependencyGraph:
    """Graph for current poses ``(n, 3)``, goal poses ``(n, 3)`` and footprints ``(n, 2)``."""
    over = overlap_matrix(corners(goal, sizes), corners(current, sizes))
    np.fill_diagonal(over, False)
    edges = tuple((int(i), int(j)) for i, j in np.argwhere(over))
    return DependencyGraph(tuple(names), edges)


def instance_dependency_graph(instance: Instance) -> DependencyGraph:
    """The graph of an instance at its start arrangement."""
    return dependency_graph(
        instance.names, instance.start_poses(), instance.goal_poses(), instance.sizes()[:, :2]
    )
