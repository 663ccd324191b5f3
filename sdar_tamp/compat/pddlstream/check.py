"""Re-check a solution by simulation, independently of the solver that found it.

The plan is run, with the classical validator (:func:`solvers.classical.validated_plan_cost`),
from the problem's initial facts plus every fact the solution's certificate says the streams
certified; every precondition must hold on the way and the goal at the end. Costs are not
re-checked (the values of cost functions are not part of the certificate).
"""

from __future__ import annotations

from dataclasses import replace

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import OBJECT_TYPE, AndEffect, Atom, Effect, IncreaseCost
from sdar_tamp.language.problem import PDDLProblem
from solvers.classical import (
    GroundAction,
    PlanningTask,
    PlanValidationError,
    validated_plan_cost,
)
from solvers.solution import Solution


def _without_costs(effect: Effect) -> Effect:
    if isinstance(effect, AndEffect):
        return AndEffect(
            tuple(_without_costs(p) for p in effect.parts if not isinstance(p, IncreaseCost))
        )
    return AndEffect(()) if isinstance(effect, IncreaseCost) else effect


def _cost_free(domain: Domain) -> Domain:
    actions = tuple(replace(a, effect=_without_costs(a.effect)) for a in domain.actions)
    durative = tuple(
        replace(
            a,
            duration=0.0,
            start_effect=_without_costs(a.start_effect),
            end_effect=_without_costs(a.end_effect),
        )
        for a in domain.durative_actions
    )
    return replace(domain, actions=actions, durative_actions=durative)


def check_solution(problem: PDDLProblem, solution: Solution) -> str | None:
    """None when ``solution.plan`` reaches the goal of ``problem`` from its initial facts and
    the certified facts; otherwise why not (also when there is no plan)."""
    if solution.plan is None:
        return "no plan"
    table = problem.objects.copy()

    def atom(fact: tuple[object, ...]) -> Atom:
        return Atom(str(fact[0]).lower(), tuple(table.name(v) for v in fact[1:]))

    facts = set(problem.facts.init)
    facts.update(atom(f) for f in solution.certificate.all_facts)
    facts.update(atom(f) for f in solution.certificate.preimage_facts)
    steps = [
        GroundAction(a.name.lower(), tuple(table.name(v) for v in a.args)) for a in solution.plan
    ]
    objects = {name: OBJECT_TYPE for name in table.names()}
    objects.update(problem.facts.objects)
    task = PlanningTask(
        domain=_cost_free(problem.domain),
        objects=objects,
        init=frozenset(f for f in facts if not f.predicate.startswith("@")),
        goal=problem.facts.goal,
        use_costs=False,
    )
    try:
        validated_plan_cost(task, steps)
    except PlanValidationError as error:
        return str(error)
    return None
