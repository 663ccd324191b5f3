"""What a plan means: :func:`run_plan` executes a whole plan from the lifted action schemas
(each step's precondition by :class:`~sdar_tamp.language.evaluator.Evaluator`, its effect by
:func:`~sdar_tamp.language.state_changes.effect_changes`) and evaluates the goal at the end;
:class:`PlanRun` is what it found.

A durative action's step is run from the durative action as written, not from its compiled
form (so the compilation is checked, not trusted): its at-start condition, its at-start
effects, then its over-all and at-end conditions in the state they make, then its at-end
effects; its cost is its duration plus any ``total-cost`` increases."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace

from sdar_tamp.errors import EvaluationError
from sdar_tamp.language.domain_model import ActionSchema, Domain
from sdar_tamp.language.durative import DurativeActionSchema
from sdar_tamp.language.evaluator import Evaluator, Support
from sdar_tamp.language.formula_model import (
    OBJECT_TYPE,
    TOTAL_COST,
    Atom,
    Formula,
    FunctionTerm,
)
from sdar_tamp.language.numeric import Comparison, evaluate, holds, rename_args
from sdar_tamp.language.state_changes import Changes, CostOf, effect_changes
from sdar_tamp.language.state_index import FactIndex, Facts, Objects
from sdar_tamp.language.substitution import Binding, bind, ground_args


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
    With ``cost_of`` (the initial values of function terms), numeric conditions are checked
    and numeric effects change the values later steps read; without it they are not.

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

    numeric = _NumericState(cost_of)
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
        failed = numeric.failed_condition(action, binding)
        if failed is not None:
            return stop(step, f"the numeric condition {failed} of {shown} does not hold")
        step_cost_of = numeric.cost_of
        evaluator = Evaluator(domain, view(state), objects, explain=explain)
        durative = domain.durative_action(name)
        if durative is not None:
            staged = _run_durative(durative, evaluator, binding, step_cost_of, view, state)
            if isinstance(staged, str):
                return stop(step, f"the {staged} condition of {shown} does not hold")
            found, done = staged
        else:
            support = evaluator.support(action.precondition, binding)
            if support is None:
                return stop(step, f"the precondition of {shown} does not hold")
            found = support
            done = effect_changes(evaluator, action.effect, binding, step_cost_of)
        extra = numeric.apply(action, binding, durative is not None)
        if extra is None:
            return stop(step, f"a numeric effect of {shown} is undefined")
        if extra:
            done = replace(done, cost=done.cost + extra)
        states.append(state)
        supports.append(found | done.support)
        changes.append(done)
        state = done.apply(state)
    evaluator = Evaluator(domain, view(state), objects, explain=explain)
    goal_support = evaluator.support(goal, {})
    if goal_support is None:
        return stop(-1, "the goal does not hold at the end of the plan")
    return PlanRun(state, tuple(states), tuple(supports), tuple(changes), goal_support)


class _NumericState:
    """The values of numeric fluents along a run: the initial ones from ``cost_of``, then as
    the steps' numeric effects change them (nothing is checked without ``cost_of``)."""

    def __init__(self, initial: CostOf | None) -> None:
        self._initial = initial
        self._changed: dict[tuple[str, tuple[str, ...]], float] = {}
        self.cost_of: CostOf | None = None if initial is None else self._value

    def _lookup(self, term: FunctionTerm) -> float | None:
        key = (term.name, term.args)
        if key in self._changed:
            return self._changed[key]
        if self._initial is None:
            return None
        try:
            return self._initial(term)
        except (KeyError, EvaluationError):
            return None

    def _value(self, term: FunctionTerm) -> float:
        value = self._lookup(term)
        if value is None:
            raise EvaluationError(f"no value for ({' '.join((term.name, *term.args))})")
        return value

    def failed_condition(self, action: ActionSchema, binding: Binding) -> str | None:
        """The first numeric condition of ``action`` that does not hold, shown; or None."""
        if self._initial is None:
            return None
        for condition in action.numeric_conditions:
            ground = Comparison(
                condition.operator,
                rename_args(condition.left, binding),
                rename_args(condition.right, binding),
            )
            if not holds(ground, self._lookup):
                return f"'{condition.operator}' at {condition.location}"
        return None

    def apply(self, action: ActionSchema, binding: Binding, durative: bool) -> float | None:
        """Apply ``action``'s numeric effects; returns the cost they add (an expression
        increasing ``total-cost``; a durative action's duration is counted apart), or None
        when a new value is undefined."""
        if self._initial is None:
            return 0.0
        cost = 0.0
        updates: dict[tuple[str, tuple[str, ...]], float] = {}
        for effect in action.numeric_effects:
            value = evaluate(
                rename_args(
                    effect.as_assignment() if effect.target.name != TOTAL_COST else effect.value,
                    binding,
                ),
                self._lookup,
            )
            if value is None:
                return None
            if effect.target.name == TOTAL_COST:
                cost += 0.0 if durative else value
            else:
                target = effect.target
                updates[(target.name, ground_args(target.args, binding))] = value
        self._changed.update(updates)
        return cost


