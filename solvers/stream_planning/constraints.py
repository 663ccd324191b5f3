"""``PlanConstraints`` skeletons compiled into the planning problem.

A skeleton is a list of ``(action name, args)``; each argument is a Python value (the action's
parameter must be that object), ``WILD`` (anything) or a string ``"?x"`` (a skeleton variable:
every occurrence in the skeleton is the same object). The problem is rewritten so that every
plan follows one of the skeletons:

* skeleton ``i`` step ``k`` becomes an action copy ``name@i.k`` that needs the stage fact
  ``(@sk<i>-<k>)`` and moves it to ``(@sk<i>-<k+1>)``;
* a fixed argument needs the static fact ``(@sk<i>-<k>-<j> obj)``; the first occurrence of a
  variable adds ``(@sk<i>-var-<x> obj)``, later occurrences need it;
* the goal also needs the final stage of some skeleton. With ``exact=True`` (the default) only
  the copies remain, so the plan is exactly a skeleton; with ``exact=False`` the domain's own
  actions stay and may come between the skeleton's steps.

Solutions name the original actions (:func:`original_name`). ``max_cost`` is applied by the
solver: plans above it are not returned.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_model import ActionSchema, Predicate
from sdar_tamp.language.formula_model import And, AndEffect, Atom, Literal, Or, Parameter
from sdar_tamp.language.options import WILD, PlanConstraints
from sdar_tamp.language.problem import PDDLProblem

MARK = "@"


def original_name(name: str) -> str:
    """The domain action behind a skeleton copy (``move@0.2`` -> ``move``)."""
    return name.split(MARK, 1)[0]


def compile_constraints(problem: PDDLProblem, constraints: PlanConstraints) -> PDDLProblem:
    """A copy of ``problem`` whose plans follow one of the skeletons (module docstring)."""
    skeletons = constraints.skeletons
    if not skeletons:
        return problem
    domain = problem.domain
    predicates = dict(domain.predicates)
    actions: list[ActionSchema] = [] if constraints.exact else list(domain.actions)
    init = set(problem.facts.init)
    finals: list[Atom] = []
    for i, skeleton in enumerate(skeletons):
        stage = [Atom(f"{MARK}sk{i}-{k}") for k in range(len(skeleton) + 1)]
        for atom in stage:
            predicates[atom.predicate] = Predicate(atom.predicate)
        init.add(stage[0])
        bound: set[str] = set()
        for k, step in enumerate(skeleton):
            schema, args = _step(domain.action, step, i, k)
            pre: list[Any] = [schema.precondition, stage[k]]
            eff: list[Any] = [schema.effect, Literal(stage[k], True), Literal(stage[k + 1])]
            for j, (parameter, value) in enumerate(zip(schema.parameters, args, strict=True)):
                if value is WILD:
                    continue
                if isinstance(value, str) and value.startswith("?"):
                    fact = f"{MARK}sk{i}-var-{value[1:]}"
                    predicates[fact] = Predicate(fact, (Parameter("?v"),))
                    if value in bound:
                        pre.append(Atom(fact, (parameter.name,)))
                    else:
                        bound.add(value)
                        eff.append(Literal(Atom(fact, (parameter.name,))))
                    continue
                fact = f"{MARK}sk{i}-{k}-{j}"
                predicates[fact] = Predicate(fact, (Parameter("?v"),))
                pre.append(Atom(fact, (parameter.name,)))
                init.add(Atom(fact, (problem.objects.name(value),)))
            # replace() keeps the schema's numeric conditions and effects (fuel, costs by
            # expression): a copy is the same action plus the stage bookkeeping
            actions.append(
                dataclasses.replace(
                    schema,
                    name=f"{schema.name}{MARK}{i}.{k}",
                    precondition=And(tuple(pre)),
                    effect=AndEffect(tuple(eff)),
                )
            )
        finals.append(stage[-1])
    final = finals[0] if len(finals) == 1 else Or(tuple(finals))
    compiled = dataclasses.replace(domain, predicates=predicates, actions=tuple(actions))
    facts = dataclasses.replace(
        problem.facts, init=frozenset(init), goal=And((problem.facts.goal, final))
    )
    copy = _shallow_copy(problem)
    copy.domain = compiled
    copy.facts = facts
    return copy


def _step(lookup: Any, step: Sequence[Any], i: int, k: int) -> tuple[ActionSchema, Sequence[Any]]:
    where = f"constraints.skeletons[{i}][{k}]"
    if not isinstance(step, Sequence) or isinstance(step, str) or len(step) != 2:
        raise ParameterError(f"{where}: expected (action name, args), got {step!r}")
    name, args = step
    try:
        schema: ActionSchema = lookup(str(name))
    except KeyError:
        raise ParameterError(f"{where}: unknown action {name!r}") from None
    if isinstance(args, str) or len(args) != len(schema.parameters):
        raise ParameterError(
            f"{where}: action {schema.name!r} takes {len(schema.parameters)} argument(s), "
            f"got {args!r}"
        )
    return schema, args


def _shallow_copy(problem: PDDLProblem) -> PDDLProblem:
    copy = object.__new__(PDDLProblem)
    copy.__dict__.update(problem.__dict__)
    return copy
