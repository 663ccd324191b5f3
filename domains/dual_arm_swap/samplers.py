"""Samplers of the dual-arm swap, and :func:`make_problem`.

Poses are the ``x`` [m] of an object's centre on a table line; the left arm reaches
``x <= SHARED`` and the right arm ``x >= -SHARED``. Objects are ``WIDTH`` wide and must not
overlap. ``sample-buffer`` draws poses uniformly over the table (seeded), so some land in the
shared middle that both arms reach.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from sdar_tamp.language.formulas import And
from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem

HERE = Path(__file__).resolve().parent
TABLE = (-1.0, 1.0)  # [m]
SHARED = 0.2  # [m] half-width of the middle strip both arms reach
WIDTH = 0.3  # [m]


class Swap:
    """The samplers of one problem, drawing from one seeded generator."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def sample_buffer(self, o: str) -> Iterator[tuple[float]]:
        lo, hi = TABLE[0] + WIDTH / 2, TABLE[1] - WIDTH / 2
        while True:
            yield (round(float(self.rng.uniform(lo, hi)), 3),)

    @staticmethod
    def reach(arm: str, p: float) -> bool:
        return p <= SHARED if arm == "left" else p >= -SHARED

    @staticmethod
    def cfree(o: str, p: float, o2: str, p2: float) -> bool:
        return o == o2 or abs(p - p2) >= WIDTH - 1e-9


def make_problem(seed: int = 0) -> PDDLProblem:
    """``X`` starts at -0.6 (left only) and ``Y`` at 0.6 (right only); swap them."""
    swap = Swap(seed)
    start = {"X": -0.6, "Y": 0.6}
    goal = {"X": 0.6, "Y": -0.6}
    init: list[tuple[object, ...]] = [("arm", "left"), ("arm", "right")]
    init += [("empty", "left"), ("empty", "right")]
    for o in start:
        init += [("obj", o), ("atpose", o, start[o])]
        for p in (start[o], goal[o]):
            init += [("pose", p), ("objpose", o, p)]
    return PDDLProblem(
        (HERE / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (HERE / "stream.pddl").read_text(encoding="utf-8"),
        {
            "sample-buffer": from_gen_fn(swap.sample_buffer),
            "test-reach": from_test(swap.reach),
            "test-cfree": from_test(swap.cfree),
        },
        init,
        And(*(("atpose", o, p) for o, p in goal.items())),
    )
