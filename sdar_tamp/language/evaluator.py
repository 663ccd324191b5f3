"""What a PDDL condition means: the one evaluator of condition formulas the solvers share.

A *state* is a set of ground atoms (closed world; see :mod:`sdar_tamp.language.state_index`).
:class:`Evaluator` decides a condition formula on one state under a binding of variables to
objects:

* ``and``/``or``/``not``/``imply`` as in logic, ``(= a b)`` by name, ``And(())`` true and
  ``Or(())`` false;
* ``exists`` looks for a witness: a parameter named by a positive atom of the body takes its
  values from that atom's facts (the atom with the fewest), any other ranges over the objects
  of its type (the first witness is the same whichever atom gave the values; a refutation
  covers those bindings only: elsewhere an absent fact makes the body false); ``forall``
  ranges over the objects of its types, but for a body ``(imply A C)`` a parameter that a
  positive atom of ``A`` names takes its values from that atom's facts (a binding outside
  them makes ``A`` false: the body holds, and relies on no fact when ``A`` is a conjunction
  of atoms);
* a type name used as a unary predicate holds for the objects of that type;
* a derived predicate is evaluated on demand from its axioms (any axiom may derive it; an
  axiom variable that is not a parameter is existential), memoised per state; positive
  recursion is cut at a repeated atom, which computes the least fixpoint of stratified axioms.

With ``explain=True`` the evaluator also says *why* a condition holds: :meth:`Evaluator.support`
returns the facts it relies on (for a negation: the true facts that make its argument false).
What an action's effect does is :mod:`sdar_tamp.language.state_changes`; executing a plan,
:mod:`sdar_tamp.language.plan_run`.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator, Sequence
from itertools import product

from sdar_tamp.errors import EvaluationError
from sdar_tamp.language.domain_model import Axiom, Domain
from sdar_tamp.language.formula_model import (
    EQUALITY,
    OBJECT_TYPE,
    And,
    Atom,
    Exists,
    Formula,
    Imply,
    Not,
    Or,
    Parameter,
    is_variable,
)
from sdar_tamp.language.state_index import Facts, Objects
from sdar_tamp.language.substitution import Binding, free_parameters, ground_atom

Support = frozenset[Atom]

EMPTY: Support = frozenset()


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
        for extended in self.every(formula.parameters, binding, formula.body):
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
        for extended in self.every(formula.parameters, binding, formula.body):
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
        facts (of the parameter's type; of the atom with the fewest facts), any other ranges
        over its type. In lexicographic order of the parameters' values."""
        hints = _positive_atoms(body)
        return _extend(parameters, [self._values(p, hints) for p in parameters], binding)

    def every(
        self, parameters: Sequence[Parameter], binding: Binding, body: Formula | None = None
    ) -> Iterator[dict[str, str]]:
        """The bindings of a universal's ``parameters`` on which its ``body`` may be false or
        rely on facts: every object of their types, but when ``body`` is ``(imply A C)`` (or
        ``(or (not A) ...)``), a parameter that a positive atom of ``A`` names takes the
        values of that atom's facts only (elsewhere ``A`` is false, so the body holds; with
        ``explain``, only when ``A`` is a conjunction of atoms, whose refutation is empty)."""
        guards = self._guards(body) if body is not None else []
        return _extend(parameters, [self._values(p, guards) for p in parameters], binding)

    def _guards(self, body: Formula) -> list[Atom]:
        """The positive atoms of the antecedent of a universal's ``body`` (see :meth:`every`)."""
        if isinstance(body, Imply):
            antecedent = body.antecedent
        elif isinstance(body, Or) and body.parts and isinstance(body.parts[0], Not):
            antecedent = body.parts[0].formula
        else:
            return []
        if self.explain:
            parts = antecedent.parts if isinstance(antecedent, And) else (antecedent,)
            if not all(isinstance(p, Atom) and p.predicate not in self._axioms for p in parts):
                return []
        return _positive_atoms(antecedent)

    def _values(self, param: Parameter, hints: Sequence[Atom]) -> Sequence[str]:
        """The values ``param`` takes: those of the (non-derived) atom of ``hints`` naming it
        with the fewest facts, of the parameter's type, sorted; the objects of its type when
        none names it or none has facts (a view may not list every atom it holds)."""
        best: Collection[tuple[str, ...]] | None = None
        position = 0
        for atom in hints:
            if param.name not in atom.args or atom.predicate in self._axioms:
                continue
            found = self.facts.args_of(atom.predicate)
            if found and (best is None or len(found) < len(best)):
                best, position = found, atom.args.index(param.name)
        if best is None:
            return self.objects.objects_of(param.type)
        return sorted(
            v for v in {args[position] for args in best} if self.objects.has_type(v, param.type)
        )

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
