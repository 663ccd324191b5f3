"""Why a stream solve found no plan, in a few short sentences."""

from __future__ import annotations

import logging
from collections.abc import Sequence

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import Formula
from sdar_tamp.language.leniency import Leniency
from sdar_tamp.language.traversal import iter_atoms, iter_effect_literals
from solvers.solution import Status
from solvers.stream_planning.calls import Overrun
from solvers.stream_planning.engine import Engine

MAX_LISTED = 5  # instances named one by one before the rest are counted


def _produced_predicates(engine: Engine, domain: Domain) -> set[str]:
    produced = {a.predicate for a in engine.store.levels}
    for action in domain.actions:
        produced |= {lit.atom.predicate for lit in iter_effect_literals(action.effect)}
    produced |= {axiom.predicate for axiom in domain.axioms}
    for external in engine.streams.values():
        produced |= {a.predicate for a in external.declaration.certified}
    produced |= {f.name for f in engine.functions.values() if f.is_predicate}
    produced |= set(domain.types.parents)
    produced.add("=")
    return produced


def diagnose(
    engine: Engine,
    domain: Domain,
    goal: Formula,
    status: Status,
    *,
    max_time: float,
    overruns: Sequence[Overrun],
    complexity: float,
    warnings: Sequence[Leniency] = (),
) -> list[str]:
    """Short sentences: goals never reachable, streams never instantiated, streams that failed.

    ``max_time`` [s] and ``overruns`` (calls that outlived the deadline) explain a timeout;
    ``complexity`` is the last complexity bound of the search; the warning-level items of
    ``warnings`` (the problem's leniencies: likely mistakes in its files) come first."""
    noted = [
        f"the problem has a warning: {item}" for item in warnings if item.level >= logging.WARNING
    ]
    reasons = list(noted)
    if status is Status.TIMEOUT:
        reasons.append(f"the time limit ({max_time:g} s) or the iteration limit ended the search")
        reasons.extend(overrun.describe() for overrun in overruns)
    produced = _produced_predicates(engine, domain)
    table = engine.table
    for atom in iter_atoms(goal):
        if atom.predicate not in produced:
            args = " ".join(repr(table.value(a)) if a in table else a for a in atom.args)
            reasons.append(
                f"goal fact ({atom.predicate} {args}) is never reached: nothing "
                f"makes '{atom.predicate}' true (no init fact, action, axiom or stream)"
            )
    known = engine.store.predicates()
    certified = {a.predicate for s in engine.streams.values() for a in s.declaration.certified}
    instantiated = {name for name, _ in engine.instances}
    for name, external in sorted(engine.streams.items()):
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
    reasons.extend(_failed_tests(engine))
    states = list(engine.instances.values())
    reasons.extend(_dry_streams(engine))
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
    if len(reasons) == len(noted):
        reasons.append(
            f"no plan exists over every fact the streams could certify (complexity {complexity:g})"
        )
    return reasons


def _failed_tests(engine: Engine) -> list[str]:
    """How often each test stream failed (a negated one: answered False)."""
    found = []
    for name, external in sorted(engine.streams.items()):
        counters = external.counters
        if external.declaration.is_test and counters.successes < counters.calls:
            found.append(
                f"test '{name}' failed {counters.calls - counters.successes} of "
                f"{counters.calls} call(s)"
            )
    for function in sorted(engine.functions.values(), key=lambda f: f.name):
        if function.stream is not None and function.values:
            false = sum(1 for value in function.values.values() if not value)
            if false:
                found.append(
                    f"test '{function.stream}' (negate=True) was false on {false} of "
                    f"{len(function.values)} input tuple(s)"
                )
    return found


def _dry_streams(engine: Engine) -> list[str]:
    """The generators whose instances all ran dry (nothing more to sample)."""
    made: dict[str, list[bool]] = {}
    for (name, _), state in engine.instances.items():
        if not state.instance.external.declaration.is_test:
            made.setdefault(name, []).append(state.instance.exhausted)
    return [
        f"stream '{name}' is exhausted: all {len(flags)} of its instance(s) gave all they had"
        for name, flags in sorted(made.items())
        if all(flags)
    ]
