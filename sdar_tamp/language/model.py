"""The typed model of a planning domain, problem and stream file.

Everything here is an immutable value. Names (predicates, actions, objects, types) are stored
lower-case, since PDDL names are case-insensitive. A *term* is a plain string: a variable when it
starts with ``?``, otherwise an object (constant) name. Objects that stand for arbitrary
Python values are given string names by :mod:`sdar_tamp.language.problem`, so solvers only
ever see strings.

Formulas::

    Atom("on", ("?x", "b1"))            # (on ?x b1); the predicate "=" is equality
    Not(Atom(...)), And((...)), Or((...)), Imply(a, b)
    Exists((Parameter("?x", "block"),), body), ForAll(...)

``And(())`` is true and ``Or(())`` is false.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TypeAlias

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.leniency import Leniency

OBJECT_TYPE = "object"
EQUALITY = "="
TOTAL_COST = "total-cost"

Term: TypeAlias = str


def is_variable(term: Term) -> bool:
    """True for a variable term (``?x``)."""
    return term.startswith("?")


@dataclass(frozen=True)
class Parameter:
    """A typed variable, e.g. ``?b - block``."""

    name: str
    type: str = OBJECT_TYPE


@dataclass(frozen=True)
class Atom:
    """``(predicate arg1 ... argn)``; ``predicate == "="`` is equality."""

    predicate: str
    args: tuple[Term, ...] = ()

    def __str__(self) -> str:
        return f"({' '.join((self.predicate, *self.args))})"


@dataclass(frozen=True)
class Not:
    formula: Formula


@dataclass(frozen=True)
class And:
    parts: tuple[Formula, ...]


@dataclass(frozen=True)
class Or:
    parts: tuple[Formula, ...]


@dataclass(frozen=True)
class Imply:
    antecedent: Formula
    consequent: Formula


@dataclass(frozen=True)
class Exists:
    parameters: tuple[Parameter, ...]
    body: Formula


@dataclass(frozen=True)
class ForAll:
    parameters: tuple[Parameter, ...]
    body: Formula


Formula: TypeAlias = Atom | Not | And | Or | Imply | Exists | ForAll

TRUE: Formula = And(())
FALSE: Formula = Or(())


# --- numeric expressions (action costs) -------------------------------------------------------


@dataclass(frozen=True)
class FunctionTerm:
    """A numeric function applied to terms, e.g. ``(distance ?a ?b)``."""

    name: str
    args: tuple[Term, ...] = ()


NumericExpr: TypeAlias = float | FunctionTerm


# --- effects ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Literal:
    """An add (``negated=False``) or delete (``negated=True``) effect on one atom."""

    atom: Atom
    negated: bool = False


@dataclass(frozen=True)
class AndEffect:
    parts: tuple[Effect, ...]


@dataclass(frozen=True)
class ForAllEffect:
    parameters: tuple[Parameter, ...]
    effect: Effect


@dataclass(frozen=True)
class When:
    """A conditional effect: ``effect`` happens when ``condition`` holds before the action."""

    condition: Formula
    effect: Effect


@dataclass(frozen=True)
class IncreaseCost:
    """``(increase (total-cost) amount)``."""

    amount: NumericExpr


Effect: TypeAlias = Literal | AndEffect | ForAllEffect | When | IncreaseCost


# --- declarations -----------------------------------------------------------------------------


@dataclass(frozen=True)
class Predicate:
    name: str
    parameters: tuple[Parameter, ...] = ()

    @property
    def arity(self) -> int:
        return len(self.parameters)


@dataclass(frozen=True)
class Function:
    name: str
    parameters: tuple[Parameter, ...] = ()


@dataclass(frozen=True)
class ActionSchema:
    """A domain's ``(:action ...)``: the lifted schema (a plan step is
    :class:`solvers.solution.Action`)."""

    name: str
    parameters: tuple[Parameter, ...]
    precondition: Formula
    effect: Effect
    location: SourceLocation | None = field(default=None, compare=False)


@dataclass(frozen=True)
class Axiom:
    """A derived predicate: ``(:derived (predicate ?params) body)``."""

    predicate: str
    parameters: tuple[Parameter, ...]
    body: Formula
    location: SourceLocation | None = field(default=None, compare=False)


@dataclass(frozen=True)
class TypeHierarchy:
    """Types and their parents; ``object`` is the root and has no parent."""

    parents: Mapping[str, str] = field(default_factory=dict)

    def ancestors(self, type_name: str) -> tuple[str, ...]:
        """``type_name`` followed by its ancestors up to ``object`` (inclusive)."""
        chain = [type_name]
        while chain[-1] != OBJECT_TYPE:
            chain.append(self.parents.get(chain[-1], OBJECT_TYPE))
        return tuple(chain)

    def is_subtype(self, child: str, parent: str) -> bool:
        return parent in self.ancestors(child)

    def types(self) -> tuple[str, ...]:
        return (OBJECT_TYPE, *sorted(self.parents))


@dataclass(frozen=True)
class Domain:
    name: str
    requirements: frozenset[str]
    types: TypeHierarchy
    constants: Mapping[str, str]  # name -> type
    predicates: Mapping[str, Predicate]
    functions: Mapping[str, Function]
    actions: tuple[ActionSchema, ...]
    axioms: tuple[Axiom, ...]
    source: str | None = field(default=None, compare=False)
    leniencies: tuple[Leniency, ...] = field(default=(), compare=False)
    """What was accepted although strict PDDL rejects it (see ``language.leniency``)."""

    @property
    def derived_predicates(self) -> frozenset[str]:
        return frozenset(axiom.predicate for axiom in self.axioms)

    def action(self, name: str) -> ActionSchema:
        for action in self.actions:
            if action.name == name.lower():
                return action
        raise KeyError(name)


@dataclass(frozen=True)
class Problem:
    name: str
    domain_name: str
    objects: Mapping[str, str]  # name -> type
    init: tuple[Atom, ...]
    numeric_init: Mapping[tuple[str, tuple[str, ...]], float]
    goal: Formula
    minimize_cost: bool = False
    source: str | None = field(default=None, compare=False)
    leniencies: tuple[Leniency, ...] = field(default=(), compare=False)
    """What was accepted although strict PDDL rejects it (see ``language.leniency``)."""


# --- stream files -----------------------------------------------------------------------------


@dataclass(frozen=True)
class Stream:
    """A conditional generator: ``:stream`` (a *test* when it has no outputs)."""

    name: str
    inputs: tuple[str, ...]
    domain: tuple[Atom, ...]
    outputs: tuple[str, ...]
    certified: tuple[Atom, ...]
    fluents: tuple[str, ...] = ()
    location: SourceLocation | None = field(default=None, compare=False)

    @property
    def is_test(self) -> bool:
        return not self.outputs


@dataclass(frozen=True)
class StreamFunction:
    """``:function``: a non-negative numeric cost term computed by Python."""

    head: FunctionTerm
    domain: tuple[Atom, ...]
    location: SourceLocation | None = field(default=None, compare=False)

    @property
    def name(self) -> str:
        return self.head.name

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.head.args


@dataclass(frozen=True)
class StreamPredicate:
    """``:predicate``: an external boolean test, usable negated in the domain."""

    head: Atom
    domain: tuple[Atom, ...]
    location: SourceLocation | None = field(default=None, compare=False)

    @property
    def name(self) -> str:
        return self.head.predicate

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.head.args


@dataclass(frozen=True)
class Rule:
    """``:rule``: an always-true test used as an inference rule."""

    parameters: tuple[str, ...]
    domain: tuple[Atom, ...]
    certified: tuple[Atom, ...]
    location: SourceLocation | None = field(default=None, compare=False)


@dataclass(frozen=True)
class StreamFile:
    name: str
    streams: tuple[Stream, ...] = ()
    functions: tuple[StreamFunction, ...] = ()
    predicates: tuple[StreamPredicate, ...] = ()
    rules: tuple[Rule, ...] = ()
    source: str | None = field(default=None, compare=False)
    leniencies: tuple[Leniency, ...] = field(default=(), compare=False)
    """What was accepted although strict PDDL rejects it (see ``language.leniency``)."""

    def merged(self, other: StreamFile) -> StreamFile:
        return StreamFile(
            name=self.name,
            streams=self.streams + other.streams,
            functions=self.functions + other.functions,
            predicates=self.predicates + other.predicates,
            rules=self.rules + other.rules,
            source=self.source,
            leniencies=self.leniencies + other.leniencies,
        )


# --- traversal helpers ------------------------------------------------------------------------


def iter_atoms(formula: Formula) -> Iterator[Atom]:
    """Every atom in ``formula`` (quantified variables left as they are)."""
    stack: list[Formula] = [formula]
    while stack:
        node = stack.pop()
        if isinstance(node, Atom):
            yield node
        elif isinstance(node, Not):
            stack.append(node.formula)
        elif isinstance(node, And | Or):
            stack.extend(node.parts)
        elif isinstance(node, Imply):
            stack.extend((node.antecedent, node.consequent))
        else:
            stack.append(node.body)


def iter_effects(effect: Effect) -> Iterator[Literal | IncreaseCost]:
    """Every leaf of ``effect`` (literals and cost increases), in order, including those
    inside conditional and universal effects."""
    stack: list[Effect] = [effect]
    while stack:
        node = stack.pop()
        if isinstance(node, Literal | IncreaseCost):
            yield node
        elif isinstance(node, AndEffect):
            stack.extend(reversed(node.parts))
        else:
            stack.append(node.effect)


def iter_effect_literals(effect: Effect) -> Iterator[Literal]:
    """Every add/delete literal inside ``effect``, including conditional and universal ones."""
    return (e for e in iter_effects(effect) if isinstance(e, Literal))


def map_atoms(
    formula: Formula, fn: Callable[[Atom, bool], Formula], positive: bool = True
) -> Formula:
    """``formula`` with every atom replaced by ``fn(atom, positive)``; ``positive`` says
    whether the atom is used positively (under an even number of negations, an implication's
    antecedent counting as one). Quantifiers are kept as they are."""
    if isinstance(formula, Atom):
        return fn(formula, positive)
    if isinstance(formula, Not):
        return Not(map_atoms(formula.formula, fn, not positive))
    if isinstance(formula, And):
        return And(tuple(map_atoms(p, fn, positive) for p in formula.parts))
    if isinstance(formula, Or):
        return Or(tuple(map_atoms(p, fn, positive) for p in formula.parts))
    if isinstance(formula, Imply):
        return Imply(
            map_atoms(formula.antecedent, fn, not positive),
            map_atoms(formula.consequent, fn, positive),
        )
    body = map_atoms(formula.body, fn, positive)
    if isinstance(formula, Exists):
        return Exists(formula.parameters, body)
    return ForAll(formula.parameters, body)


def map_conditions(effect: Effect, fn: Callable[[Formula], Formula]) -> Effect:
    """``effect`` with the condition of every conditional effect replaced by ``fn(condition)``."""
    if isinstance(effect, AndEffect):
        return AndEffect(tuple(map_conditions(p, fn) for p in effect.parts))
    if isinstance(effect, ForAllEffect):
        return ForAllEffect(effect.parameters, map_conditions(effect.effect, fn))
    if isinstance(effect, When):
        return When(fn(effect.condition), map_conditions(effect.effect, fn))
    return effect


def substitute(formula: Formula, mapping: Mapping[str, str]) -> Formula:
    """Replace free variables of ``formula`` by ``mapping``; bound variables are shadowed."""
    if isinstance(formula, Atom):
        return Atom(formula.predicate, tuple(mapping.get(a, a) for a in formula.args))
    if isinstance(formula, Not):
        return Not(substitute(formula.formula, mapping))
    if isinstance(formula, And):
        return And(tuple(substitute(p, mapping) for p in formula.parts))
    if isinstance(formula, Or):
        return Or(tuple(substitute(p, mapping) for p in formula.parts))
    if isinstance(formula, Imply):
        return Imply(
            substitute(formula.antecedent, mapping), substitute(formula.consequent, mapping)
        )
    inner = {k: v for k, v in mapping.items() if k not in {p.name for p in formula.parameters}}
    body = substitute(formula.body, inner)
    return (
        Exists(formula.parameters, body)
        if isinstance(formula, Exists)
        else ForAll(formula.parameters, body)
    )
