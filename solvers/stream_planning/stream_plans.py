"""Stream plans: the optimistic results an optimistic plan rests on, and what making them real
is expected to cost (PDDLStream's stream efforts, optionally added to the plan cost)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import And, Atom, Formula
from sdar_tamp.language.options import StreamInfo
from sdar_tamp.language.substitution import ground_atom
from solvers.stream_planning.optimistic import OptimisticWorld, OptResult


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
            total += overhead / (1.0 if options.p_success is None else options.p_success)
    return total


class ActionEfforts:
    """The extra cost of an optimistic action (PDDLStream's stream efforts in the plan cost):
    ``weight`` times the effort (:func:`stream_plan_effort`) of the optimistic results behind
    the positive preconditions of the action, each result counted once."""

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

    def __call__(self, name: str, args: tuple[str, ...]) -> float:
        action = self.domain.action(name)
        binding = {p.name: a for p, a in zip(action.parameters, args, strict=True)}
        provenance = self.world.provenance
        facts = [a for a in positive_atoms(action.precondition, binding) if a in provenance]
        if not facts:
            return 0.0
        results = extract_stream_plan(facts, self.world)
        return self.weight * stream_plan_effort(results, self.info, self.unit_efforts)


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
