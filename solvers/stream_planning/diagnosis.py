"""Why a stream solve found no plan, in a few short sentences."""

from __future__ import annotations

from typing import TYPE_CHECKING

from sdar_tamp.language.model import iter_atoms, iter_effect_literals
from solvers.solution import Status

if TYPE_CHECKING:
    from solvers.stream_planning.algorithms import StreamSolver

MAX_LISTED = 5  # instances named one by one before the rest are counted


def _produced_predicates(solver: StreamSolver) -> set[str]:
    domain = solver.problem.domain
    produced = {a.predicate for a in solver.engine.store.levels}
    for action in domain.actions:
        produced |= {lit.atom.predicate for lit in iter_effect_literals(action.effect)}
    produced |= {axiom.predicate for axiom in domain.axioms}
    for external in solver.engine.streams.values():
        produced |= {a.predicate for a in external.declaration.certified}
    produced |= {f.name for f in solver.engine.functions.values() if f.is_predicate}
    produced |= set(domain.types.parents)
    produced.add("=")
    return produced


def diagnose(solver: StreamSolver, status: Status) -> list[str]:
    """Short sentences: goals never reachable, streams never instantiated, streams that failed."""
    reasons: list[str] = []
    if status is Status.TIMEOUT:
        reasons.append(
            f"the time limit ({solver.options.max_time:g} s) or the iteration limit "
            "ended the search"
        )
        reasons.extend(overrun.describe() for overrun in solver.runner.overruns)
    produced = _produced_predicates(solver)
    table = solver.engine.table
    for atom in iter_atoms(solver.goal):
        if atom.predicate not in produced:
            args = " ".join(repr(table.value(a)) if a in table else a for a in atom.args)
            reasons.append(
                f"goal fact ({atom.predicate} {args}) is never reached: nothing "
                f"makes '{atom.predicate}' true (no init fact, action, axiom or stream)"
            )
    known = solver.engine.store.predicates()
    certified = {
        a.predicate for s in solver.engine.streams.values() for a in s.declaration.certified
    }
    instantiated = {name for name, _ in solver.engine.instances}
    for name, external in sorted(solver.engine.streams.items()):
        if name not in instantiated:
            missing = sorted(
                {a.predicate for a in external.declaration.domain if a.predicate not in known}
            )
            detail = (
                (
                    f"no fact of {', '.join(missing)} was ever known"
                    + (
                        " (only streams could certify it, and none did)"
                        if set(missing) <= certified
                        else ""
                    )
                )
                if missing
                else ("its domain facts never held together")
            )
            reasons.append(f"stream '{name}' was never instantiated: {detail}")
        elif external.counters.calls and not external.counters.successes:
            reasons.append(
                f"stream '{name}' was called {external.counters.calls} time(s) and "
                "never produced an output"
            )
    states = list(solver.engine.instances.values())
    dry = [
        s.instance
        for s in states
        if s.instance.exhausted
        and not s.instance.results
        and not s.instance.external.declaration.is_test
    ]
    for instance in dry[:MAX_LISTED]:
        reasons.append(
            f"{instance.describe(table)} ran dry after {instance.calls} call(s) "
            "without producing an output"
        )
    if len(dry) > MAX_LISTED:
        reasons.append(f"... and {len(dry) - MAX_LISTED} more stream instance(s) ran dry")
    exhausted = sum(1 for s in states if s.instance.exhausted)
    if exhausted:
        reasons.append(f"{exhausted} stream instance(s) were exhausted")
    if not reasons:
        reasons.append(
            "no plan exists over every fact the streams could certify "
            f"(complexity {solver.stats['complexity']:g})"
        )
    return reasons
