"""What a plan means: :func:`run_plan` executes a whole plan from the lifted action schemas
(each step's precondition by :class:`~sdar_tamp.language.evaluator.Evaluator`, its effect by
:func:`~sdar_tamp.language.state_changes.effect_changes`) and evaluates the goal at the end;
:class:`PlanRun` is what it found."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from sdar_tamp.language.domain_model import ActionSchema, Domain
from sdar_tamp.language.evaluator import Evaluator, Support
from sdar_tamp.language.formula_model import OBJECT_TYPE, Atom, Formula
from sdar_tamp.language.state_changes import Changes, CostOf, effect_changes
from sdar_tamp.language.state_index import FactIndex, Facts, Objects
from sdar_tamp.language.substitution import bind


def check_arguments(action: ActionSchema, args: Sequence[str], objects: Objects) -> str | None:
    """Why ``args`` cannot instantiate ``action`` (arity, an unknown object, a wrong type);
    None when they can."""
    if len(args) != len(action.parameters):
        return f"({' '.join((action.name, *args))}) has the wrong number of arguments"
    for parameter, arg in zip(action.parameters, args, strict=True):
        if not objects.has_type(arg, OBJECT_TYPE):
            return f"unknown object {arg}"
        if not objects.has_type(arg, parameter.type):
            return f"{arg} is not of type {parameter.type}"
    return None


@dataclass(frozen=True)
class PlanRun:
    """The execution of a plan (:func:`run_plan`).

    ``states[k]`` is the state before step ``k``, ``supports[k]`` the facts step ``k``'s
    precondition and effect conditions relied on there, and ``changes[k]`` what it did (for
    the steps executed). ``failed_step`` is the step that could not be applied, ``-1`` when
    the goal does not hold at the end, None when the plan is valid; ``reason`` says why.
    """

    final_state: frozenset[Atom]
    states: tuple[frozenset[Atom], ...] = ()
    supports: tuple[Support, ...] = ()
    changes: tuple[Changes, ...] = ()
    goal_support: Support | None = None
    failed_step: int | None = None
    reason: str = ""

    @property
    def valid(self) -> bool:
        return self.failed_step is None

    @property
    def cost(self) -> float:
        """The sum of the executed steps' costs."""
        return sum(c.cost for c in self.changes)


def run_plan(
    domain: Domain,
    objects: Objects,
    init: Iterable[Atom],
    plan: Sequence[tuple[str, Sequence[str]]],
    goal: Formula,
    cost_of: CostOf | None = None,
    *,
    explain: bool = False,
    view: Callable[[frozenset[Atom]], Facts] = FactIndex,
) -> PlanRun:
    """Execute ``plan`` (``(action name, arguments)`` steps) from ``init`` and evaluate
    ``goal`` at the end. A step that names no action of ``domain``, has bad arguments or whose
    precondition does not hold ends the run (see :class:`PlanRun`).

    ``view`` makes what conditions are evaluated on from a state (by default its facts as they
    are; a solver may let it answer for atoms it assumes, which then appear in the supports).

    Raises:
        EvaluationError: a formula has a variable that nothing binds.
    """
    state = frozenset(init)
    states: list[frozenset[Atom]] = []
    supports: list[Support] = []
    changes: list[Changes] = []

    def stop(step: int, reason: str) -> PlanRun:
        return PlanRun(
            state, tuple(states), tuple(supports), tuple(changes), None, step, reason
        )  # fmt: skip

    for step, (name, args) in enumerate(plan):
        shown = f"({' '.join((name, *args))})"
        try:
            action = domain.action(name)
        except KeyError:
            return stop(step, f"unknown action {shown}")
        problem = check_arguments(action, args, objects)
        if problem is not None:
            return stop(step, problem)
        binding = bind(action, args)
        evaluator = Evaluator(domain, view(state), objects, explain=explain)
        found = evaluator.support(action.precondition, binding)
        if found is None:
            return stop(step, f"the precondition of {shown} does not hold")
        done = effect_changes(evaluator, action.effect, binding, cost_of)
        states.append(state)
        supports.append(found | done.support)
        changes.append(done)
        state = done.apply(state)
    evaluator = Evaluator(domain, view(state), objects, explain=explain)
    goal_support = evaluator.support(goal, {})
    if goal_support is None:
        return stop(-1, "the goal does not hold at the end of the plan")
    return PlanRun(state, tuple(states), tuple(supports), tuple(changes), goal_support)
