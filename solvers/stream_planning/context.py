"""The state of one stream planning solve and the steps every algorithm takes on it: plan
over a set of facts, call a stream instance, check a plan on the real facts, keep the best
plan, forget failures when the complexity level rises (nothing here is global)."""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Collection, Mapping
from itertools import chain
from typing import Any

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import Atom, FunctionTerm
from sdar_tamp.language.generators import SINGLE_CALL
from sdar_tamp.language.options import never_assumed
from sdar_tamp.language.problem import PDDLProblem, infer_object_types
from sdar_tamp.logs import get_logger
from solvers.classical import PlanningTask, PlanStatus
from solvers.classical import plan as classical_plan
from solvers.classical.fast_downward import plan_task_with_fast_downward
from solvers.stream_planning.assumed import Assumed
from solvers.stream_planning.blocked_calls import Blocks, guard_fluent_uses
from solvers.stream_planning.calls import CallRunner
from solvers.stream_planning.costs import guard_costs
from solvers.stream_planning.deferred import resolve_plan
from solvers.stream_planning.engine import Engine, InstanceState
from solvers.stream_planning.negation import negated_predicates, resolve_negated_uses
from solvers.stream_planning.optimistic import OptimisticBuilder, OptimisticWorld
from solvers.stream_planning.options import StreamOptions
from solvers.stream_planning.preimage import PlanCheck, simulate
from solvers.stream_planning.statistics import SearchStatistics
from solvers.stream_planning.stream_plans import ActionEfforts

LOG = get_logger(__name__)

MIN_SWEEP_SECONDS = 0.05
"""A sweep of a failed test's siblings may always take this long [s] (for very fast searches)."""
PlanSteps = list[tuple[str, tuple[str, ...]]]
#: [s] the least time a drain of samplers may take before its time bound applies
#: (:meth:`SolveContext.drain`)
DRAIN_SECONDS = 0.5


class SolveTimeout(Exception):
    """The solve's ``max_time`` is up."""


