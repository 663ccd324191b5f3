"""Lifted plan simulation that also says which initial facts a plan relies on (its preimage).

This is independent of the classical planner's grounding: it executes the plan with
:func:`sdar_tamp.language.plan_run.run_plan` on explicit states, with an explaining evaluator
that picks one witness for each disjunction and existential. It serves two purposes: the stream
plan of an optimistic plan is the set of stream results behind the initial facts the plan
needs, and a finished plan is validated against the real facts (and its cost computed).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import Atom, Formula
from sdar_tamp.language.plan_run import run_plan
from sdar_tamp.language.state_changes import CostOf
from sdar_tamp.language.state_index import FactIndex, Facts, TypedObjects


@dataclass(frozen=True)
class PlanCheck:
    """The outcome of :func:`simulate`: ``valid``, the failing step (or -1 for the goal), the
    initial facts the plan needs, and the final state.

    ``states[k]`` is the state before step ``k`` and ``supports[k]`` the facts step ``k``'s
    precondition and effect conditions rely on in it (for the steps simulated; when the plan
    is valid, one more entry each: the final state and the goal's support). ``cost`` is the
    sum of the simulated steps' costs (0 without a ``cost_of``).
    """

    valid: bool
    failed_step: int | None
    needed: frozenset[Atom]
    final_state: frozenset[Atom]
    states: tuple[frozenset[Atom], ...] = ()
    supports: tuple[frozenset[Atom], ...] = ()
    cost: float = 0.0


def simulate(
    domain: Domain,
    objects: Mapping[str, str],
    init: Iterable[Atom],
    plan: Sequence[tuple[str, tuple[str, ...]]],
    goal: Formula,
    cost_of: CostOf | None = None,
    view: Callable[[frozenset[Atom]], Facts] = FactIndex,
) -> PlanCheck:
    """Run ``plan`` from ``init``; report validity and the initial facts it relies on.

    ``cost_of`` gives a ground cost term's value (without it, costs count 0); ``view`` what
    conditions are evaluated on (:func:`~sdar_tamp.language.plan_run.run_plan`).
    """
    run = run_plan(
        domain, TypedObjects(domain, objects), init, plan, goal, cost_of, explain=True, view=view
    )  # fmt: skip
    added: set[Atom] = set()
    needed: set[Atom] = set()
    for support, changes in zip(run.supports, run.changes, strict=True):
        needed |= support - added
        added |= changes.adds
    states, supports = run.states, run.supports
    if not run.valid:
        needed -= added  # a failed run keeps only the facts true from the start
    elif run.goal_support is not None:
        needed |= run.goal_support - added
        states, supports = (*states, run.final_state), (*supports, run.goal_support)
    return PlanCheck(
        run.valid,
        run.failed_step,
        frozenset(needed),
        run.final_state,
        states,
        supports,
        run.cost,
    )
