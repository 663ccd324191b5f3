"""The search loop of the stream planning algorithms (PDDLStream's incremental, focused,
binding and adaptive), one loop for all, with what differs in a policy (:mod:`.policies`).

Each pass builds the world at the complexity level (the optimistic one, or for incremental the
real facts with only fluent streams optimistic), plans over it, and hands the stream plan of a
new optimistic plan to the policy as a skeleton; a search without a new plan raises the level.

A ``:fluents`` stream is called with the fluent facts of the state of the step that uses its
certified facts (:mod:`.fluents`); what it certifies holds in that state only, so it never
becomes a fact an optimistic plan may use freely, and a stream plan with fluent streams is
bound (as in binding) even by focused. A failed fluent call blocks the stream's facts in states
like the one it failed in (:mod:`.blocked_calls`), so the next optimistic plan goes another way.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any, cast

from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.plan_run import plan_timing
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.logs import get_logger
from solvers.solution import (
    Action,
    Certificate,
    DurativeAction,
    Solution,
    Status,
    StreamStatistics,
)
from solvers.stream_planning.calls import CallTimeout
from solvers.stream_planning.constraints import original_name
from solvers.stream_planning.context import PlanSteps, SolveContext, SolveTimeout
from solvers.stream_planning.diagnosis import diagnose
from solvers.stream_planning.fluents import FluentPlan, fluent_plan
from solvers.stream_planning.optimistic import OptimisticWorld, OptResult, is_placeholder
from solvers.stream_planning.options import StreamOptions
from solvers.stream_planning.policies import policy_for
from solvers.stream_planning.preimage import simulate
from solvers.stream_planning.progress import RoundLog
from solvers.stream_planning.skeletons import Skeleton
from solvers.stream_planning.stream_plans import extract_stream_plan, stream_plan_effort

LOG = get_logger(__name__)


class StreamSolver:
    """One solve of one problem with the algorithm ``options.algorithm`` names (all state
    lives in its :class:`~.context.SolveContext` and its policy, nothing is global)."""

    def __init__(
        self,
        problem: PDDLProblem,
        options: StreamOptions,
        stream_info: Mapping[str, Any] | None = None,
    ) -> None:
        self.context = SolveContext(problem, options, stream_info)
        self.policy = policy_for(self.context)
        self.log = RoundLog(options.verbose)
        # a real plan cost more than assumed once its deferred functions were evaluated: the
        # search goes on at its level only for a cheaper one on the real facts known
        self.confirming = False

    def solve(self) -> Solution:
        context = self.context
        try:
            context.engine.start()
            status = self._search()
        except (SolveTimeout, CallTimeout):
            status = Status.TIMEOUT
        finally:
            context.runner.close()
        if context.best is not None:
            status = Status.SOLVED
        self._end(status.value)  # a round the time limit ended
        solution = self._solution(status)
        self.log.summary(
            context.options.algorithm,
            solution.status.value,
            solution.statistics,
            solution.streams,
            solution.diagnosis,
        )
        return solution

    def _end(self, outcome: str) -> None:
        """The current round ended with ``outcome`` (its line, with ``verbose``)."""
        self.log.end(outcome, self.context.calls, len(self.context.engine.store), self._phases())

    def _phases(self) -> tuple[float, float, float, float]:
        """The solve's world, grounding, search (without grounding) and sampling times [s]."""
        stats = self.context.stats
        search = stats.search_time - stats.grounding_time
        return (stats.world_time, stats.grounding_time, search, stats.sample_time)

    def _world(self, level: int) -> OptimisticWorld:
        """The facts to plan over: the optimistic world, or in incremental without fluent
        streams (nothing optimistic), just the real facts."""
        context = self.context
        engine = context.engine
        lazy = self.policy.lazy
        if lazy and not any(context.fluent_streams.values()):
            return OptimisticWorld(dict(engine.planning_facts()), {}, dict(engine.numeric))
        # confirming a real plan: a plan on new samples would end the search (the known plan
        # stands), so only the real facts (deferred tests and costs still assumed) are
        # searched, a smaller task; a cheaper real plan the optimistic one hid is found too
        return self._build(level, further=False, lazy=lazy or self.confirming)

    def _build(self, level: int, further: bool, lazy: bool | None = None) -> OptimisticWorld:
        """The optimistic world at ``level`` (its time counted in ``world_time``); ``lazy``:
        real streams add no optimistic results (default: the policy's)."""
        context = self.context
        start = time.perf_counter()
        try:
            return context.builder.build(
                level,
                self.policy.lazy if lazy is None else lazy,
                further=further,
                check_time=context.check_time,
            )
        finally:
            context.stats.world_time += time.perf_counter() - start

    def _complete(self, world: OptimisticWorld) -> bool:
        """Nothing left out at this level: no plan now means no plan at all."""
        context = self.context
        if not world.complete or context.blocks.temporary:
            return False
        # later calls (left out above the level) could give the several new values of one
        # instance a plan needs; mapped onto its one placeholder, a relaxed plan stays one, so
        # only a goal that is not relaxed-reachable proves that they would not help
        if world.more_calls and not context.unreachable:
            return False
        if any(
            s.instance.disabled and not s.instance.exhausted
            for s in context.engine.instances.values()
        ):
            return False
        return not self.policy.lazy or all(
            s.instance.exhausted or s.instance.external.declaration.fluents
            for s in context.engine.instances.values()
        )

    def _search(self) -> Status:
        """The loop all algorithms share: build the world at the level, plan, hand the new
        skeleton to the policy, or, with no new plan, raise the level."""
        context = self.context
        options = context.options
        stats = context.stats
        policy = self.policy
        level = options.initial_complexity
        tried: set[tuple[object, ...]] = set()  # (plan, optimistic results) met at this level
        log = self.log
        while True:
            if stats.iterations >= options.max_iterations:
                return Status.TIMEOUT
            stats.iterations += 1
            stats.complexity = level
            log.begin(
                stats.iterations, level, context.calls, len(context.engine.store), self._phases()
            )
            policy.prepare(level)
            world, found = self._plan_at(level)
            ordered = None if found is None else self._new_plan(world, found[0], tried)
            if found is None or ordered is None:
                # no new plan: work on the queued skeletons, and raise the level (what they
                # wait for may lie above it)
                missed = "no plan" if found is None else "plan met before"
                if self.confirming and context.best is not None:
                    self._end(f"{missed} cheaper than the best real plan")
                    return Status.SOLVED
                if policy.no_new_plan(len(world.facts)):
                    self._end(f"{missed}; a queued skeleton is solved")
                    return Status.SOLVED
                if not policy.waiting and self._complete(world):
                    self._end(f"{missed}; nothing is left out: infeasible")
                    return Status.INFEASIBLE
                if not policy.lazy and not policy.waiting and world.more_calls:
                    # once a skeleton was made, and while the world leaves instances out above
                    # the level, only instances a skeleton called get more calls (PDDLStream
                    # samples its skeletons' streams between levels, no other); before the
                    # first skeleton (for DRAIN_SECONDS at most: a guess), or once every
                    # instance is in but later calls' outputs, all of them (PDDLStream would
                    # end there, infeasible)
                    called_only = stats.skeletons > 0 and not world.complete
                    guess = stats.skeletons == 0 and not world.complete
                    context.drain(level, called_only=called_only, guess=guess)
                level += options.complexity_step
                if not policy.lazy and level < world.next_level < math.inf:
                    # the levels between add nothing to the optimistic world: skip them
                    level = int(world.next_level)
                if level > options.max_complexity:
                    self._end(f"{missed}; max_complexity reached")
                    return Status.INFEASIBLE
                self._end(f"{missed}; level -> {level}")
                context.lift()
                tried.clear()
                continue
            actions, cost = found
            if self.confirming and any(r.kind == "stream" for r in ordered.stream_plan):
                # a cheaper plan would need new samples: the known one stands (binding and
                # adaptive end at their first real plan too; searching on, one skeleton a
                # round, cost focused half of its rounds on continuous_tamp)
                self._end("a cheaper plan needs new samples: the best real plan stands")
                return Status.SOLVED
            if context.builder.refine(ordered.stream_plan):
                # it uses shared placeholders: plan again with the instances' own
                self._end("plan on shared placeholders: refined")
                continue
            if not any(r.kind == "stream" for r in ordered.stream_plan) and not any(
                is_placeholder(a) for _, args in actions for a in args
            ):
                evaluated = context.deferred_calls
                for result in ordered.stream_plan:  # its deferred predicates, in order
                    if result.kind == "predicate":
                        context.evaluate_deferred(result.external, result.inputs)
                        if Atom(result.external, result.inputs) not in context.engine.store:
                            break
                valid, check = context.real_check(actions)
                if not valid and context.deferred_calls > evaluated:
                    # a deferred test it relied on is false: plan again without it
                    self._end("plan on deferred tests: one failed")
                    continue
                dearer = not options.unit_costs and check.cost > cost + 1e-9
                if valid and dearer and context.deferred_calls > evaluated:
                    # its cost terms, evaluated now, cost more than the search assumed: keep
                    # it, and search again at this level for a plan cheaper than it, with the
                    # values known (no such plan: this one stands)
                    self.confirming = True
                    context.record(actions, check)
                    self._end(f"real plan at cost {check.cost:g} (assumed {cost:g}): search again")
                    continue
                self._end(
                    f"real plan ({len(actions)} actions, cost {check.cost:g})"
                    if valid
                    else "real plan failed validation"
                )
                if valid and context.record(actions, check):
                    return Status.SOLVED
                if not valid:
                    LOG.debug("plan on real facts failed validation; raising complexity")
                    level += options.complexity_step
                elif policy.lazy:
                    # incremental looks for a cheaper plan on more facts (as PDDLStream's
                    # does): the next search covers these facts too, bounded by this plan
                    level += options.complexity_step
                    if level > options.max_complexity:
                        return Status.INFEASIBLE
                    tried.clear()
                continue
            stats.skeletons += 1
            solved = policy.take(self._skeleton(ordered, cost))
            streams = sum(r.kind == "stream" for r in ordered.stream_plan)
            self._end(
                f"new skeleton ({len(actions)} actions, {streams} stream results"
                f"{', bound: solved' if solved else ''})"
            )
            if solved:
                return Status.SOLVED

    def _plan_at(self, level: int) -> tuple[OptimisticWorld, tuple[PlanSteps, float] | None]:
        """The world at ``level`` and a plan over it with its cost (None: no plan, or no
        search once ``max_skeletons`` skeletons were made)."""
        context = self.context
        world = self._world(level)
        context.unreachable = False
        found = None
        if context.stats.skeletons < context.options.max_skeletons:
            found = context.plan(world.facts, world.numeric, world)
            if (
                found is None
                and world.more_calls
                and world.further_level <= level
                and not context.unreachable
                and not self.confirming
            ):
                # no plan with one new output per instance: offer later calls' outputs (when
                # they all lie above the level, the same world, not built again: the same
                # search would fail)
                further = self._build(level, further=True)
                if further.facts.keys() != world.facts.keys():
                    found = context.plan(further.facts, further.numeric, further)
                world = further
        return world, found

    def _new_plan(
        self, world: OptimisticWorld, actions: PlanSteps, tried: set[tuple[object, ...]]
    ) -> FluentPlan | None:
        """The plan's actions and stream plan, ordered so that fluent streams see the state of
        the step that uses them; None when the plan was met before at this level."""
        context = self.context
        stream_plan: list[OptResult] = []
        check = None
        assumed = context.assumed
        if world.provenance or assumed.predicates:  # (else all facts are real)
            check = simulate(
                context.problem.domain, context.objects(world.facts), world.facts, actions,
                context.goal, view=assumed.view(context.engine.refuted),
            )  # fmt: skip
            for atom in assumed.assumed_in(check.needed, world.facts):
                # a deferred predicate instance the plan relies on: a result of the plan
                external = assumed.predicates[atom.predicate]
                domain = external.domain(atom.args)
                level = max((world.facts.get(a, 0) for a in domain), default=0)
                world.provenance[atom] = OptResult(
                    atom.predicate, atom.args, (), domain, (atom,), level, "predicate"
                )
            stream_plan = extract_stream_plan(check.needed, world)
        # The same actions on the same optimistic results: nothing learnt since this plan was
        # met, as if none. (The same actions on real facts are new.)
        key = (
            tuple(actions),
            tuple((r.external, r.inputs) for r in stream_plan if r.kind == "stream"),
        )
        if key in tried:
            return None
        tried.add(key)
        if check is None:
            return FluentPlan([], {}, list(actions))
        return fluent_plan(stream_plan, check, context.fluent_streams, actions)

    def _skeleton(self, ordered: FluentPlan, cost: float) -> Skeleton:
        """The skeleton of a new optimistic plan: first in the queue by cost (plus the effort
        of its stream plan with ``effort_weight``), ties to the older."""
        context = self.context
        options = context.options
        priority = cost
        if options.effort_weight is not None:
            efforts = {n: e.info for n, e in context.engine.streams.items()}
            effort = stream_plan_effort(ordered.stream_plan, efforts, options.unit_efforts)
            priority += options.effort_weight * effort
        return Skeleton(
            (0, priority, context.next_order()),
            ordered.actions,
            ordered.stream_plan,
            fluents=ordered.fluents,
        )

    def _solution(self, status: Status) -> Solution:
        context = self.context
        stats = context.stats
        engine = context.engine
        table = engine.table
        streams = {
            name: StreamStatistics(c.calls, c.successes, c.outputs, c.time)
            for name, c in (
                *((n, e.counters) for n, e in engine.streams.items()),
                *((e.stream or n, e.counters) for n, e in engine.functions.items()),
            )
        }
        stats.time = time.perf_counter() - context.start
        stats.facts = len(engine.store)

        def fact(atom: Atom) -> tuple[Any, ...]:
            return (atom.predicate, *(table.value(a) for a in atom.args))

        real = [a for a in engine.store.levels if not a.predicate.startswith("@")]
        if context.best is None:
            return Solution(
                None,
                math.inf,
                Certificate(tuple(fact(a) for a in real), ()),
                status,
                stats.as_mapping(),
                streams,
                diagnose(
                    engine,
                    context.problem.domain,
                    context.goal,
                    status,
                    max_time=context.options.max_time,
                    overruns=context.runner.overruns,
                    complexity=stats.complexity,
                    warnings=context.problem.leniencies,
                ),
            )
        cost, actions, needed = context.best
        plan = [
            Action(original_name(name), tuple(table.value(a) for a in args))
            for name, args in actions
        ]
        domain = context.problem.domain
        if domain.temporal:  # each step's start and duration, steps one after the other
            numeric = engine.numeric
            timing = plan_timing(
                domain, actions, lambda term: numeric.get((term.name, term.args), 0.0)
            )
            timed = [
                DurativeAction(a.name, a.args, start, length)
                for a, (start, length) in zip(plan, timing, strict=True)
            ]
            plan = cast(list[Action], timed)  # read as Actions: name and args come first
        certificate = Certificate(
            tuple(fact(a) for a in real),
            tuple(fact(a) for a in sorted(needed, key=str) if not a.predicate.startswith("@")),
        )
        return Solution(plan, cost, certificate, Status.SOLVED, stats.as_mapping(), streams)
