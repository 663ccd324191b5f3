"""Deferred tests and functions in the optimistic problem, without an instance each.

A deferred ``:predicate`` (a negated test included, :mod:`.negation`) is assumed true wherever
its domain holds, unless an evaluation refuted it: the domain the optimistic search plans with
reads each of its atoms ``(P args)`` as ``(and <P's domain on args> (not (@refuted:P args)))``
(:meth:`Assumed.rewrite`), and a refuted instance adds one ``@refuted:P`` fact
(:attr:`~.engine.Engine.refuted`). So the optimistic world holds no fact per instance, and a
failed check blocks its instance in the next searches without grounding anything again. This is
how PDDLStream keeps a lazy negated test out of its optimistic task: there, a use of the test's
certified fact becomes its domain facts and the negation of a blocked fact, the negated literals
of the candidate plan's preimage name the instances to check, and a failed one adds its blocked
fact.

Which instances a plan relies on is read off the plan: it is simulated on a view of the facts
that answers for the assumed atoms too (:class:`AssumedFacts`), so they appear in the facts the
plan needs (:func:`~.preimage.simulate`), through derived predicates as well.

A deferred ``:function`` costs nothing per instance either: the cost guard ``(@fn:f args)``
(:mod:`.costs`) becomes ``f``'s domain on ``args``, and the search reads a term's optimistic
value when it grounds an action that needs it (:class:`OptimisticCosts`).

A predicate is assumed only when no stream, function or rule needs it in its domain (else the
optimistic world would miss what follows from it); the engine evaluates those at once. As in
PDDLStream, the search reads an assumed predicate through its domain only: a fact of it given in
the initial state whose domain facts do not hold is not used.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass, replace

from sdar_tamp.language.domain_model import Domain, Predicate
from sdar_tamp.language.formula_model import And, Atom, Formula, Not, Parameter
from sdar_tamp.language.state_index import FactIndex, Facts
from sdar_tamp.language.traversal import map_atoms, map_conditions
from solvers.stream_planning.engine import function_guard
from solvers.stream_planning.externals import FunctionExternal

REFUTED_PREFIX = "@refuted:"


def refuted_predicate(name: str) -> str:
    """The predicate that says an instance of deferred predicate ``name`` is false."""
    return f"{REFUTED_PREFIX}{name}"


def refuted_fact(atom: Atom) -> Atom:
    return Atom(refuted_predicate(atom.predicate), atom.args)


@dataclass(frozen=True)
class Assumed:
    """The deferred predicates and functions of one solve (by name), and the domain's types."""

    predicates: Mapping[str, FunctionExternal]
    functions: Mapping[str, FunctionExternal]
    types: frozenset[str] = frozenset()

    def __bool__(self) -> bool:
        return bool(self.predicates or self.functions)

    def names(self) -> frozenset[str]:
        return frozenset(self.predicates) | frozenset(self.functions)

    def _read(self, atom: Atom, _positive: bool) -> Formula:
        external = self.predicates.get(atom.predicate)
        if external is not None:
            domain = external.domain(atom.args)
            return And((*domain, Not(Atom(refuted_predicate(atom.predicate), atom.args))))
        for name, function in self.functions.items():
            if atom.predicate == function_guard(name):
                return And(function.domain(atom.args))
        return atom

    def formula(self, formula: Formula) -> Formula:
        """``formula`` with each assumed atom read as its domain and not refuted."""
        if not self:
            return formula
        return map_atoms(formula, self._read)

    def rewrite(self, domain: Domain) -> Domain:
        """``domain`` as the optimistic search reads it (unchanged when nothing is assumed)."""
        if not self:
            return domain
        predicates = dict(domain.predicates)
        for name, external in self.predicates.items():
            refuted = refuted_predicate(name)
            arity = len(external.declaration.inputs)
            predicates[refuted] = Predicate(
                refuted, tuple(Parameter(f"?x{i}") for i in range(arity))
            )
        actions = tuple(
            replace(
                a,
                precondition=self.formula(a.precondition),
                effect=map_conditions(a.effect, self.formula),
            )
            for a in domain.actions
        )
        axioms = tuple(replace(a, body=self.formula(a.body)) for a in domain.axioms)
        return replace(domain, predicates=predicates, actions=actions, axioms=axioms)

    def view(self, refuted: Collection[Atom]) -> Callable[[frozenset[Atom]], Facts]:
        """The view :func:`~.preimage.simulate` evaluates a plan on: the facts, and the
        assumed atoms whose domain holds and that ``refuted`` does not hold."""
        if not self.predicates:
            return FactIndex
        return lambda atoms: AssumedFacts(atoms, self, refuted)

    def assumed_in(self, atoms: Iterable[Atom], known: Collection[Atom]) -> list[Atom]:
        """The atoms of ``atoms`` that rest on an assumption (assumed predicates not in
        ``known``), sorted."""
        return sorted(
            (a for a in atoms if a.predicate in self.predicates and a not in known), key=str
        )


class AssumedFacts(FactIndex):
    """A state's facts, and the atoms of assumed predicates whose domain holds in it and that
    are not refuted (their arguments range over the state's facts: ``args_of`` lists none)."""

    def __init__(self, atoms: Iterable[Atom], assumed: Assumed, refuted: Collection[Atom]) -> None:
        super().__init__(atoms)
        self.assumed = assumed
        self.refuted = refuted

    def __contains__(self, atom: object) -> bool:
        if atom in self.atoms:
            return True
        if not isinstance(atom, Atom):
            return False
        external = self.assumed.predicates.get(atom.predicate)
        if external is None or atom in self.refuted:
            return False
        return all(
            d in self.atoms or (len(d.args) == 1 and d.predicate in self.assumed.types)
            for d in external.domain(atom.args)
        )

    def args_of(self, predicate: str) -> Collection[tuple[str, ...]]:
        # the known atoms of an assumed predicate are not all of them: an existential takes
        # its candidates from the other atoms of its body, or from the objects of its type
        if predicate in self.assumed.predicates:
            return ()
        return super().args_of(predicate)


class OptimisticCosts(dict[tuple[str, tuple[str, ...]], float]):
    """Known cost terms, and for the deferred functions ``deferred`` the optimistic value of
    any other term, computed by ``optimistic`` when first asked for (and kept)."""

    def __init__(
        self,
        known: Mapping[tuple[str, tuple[str, ...]], float],
        deferred: Collection[str],
        optimistic: Callable[[str, tuple[str, ...]], float],
    ) -> None:
        super().__init__(known)
        self.deferred = deferred
        self.optimistic = optimistic

    def __contains__(self, key: object) -> bool:
        if dict.__contains__(self, key):
            return True
        return isinstance(key, tuple) and len(key) == 2 and key[0] in self.deferred

    def __missing__(self, key: tuple[str, tuple[str, ...]]) -> float:
        if key[0] not in self.deferred:
            raise KeyError(key)
        value = self[key] = self.optimistic(*key)
        return value

    def get(self, key: tuple[str, tuple[str, ...]], default: float | None = None) -> float | None:  # type: ignore[override]
        if key in self:
            return self[key]
        return default
