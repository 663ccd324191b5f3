"""Every teaching domain problem parses, grounds, and is solved by the default planner."""

from __future__ import annotations

import pytest
from classical_helpers import DOMAINS, load

from solvers.classical import PlanStatus, plan

PROBLEMS = sorted(
    (folder.name, problem.stem)
    for folder in DOMAINS.iterdir()
    if folder.name in {"blocksworld", "logistics", "briefcase", "delivery_costs"}
    for problem in (folder / "problems").glob("*.pddl")
)


def test_each_teaching_domain_has_problems() -> None:
    assert {d for d, _ in PROBLEMS} == {"blocksworld", "logistics", "briefcase", "delivery_costs"}
    for domain in {d for d, _ in PROBLEMS}:
        assert (DOMAINS / domain / "__init__.py").exists()


@pytest.mark.parametrize(("domain", "problem"), PROBLEMS)
@pytest.mark.parametrize("lazy", [False, True])
def test_teaching_problem_is_solved(domain: str, problem: str, lazy: bool) -> None:
    result = plan(load(domain, problem), lazy=lazy, time_limit=20.0)
    assert result.status is PlanStatus.SOLVED
    assert result.plan