class SolveContext:
    """One solve of one problem: its engine, optimistic worlds, blocks, counters and best plan."""

    def __init__(
        self,
        problem: PDDLProblem,
        options: StreamOptions,
        stream_info: Mapping[str, Any] | None = None,
    ) -> None:
        self.problem = problem
        self.options = options
        self.start = time.perf_counter()
        self.goal = problem.facts.goal
        negated = negated_predicates(problem.domain, self.goal)
        stream_info = resolve_negated_uses(problem.streams, stream_info, problem.domain, negated)
        self.runner = CallRunner(self.start + options.max_time, options.enforce_max_time)
        # incremental plans on real facts only: it evaluates every function at once
        defer = options.algorithm != "incremental"
        self.engine = Engine(problem, stream_info, self.runner, defer, negated)
        functions = self.engine.functions
        deferred = {n: f for n, f in functions.items() if self.engine.defers(f)}
        self.assumed = Assumed(
            {n: f for n, f in deferred.items() if f.is_predicate},
            {n: f for n, f in deferred.items() if not f.is_predicate},
            frozenset(problem.domain.types.parents) | {"object"},
        )
        # the search's domain and goal: deferred instances assumed (see assumed.py)
        self.domain: Domain = self.assumed.rewrite(guard_costs(problem.domain))
        self.search_goal = self.assumed.formula(self.goal)
        # p_success=0 streams (no effort) are never assumed, as in PDDLStream, unless efforts
        # weigh on plans: then their results cost overhead / 1e-9 efforts (stream_plans.py)
        pruned = frozenset(
            name
            for name, stream in self.engine.streams.items()
            if options.effort_weight is None and never_assumed(stream.info)
        )
        self.builder = OptimisticBuilder(self.engine, negated, self.assumed, pruned)
        self.fluent_streams = {n: e.declaration.fluents for n, e in self.engine.streams.items()}
        self.blocks = Blocks(guard_fluent_uses(self.domain, problem.streams.streams))
        self.stats = SearchStatistics()
        self.best: tuple[float, PlanSteps, frozenset[Atom]] | None = None
        self.calls = 0  # stream calls made so far (the queue's work is counted in calls)
        self.deferred_calls = 0  # deferred tests and functions evaluated for candidate plans
        self.unreachable = False  # the last plan search found the goal relaxed-unreachable
        self.searched = 0  # facts the last plan search planned over
        self.search_seconds = 0.0  # [s] the plan searches since the last drain took
        self.last_search_seconds = 0.0  # [s] the last plan search took
        self._order = 0

    def next_order(self) -> int:
        """A number larger than all given before (ties among skeletons go to the older)."""
        order = self._order
        self._order += 1
        return order

    def remaining(self) -> float:
        return self.options.max_time - (time.perf_counter() - self.start)

    def check_time(self) -> None:
        """Raise :class:`SolveTimeout` when the solve's time is up."""
        if self.remaining() <= 0:
            raise SolveTimeout

    def objects(self, facts: Collection[Atom]) -> dict[str, str]:
        """The objects of the problem and of ``facts``, with the types the facts imply."""
        constants = self.problem.domain.constants
        names = dict.fromkeys(self.problem.facts.objects, "object")
        names.update(dict.fromkeys(constants, "object"))
        names.update(dict.fromkeys(chain.from_iterable(atom.args for atom in facts), "object"))
        declared = {n: constants.get(n, "object") for n in names}
        types = self.problem.domain.types
        return infer_object_types(
            declared, (a for a in facts if len(a.args) == 1 and a.predicate in types.parents), types
        )

    def plan(
        self,
        facts: Mapping[Atom, int],
        numeric: Mapping[tuple[str, tuple[str, ...]], float],
        world: OptimisticWorld | None = None,
    ) -> tuple[PlanSteps, float] | None:
        """A classical plan over ``facts``; None when there is none. With ``effort_weight``,
        each action of the optimistic ``world`` also pays for the stream effort behind it."""
        self.check_time()
        self.searched = len(facts)
        limit = min(self.remaining(), self.options.max_planner_time)
        domain = self.blocks.domain()
        extra = None
        if self.options.effort_weight is not None and world is not None and world.provenance:
            info = {n: e.info for n, e in self.engine.streams.items()}
            extra = ActionEfforts(
                domain, world, info, self.options.effort_weight, self.options.unit_efforts
            )
        task = PlanningTask(
            domain,
            self.objects(facts),
            frozenset(facts) | self.blocks.facts(),
            self.search_goal,
            numeric,
            use_costs=not self.options.unit_costs,
            extra_cost=extra,
        )
        start = time.perf_counter()
        planner = plan_task_with_fast_downward if self.options.backend == "fd" else classical_plan
        result = planner(
            task,
            search=self.options.search,
            heuristic=self.options.heuristic,
            weight=self.options.weight,
            time_limit=limit,
            # with efforts, the bound applies to cost plus effort (as in PDDLStream)
            cost_bound=self._cost_bound(),
        )
        self.last_search_seconds = time.perf_counter() - start
        self.stats.search_time += self.last_search_seconds
        self.stats.grounding_time += result.statistics.grounding_time
        self.search_seconds += self.last_search_seconds
        statistics = result.statistics
        LOG.debug(
            "plan search: %s, %d facts, %d ground operators, %d expanded, %.3f s",
            result.status.value, len(facts), statistics.ground_actions, statistics.expanded,
            time.perf_counter() - start,
        )  # fmt: skip
        # nothing expanded: the goal is not reachable even ignoring deletes
        self.unreachable = result.status is PlanStatus.UNSOLVABLE and (
            result.statistics.expanded == 0
        )
        if result.status is PlanStatus.TIMEOUT:
            self.check_time()
            return None
        if result.plan is None:
            return None
        return [(step.name, step.args) for step in result.plan], result.cost

    def _cost_bound(self) -> float:
        """The planner keeps only plans cheaper than this: plans above ``max_cost`` are never
        returned, and once a plan is known (anytime), only cheaper ones are of interest."""
        bound = math.nextafter(self.options.max_cost, math.inf)
        return min(bound, self.best[0]) if self.best is not None else bound

    def sample(self, state: InstanceState) -> bool:
        """Call a real instance once; True when it produced."""
        start = time.perf_counter()
        self.calls += 1
        produced = self.engine.sample(state)
        self.stats.sample_time += time.perf_counter() - start
        return produced

    def sweep_test(self, failed: InstanceState, disable: bool) -> int:
        """A test instance of a candidate plan failed: call the test's other uncalled real
        instances within the complexity level, in the order they were made, up to
        ``search_sample_ratio`` times the facts of the last plan search (the next search costs
        about that much; each failure it is spared saves a search), and within
        ``search_sample_ratio`` times the last search's time. Returns the calls made.

        Without this, each search finds the next untested combination, one per search; a
        test is cheap next to a search, so a failed one has its siblings evaluated in a batch.
        ``disable``: a failed sibling is disabled until the level rises (focused, binding).
        """
        external = failed.instance.external
        if external.declaration.outputs or external.declaration.fluents:
            return 0
        budget = self.options.search_sample_ratio * max(self.searched, 1)
        level = self.stats.complexity
        calls = 0
        start = time.perf_counter()
        for key in self.engine.instance_keys:
            if calls >= budget or self._sweep_spent(start):
                break
            if key[0] != external.name:
                continue
            state = self.engine.instances[key]
            instance = state.instance
            if instance.calls or instance.exhausted or state.next_level > level:
                continue
            self.check_time()
            calls += 1
            if not self.sample(state) and disable:
                self.failed(state)
        return calls

    def _sweep_spent(self, start: float) -> bool:
        """A sweep that began at ``start`` has taken ``search_sample_ratio`` times as long as
        the last plan search (at least :data:`MIN_SWEEP_SECONDS`): it stops there, however few
        calls it made (expensive tests: a collision test along a long trajectory), as the
        search and the sampling are balanced in time."""
        spent = time.perf_counter() - start
        return spent > self.options.search_sample_ratio * max(
            self.last_search_seconds, MIN_SWEEP_SECONDS
        )

    def evaluate_deferred(self, name: str, inputs: tuple[str, ...]) -> bool:
        """Evaluate a deferred function or predicate instance a plan uses (False: it was not
        deferred)."""
        self.check_time()
        start = time.perf_counter()
        called = self.engine.evaluate(name, inputs)
        self.stats.sample_time += time.perf_counter() - start
        self.deferred_calls += called
        false = called and Atom(name, inputs) not in self.engine.store
        if false and self.engine.functions[name].is_predicate:
            self.sweep_deferred(name, inputs)
        return called

    def sweep_deferred(self, name: str, inputs: tuple[str, ...]) -> int:
        """A deferred predicate a plan used came out false: evaluate other deferred instances
        of it, those sharing the most inputs with it first (the likeliest to fail too), up to
        ``search_sample_ratio`` times the real facts known, those of deferred predicates left
        out. (:meth:`sweep_test` allows as many as the facts of the last search; here those
        include every deferred instance, so that budget would call nearly all of them.) It
        stops, too, once it has taken
        ``search_sample_ratio`` times the last search's time. Returns the calls made."""
        engine = self.engine
        # the facts of deferred predicates do not count: each sweep adds some, and the next
        # sweep's budget would grow with them (without bound, on a test that is mostly true)
        known = engine.store.count_except(engine.functions)
        budget = self.options.search_sample_ratio * max(known, 1)
        siblings = [k for k in engine.deferred if k[0] == name]
        if len(siblings) > budget:  # the budget's worth that share the most inputs, in order
            siblings = heapq.nsmallest(
                int(budget) + 1,
                siblings,
                key=lambda k: -sum(a == b for a, b in zip(k[1], inputs, strict=True)),
            )
        calls = 0
        start = time.perf_counter()
        for key in siblings:
            if calls >= budget or self._sweep_spent(start):
                break
            self.check_time()
            calls += engine.evaluate(*key)
        self.stats.sample_time += time.perf_counter() - start
        self.deferred_calls += calls
        return calls

    def drain(self, level: int, called_only: bool = False, guess: bool = False) -> int:
        """No new plan at ``level`` while some samplers could still give more: call them.
        With ``called_only``, only instances called before (by a skeleton): the loop asks for
        that while the optimistic world leaves instances out above the level, as PDDLStream
        samples only its skeletons' streams between levels (an instance no plan wanted
        stays optimistic, and its real values do not swell the next searches). ``guess``
        (before the first skeleton, no plan has asked for any value yet): the calls stop
        after :data:`DRAIN_SECONDS`, whatever the searches took.

        The real instances of streams with outputs that may answer more than once (not
        fluent, not single-answer adapters, no callable ``opt_gen_fn``), within the level
        after ``level``, are called in the order they were made, in passes, until none is
        left or the calls reach ``search_sample_ratio`` times the facts of the last search
        (the next search costs about that much). Without this, a focused algorithm calls an
        instance only when a plan needs it, so a finite sampler whose values no plan wants
        keeps later calls on offer, and the world grows with every level, for ever.

        The calls also stop once they took ``search_sample_ratio`` times as long as the
        searches since the last drain, and at least :data:`DRAIN_SECONDS` (after one call at
        least): PDDLStream's balance of sampling and search time, for samplers that take
        seconds a call (a motion planner), which would otherwise hold the next search back for
        minutes. Fast samplers never reach it (a seeded run makes the same calls). Returns
        the calls made."""
        budget = self.options.search_sample_ratio * max(self.searched, 1)
        seconds = max(self.options.search_sample_ratio * self.search_seconds, DRAIN_SECONDS)
        if guess:
            seconds = DRAIN_SECONDS
        self.search_seconds = 0.0
        start = time.perf_counter()
        limit = level + self.options.complexity_step
        calls = 0
        progress = True
        while progress and calls < budget:
            progress = False
            for key in list(self.engine.instance_keys):
                if calls >= budget or (calls and time.perf_counter() - start >= seconds):
                    return calls
                state = self.engine.instances[key]
                instance = state.instance
                external = instance.external
                if (
                    instance.exhausted
                    or (called_only and not instance.calls)
                    or instance.disabled
                    or state.next_level > limit
                    or not external.declaration.outputs
                    or external.declaration.fluents
                    or getattr(external.gen_fn, SINGLE_CALL, False)
                    or callable(external.info.opt_gen_fn)
                ):
                    continue
                self.check_time()
                calls += 1
                progress = True
                self.sample(state)
        return calls

    def real_check(
        self, actions: PlanSteps, trusted: frozenset[Atom] = frozenset()
    ) -> tuple[bool, PlanCheck]:
        """Is the plan valid on the real facts, each fact a fluent stream certified used only
        in the state it was certified in (or ``trusted``: bound by the plan's skeleton)? The
        deferred tests and functions the plan relies on are evaluated first
        (:func:`~.deferred.resolve_plan`). The check also gives the facts it needs and its
        cost."""
        engine = self.engine
        start = time.perf_counter()
        resolve_plan(
            engine,
            self.assumed,
            self.evaluate_deferred,
            self.problem.domain,
            self.objects,
            actions,
            self.goal,
        )
        self.stats.sample_time += time.perf_counter() - start
        facts = engine.store.levels
        numeric = engine.numeric

        def cost_of(term: FunctionTerm) -> float:
            return numeric.get((term.name, term.args), 0.0)

        check = simulate(
            self.problem.domain, self.objects(facts), facts, actions, self.goal, cost_of
        )  # fmt: skip
        if not check.valid or not engine.hidden:
            return check.valid, check
        for state, support in zip(check.states, check.supports, strict=True):
            hidden = (support & engine.hidden) - trusted
            if any(not engine.certified_in(a, state) for a in hidden):
                return False, check
        return True, check

    def failed(self, state: InstanceState) -> None:
        """A call produced nothing: a fluent instance blocks its facts in states like its own
        (for good once exhausted); another instance is disabled until the level rises."""
        instance = state.instance
        if instance.external.declaration.fluents:
            self.blocks.add(
                instance.external.name, instance.inputs, instance.fluents, instance.exhausted
            )
        else:
            self.engine.disable(state)

    def lift(self) -> None:
        """The complexity level rose: failures that may not repeat are forgotten."""
        for state in self.engine.instances.values():
            state.instance.disabled = False
        self.blocks.lift()

    def record(self, actions: PlanSteps, check: PlanCheck) -> bool:
        """Keep a real plan if it is the best so far (its cost: its length with unit costs,
        else the sum of its steps' costs); True when it is good enough to stop."""
        cost = float(len(actions)) if self.options.unit_costs else check.cost
        needed = check.needed
        if cost > self.options.max_cost:
            return False
        if self.best is None or cost < self.best[0]:
            self.best = (cost, actions, needed)
        return self.best[0] <= self.options.success_cost
