"""The fluent state each ``:fluents`` stream of a stream plan is called in.

A fluent stream's answer depends on the state of the plan step that uses its output (a motion
must avoid the objects *where they are at that step*). The optimistic plan is simulated from the
initial state; a fluent result's state is the one before the first step whose precondition (or
effect condition, or the goal) relies on a fact certified by the result or by one of its
descendants in the stream plan. Its fluent facts may name placeholders of other results (an
object moved to a pose not sampled yet), so those results are ordered before it.

A result the plan uses directly at several steps whose states differ (the same motion made
twice, among objects that moved in between) is split, as in PDDLStream: one copy per state,
each with its own output placeholders, which the steps of that state then use. A result that
cannot be split (another result depends on it, or an action's effect or the goal names its
outputs) is called in the state of its first use and trusted at its later uses (PDDLStream
refuses such domains).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.substitution import ground_atom
from solvers.stream_planning.optimistic import OptResult, is_placeholder
from solvers.stream_planning.preimage import PlanCheck

Fluents = tuple[Atom, ...]


@dataclass(frozen=True)
class FluentPlan:
    """A stream plan ordered for its fluent streams, and the fluent facts (possibly naming
    placeholders) of each fluent result, by index in ``stream_plan``."""

    stream_plan: list[OptResult]
    fluents: dict[int, Fluents]
    actions: list[tuple[str, tuple[str, ...]]]  # the plan, split results' outputs renamed


def first_use(stream_plan: Sequence[OptResult], check: PlanCheck) -> dict[int, int]:
    """For each result: the first step (``len(plan)`` for the goal) relying on its facts or on
    those of its descendants; 0 when nothing does."""
    closure = [set(r.certified) for r in stream_plan]
    for i in reversed(range(len(stream_plan))):  # dependencies come first: descendants later
        for j in range(i + 1, len(stream_plan)):
            if closure[i] & set(stream_plan[j].domain):
                closure[i] |= closure[j]
    steps: dict[int, int] = {}
    for i, facts in enumerate(closure):
        steps[i] = next((k for k, s in enumerate(check.supports) if s & facts), 0)
    return steps


def fluent_plan(
    stream_plan: Sequence[OptResult],
    check: PlanCheck,
    declared: Mapping[str, tuple[str, ...]],
    actions: Sequence[tuple[str, tuple[str, ...]]] = (),
) -> FluentPlan:
    """The fluent facts of each fluent result (``declared`` maps a stream to its ``:fluents``
    predicates) and the stream plan reordered so that the producers of placeholders in them
    come first. ``check`` is the simulation of the optimistic plan ``actions`` over the
    optimistic facts; a result used at steps of different states is split (see above)."""
    if not any(declared.get(r.external) for r in stream_plan) or not check.states:
        return FluentPlan(list(stream_plan), {}, list(actions))
    steps = first_use(stream_plan, check)
    plan = list(stream_plan)
    renamed = [list(args) for _, args in actions]
    facts: dict[int, Fluents] = {}
    for i, result in enumerate(stream_plan):
        wanted = set(declared.get(result.external, ()))
        if not wanted:
            continue
        state = check.states[min(steps[i], len(check.states) - 1)]
        facts[i] = _fluents(state, wanted)
        groups = _use_groups(i, stream_plan, check, wanted, actions)
        for fluents, group in groups[1:]:
            names = {o: f"{o}@{group[0]}" for o in result.outputs}
            certified = tuple(ground_atom(a, names) for a in result.certified)
            for k in group:
                renamed[k] = [names.get(n, n) for n in renamed[k]]
            facts[len(plan)] = fluents
            plan.append(replace(result, outputs=tuple(names.values()), certified=certified))
    order = _order(plan, facts)
    position = {old: new for new, old in enumerate(order)}
    return FluentPlan(
        [plan[i] for i in order],
        {position[i]: f for i, f in facts.items()},
        [(name, tuple(args)) for (name, _), args in zip(actions, renamed, strict=True)],
    )


def _fluents(state: frozenset[Atom], wanted: set[str]) -> Fluents:
    return tuple(sorted((a for a in state if a.predicate in wanted), key=str))


def _use_groups(
    index: int,
    stream_plan: Sequence[OptResult],
    check: PlanCheck,
    wanted: set[str],
    actions: Sequence[tuple[str, tuple[str, ...]]],
) -> list[tuple[Fluents, list[int]]]:
    """The steps that use result ``index`` directly, grouped by their fluent facts (first use
    first); a single group when the result cannot be split: another result depends on it, the
    goal uses its outputs, or a step that does not use its facts names its outputs."""
    result = stream_plan[index]
    certified = set(result.certified)
    if any(certified & set(r.domain) for r in stream_plan):
        return []
    uses = [k for k, support in enumerate(check.supports) if support & certified]
    outputs = set(result.outputs)
    if outputs and len(actions) in uses:
        return []
    if any(outputs & set(args) for k, (_, args) in enumerate(actions) if k not in uses):
        return []
    groups: dict[Fluents, list[int]] = {}
    for k in uses:
        groups.setdefault(_fluents(check.states[k], wanted), []).append(k)
    return list(groups.items())


def _order(stream_plan: Sequence[OptResult], fluents: Mapping[int, Fluents]) -> list[int]:
    """A stable topological order: each result after the producers of the placeholders in its
    inputs and fluent facts and after the results certifying its domain. A cycle keeps the
    original order (the skeleton then fails when it meets an unbound placeholder)."""
    producer = {n: i for i, r in enumerate(stream_plan) for n in r.outputs}
    certifier = {a: i for i, r in enumerate(stream_plan) for a in r.certified}
    needs: list[set[int]] = []
    for i, result in enumerate(stream_plan):
        names = {n for n in result.inputs if is_placeholder(n)}
        names |= {n for a in fluents.get(i, ()) for n in a.args if is_placeholder(n)}
        deps = {producer[n] for n in names if n in producer}
        deps |= {certifier[a] for a in result.domain if a in certifier}
        needs.append(deps - {i})
    placed: list[int] = []
    done: set[int] = set()
    while len(placed) < len(stream_plan):
        ready = next(
            (i for i in range(len(stream_plan)) if i not in done and needs[i] <= done), None
        )
        if ready is None:
            return list(range(len(stream_plan)))
        placed.append(ready)
        done.add(ready)
    return placed
