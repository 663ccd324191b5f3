"""One search loop, one policy per algorithm, chosen once from the options; the solve's
counters reach users as the ``Solution.statistics`` mapping of the statistics record."""

from __future__ import annotations

from dataclasses import fields

import pytest

from domains.dual_arm_swap.samplers import make_problem
from solvers.solve import solve
from solvers.stream_planning.options import StreamOptions
from solvers.stream_planning.policies import (
    ALGORITHMS,
    AdaptivePolicy,
    BindingPolicy,
    FocusedPolicy,
    IncrementalPolicy,
)
from solvers.stream_planning.solver import StreamSolver
from solvers.stream_planning.statistics import SearchStatistics

EXPECTED = {
    "incremental": IncrementalPolicy,
    "focused": FocusedPolicy,
    "binding": BindingPolicy,
    "adaptive": AdaptivePolicy,
}


def test_the_algorithms_are_the_policies() -> None:
    assert ALGORITHMS == ("incremental", "focused", "binding", "adaptive")


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_the_options_choose_the_policy(algorithm: str) -> None:
    solver = StreamSolver(make_problem(seed=0), StreamOptions(algorithm=algorithm))
    assert type(solver.policy) is EXPECTED[algorithm]
    assert solver.policy.lazy is (algorithm == "incremental")
    solver.context.runner.close()


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_statistics_are_the_record_as_a_mapping(algorithm: str) -> None:
    solution = solve(make_problem(seed=0), algorithm=algorithm, seed=0, verbose=False)
    assert solution.solved
    assert list(solution.statistics) == [f.name for f in fields(SearchStatistics)]
    counts = ("iterations", "skeletons", "complexity", "facts")
    assert all(type(solution.statistics[name]) is int for name in counts)
    assert solution.statistics["iterations"] >= 1
    assert solution.statistics["time"] >= solution.statistics["search_time"] > 0
