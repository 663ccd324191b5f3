"""Deferred tests and functions: evaluated for the candidate plan's instances only.

In the optimistic algorithms a ``:function``, a ``:predicate`` and a test stream with
``StreamInfo(negate=True)`` are not called when their domain holds (:class:`~.engine.Engine`
records the instance as deferred); the optimistic world gives each deferred instance its
optimistic value (a function ``FunctionInfo.opt_fn``, default 1; a predicate true), so a plan
may use it. Before a plan is checked on the real facts, :func:`resolve_plan` calls the deferred
instances that plan relies on: the cost terms of its steps, and the predicate facts its
preconditions, effect conditions and goal rest on (through derived predicates too: an
``UnsafePose`` derived from ``(not (CFree ...))`` rests on the ``CFree`` facts it was refuted
by). A predicate that comes out false makes the plan invalid; the next search plans without it.

A deferred predicate that comes out false has its siblings evaluated in a batch, as a failed
test does (:meth:`~.context.SolveContext.sweep_deferred`): without that, each search would find
the next untried instance, one per search.

A predicate the domain uses negated is never deferred: a plan relies on its *absence*, which
the check cannot name; it is evaluated as soon as its domain holds, as before.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Mapping

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import Atom, Formula, FunctionTerm, IncreaseCost
from sdar_tamp.language.numeric import numeric_terms
from sdar_tamp.language.traversal import iter_effects
from solvers.stream_planning.assumed import Assumed
from solvers.stream_planning.engine import Engine
from solvers.stream_planning.preimage import simulate

PlanSteps = list[tuple[str, tuple[str, ...]]]


def cost_terms(domain: Domain, actions: Iterable[tuple[str, tuple[str, ...]]]) -> list[Atom]:
    """The ground cost terms ``(f args)`` of a plan's steps, as atoms, in plan order (terms
    under conditional effects included: the check decides whether they apply), and the terms
    of functions its numeric conditions and effects read (numeric fluents aside)."""
    terms: list[Atom] = []
    fluents = domain.numeric_fluents
    for name, args in actions:
        action = domain.action(name)
        binding = {p.name: a for p, a in zip(action.parameters, args, strict=True)}
        used = [
            effect.amount
            for effect in iter_effects(action.effect)
            if isinstance(effect, IncreaseCost) and isinstance(effect.amount, FunctionTerm)
        ]
        used.extend(t for t in numeric_terms(action) if t.name not in fluents)
        for term in used:
            terms.append(Atom(term.name, tuple(binding.get(a, a) for a in term.args)))
    return terms


def resolve_plan(
    engine: Engine,
    assumed: Assumed,
    evaluate: Callable[[str, tuple[str, ...]], bool],
    domain: Domain,
    objects: Callable[[Collection[Atom]], Mapping[str, str]],
    actions: PlanSteps,
    goal: Formula,
) -> int:
    """Evaluate (with ``evaluate``) the deferred instances ``actions`` relies on; returns how
    many were called.

    The cost terms first; then, as long as the plan is not valid on the real facts, it is run
    on the real facts with every deferred predicate instance whose domain holds assumed true
    (unless refuted: :class:`~.assumed.AssumedFacts`), and the assumed facts that run needs are
    evaluated in order until one is false (the run then needs other facts: run it again) or
    none is left. Each pass evaluates at least one instance, so this ends.
    """
    calls = 0
    for term in cost_terms(domain, actions):
        calls += evaluate(term.predicate, term.args)
    if not assumed.predicates:
        return calls
    view = assumed.view(engine.refuted)
    while True:
        # a deferred predicate is used positively only (the negated ones are never deferred):
        # a plan valid without its facts stays valid whatever they turn out to be
        real = engine.store.levels
        if simulate(domain, objects(real), real, actions, goal).valid:
            break
        check = simulate(domain, objects(real), real, actions, goal, view=view)
        needed = assumed.assumed_in(check.needed, engine.store.levels)
        made = 0
        for atom in needed:
            made += evaluate(atom.predicate, atom.args)
            if atom not in engine.store:
                break
        calls += made
        if not made:
            break
    return calls
