"""``pddlstream.algorithms.satisfaction``: constraint satisfaction over streams.

A :class:`SatisfactionProblem` asks for values of the free parameters (``?x1`` ...) of a list
of terms (facts over parameters and values, and ``('minimize', (function, ...))`` costs) such
that every fact is certified by the streams. It is solved as a planning problem with one
action whose parameters are the free parameters, whose precondition is the facts and whose
cost is the sum of the minimised functions; the plan's arguments are the assignment.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, NamedTuple

from sdar_tamp.compat.pddlstream.language.constants import MINIMIZE, is_parameter
from sdar_tamp.compat.pddlstream.language.problem import PDDLProblem
from sdar_tamp.compat.pddlstream.utils import str_from_object
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.sexpr import SList, Symbol, read_sexpr
from solvers.solution import Certificate, Solution

__all__ = [
    "SatisfactionProblem",
    "SatisfactionSolution",
    "constraint_satisfaction",
    "dump_assignment",
    "pddl_from_csp",
]

ACTION = "satisfy-terms"
GOAL = "csp-satisfied"
_CONNECTIVES = {"and", "or", "not", "imply", "=", "exists", "forall"}


class SatisfactionProblem(NamedTuple):
    stream_pddl: Any
    stream_map: Mapping[str, Callable[..., Any]] | str
    init: Sequence[Sequence[Any]]
    terms: Sequence[Sequence[Any]]


class SatisfactionSolution(NamedTuple):
    """``bindings`` maps each parameter to its value (None without a solution)."""

    bindings: dict[str, Any] | None
    cost: float
    facts: Certificate


def _atoms(node: Any, found: dict[str, int]) -> None:
    if not isinstance(node, SList) or not node.items:
        return
    head = node.items[0]
    if isinstance(head, Symbol) and not head.text.startswith(":"):
        if head.text in _CONNECTIVES:
            for item in node.items[1:]:
                _atoms(item, found)
            return
        found.setdefault(head.text, len(node.items) - 1)
        return
    for item in node.items:
        _atoms(item, found)


def _declared(stream_texts: Iterable[str]) -> tuple[dict[str, int], dict[str, int]]:
    """``(predicates, functions)`` with their arities, read from stream files."""
    predicates: dict[str, int] = {}
    functions: dict[str, int] = {}
    for text in stream_texts:
        root = read_sexpr(text, "stream.pddl")
        for section in root.items:
            if not isinstance(section, SList) or not section.items:
                continue
            keyword = section.items[0]
            if isinstance(keyword, Symbol) and keyword.text == ":function":
                head = section.items[1]
                if isinstance(head, SList) and isinstance(head.items[0], Symbol):
                    functions[head.items[0].text] = len(head.items) - 1
                for item in section.items[2:]:
                    _atoms(item, predicates)
            else:
                _atoms(section, predicates)
    return predicates, functions


def pddl_from_csp(
    stream_pddl: Any,
    stream_map: Mapping[str, Callable[..., Any]] | str,
    init: Sequence[Sequence[Any]],
    terms: Sequence[Sequence[Any]],
) -> tuple[PDDLProblem, tuple[str, ...]]:
    """The planning problem of a satisfaction problem, and its parameters in action order."""
    texts = [stream_pddl] if isinstance(stream_pddl, str) else list(stream_pddl or [])
    predicates, functions = _declared(texts)
    constants: dict[str, Any] = {}
    names: dict[int, str] = {}

    def term(value: Any) -> str:
        if is_parameter(value):
            return str(value).lower()
        key = id(value)
        if key not in names:
            names[key] = f"csp-value{len(names)}"
            constants[names[key]] = value
        return names[key]

    conditions: list[str] = []
    costs: list[str] = []
    parameters: dict[str, None] = {}
    for fact in terms:
        if not fact:
            raise ParameterError("a satisfaction term must be a non-empty tuple")
        if str(fact[0]).lower() == MINIMIZE:
            head = fact[1]
            name = str(head[0]).lower()
            functions.setdefault(name, len(head) - 1)
            args = [term(a) for a in head[1:]]
            costs.append(f"(increase (total-cost) ({' '.join((name, *args))}))")
            parameters.update((a, None) for a in args if a.startswith("?"))
            continue
        name = str(fact[0]).lower()
        predicates.setdefault(name, len(fact) - 1)
        args = [term(a) for a in fact[1:]]
        conditions.append(f"({' '.join((name, *args))})")
        parameters.update((a, None) for a in args if a.startswith("?"))
    for fact in init:
        predicates.setdefault(str(fact[0]).lower(), len(fact) - 1)

    def declare(name: str, arity: int) -> str:
        return f"({' '.join((name, *(f'?a{i}' for i in range(arity))))})"

    effect = " ".join([f"({GOAL})", *costs])
    domain = (
        "(define (domain satisfaction) (:requirements :strips :equality :action-costs)\n"
        + (f"  (:constants {' '.join(constants)})\n" if constants else "")
        + f"  (:predicates {' '.join(declare(n, a) for n, a in predicates.items())} ({GOAL}))\n"
        + "  (:functions (total-cost)"
        + "".join(f" {declare(n, a)}" for n, a in functions.items())
        + ")\n"
        + f"  (:action {ACTION} :parameters ({' '.join(parameters)})\n"
        + f"    :precondition (and {' '.join(conditions)})\n"
        + f"    :effect (and {effect})))"
    )
    problem = PDDLProblem(domain, constants, stream_pddl, stream_map, list(init), (GOAL,))
    return problem, tuple(parameters)


def bindings_from_solution(parameters: Sequence[str], solution: Solution) -> dict[str, Any] | None:
    if solution.plan is None:
        return None
    for action in solution.plan:
        if action.name == ACTION:
            return dict(zip(parameters, action.args, strict=True))
    return None


def constraint_satisfaction(
    problem: SatisfactionProblem | Sequence[Any],
    stream_info: Mapping[str, Any] | None = None,
    costs: bool = True,
    max_cost: float = math.inf,
    success_cost: float = math.inf,
    max_time: float = math.inf,
    unit_efforts: bool = False,
    max_effort: float = math.inf,
    max_skeletons: float = math.inf,
    search_sample_ratio: float = 1,
    verbose: bool = True,
    **search_args: Any,
) -> SatisfactionSolution:
    """Values for the free parameters of ``problem.terms`` (see module docstring), found with
    the adaptive algorithm; ``costs=False`` ignores the minimised functions."""
    from sdar_tamp.compat.pddlstream.algorithms.meta import solve

    stream_pddl, stream_map, init, terms = problem
    if not costs:
        terms = [t for t in terms if str(t[0]).lower() != MINIMIZE]
    planning, parameters = pddl_from_csp(stream_pddl, stream_map, init, terms)
    solution = solve(
        planning,
        algorithm="adaptive",
        stream_info=stream_info,
        unit_costs=False,
        success_cost=success_cost,
        max_cost=max_cost,
        max_time=max_time,
        unit_efforts=unit_efforts,
        max_effort=max_effort,
        max_skeletons=max_skeletons,
        search_sample_ratio=search_sample_ratio,
        verbose=verbose,
        **search_args,
    )
    bindings = bindings_from_solution(parameters, solution)
    return SatisfactionSolution(bindings, solution.cost, solution.certificate)


def dump_assignment(solution: SatisfactionSolution | Sequence[Any]) -> None:
    """Print whether it is solved, its cost, fact counts and the assignment."""
    bindings, cost, facts = solution
    all_facts = getattr(facts, "all_facts", facts)
    print()
    print(f"Solved: {bindings is not None}")
    print(f"Cost: {cost:.3f}")
    print(f"Total facts: {len(all_facts)}")
    print(f"Fact counts: {str_from_object(Counter(str(f[0]) for f in all_facts))}")
    if bindings is None:
        return
    print("Assignments:")
    for parameter in sorted(bindings):
        print(f"{parameter} = {str_from_object(bindings[parameter])}")
