"""Plan validation by independent simulation.

Actions are simulated from the *lifted* schemas: each step's precondition formula is evaluated on
a set of atoms (quantifiers range over the typed objects), effects (conditional and universal)
are evaluated in the state before the step, deletes are applied before adds, and costs are looked
up from the task's numeric values. Derived predicates are recomputed after every step from the
ground axioms (a plain stratified fixpoint over atoms). Finally the goal formula is evaluated.
Nothing here shares code with the search's bitset machinery.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from sdar_tamp.language.model import (
    EQUALITY,
    OBJECT_TYPE,
    And,
    AndEffect,
    Atom,
    Effect,
    Exists,
    ForAll,
    ForAllEffect,
    Formula,
    FunctionTerm,
    Imply,
    IncreaseCost,
    Literal,
    Not,
    Or,
    Parameter,
    When,
)
from solvers.classical.errors import PlanValidationError
from solvers.classical.problem import GroundAction, PlanningTask
from solvers.classical.task import GroundTask


class _Simulator:
    def __init__(self, task: PlanningTask, ground_task: GroundTask) -> None:
        self.task = task
        self.ground_task = ground_task
        self.derived = task.domain.derived_predicates | {
            ground_task.facts[i].predicate for i in ground_task.derived
        }
        self.objects: dict[str, list[str]] = {}
        for obj, obj_type in task.objects.items():
            for ancestor in task.domain.types.ancestors(obj_type):
                self.objects.setdefault(ancestor, []).append(obj)
        facts = ground_task.facts
        self._index: tuple[set[Atom], dict[str, list[tuple[str, ...]]]] | None = None
        self.axioms = [
            (
                a.stratum,
                facts[a.head],
                [facts[f] for f in a.body],
                [facts[f] for f in a.negative_body],
            )
            for a in sorted(ground_task.axioms, key=lambda a: a.stratum)
        ]

    def of_type(self, type_name: str) -> list[str]:
        return self.objects.get(type_name, [])

    def initial(self) -> set[Atom]:
        state = {atom for atom in self.task.init if atom.predicate not in self.derived}
        for type_name, objects in self.objects.items():
            state.update(Atom(type_name, (obj,)) for obj in objects)
        return self.close(state)

    def close(self, state: set[Atom]) -> set[Atom]:
        state = {atom for atom in state if atom.predicate not in self.derived}
        strata = sorted({stratum for stratum, *_ in self.axioms})
        for stratum in strata:
            layer = [a for a in self.axioms if a[0] == stratum]
            changed = True
            while changed:
                changed = False
                for _, head, body, negative in layer:
                    if head in state:
                        continue
                    if all(f in state for f in body) and not any(f in state for f in negative):
                        state.add(head)
                        changed = True
        return state

    def holds(self, formula: Formula, state: set[Atom], binding: Mapping[str, str]) -> bool:
        if isinstance(formula, Atom):
            args = tuple(binding.get(a, a) for a in formula.args)
            if formula.predicate == EQUALITY:
                return len(set(args)) <= 1
            return Atom(formula.predicate, args) in state
        if isinstance(formula, Not):
            return not self.holds(formula.formula, state, binding)
        if isinstance(formula, And):
            return all(self.holds(p, state, binding) for p in formula.parts)
        if isinstance(formula, Or):
            return any(self.holds(p, state, binding) for p in formula.parts)
        if isinstance(formula, Imply):
            return not self.holds(formula.antecedent, state, binding) or self.holds(
                formula.consequent, state, binding
            )
        if isinstance(formula, Exists):
            # a witness satisfies the body's positive atoms: take candidates from the state
            hints = self._candidates(formula.parameters, formula.body, state)
            combos = self.bindings(formula.parameters, binding, hints)
            return any(self.holds(formula.body, state, b) for b in combos)
        assert isinstance(formula, ForAll)
        combos = self.bindings(formula.parameters, binding)
        return all(self.holds(formula.body, state, b) for b in combos)

    def _candidates(
        self, parameters: Sequence[Parameter], body: Formula, state: set[Atom]
    ) -> dict[str, set[str]]:
        """For parameters that a positive conjunct of ``body`` names: the values that conjunct
        allows in ``state`` (a superset of every witness's value)."""
        if self._index is None or self._index[0] is not state:
            index: dict[str, list[tuple[str, ...]]] = {}
            for atom in state:
                index.setdefault(atom.predicate, []).append(atom.args)
            self._index = (state, index)
        index = self._index[1]
        parts = body.parts if isinstance(body, And) else (body,)
        found: dict[str, set[str]] = {}
        for part in parts:
            if not isinstance(part, Atom) or part.predicate == EQUALITY:
                continue
            for parameter in parameters:
                if parameter.name in part.args and parameter.name not in found:
                    position = part.args.index(parameter.name)
                    found[parameter.name] = {a[position] for a in index.get(part.predicate, ())}
        return found

    def bindings(
        self,
        parameters: Sequence[Parameter],
        binding: Mapping[str, str],
        candidates: Mapping[str, set[str]] | None = None,
    ) -> list[dict[str, str]]:
        result = [dict(binding)]
        for parameter in parameters:
            values = self.of_type(parameter.type)
            if candidates is not None and parameter.name in candidates:
                allowed = candidates[parameter.name]
                values = [o for o in values if o in allowed]
            result = [{**b, parameter.name: o} for b in result for o in values]
        return result

    def effects(
        self,
        effect: Effect,
        state: set[Atom],
        binding: Mapping[str, str],
        adds: set[Atom],
        deletes: set[Atom],
    ) -> float:
        if isinstance(effect, Literal):
            atom = Atom(effect.atom.predicate, tuple(binding.get(a, a) for a in effect.atom.args))
            (deletes if effect.negated else adds).add(atom)
            return 0.0
        if isinstance(effect, AndEffect):
            return sum(self.effects(p, state, binding, adds, deletes) for p in effect.parts)
        if isinstance(effect, ForAllEffect):
            return sum(
                self.effects(effect.effect, state, b, adds, deletes)
                for b in self.bindings(effect.parameters, binding)
            )
        if isinstance(effect, When):
            if self.holds(effect.condition, state, binding):
                return self.effects(effect.effect, state, binding, adds, deletes)
            return 0.0
        assert isinstance(effect, IncreaseCost)
        amount = effect.amount
        if isinstance(amount, FunctionTerm):
            key = (amount.name, tuple(binding.get(a, a) for a in amount.args))
            if key not in self.task.numeric_init:
                raise PlanValidationError(f"no value for cost term {key}")
            return float(self.task.numeric_init[key])
        return float(amount)


def validate_plan(
    task: PlanningTask, ground_task: GroundTask, plan: Sequence[GroundAction]
) -> float:
    """The cost of ``plan`` if it solves ``task``; otherwise :class:`PlanValidationError`."""
    sim = _Simulator(task, ground_task)
    state = sim.initial()
    total = 0.0
    for step, action in enumerate(plan, start=1):
        try:
            schema = task.domain.action(action.name)
        except KeyError:
            raise PlanValidationError(f"step {step}: unknown action {action}") from None
        if len(schema.parameters) != len(action.args):
            raise PlanValidationError(f"step {step}: {action} has the wrong number of arguments")
        for parameter, arg in zip(schema.parameters, action.args, strict=True):
            if arg not in sim.of_type(parameter.type) and parameter.type != OBJECT_TYPE:
                raise PlanValidationError(f"step {step}: {arg} is not of type {parameter.type}")
            if arg not in task.objects:
                raise PlanValidationError(f"step {step}: unknown object {arg}")
        binding = {p.name: a for p, a in zip(schema.parameters, action.args, strict=True)}
        if not sim.holds(schema.precondition, state, binding):
            raise PlanValidationError(f"step {step}: precondition of {action} does not hold")
        adds: set[Atom] = set()
        deletes: set[Atom] = set()
        cost = sim.effects(schema.effect, state, binding, adds, deletes)
        total += cost if task.use_costs else 1.0
        state = sim.close((state - deletes) | adds)
    if not sim.holds(task.goal, state, {}):
        raise PlanValidationError("the goal does not hold at the end of the plan")
    return total