def _run_durative(
    action: DurativeActionSchema,
    evaluator: Evaluator,
    binding: Binding,
    cost_of: CostOf | None,
    view: Callable[[frozenset[Atom]], Facts],
    state: frozenset[Atom],
) -> tuple[Support, Changes] | str:
    """``action`` run alone from ``state``: what its conditions relied on in ``state`` and
    what it did, or which condition failed (``at-start``, ``over-all``, ``at-end``)."""
    found = evaluator.support(action.at_start, binding)
    if found is None:
        return "at-start"
    start = effect_changes(evaluator, action.start_effect, binding, cost_of)
    middle = start.apply(state)
    later = Evaluator(evaluator.domain, view(middle), evaluator.objects, explain=evaluator.explain)
    over = later.support(action.over_all, binding)
    if over is None:
        return "over-all"
    end_found = later.support(action.at_end, binding)
    if end_found is None:
        return "at-end"
    end = effect_changes(later, action.end_effect, binding, cost_of)
    final = end.apply(middle)
    length = 0.0
    if cost_of is not None:
        value = evaluate(rename_args(action.duration, binding), cost_of)
        if value is None:
            raise EvaluationError(f"the duration of {action.name!r} is undefined")
        length = value
    # facts the start effects made are the action's own, not something it relies on
    relied = found | start.support | ((over | end_found | end.support) - start.adds)
    changes = Changes(
        final - state, state - final, start.cost + end.cost + length, frozenset(relied)
    )
    return relied, changes


def plan_timing(
    domain: Domain, plan: Sequence[tuple[str, Sequence[str]]], cost_of: CostOf
) -> tuple[tuple[float, float], ...]:
    """The ``(start, duration)`` of each step of ``plan`` run one after the other from time 0:
    a durative action lasts its duration (an expression, evaluated when the step starts:
    ``cost_of`` gives a function term's initial value, numeric effects of earlier steps change
    it), an instantaneous action 0.

    Raises:
        EvaluationError: a step names no action of ``domain``, has the wrong arity or an
            undefined duration.
    """
    timing: list[tuple[float, float]] = []
    now = 0.0
    changed: dict[tuple[str, tuple[str, ...]], float] = {}

    def lookup(term: FunctionTerm) -> float | None:
        key = (term.name, term.args)
        return changed[key] if key in changed else cost_of(term)

    for name, args in plan:
        action = domain.durative_action(name)
        length = 0.0
        if action is not None:
            if len(args) != len(action.parameters):
                raise EvaluationError(f"({' '.join((name, *args))}) has the wrong arity")
            binding = dict(zip((p.name for p in action.parameters), args, strict=True))
            value = evaluate(rename_args(action.duration, binding), lookup)
            if value is None:
                raise EvaluationError(f"the duration of ({' '.join((name, *args))}) is undefined")
            length = value
        _apply_numeric(domain, name, args, lookup, changed)
        timing.append((now, length))
        now += length
    return tuple(timing)


def _apply_numeric(
    domain: Domain,
    name: str,
    args: Sequence[str],
    lookup: Callable[[FunctionTerm], float | None],
    changed: dict[tuple[str, tuple[str, ...]], float],
) -> None:
    """Record the numeric fluents that step ``(name args)`` changes."""
    try:
        schema = domain.action(name)
    except KeyError:
        return
    binding = dict(zip((p.name for p in schema.parameters), args, strict=False))
    updates = {}
    for effect in schema.numeric_effects:
        if effect.target.name == TOTAL_COST:
            continue
        value = evaluate(rename_args(effect.as_assignment(), binding), lookup)
        if value is not None:
            target = effect.target
            updates[(target.name, ground_args(target.args, binding))] = value
    changed.update(updates)
