"""What a PDDL condition, an action and a plan mean: the one evaluator the solvers share.

A *state* is a set of ground atoms (closed world). :class:`Evaluator` decides a condition
formula on one state under a binding of variables to objects:

* ``and``/``or``/``not``/``imply`` as in logic, ``(= a b)`` by name, ``And(())`` true and
  ``Or(())`` false;
* ``exists`` looks for a witness: a parameter named by a positive atom of the body takes its
  values from that atom's facts, any other ranges over the objects of its type; ``forall``
  ranges over the objects of its types;
* a type name used as a unary predicate holds for the objects of that type;
* a derived predicate is evaluated on demand from its axioms (any axiom may derive it; an
  axiom variable that is not a parameter is existential), memoised per state; positive
  recursion is cut at a repeated atom, which computes the least fixpoint of stratified axioms.

With ``explain=True`` the evaluator also says *why* a condition holds: :meth:`Evaluator.support`
returns the facts it relies on (for a negation: the true facts that make its argument false).

An action's effect is evaluated in the state before the action (:func:`effect_changes`):
conditional effects whose condition holds there, universal effects over the objects of their
types, deletes applied before adds (:meth:`Changes.apply`, so an atom both added and deleted
stays true), and ``(increase (total-cost) ...)`` summed through a ``cost_of`` callback.
:func:`run_plan` executes a whole plan and evaluates the goal at the end.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from itertools import product
from typing import Protocol

from sdar_tamp.errors import ActionError, EvaluationError
from sdar_tamp.language.model import (
    EQUALITY,
    OBJECT_TYPE,
    ActionSchema,
    And,
    AndEffect,
    Atom,
    Axiom,
    Domain,
    Effect,
    Exists,
    ForAllEffect,
    Formula,
    FunctionTerm,
    Imply,
    Literal,
    Not,
    Or,
    Parameter,
    Term,
    When,
    is_variable,
)

Binding = Mapping[str, str]
Support = frozenset[Atom]
CostOf = Callable[[FunctionTerm], float]

EMPTY: Support = frozenset()

__all__ = [
    "EMPTY",
    "Binding",
    "Changes",
    "CostOf",
    "Evaluator",
    "FactIndex",
    "Facts",
    "Objects",
    "PlanRun",
    "Support",
    "TypedObjects",
    "bind",
    "check_arguments",
    "effect_changes",
    "free_parameters",
    "ground_args",
    "ground_atom",
    "run_plan",
]


# --- substitution -----------------------------------------------------------------------------


def ground_args(args: Iterable[Term], binding: Binding) -> tuple[str, ...]:
    """``args`` with every bound variable replaced by its value."""
    return tuple(binding.get(a, a) for a in args)


def ground_atom(atom: Atom, binding: Binding) -> Atom:
    """``atom`` with every bound variable replaced by its value."""
    return Atom(atom.predicate, ground_args(atom.args, binding))


def bind(action: ActionSchema, args: Sequence[str]) -> dict[str, str]:
    """The binding of ``action``'s parameters to ``args``.

    Raises:
        ActionError: ``args`` has not one value per parameter.
    """
    if len(args) != len(action.parameters):
        raise ActionError(
            f"({' '.join((action.name, *args))}): wrong number of arguments "
            f"(expected {len(action.parameters)}, got {len(args)})"
        )
    return {p.name: a for p, a in zip(action.parameters, args, strict=True)}


def free_parameters(formula: Formula, bound: Iterable[str]) -> tuple[Parameter, ...]:
    """The variables of ``formula`` that neither ``bound`` nor a quantifier binds, in order of
    first use (typed ``object``)."""
    seen: dict[str, None] = {}

    def visit(node: Formula, scope: frozenset[str]) -> None:
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

    visit(formula, frozenset(bound))
    return tuple(Parameter(name) for name in seen)


# --- what a state offers ----------------------------------------------------------------------


class Facts(Protocol):
    """The ground atoms of a state, indexed by predicate."""

    def __contains__(self, atom: object) -> bool: ...

    def args_of(self, predicate: str) -> Collection[tuple[str, ...]]:
        """The argument tuples of the ``predicate`` atoms in the state."""
        ...


class Objects(Protocol):
    """The typed objects quantifiers range over."""

    def objects_of(self, type_name: str) -> Sequence[str]:
        """The objects of ``type_name`` (or of a subtype)."""
        ...

    def has_type(self, name: str, type_name: str) -> bool:
        """Whether ``name`` is an object of ``type_name`` (or of a subtype)."""
        ...


class FactIndex:
    """A fixed set of atoms, indexed by predicate (implements :class:`Facts`)."""

    def __init__(self, atoms: Iterable[Atom]) -> None:
        self.atoms = frozenset(atoms)
        self._by_predicate: dict[str, list[tuple[str, ...]]] = {}
        for atom in self.atoms:
            self._by_predicate.setdefault(atom.predicate, []).append(atom.args)

    def __contains__(self, atom: object) -> bool:
        return atom in self.atoms

    def args_of(self, predicate: str) -> Collection[tuple[str, ...]]:
        return self._by_predicate.get(predicate, ())


class TypedObjects:
    """Objects and their declared types (implements :class:`Objects`); objects of a type are
    listed sorted by name."""

    def __init__(self, domain: Domain, objects: Mapping[str, str]) -> None:
        self.types = domain.types
        self.objects = objects
        self._of_type: dict[str, list[str]] = {}

    def objects_of(self, type_name: str) -> Sequence[str]:
        found = self._of_type.get(type_name)
        if found is None:
            found = sorted(n for n, t in self.objects.items() if self.has_type(n, type_name))
            self._of_type[type_name] = found
        return found

    def has_type(self, name: str, type_name: str) -> bool:
        own = self.objects.get(name)
        return own is not None and (
            own == type_name or type_name == OBJECT_TYPE or self.types.is_subtype(own, type_name)
        )


# --- conditions -------------------------------------------------------------------------------


class Evaluator:
    """Condition formulas on one state (see the module docstring for the semantics).

    ``explain`` makes :meth:`support` collect the facts a true formula relies on; without it
    every support is empty (and cheaper to compute). The state must not change while the
    evaluator is in use (derived atoms are memoised).
    """

    def __init__(
        self, domain: Domain, facts: Facts, objects: Objects, *, explain: bool = False
    ) -> None:
        self.domain = domain
        self.facts = facts
        self.objects = objects
        self.explain = explain
        self._axioms: dict[str, list[Axiom]] = {}
        for axiom in domain.axioms:
            self._axioms.setdefault(axiom.predicate, []).append(axiom)
        self._type_names = frozenset(domain.types.parents) | {OBJECT_TYPE}
        self._memo: dict[Atom, Support | None] = {}
        self._active: set[Atom] = set()
        self._cut = False
        self._refuting: set[Atom] = set()

    def holds(self, formula: Formula, binding: Binding) -> bool:
        """Whether ``formula`` is true under ``binding``.

        Raises:
            EvaluationError: an atom has a variable that nothing binds.
        """
        return self.support(formula, binding) is not None

    def support(self, formula: Formula, binding: Binding) -> Support | None:
        """None when ``formula`` is false; else the facts it relies on (with ``explain``; one
        witness for each disjunction and existential, the first found)."""
        if isinstance(formula, Atom):
            return self.atom(ground_atom(formula, binding))
        if isinstance(formula, Not):
            if self.support(formula.formula, binding) is not None:
                return None
            return self.refutation(formula.formula, binding) if self.explain else EMPTY
        if isinstance(formula, And):
            total: set[Atom] = set()
            for part in formula.parts:
                found = self.support(part, binding)
                if found is None:
                    return None
                if found:
                    total |= found
            return frozenset(total) if total else EMPTY
        if isinstance(formula, Or):
            for part in formula.parts:
                found = self.support(part, binding)
                if found is not None:
                    return found
            return None
        if isinstance(formula, Imply):
            return self.support(Or((Not(formula.antecedent), formula.consequent)), binding)
        if isinstance(formula, Exists):
            for extended in self.witnesses(formula.parameters, formula.body, binding):
                found = self.support(formula.body, extended)
                if found is not None:
                    return found
            return None
        collected: set[Atom] = set()
        for extended in self.every(formula.parameters, binding):
            found = self.support(formula.body, extended)
            if found is None:
                return None
            collected |= found
        return frozenset(collected) if collected else EMPTY

    def refutation(self, formula: Formula, binding: Binding) -> Support:
        """For a false ``formula``: the true facts that make it false (those under a negation).

        Absent facts need no support; a negation that fails does, through what makes its
        argument true. This is what a negated condition relies on.
        """
        if isinstance(formula, Atom):
            atom = ground_atom(formula, binding)
            if atom.predicate in self._axioms:
                return self._derived_refutation(atom)
            return EMPTY
        if isinstance(formula, Not):
            return self.support(formula.formula, binding) or EMPTY
        if isinstance(formula, And):
            for part in formula.parts:
                if self.support(part, binding) is None:
                    return self.refutation(part, binding)
            return EMPTY
        if isinstance(formula, Or):
            return EMPTY.union(*(self.refutation(p, binding) for p in formula.parts))
        if isinstance(formula, Imply):
            return self.refutation(Or((Not(formula.antecedent), formula.consequent)), binding)
        if isinstance(formula, Exists):
            return EMPTY.union(
                *(
                    self.refutation(formula.body, extended)
                    for extended in self.witnesses(formula.parameters, formula.body, binding)
                )
            )
        for extended in self.every(formula.parameters, binding):
            if self.support(formula.body, extended) is None:
                return self.refutation(formula.body, extended)
        return EMPTY

    def atom(self, atom: Atom) -> Support | None:
        """A ground atom: equality, a derived predicate, a fact, or a type."""
        if any(is_variable(a) for a in atom.args):
            raise EvaluationError(f"unbound variable in {atom}")
        if atom.predicate == EQUALITY:
            return EMPTY if len(set(atom.args)) <= 1 else None
        if atom.predicate in self._axioms:
            return self._derived(atom)
        if atom in self.facts:
            return frozenset((atom,)) if self.explain else EMPTY
        is_type = atom.predicate in self._type_names and len(atom.args) == 1
        if is_type and self.objects.has_type(atom.args[0], atom.predicate):
            return EMPTY
        return None

    # -- quantifiers ---------------------------------------------------------------------------
    def witnesses(
        self, parameters: Sequence[Parameter], body: Formula, binding: Binding
    ) -> Iterator[dict[str, str]]:
        """Candidate bindings of an existential's ``parameters`` (a superset of its witnesses):
        a parameter that a positive atom of ``body`` names takes the values of that atom's
        facts (of the parameter's type), any other ranges over its type. In lexicographic order
        of the parameters' values."""
        hints = _positive_atoms(body)
        candidates: list[Sequence[str]] = []
        for param in parameters:
            values: Collection[tuple[str, ...]] | None = None
            for atom in hints:
                if param.name in atom.args and atom.predicate not in self._axioms:
                    found = self.facts.args_of(atom.predicate)
                    if found:
                        position = atom.args.index(param.name)
                        values = found
                        break
            if values is None:
                candidates.append(self.objects.objects_of(param.type))
            else:
                candidates.append(
                    sorted(
                        v
                        for v in {args[position] for args in values}
                        if self.objects.has_type(v, param.type)
                    )
                )
        return _extend(parameters, candidates, binding)

    def every(self, parameters: Sequence[Parameter], binding: Binding) -> Iterator[dict[str, str]]:
        """Every binding of ``parameters`` to objects of their types (universal quantifiers)."""
        return _extend(parameters, [self.objects.objects_of(p.type) for p in parameters], binding)

    # -- derived predicates --------------------------------------------------------------------
    def _axiom_body(self, axiom: Axiom, atom: Atom) -> tuple[Formula, dict[str, str]]:
        binding = {p.name: a for p, a in zip(axiom.parameters, atom.args, strict=True)}
        free = free_parameters(axiom.body, binding)
        return (Exists(free, axiom.body) if free else axiom.body), binding

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
            if len(axiom.parameters) != len(atom.args):
                raise EvaluationError(
                    f"{atom}: derived predicate {atom.predicate!r} takes "
                    f"{len(axiom.parameters)} argument(s)"
                )
            if not all(
                self.objects.has_type(a, p.type)
                for p, a in zip(axiom.parameters, atom.args, strict=True)
            ):
                continue
            body, binding = self._axiom_body(axiom, atom)
            result = self.support(body, binding)
            if result is not None:
                break
        self._active.discard(atom)
        if result is not None or not self._cut:
            self._memo[atom] = result  # a failure seen through a cycle may change: not cached
        self._cut = self._cut or outer_cut
        return result

    def _derived_refutation(self, atom: Atom) -> Support:
        if atom in self._refuting:
            return EMPTY
        self._refuting.add(atom)
        collected: set[Atom] = set()
        for axiom in self._axioms[atom.predicate]:
            body, binding = self._axiom_body(axiom, atom)
            collected |= self.refutation(body, binding)
        self._refuting.discard(atom)
        return frozenset(collected)


def _positive_atoms(formula: Formula) -> list[Atom]:
    if isinstance(formula, Atom):
        return [formula] if formula.predicate != EQUALITY else []
    if isinstance(formula, And):
        return [a for part in formula.parts for a in _positive_atoms(part)]
    return []


def _extend(
    parameters: Sequence[Parameter], candidates: Sequence[Sequence[str]], binding: Binding
) -> Iterator[dict[str, str]]:
    for combo in product(*candidates):
        yield {**binding, **{p.name: v for p, v in zip(parameters, combo, strict=True)}}


# --- effects ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Changes:
    """What one action does to a state: ``adds``, ``deletes``, its ``cost``, and (with an
    explaining evaluator) the facts its effect conditions relied on (``support``)."""

    adds: frozenset[Atom] = frozenset()
    deletes: frozenset[Atom] = frozenset()
    cost: float = 0.0
    support: Support = EMPTY

    def apply(self, state: frozenset[Atom]) -> frozenset[Atom]:
        """The next state: deletes first, then adds (an atom both added and deleted holds)."""
        return (state - self.deletes) | self.adds


def effect_changes(
    evaluator: Evaluator, effect: Effect, binding: Binding, cost_of: CostOf | None = None
) -> Changes:
    """The changes ``effect`` makes, evaluated in ``evaluator``'s state (the one before the
    action). ``cost_of`` gives a ground cost term's value; without it costs count 0.

    Raises:
        EvaluationError: an effect atom or cost term has a variable that nothing binds.
    """
    adds: set[Atom] = set()
    deletes: set[Atom] = set()
    support: set[Atom] = set()
    cost = 0.0

    def visit(node: Effect, inner: Binding) -> None:
        nonlocal cost
        if isinstance(node, Literal):
            atom = ground_atom(node.atom, inner)
            if any(is_variable(a) for a in atom.args):
                raise EvaluationError(f"unbound variable in the effect {atom}")
            (deletes if node.negated else adds).add(atom)
        elif isinstance(node, AndEffect):
            for part in node.parts:
                visit(part, inner)
        elif isinstance(node, ForAllEffect):
            for extended in evaluator.every(node.parameters, inner):
                visit(node.effect, extended)
        elif isinstance(node, When):
            found = evaluator.support(node.condition, inner)
            if found is not None:
                support.update(found)
                visit(node.effect, inner)
        else:
            amount = node.amount
            if isinstance(amount, FunctionTerm):
                term = FunctionTerm(amount.name, ground_args(amount.args, inner))
                if any(is_variable(a) for a in term.args):
                    raise EvaluationError(f"unbound variable in the cost term {term}")
                if cost_of is not None:
                    cost += cost_of(term)
            elif cost_of is not None:
                cost += amount

    visit(effect, binding)
    return Changes(frozenset(adds), frozenset(deletes), cost, frozenset(support))


# --- plans ------------------------------------------------------------------------------------


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
) -> PlanRun:
    """Execute ``plan`` (``(action name, arguments)`` steps) from ``init`` and evaluate
    ``goal`` at the end. A step that names no action of ``domain``, has bad arguments or whose
    precondition does not hold ends the run (see :class:`PlanRun`).

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
        evaluator = Evaluator(domain, FactIndex(state), objects, explain=explain)
        found = evaluator.support(action.precondition, binding)
        if found is None:
            return stop(step, f"the precondition of {shown} does not hold")
        done = effect_changes(evaluator, action.effect, binding, cost_of)
        states.append(state)
        supports.append(found | done.support)
        changes.append(done)
        state = done.apply(state)
    evaluator = Evaluator(domain, FactIndex(state), objects, explain=explain)
    goal_support = evaluator.support(goal, {})
    if goal_support is None:
        return stop(-1, "the goal does not hold at the end of the plan")
    return PlanRun(state, tuple(states), tuple(supports), tuple(changes), goal_support)
