"""Lifted plan simulation that also says which initial facts a plan relies on (its preimage).

This is independent of the classical planner's grounding: it evaluates the domain's formulas
directly on explicit states, picking one witness for each disjunction and existential. It serves
two purposes: the stream plan of an optimistic plan is the set of stream results behind the
initial facts the plan needs, and a finished plan is validated against the real facts.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from itertools import product

from sdar_tamp.language.model import (
    EQUALITY,
    And,
    AndEffect,
    Atom,
    Axiom,
    Domain,
    Effect,
    Exists,
    ForAllEffect,
    Formula,
    Imply,
    IncreaseCost,
    Literal,
    Not,
    Or,
    Parameter,
    When,
    is_variable,
)

Support = frozenset[Atom]


@dataclass(frozen=True)
class PlanCheck:
    """The outcome of :func:`simulate`: ``valid``, the failing step (or -1 for the goal), the
    initial facts the plan needs, and the final state.

    ``states[k]`` is the state before step ``k`` and ``supports[k]`` the facts step ``k``'s
    precondition and effect conditions rely on in it (for the steps simulated; when the plan
    is valid, one more entry each: the final state and the goal's support).
    """

    valid: bool
    failed_step: int | None
    needed: frozenset[Atom]
    final_state: frozenset[Atom]
    states: tuple[frozenset[Atom], ...] = ()
    supports: tuple[frozenset[Atom], ...] = ()


class _Evaluator:
    def __init__(self, domain: Domain, objects: Mapping[str, str], state: frozenset[Atom]) -> None:
        self.domain = domain
        self.state = state
        self.objects = objects
        self._by_predicate: dict[str, list[tuple[str, ...]]] = {}
        for atom in state:
            self._by_predicate.setdefault(atom.predicate, []).append(atom.args)
        self._axioms: dict[str, list[Axiom]] = {}
        for axiom in domain.axioms:
            self._axioms.setdefault(axiom.predicate, []).append(axiom)
        self._memo: dict[Atom, Support | None] = {}
        self._active: set[Atom] = set()
        self._cut = False
        self._refuting: set[Atom] = set()
        self._typed: dict[str, list[str]] = {}  # objects_of, per type

    def objects_of(self, type_name: str) -> list[str]:
        found = self._typed.get(type_name)
        if found is None:
            hierarchy = self.domain.types
            found = sorted(n for n, t in self.objects.items() if hierarchy.is_subtype(t, type_name))
            self._typed[type_name] = found
        return found

    def has_type(self, name: str, type_name: str) -> bool:
        own = self.objects.get(name)
        return own is not None and self.domain.types.is_subtype(own, type_name)

    def support(self, formula: Formula, binding: Mapping[str, str]) -> Support | None:
        if isinstance(formula, Atom):
            return self._atom(
                Atom(formula.predicate, tuple(binding.get(a, a) for a in formula.args))
            )
        if isinstance(formula, Not):
            if self.support(formula.formula, binding) is not None:
                return None
            return self.refutation(formula.formula, binding)
        if isinstance(formula, And):
            total: set[Atom] = set()
            for part in formula.parts:
                found = self.support(part, binding)
                if found is None:
                    return None
                total |= found
            return frozenset(total)
        if isinstance(formula, Or):
            for part in formula.parts:
                found = self.support(part, binding)
                if found is not None:
                    return found
            return None
        if isinstance(formula, Imply):
            return self.support(Or((Not(formula.antecedent), formula.consequent)), binding)
        if isinstance(formula, Exists):
            for extended in self._bindings(formula.parameters, formula.body, binding):
                found = self.support(formula.body, extended)
                if found is not None:
                    return found
            return None
        collected: set[Atom] = set()
        for extended in self._bindings(formula.parameters, None, binding):
            found = self.support(formula.body, extended)
            if found is None:
                return None
            collected |= found
        return frozenset(collected)

    def refutation(self, formula: Formula, binding: Mapping[str, str]) -> Support:
        """For a false ``formula``: the true facts that make it false (those under a negation).

        Absent facts need no support; a negation that fails does, through what makes its
        argument true. This is what a negated precondition relies on.
        """
        if isinstance(formula, Atom):
            atom = Atom(formula.predicate, tuple(binding.get(a, a) for a in formula.args))
            if atom.predicate in self._axioms:
                return self._derived_refutation(atom)
            return frozenset()
        if isinstance(formula, Not):
            return self.support(formula.formula, binding) or frozenset()
        if isinstance(formula, And):
            for part in formula.parts:
                if self.support(part, binding) is None:
                    return self.refutation(part, binding)
            return frozenset()
        if isinstance(formula, Or):
            return frozenset().union(*(self.refutation(p, binding) for p in formula.parts))
        if isinstance(formula, Imply):
            return self.refutation(Or((Not(formula.antecedent), formula.consequent)), binding)
        if isinstance(formula, Exists):
            return frozenset().union(
                *(
                    self.refutation(formula.body, extended)
                    for extended in self._bindings(formula.parameters, formula.body, binding)
                )
            )
        for extended in self._bindings(formula.parameters, None, binding):
            if self.support(formula.body, extended) is None:
                return self.refutation(formula.body, extended)
        return frozenset()

    def _derived_refutation(self, atom: Atom) -> Support:
        if atom in self._refuting:
            return frozenset()
        self._refuting.add(atom)
        collected: set[Atom] = set()
        for axiom in self._axioms[atom.predicate]:
            binding = {p.name: a for p, a in zip(axiom.parameters, atom.args, strict=True)}
            free = _free_parameters(axiom.body, set(binding))
            body = Exists(free, axiom.body) if free else axiom.body
            collected |= self.refutation(body, binding)
        self._refuting.discard(atom)
        return frozenset(collected)

    def _bindings(
        self, params: Sequence[Parameter], body: Formula | None, binding: Mapping[str, str]
    ) -> Iterator[dict[str, str]]:
        """Candidate values: from a positive fact of the body when there is one, else by type."""
        candidates: list[list[str]] = []
        hints = _positive_atoms(body) if body is not None else []
        for param in params:
            values: set[str] | None = None
            for atom in hints:
                if param.name in atom.args and atom.predicate in self._by_predicate:
                    position = atom.args.index(param.name)
                    values = {args[position] for args in self._by_predicate[atom.predicate]}
                    break
            typed = self.objects_of(param.type)
            candidates.append(sorted(values & set(typed)) if values is not None else typed)
        for combo in product(*candidates):
            yield {**binding, **{p.name: v for p, v in zip(params, combo, strict=True)}}

    def _atom(self, atom: Atom) -> Support | None:
        if any(is_variable(a) for a in atom.args):
            raise ValueError(f"unbound variable in {atom}")
        if atom.predicate == EQUALITY:
            return frozenset() if atom.args[0] == atom.args[1] else None
        if atom.predicate in self._axioms:
            return self._derived(atom)
        if atom in self.state:
            return frozenset((atom,))
        if atom.predicate in self.domain.types.parents and len(atom.args) == 1:
            own = self.objects.get(atom.args[0])
            if own is not None and self.domain.types.is_subtype(own, atom.predicate):
                return frozenset()
        return None

    def _derived(self, atom: Atom) -> Support | None:
        if atom in self._memo:
            return self._memo[atom]
        if atom in self._active:
            self._cut = True
            return None
        self._active.add(atom)
        outer_cut, self._cut = self._cut, False
        result: Support | None = None
        for axiom in self._axioms[atom.predicate]:
            binding = {p.name: a for p, a in zip(axiom.parameters, atom.args, strict=True)}
            if not all(
                self.has_type(a, p.type) for p, a in zip(axiom.parameters, atom.args, strict=True)
            ):
                continue
            free = _free_parameters(axiom.body, set(binding))
            body = Exists(free, axiom.body) if free else axiom.body
            result = self.support(body, binding)
            if result is not None:
                break
        self._active.discard(atom)
        if result is not None or not self._cut:
            self._memo[atom] = result  # a failure seen through a cycle may change: not cached
        self._cut = self._cut or outer_cut
        return result


def _positive_atoms(formula: Formula) -> list[Atom]:
    if isinstance(formula, Atom):
        return [formula] if formula.predicate != EQUALITY else []
    if isinstance(formula, And):
        return [a for part in formula.parts for a in _positive_atoms(part)]
    return []


def _free_parameters(formula: Formula, bound: set[str]) -> tuple[Parameter, ...]:
    seen: dict[str, None] = {}

    def visit(node: Formula, scope: set[str]) -> None:
        if isinstance(node, Atom):
            for arg in node.args:
                if is_variable(arg) and arg not in scope:
                    seen.setdefault(arg)
        elif isinstance(node, Not):
            visit(node.formula, scope)
        elif isinstance(node, And | Or):
            for part in node.parts:
                visit(part, scope)
        elif isinstance(node, Imply):
            visit(node.antecedent, scope)
            visit(node.consequent, scope)
        else:
            visit(node.body, scope | {p.name for p in node.parameters})

    visit(formula, bound)
    return tuple(Parameter(name) for name in seen)


def _effects(
    evaluator: _Evaluator, effect: Effect, binding: Mapping[str, str], needed: set[Atom]
) -> Iterable[tuple[Atom, bool]]:
    if isinstance(effect, Literal):
        atom = effect.atom
        yield Atom(atom.predicate, tuple(binding.get(a, a) for a in atom.args)), effect.negated
    elif isinstance(effect, AndEffect):
        for part in effect.parts:
            yield from _effects(evaluator, part, binding, needed)
    elif isinstance(effect, ForAllEffect):
        for extended in evaluator._bindings(effect.parameters, None, binding):
            yield from _effects(evaluator, effect.effect, extended, needed)
    elif isinstance(effect, When):
        support = evaluator.support(effect.condition, binding)
        if support is not None:
            needed |= support
            yield from _effects(evaluator, effect.effect, binding, needed)
    elif isinstance(effect, IncreaseCost):
        return


def simulate(
    domain: Domain,
    objects: Mapping[str, str],
    init: Iterable[Atom],
    plan: Sequence[tuple[str, tuple[str, ...]]],
    goal: Formula,
) -> PlanCheck:
    """Run ``plan`` from ``init``; report validity and the initial facts it relies on."""
    state = frozenset(init)
    added: set[Atom] = set()
    needed: set[Atom] = set()
    states: list[frozenset[Atom]] = []
    supports: list[frozenset[Atom]] = []

    def failed(step: int) -> PlanCheck:
        return PlanCheck(
            False, step, frozenset(needed - added), state, tuple(states), tuple(supports)
        )

    for step, (name, args) in enumerate(plan):
        action = domain.action(name)
        evaluator = _Evaluator(domain, objects, state)
        binding = {p.name: a for p, a in zip(action.parameters, args, strict=True)}
        if any(
            not evaluator.has_type(a, p.type) for p, a in zip(action.parameters, args, strict=True)
        ):
            return failed(step)
        support = evaluator.support(action.precondition, binding)
        if support is None:
            return failed(step)
        step_needed: set[Atom] = set(support)
        changes = list(_effects(evaluator, action.effect, binding, step_needed))
        states.append(state)
        supports.append(frozenset(step_needed))
        needed |= step_needed - added
        deletes = {atom for atom, negated in changes if negated}
        adds = {atom for atom, negated in changes if not negated}
        state = (state - deletes) | adds
        added |= adds
    evaluator = _Evaluator(domain, objects, state)
    support = evaluator.support(goal, {})
    if support is None:
        return failed(-1)
    needed |= support - added
    states.append(state)
    supports.append(support)
    return PlanCheck(True, None, frozenset(needed), state, tuple(states), tuple(supports))
