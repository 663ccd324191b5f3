"""Shared helpers of the classical-planner tests: load the teaching domains."""

from __future__ import annotations

from pathlib import Path

from sdar_tamp.language import parse_domain, parse_problem
from solvers.classical import PlanningTask, task_from_problem

DOMAINS = Path(__file__).resolve().parents[2] / "domains"


def load(domain: str, problem: str, **options: bool) -> PlanningTask:
    """The task of ``domains/<domain>/problems/<problem>.pddl``."""
    folder = DOMAINS / domain
    parsed_domain = parse_domain((folder / "domain.pddl").read_text(), "domain.pddl")
    parsed = parse_problem((folder / "problems" / f"{problem}.pddl").read_text(), parsed_domain)
    return task_from_problem(parsed_domain, parsed, **options)


def load_text(domain: str, problem_text: str, **options: bool) -> PlanningTask:
    """The task of a problem given as text, for a teaching domain."""
    parsed_domain = parse_domain((DOMAINS / domain / "domain.pddl").read_text(), "domain.pddl")
    return task_from_problem(parsed_domain, parse_problem(problem_text, parsed_domain), **options)
