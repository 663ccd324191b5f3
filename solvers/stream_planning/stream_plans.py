"""Stream plans: the optimistic results an optimistic plan rests on, and what making them real
is expected to cost (PDDLStream's stream efforts, optionally added to the plan cost)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import And, Atom, Formula
from sdar_tamp.language.options import StreamInfo
from sdar_tamp.language.substitution import ground_atom
from solvers.stream_planning.optimistic import OptimisticWorld, OptResult

#: the p_success a ``p_success=0`` stream is costed with where it is assumed at all (with an
#: ``effort_weight``; else it is pruned, see ``context.py``): overhead / 1e-9 efforts
LAST_RESORT_P_SUCCESS = 1e-9


def stream_plan_effort(
    stream_plan: Sequence[OptResult], info: Mapping[str, StreamInfo], unit_efforts: bool = False
) -> float:
    """Expected effort of making a stream plan real: per stream call ``StreamInfo.effort`` if
    set, else 1 with ``unit_efforts``, else ``overhead / p_success`` (defaults 1 and 1)."""
    total = 0.0
    for result in stream_plan:
        if result.kind != "stream":
            continue
        options = info[result.external]
        if options.effort is not None:
            total += options.effort
        elif unit_efforts:
            total += 1.0
        else:
            overhead = 1.0 if options.overhead is None else options.overhead
            p_success = 1.0 if options.p_success is None else options.p_success
            total += overhead / max(p_success, LAST_RESORT_P_SUCCESS)
    return total


class ActionEfforts:
    """The extra cost of an optimistic action (PDDLStream's stream efforts in the plan cost):
    ``weight`` times the effort (:func:`stream_plan_effort`) of the optimistic results behind
    the positive preconditions of the action, each result counted once.

    One instance serves one grounding: the optimistic results behind each fact are found once
    and shared by every action that needs the fact (in the order and with the sum
    :func:`extract_stream_plan` gives)."""

    def __init__(
        self,
        domain: Domain,
        world: OptimisticWorld,
        info: Mapping[str, StreamInfo],
        weight: float,
        unit_efforts: bool,
    ) -> None:
        self.domain = domain
        self.world = world
        self.info = info
        self.weight = weight
        self.unit_efforts = unit_efforts
        # action name -> its positive preconditions, as (predicate, arguments: the index of
        # an action parameter, or a constant)
        self._atoms: dict[str, list[tuple[str, tuple[int | str, ...]]]] = {}
        self._texts: dict[_Key, str] = {}
        # facts keyed by (predicate, arguments): tuples hash in C, atoms in Python
        self._provenance = {(a.predicate, a.args): r for a, r in world.provenance.items()}
        self._behind: dict[_Key, tuple[OptResult, ...]] = {}  # fact -> results, deps first

    def __call__(self, name: str, args: tuple[str, ...]) -> float:
        templates = self._atoms.get(name)
        if templates is None:
            action = self.domain.action(name)
            position = {p.name: i for i, p in enumerate(action.parameters)}
            atoms = positive_atoms(action.precondition, {})
            templates = self._atoms[name] = [
                (a.predicate, tuple(position.get(t, t) for t in a.args)) for a in atoms
            ]
        provenance = self._provenance
        facts = []
        for predicate, spec in templates:
            key = (predicate, tuple([args[t] if type(t) is int else t for t in spec]))
            if key in provenance:
                facts.append(key)
        if not facts:
            return 0.0
        if len(facts) > 1:
            facts.sort(key=self._text)
        results: list[OptResult] = []
        seen: set[int] = set()
        for key in facts:
            for result in self._results_behind(key):
                if id(result) not in seen:
                    seen.add(id(result))
                    results.append(result)
        return self.weight * stream_plan_effort(results, self.info, self.unit_efforts)

    def _text(self, key: _Key) -> str:
        """``str`` of the atom ``key`` stands for (the order :func:`extract_stream_plan` takes),
        kept: many actions share a fact."""
        text = self._texts.get(key)
        if text is None:
            text = self._texts[key] = _text(key)
        return text

    def _results_behind(self, key: _Key) -> tuple[OptResult, ...]:
        """The optimistic results behind a fact, dependencies first (as
        :func:`extract_stream_plan` orders them for that fact alone)."""
        known = self._behind.get(key)
        if known is not None:
            return known
        result = self._provenance.get(key)
        order: list[OptResult] = []
        if result is not None:
            seen: set[int] = {id(result)}
            for dependency in result.domain:
                for earlier in self._results_behind((dependency.predicate, dependency.args)):
                    if id(earlier) not in seen:
                        seen.add(id(earlier))
                        order.append(earlier)
            order.append(result)
        self._behind[key] = behind = tuple(order)
        return behind


_Key = tuple[str, tuple[str, ...]]


def _text(key: _Key) -> str:
    """``str`` of the atom ``key`` stands for (the order :func:`extract_stream_plan` takes)."""
    return f"({' '.join((key[0], *key[1]))})"


def positive_atoms(formula: Formula, binding: Mapping[str, str]) -> list[Atom]:
    """The atoms a formula needs true in every case: those under conjunctions only."""
    if isinstance(formula, Atom):
        return [ground_atom(formula, binding)]
    if isinstance(formula, And):
        return [atom for part in formula.parts for atom in positive_atoms(part, binding)]
    return []


def extract_stream_plan(needed: Iterable[Atom], world: OptimisticWorld) -> list[OptResult]:
    """The optimistic results behind ``needed`` facts, dependencies first."""
    order: list[OptResult] = []
    seen: set[int] = set()

    def visit(atom: Atom) -> None:
        result = world.provenance.get(atom)
        if result is None or id(result) in seen:
            return
        seen.add(id(result))
        for dependency in result.domain:
            visit(dependency)
        order.append(result)

    for atom in sorted(needed, key=str):
        visit(atom)
    return order
