"""Samplers of the narrow-region domain, and :func:`make_problem`.

A block of width ``w`` [m] fits in a region ``(lo, hi)`` [m] at the centres ``x`` with
``lo + w/2 <= x <= hi - w/2``; ``sample-pose`` enumerates those centres on a grid of ``STEP``
[m] in a seeded random order, and stops. When the block is wider than the region it yields
nothing, so every instance is eventually exhausted and the solver can prove infeasibility.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem

HERE = Path(__file__).resolve().parent
STEP = 0.5  # [m]


class Grid:
    """Finite pose samplers over the regions of one problem."""

    def __init__(
        self, widths: Mapping[str, float], regions: Mapping[str, tuple[float, float]], seed: int
    ) -> None:
        self.widths = dict(widths)
        self.regions = dict(regions)
        self.rng = np.random.default_rng(seed)

    def sample_pose(self, b: str, r: str) -> Iterator[tuple[float]]:
        lo, hi = self.regions[r]
        half = self.widths[b] / 2
        count = int(np.floor((hi - lo - 2 * half) / STEP + 1e-9)) + 1
        centres = [round(lo + half + STEP * k, 3) for k in range(max(count, 0))]
        for index in self.rng.permutation(len(centres)):
            yield (centres[int(index)],)

    def cfree(self, b: str, p: float, b2: str, p2: float) -> bool:
        return b == b2 or abs(p - p2) >= (self.widths[b] + self.widths[b2]) / 2 - 1e-9


def make_problem(goal_width: float = 0.8, seed: int = 0) -> PDDLProblem:
    """Block A (1 m wide) must go into a goal region ``goal_width`` [m] wide.

    With the default 0.8 m the problem is infeasible; with ``goal_width >= 1`` it is solvable.
    """
    widths = {"A": 1.0, "B": 1.0}
    regions = {"table": (-3.0, 1.0), "goal": (2.0, 2.0 + goal_width)}
    grid = Grid(widths, regions, seed)
    init: list[tuple[object, ...]] = [("handempty",)]
    init += [("region", r) for r in regions]
    for block, x in (("A", -2.0), ("B", 0.0)):
        init += [("block", block), ("pose", x), ("blockpose", block, x), ("atpose", block, x)]
        init += [("contained", block, x, "table")]
    return PDDLProblem(
        (HERE / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (HERE / "stream.pddl").read_text(encoding="utf-8"),
        {"sample-pose": from_gen_fn(grid.sample_pose), "test-cfree": from_test(grid.cfree)},
        init,
        ("in", "A", "goal"),
    )
