"""What a state offers an evaluator: its facts indexed by predicate, and the typed objects
quantifiers range over (the protocols :class:`Facts` and :class:`Objects`, and their plain
implementations :class:`FactIndex` and :class:`TypedObjects`).

A *state* is a set of ground atoms (closed world).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import Protocol

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import OBJECT_TYPE, Atom


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
        # filled per predicate when first asked for (a plan's states are many and large, and
        # most are asked about few predicates, or none)
        self._by_predicate: dict[str, list[tuple[str, ...]]] = {}

    def __contains__(self, atom: object) -> bool:
        return atom in self.atoms

    def args_of(self, predicate: str) -> Collection[tuple[str, ...]]:
        found = self._by_predicate.get(predicate)
        if found is None:
            found = [atom.args for atom in self.atoms if atom.predicate == predicate]
            self._by_predicate[predicate] = found
        return found


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
