"""Known facts with their complexity levels, and the instantiation of stream domains over them."""

from __future__ import annotations

from collections.abc import Collection, Iterator, Sequence
from dataclasses import dataclass

from sdar_tamp.language.formula_model import Atom, is_variable


class FactStore:
    """Ground atoms, each with the lowest complexity level at which it is known, indexed by
    predicate and by (predicate, argument position, value) for joins."""

    def __init__(self) -> None:
        self.levels: dict[Atom, int] = {}
        self._by_predicate: dict[str, dict[tuple[str, ...], int]] = {}
        self._by_argument: dict[tuple[str, int, str], dict[tuple[str, ...], int]] = {}

    def add(self, atom: Atom, level: int) -> bool:
        """Record ``atom``; True when it is new (a lower level for a known atom is kept too)."""
        old = self.levels.get(atom)
        if old is not None and old <= level:
            return False
        self.levels[atom] = level
        self._by_predicate.setdefault(atom.predicate, {})[atom.args] = level
        for position, value in enumerate(atom.args):
            self._by_argument.setdefault((atom.predicate, position, value), {})[atom.args] = level
        return old is None

    def copy(self) -> FactStore:
        """A store with the same atoms and levels (and the same iteration orders)."""
        store = FactStore()
        store.levels = dict(self.levels)
        store._by_predicate = {p: dict(found) for p, found in self._by_predicate.items()}
        store._by_argument = {k: dict(found) for k, found in self._by_argument.items()}
        return store

    def _candidates(self, atom: Atom, binding: dict[str, str]) -> dict[tuple[str, ...], int]:
        """The known argument tuples of ``atom``'s predicate that may match it: those with the
        value of its most selective bound argument, or all of them."""
        best = self._by_predicate.get(atom.predicate, {})
        for position, term in enumerate(atom.args):
            value = binding.get(term) if is_variable(term) else term
            if value is None:
                continue
            found = self._by_argument.get((atom.predicate, position, value), {})
            if len(found) < len(best):
                best = found
        return best

    def __contains__(self, atom: object) -> bool:
        return atom in self.levels

    def count_except(self, predicates: Collection[str]) -> int:
        """How many atoms are known, those of ``predicates`` left out."""
        return sum(len(found) for p, found in self._by_predicate.items() if p not in predicates)

    def __len__(self) -> int:
        return len(self.levels)

    def predicates(self) -> frozenset[str]:
        return frozenset(self._by_predicate)

    def join(
        self, atoms: Sequence[Atom], binding: dict[str, str], level: int = 0
    ) -> Iterator[tuple[dict[str, str], int]]:
        """Every extension of ``binding`` under which all ``atoms`` are known, with the highest
        level among the facts used."""
        if not atoms:
            yield binding, level
            return
        # bind the most constrained atom first
        index = max(
            range(len(atoms)),
            key=lambda i: sum(1 for t in atoms[i].args if not is_variable(t) or t in binding),
        )
        atom, rest = atoms[index], [*atoms[:index], *atoms[index + 1 :]]
        for args, fact_level in self._candidates(atom, binding).items():
            extended = _unify(atom.args, args, binding)
            if extended is not None:
                yield from self.join(rest, extended, max(level, fact_level))


def _unify(
    pattern: tuple[str, ...], args: tuple[str, ...], binding: dict[str, str]
) -> dict[str, str] | None:
    if len(pattern) != len(args):
        return None
    result = binding
    for term, value in zip(pattern, args, strict=True):
        if is_variable(term):
            bound = result.get(term)
            if bound is None:
                if result is binding:
                    result = dict(binding)
                result[term] = value
            elif bound != value:
                return None
        elif term != value:
            return None
    return result


@dataclass(frozen=True)
class Query:
    """The domain of an external: which inputs make an instance."""

    name: str
    inputs: tuple[str, ...]
    domain: tuple[Atom, ...]


class Instantiator:
    """Finds new instances of queries as facts arrive (each instance once)."""

    def __init__(self, queries: Sequence[Query], store: FactStore) -> None:
        self.queries = tuple(queries)
        self.store = store
        self.seen: set[tuple[str, tuple[str, ...]]] = set()
        self._by_predicate: dict[str, list[tuple[Query, int]]] = {}
        for query in self.queries:
            for position, atom in enumerate(query.domain):
                self._by_predicate.setdefault(atom.predicate, []).append((query, position))

    def initial(self, skip: Collection[str] = ()) -> Iterator[tuple[Query, tuple[str, ...], int]]:
        """Instances from the facts already in the store (and those of empty domains), but
        for the queries named in ``skip``."""
        for query in self.queries:
            if query.name in skip:
                continue
            for binding, level in self.store.join(query.domain, {}):
                yield from self._emit(query, binding, level)

    def new_fact(self, atom: Atom) -> Iterator[tuple[Query, tuple[str, ...], int]]:
        """Instances whose domain uses ``atom`` (just added to the store)."""
        level = self.store.levels[atom]
        for query, position in self._by_predicate.get(atom.predicate, ()):
            start = _unify(query.domain[position].args, atom.args, {})
            if start is None:
                continue
            rest = [*query.domain[:position], *query.domain[position + 1 :]]
            for binding, used in self.store.join(rest, start, level):
                yield from self._emit(query, binding, used)

    def _emit(
        self, query: Query, binding: dict[str, str], level: int
    ) -> Iterator[tuple[Query, tuple[str, ...], int]]:
        inputs = tuple(binding[v] for v in query.inputs)
        key = (query.name, inputs)
        if key not in self.seen:
            self.seen.add(key)
            yield query, inputs, level
