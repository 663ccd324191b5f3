"""The 2-D kitchen (``domains/kitchen_2d``): its samplers' geometry, and its variants solved by
every algorithm (the plan re-checked here: both cups end inside the shelf, apart)."""

from __future__ import annotations

import itertools
import math

import pytest
from stream_helpers import ALGORITHMS

from domains.kitchen_2d.samplers import CUP, Kitchen, make_problem, stream_info
from solvers.solution import Solution, Status
from solvers.solve import solve

SHELF = (0.5, 1.0, 1.5, 1.35)


def _final_poses(solution: Solution) -> dict[str, tuple[float, float]]:
    assert solution.plan is not None
    poses = {}
    for action in solution.plan:
        if action.name == "place":
            poses[action.args[0]] = action.args[1]
    return poses


def test_grid_sampler_is_finite_and_inside() -> None:
    kitchen = Kitchen({"shelf": SHELF}, "grid", seed=0)
    poses = [p for (p,) in kitchen.sample_pose("cup1", "shelf")]
    assert len(poses) == len(set(poses)) == 15 * 2  # 0.7 m x 0.05 m of centres, 5 cm apart
    assert all(0.65 - 1e-9 <= x <= 1.35 + 1e-9 and 1.15 - 1e-9 <= y <= 1.2 + 1e-9 for x, y in poses)


def test_random_sampler_is_endless_and_seeded() -> None:
    first = Kitchen({"shelf": SHELF}, "random", seed=4).sample_pose("cup1", "shelf")
    second = Kitchen({"shelf": SHELF}, "random", seed=4).sample_pose("cup1", "shelf")
    drawn = [next(first) for _ in range(100)]
    assert drawn == [next(second) for _ in range(100)] and len(set(drawn)) == 100


def test_a_region_too_small_yields_nothing() -> None:
    kitchen = Kitchen({"slot": (0.0, 0.0, 0.2, 0.35)}, "grid", seed=0)
    assert list(kitchen.sample_pose("cup1", "slot")) == []


def test_unknown_sampler_is_refused() -> None:
    with pytest.raises(ValueError, match="sampler must be one of"):
        Kitchen({}, "sobol", seed=0)


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize(("sampler", "negate"), [("grid", False), ("random", True)])
def test_feasible_variants_are_solved(algorithm: str, sampler: str, negate: bool) -> None:
    solution = solve(
        make_problem(1.0, sampler, seed=1),
        algorithm=algorithm,
        stream_info=stream_info(negate),
        max_time=60,
        seed=1,
        verbose=False,
    )
    assert solution.status is Status.SOLVED, solution.diagnosis
    poses = _final_poses(solution)
    assert set(poses) == {"cup1", "cup2"}
    (x1, y1), (x2, y2) = poses.values()
    assert math.dist((x1, y1), (x2, y2)) >= CUP - 1e-9
    for x, y in poses.values():
        assert SHELF[0] + CUP / 2 - 1e-9 <= x <= SHELF[2] - CUP / 2 + 1e-9
        assert SHELF[1] + CUP / 2 - 1e-9 <= y <= SHELF[3] - CUP / 2 + 1e-9


@pytest.mark.parametrize("algorithm", ["focused", "adaptive"])
def test_a_round_never_searches_the_same_facts_twice(
    algorithm: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """When no plan is found and the world with later calls' outputs adds no fact (they all lie
    above the level), that world is not searched again: the search would fail the same way."""
    from solvers.stream_planning.context import SolveContext

    searched: list[tuple[int, frozenset[object]]] = []
    original = SolveContext.plan

    def plan(self: SolveContext, facts, numeric, world=None):  # type: ignore[no-untyped-def]
        searched.append((self.stats.iterations, frozenset(facts)))
        return original(self, facts, numeric, world)

    monkeypatch.setattr(SolveContext, "plan", plan)
    solution = solve(
        make_problem(1.0, "grid", 0),
        algorithm=algorithm,
        stream_info=stream_info(False),
        max_time=60,
        seed=0,
        verbose=False,
    )
    assert solution.status is Status.SOLVED
    assert all(a != b for a, b in itertools.pairwise(searched))
