"""The stream planning algorithms: incremental, focused, binding and adaptive.

- incremental: call every stream instance up to the complexity level, plan on real facts, raise
  the level. ``:fluents`` streams are the exception: their answer depends on the state, so they
  are offered optimistically and called, as in binding, in the state of the step that uses them.
- focused: plan in the optimistic world, extract the stream plan the optimistic plan needs, call
  the instances of its first layer (real inputs) once each, disable failures until the level
  rises, plan again.
- binding: as focused, but walk the whole stream plan, binding placeholders to the outputs of
  earlier calls, so one pass can turn an optimistic plan into a real one.
- adaptive: binding with a queue of skeletons (optimistic plans) that are revisited; after each
  search, each queued skeleton is worked on about ``search_sample_ratio`` times, and after a
  search that found no new plan the queue may go on until its stream calls reach
  ``search_sample_ratio`` times the facts that search planned over (the next search, at a
  higher level, costs at least as much). The balance is counted in visits and calls, not
  measured in seconds, so a seeded run is reproducible.

A ``:fluents`` stream is called with the fluent facts of the state of the step that uses its
certified facts (:mod:`.fluents`); what it certifies holds in that state only, so it never
becomes a fact an optimistic plan may use freely, and a stream plan with fluent streams is
bound (as in binding) even by focused. A failed fluent call blocks the stream's facts in states
like the one it failed in (:mod:`.blocking`), so the next optimistic plan goes another way.
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from itertools import chain
from typing import Any

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import And, Atom, Formula, FunctionTerm
from sdar_tamp.language.objects import ObjectTable
from sdar_tamp.language.options import StreamInfo
from sdar_tamp.language.problem import PDDLProblem, infer_object_types
from sdar_tamp.language.substitution import ground_atom
from sdar_tamp.logs import get_logger
from solvers.classical import PlanningTask, PlanStatus
from solvers.classical import plan as classical_plan
from solvers.classical.fast_downward import plan_task_with_fast_downward
from solvers.solution import Action, Certificate, Solution, Status, StreamStatistics
from solvers.stream_planning.blocked_calls import Blocks, guard_fluent_uses
from solvers.stream_planning.calls import CallRunner, CallTimeout
from solvers.stream_planning.constraints import original_name
from solvers.stream_planning.costs import guard_costs, has_costs
from solvers.stream_planning.diagnosis import diagnose
from solvers.stream_planning.engine import Engine, InstanceState
from solvers.stream_planning.fluents import FluentPlan, Fluents, fluent_plan
from solvers.stream_planning.negation import check_negated_uses
from solvers.stream_planning.optimistic import (
    OptimisticBuilder,
    OptimisticWorld,
    OptResult,
    is_placeholder,
    negated_predicates,
)
from solvers.stream_planning.preimage import PlanCheck, simulate

LOG = get_logger(__name__)
ALGORITHMS = ("incremental", "focused", "binding", "adaptive")
PlanSteps = list[tuple[str, tuple[str, ...]]]


@dataclass(frozen=True)
class StreamOptions:
    """The solve() options the stream algorithms use (validated by :func:`solvers.solve`)."""

    algorithm: str = "adaptive"
    unit_costs: bool = False
    success_cost: float = math.inf
    max_time: float = math.inf
    max_iterations: float = math.inf
    max_skeletons: float = math.inf
    search_sample_ratio: float = 1.0
    initial_complexity: int = 0
    complexity_step: int = 1
    max_complexity: float = math.inf
    max_planner_time: float = math.inf
    search: str = "wastar"
    heuristic: str = "ff"
    weight: float = 2.0
    backend: str = "sdar"  # the classical planner: "sdar" (this package's) or "fd" (Fast Downward)
    max_cost: float = math.inf  # plans above it are not returned (PlanConstraints.max_cost)
    effort_weight: float | None = None  # optimistic actions pay weight * stream effort
    unit_efforts: bool = False  # every stream call has effort 1
    enforce_max_time: bool = True  # user calls in a worker thread, abandoned at max_time


@dataclass(order=True)
class Skeleton:
    """An optimistic plan and the stream plan that would make it real."""

    priority: tuple[int, float, int]
    actions: PlanSteps = field(compare=False)
    stream_plan: list[OptResult] = field(compare=False)
    attempts: int = field(default=0, compare=False)
    chosen: dict[int, tuple[str, ...]] = field(default_factory=dict, compare=False)
    fluents: dict[int, Fluents] = field(default_factory=dict, compare=False)
    used: dict[int, int] = field(default_factory=dict, compare=False)  # fluent results taken
    states: dict[int, InstanceState] = field(default_factory=dict, compare=False)


class _Timeout(Exception):
    pass


class StreamSolver:
    """One solve of one problem (all state lives here, nothing is global)."""

    def __init__(
        self,
        problem: PDDLProblem,
        options: StreamOptions,
        stream_info: Mapping[str, Any] | None = None,
    ) -> None:
        self.problem = problem
        self.options = options
        self.start = time.perf_counter()
        self.domain: Domain = guard_costs(problem.domain)
        self.goal = problem.facts.goal
        negated = negated_predicates(problem.domain, self.goal)
        check_negated_uses(problem.streams.streams, stream_info, negated)
        self.runner = CallRunner(self.start + options.max_time, options.enforce_max_time)
        self.engine = Engine(problem, stream_info, self.runner)
        self.builder = OptimisticBuilder(self.engine, negated)
        self.fluent_streams = {n: e.declaration.fluents for n, e in self.engine.streams.items()}
        self.blocks = Blocks(guard_fluent_uses(self.domain, problem.streams.streams))
        self.stats: dict[str, float] = {
            "iterations": 0,
            "skeletons": 0,
            "search_time": 0.0,
            "sample_time": 0.0,
            "complexity": 0,
        }
        self.best: tuple[float, PlanSteps, frozenset[Atom]] | None = None
        # a domain without cost effects plans with unit costs (zero costs would blind search)
        self.use_costs = not options.unit_costs and has_costs(problem.domain)
        self.queue: list[Skeleton] = []
        self._order = 0
        self._calls = 0  # stream calls made so far (the queue's work is counted in calls)
        self._unreachable = False  # the last plan search found the goal relaxed-unreachable
        # incremental: the instances (but fluent ones) that may still be called, and how many
        # of the engine's instances (in creation order) have been looked at for it
        self._callable: dict[tuple[str, tuple[str, ...]], InstanceState] = {}
        self._seen_instances = 0

    # --- helpers --------------------------------------------------------------------------

    @property
    def table(self) -> ObjectTable:
        return self.engine.table

    def remaining(self) -> float:
        return self.options.max_time - (time.perf_counter() - self.start)

    def _check_time(self) -> None:
        if self.remaining() <= 0:
            raise _Timeout

    def _objects(self, facts: Collection[Atom]) -> dict[str, str]:
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
        self._check_time()
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
            self._objects(facts),
            frozenset(facts) | self.blocks.facts(),
            self.goal,
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
        self.stats["search_time"] += time.perf_counter() - start
        statistics = result.statistics
        LOG.debug(
            "plan search: %s, %d facts, %d ground operators, %d expanded, %.3f s",
            result.status.value, len(facts), statistics.ground_actions, statistics.expanded,
            time.perf_counter() - start,
        )  # fmt: skip
        # nothing expanded: the goal is not reachable even ignoring deletes
        self._unreachable = result.status is PlanStatus.UNSOLVABLE and (
            result.statistics.expanded == 0
        )
        if result.status is PlanStatus.TIMEOUT:
            self._check_time()
            return None
        if result.plan is None:
            return None
        return [(step.name, step.args) for step in result.plan], result.cost

    def _cost_bound(self) -> float:
        """The planner keeps only plans cheaper than this: plans above ``max_cost`` are never
        returned, and once a plan is known (anytime), only cheaper ones are of interest."""
        bound = math.nextafter(self.options.max_cost, math.inf)
        return min(bound, self.best[0]) if self.best is not None else bound

    def _sample(self, name: str, inputs: tuple[str, ...]) -> bool | None:
        """Call a real instance once; None when it does not exist."""
        state = self.engine.instance(name, inputs)
        if state is None:
            return None
        return self._sample_state(state)

    def _sample_state(self, state: InstanceState) -> bool:
        start = time.perf_counter()
        self._calls += 1
        produced = self.engine.sample(state)
        self.stats["sample_time"] += time.perf_counter() - start
        return produced

    def _real_check(
        self, actions: PlanSteps, trusted: frozenset[Atom] = frozenset()
    ) -> tuple[bool, PlanCheck]:
        """Is the plan valid on the real facts, each fact a fluent stream certified used only
        in the state it was certified in (or ``trusted``: bound by the plan's skeleton)? The
        check also gives the facts it needs and its cost."""
        engine = self.engine
        facts = engine.store.levels
        numeric = engine.numeric

        def cost_of(term: FunctionTerm) -> float:
            return numeric.get((term.name, term.args), 0.0)

        check = simulate(
            self.problem.domain, self._objects(facts), facts, actions, self.goal, cost_of
        )  # fmt: skip
        if not check.valid or not engine.hidden:
            return check.valid, check
        for state, support in zip(check.states, check.supports, strict=True):
            hidden = (support & engine.hidden) - trusted
            if any(not engine.certified_in(a, state) for a in hidden):
                return False, check
        return True, check

    def _failed(self, state: InstanceState) -> None:
        """A call produced nothing: a fluent instance blocks its facts in states like its own
        (for good once exhausted); another instance is disabled until the level rises."""
        instance = state.instance
        if instance.external.declaration.fluents:
            self.blocks.add(
                instance.external.name, instance.inputs, instance.fluents, instance.exhausted
            )
        else:
            self.engine.disable(state)

    def _lift(self) -> None:
        """The complexity level rose: failures that may not repeat are forgotten."""
        for state in self.engine.instances.values():
            state.instance.disabled = False
        self.blocks.lift()

    def _record(self, actions: PlanSteps, check: PlanCheck) -> bool:
        """Keep a real plan if it is the best so far (its cost: its length with unit costs,
        else the sum of its steps' costs); True when it is good enough to stop."""
        cost = float(len(actions)) if self.options.unit_costs else check.cost
        needed = check.needed
        if cost > self.options.max_cost:
            return False
        if self.best is None or cost < self.best[0]:
            self.best = (cost, actions, needed)
        return self.best[0] <= self.options.success_cost

    # --- algorithms ---------------------------------------------------------------------

    def solve(self) -> Solution:
        try:
            self.engine.start()
            if self.options.algorithm == "incremental":
                status = self._incremental()
            else:
                status = self._focused()
        except (_Timeout, CallTimeout):
            status = Status.TIMEOUT
        finally:
            self.runner.close()
        if self.best is not None:
            status = Status.SOLVED
        return self._solution(status)

    def _incremental(self) -> Status:
        return self._search(lazy=True)

    def _focused(self) -> Status:
        return self._search(lazy=False)

    def _sample_up_to(self, level: int) -> None:
        """Incremental: call every instance (but fluent ones) until all exceed ``level``.

        Each pass calls, in the order of their keys, the instances known when it began that
        are within ``level``, once each; passes repeat until none is. Only instances that may
        still produce are looked at (:attr:`_callable`: exhausted ones drop out for good)."""
        engine = self.engine
        callable_ = self._callable
        keys = engine.instance_keys
        progress = True
        while progress:
            progress = False
            for key in keys[self._seen_instances :]:
                state = engine.instances[key]
                if not state.instance.external.declaration.fluents:
                    callable_[key] = state
            self._seen_instances = len(keys)
            for key in sorted(callable_):
                state = callable_[key]
                if state.instance.exhausted:
                    del callable_[key]
                    continue
                if state.next_level <= level:
                    self._check_time()
                    self._sample_state(state)
                    progress = True
                    if state.instance.exhausted:
                        del callable_[key]

    def _world(self, level: int, lazy: bool) -> OptimisticWorld:
        """The facts to plan over: the optimistic world, or in incremental without fluent
        streams (nothing optimistic), just the real facts."""
        engine = self.engine
        if lazy and not any(self.fluent_streams.values()):
            return OptimisticWorld(dict(engine.planning_facts()), {}, dict(engine.numeric))
        return self.builder.build(level, lazy, check_time=self._check_time)

    def _complete(self, world: OptimisticWorld, lazy: bool) -> bool:
        """Nothing left out at this level: no plan now means no plan at all."""
        if not world.complete or self.blocks.temporary:
            return False
        # later calls (left out above the level) could give the several new values of one
        # instance a plan needs; mapped onto its one placeholder, a relaxed plan stays one, so
        # only a goal that is not relaxed-reachable proves that they would not help
        if world.more_calls and not self._unreachable:
            return False
        if any(s.instance.disabled for s in self.engine.instances.values()):
            return False
        return not lazy or all(
            s.instance.exhausted or s.instance.external.declaration.fluents
            for s in self.engine.instances.values()
        )

    def _search(self, lazy: bool) -> Status:
        """The common loop. ``lazy`` (incremental): the real instances are all called up to the
        level before planning, and only fluent streams stay optimistic."""
        options = self.options
        level = options.initial_complexity
        tried: set[tuple[object, ...]] = set()  # (plan, optimistic results) met at this level
        while True:
            if self.stats["iterations"] >= options.max_iterations:
                return Status.TIMEOUT
            self.stats["iterations"] += 1
            self.stats["complexity"] = level
            if lazy:
                self._sample_up_to(level)
            world = self._world(level, lazy)
            self._unreachable = False
            found = None
            if self.stats["skeletons"] < options.max_skeletons:
                found = self.plan(world.facts, world.numeric, world)
                if found is None and world.more_calls and not self._unreachable:
                    # no plan with one new output per instance: offer later calls' outputs
                    world = self.builder.build(
                        level, lazy, further=True, check_time=self._check_time
                    )
                    found = self.plan(world.facts, world.numeric, world)
            stream_plan: list[OptResult] = []
            check = None
            if found is not None and world.provenance:  # (else all facts are real)
                check = simulate(
                    self.problem.domain, self._objects(world.facts), world.facts, found[0],
                    self.goal,
                )  # fmt: skip
                stream_plan = extract_stream_plan(check.needed, world)
            if found is not None:
                # The same actions on the same optimistic results: nothing learnt since this
                # plan was met, as if none. (The same actions on real facts are new.)
                key = (
                    tuple(found[0]),
                    tuple((r.external, r.inputs) for r in stream_plan if r.kind == "stream"),
                )
                if key in tried:
                    found = None
                tried.add(key)
            if found is None:
                # no new plan: work on the queued skeletons, and raise the level (what they
                # wait for may lie above it)
                if self.queue and self._process_queue(searched=len(world.facts)):
                    return Status.SOLVED
                if not self.queue and self._complete(world, lazy):
                    return Status.INFEASIBLE
                level += options.complexity_step
                if level > options.max_complexity:
                    return Status.INFEASIBLE
                self._lift()
                tried.clear()
                continue
            actions, cost = found
            ordered = (
                fluent_plan(stream_plan, check, self.fluent_streams, actions)
                if check is not None
                else FluentPlan([], {}, list(actions))
            )
            stream_plan = ordered.stream_plan
            if self.builder.refine(stream_plan):
                continue  # it uses shared placeholders: plan again with the instances' own
            if not any(r.kind == "stream" for r in stream_plan) and not any(
                is_placeholder(a) for _, args in actions for a in args
            ):
                valid, check = self._real_check(actions)
                if valid and self._record(actions, check):
                    return Status.SOLVED
                if not valid:
                    LOG.debug("plan on real facts failed validation; raising complexity")
                    level += options.complexity_step
                elif lazy:
                    # incremental looks for a cheaper plan on more facts (as PDDLStream's
                    # does): the next search covers these facts too, bounded by this plan
                    level += options.complexity_step
                    if level > options.max_complexity:
                        return Status.INFEASIBLE
                    tried.clear()
                continue
            self.stats["skeletons"] += 1
            priority = cost
            if options.effort_weight is not None:
                efforts = {n: e.info for n, e in self.engine.streams.items()}
                effort = stream_plan_effort(stream_plan, efforts, options.unit_efforts)
                priority += options.effort_weight * effort
            skeleton = Skeleton(
                (0, priority, self._order), ordered.actions, stream_plan, fluents=ordered.fluents
            )
            self._order += 1
            if options.algorithm == "focused" and not ordered.fluents:
                self._sample_first_layer(skeleton)
            elif options.algorithm == "adaptive":
                heapq.heappush(self.queue, skeleton)
                if self._process_queue():
                    return Status.SOLVED
            elif self._process(skeleton) is True:
                return Status.SOLVED

    def _sample_first_layer(self, skeleton: Skeleton) -> None:
        for index, result in enumerate(skeleton.stream_plan):
            if result.kind != "stream" or any(is_placeholder(n) for n in result.inputs):
                continue
            state = self._instance(skeleton, index, result.inputs, {})
            if state is None:
                continue
            self._check_time()
            if not self._sample_state(state):
                self._failed(state)

    def _instance(
        self, skeleton: Skeleton, index: int, inputs: tuple[str, ...], bindings: Mapping[str, str]
    ) -> InstanceState | None:
        """The real instance for stream step ``index`` on ``inputs``: for a fluent stream, the
        one seeing that step's fluent facts. None when it does not exist (yet)."""
        name = skeleton.stream_plan[index].external
        if index not in skeleton.fluents:
            return self.engine.instance(name, inputs)
        fluents = tuple(
            sorted(
                (ground_atom(a, bindings) for a in skeleton.fluents[index]),
                key=str,
            )
        )
        if any(is_placeholder(n) for a in fluents for n in a.args):
            return None
        return self.engine.fluent_instance(name, inputs, fluents)

    def _process_queue(self, searched: int = 0) -> bool:
        """Work on queued skeletons; True when solved.

        Each skeleton gets about ``search_sample_ratio`` visits. After a search over
        ``searched`` facts that found no new plan, the queue may go on until its stream calls
        reach ``search_sample_ratio * searched``: the next search (at a higher level, over a
        larger world) costs at least as much as this one did, so sampling gets a share that
        grows with the search's (as PDDLStream's sample time follows its search time, here
        counted, so a seeded run is reproducible). A visit counts at least one call.
        """
        ratio = self.options.search_sample_ratio
        budget = max(ratio * len(self.queue), ratio * searched, 1.0)  # inf: until solved
        spent = 0
        while spent < budget and self.queue:
            self._check_time()
            skeleton = heapq.heappop(self.queue)
            before = self._calls
            outcome = self._process(skeleton)
            spent += max(1, self._calls - before)
            if outcome is True:
                return True
            if outcome is False:  # still possible: requeue behind the others
                skeleton.attempts += 1
                skeleton.priority = (skeleton.attempts, skeleton.priority[1], self._order)
                self._order += 1
                heapq.heappush(self.queue, skeleton)
        return False

    def _process(self, skeleton: Skeleton) -> bool | None:
        """Bind a skeleton's stream plan. True: solved; False: retry later; None: dead.

        A placeholder stands for a *new* output of its instance (outputs already produced are
        real objects the planner can use directly), so each stream step samples afresh unless
        this skeleton already holds an output for it.
        """
        bindings: dict[str, str] = {}
        store = self.engine.store
        for index, result in enumerate(skeleton.stream_plan):
            inputs = tuple(bindings.get(n, n) for n in result.inputs)
            if any(is_placeholder(n) for n in inputs):
                return None
            if result.kind == "predicate":
                if Atom(result.external, inputs) not in store:
                    return self._upstream_retry(skeleton, index)
                continue
            if result.kind in ("rule", "function"):
                continue
            self._check_time()
            state = self._instance(skeleton, index, inputs, bindings)
            if state is None:
                return None
            if skeleton.states.get(index) is not state:
                skeleton.chosen.pop(index, None)  # outputs of another instance: not for this one
            skeleton.states[index] = state
            if index not in skeleton.chosen:
                outputs = self._take(skeleton, index, state)
                if outputs is None:
                    if not state.instance.exhausted:
                        return False
                    return self._upstream_retry(skeleton, index)
                skeleton.chosen[index] = outputs
            for placeholder, value in zip(result.outputs, skeleton.chosen[index], strict=True):
                if bindings.setdefault(placeholder, value) != value:
                    return None  # a shared placeholder would need two values: not this skeleton
        actions = [
            (name, tuple(bindings.get(a, a) for a in args)) for name, args in skeleton.actions
        ]
        if any(is_placeholder(a) for _, args in actions for a in args):
            return None
        # a fluent result is certified for the state fluent_plan gave it (the state of its
        # first use when it cannot be split): its facts are trusted at the steps it serves
        trusted = frozenset(
            ground_atom(a, bindings)
            for i, r in enumerate(skeleton.stream_plan)
            if i in skeleton.fluents
            for a in r.certified
        )
        valid, check = self._real_check(actions, trusted)
        if valid:
            return True if self._record(actions, check) else None
        return self._upstream_retry(skeleton, len(skeleton.stream_plan))

    def _take(self, skeleton: Skeleton, index: int, state: InstanceState) -> tuple[str, ...] | None:
        """Outputs for stream step ``index`` of a skeleton, or None when the call failed.

        A test that already passed passes. A fluent instance's outputs hold in its state only,
        so the planner never saw them: the skeleton takes those it has not tried yet before
        calling again. Other generators are called afresh (the planner saw their outputs).
        """
        instance = state.instance
        results = instance.results
        if not instance.external.declaration.outputs and results:
            return ()
        fluent = bool(instance.external.declaration.fluents)
        taken = skeleton.used.get(index, 0)
        if fluent and taken < len(results):
            skeleton.used[index] = taken + 1
            return results[taken].outputs
        before = len(results)
        if not instance.exhausted:
            self._sample_state(state)
        if len(results) == before:
            if fluent or self.options.algorithm != "adaptive":
                self._failed(state)
            return None
        skeleton.used[index] = len(results)
        return results[-1].outputs

    def _upstream_retry(self, skeleton: Skeleton, index: int) -> bool | None:
        """Step ``index`` cannot succeed with the outputs chosen before it: resample those
        that can give others (False), unless none can (None: dead).

        A step that cannot give other outputs (a single-call stream, an exhausted generator)
        keeps what it gave this skeleton: called again it would produce nothing, and its
        output stays valid as long as its inputs do (:meth:`_process` drops it when a
        resampled step upstream changes them).
        """
        retry = [i for i in skeleton.chosen if i < index and self._can_retry(skeleton, i)]
        for i in retry:
            del skeleton.chosen[i]
        return False if retry else None

    def _can_retry(self, skeleton: Skeleton, index: int) -> bool:
        """Can stream step ``index`` give other outputs (a test cannot)?"""
        state = skeleton.states.get(index)
        if state is None or not state.instance.external.declaration.outputs:
            return False
        instance = state.instance
        untried = skeleton.used.get(index, 0) < len(instance.results)
        return not instance.exhausted or (bool(instance.external.declaration.fluents) and untried)

    # --- result -------------------------------------------------------------------------

    def _solution(self, status: Status) -> Solution:
        engine = self.engine
        table = engine.table
        streams = {
            name: StreamStatistics(c.calls, c.successes, c.outputs, c.time)
            for name, c in (
                *((n, e.counters) for n, e in engine.streams.items()),
                *((e.stream or n, e.counters) for n, e in engine.functions.items()),
            )
        }
        self.stats["time"] = time.perf_counter() - self.start
        self.stats["facts"] = len(engine.store)

        def fact(atom: Atom) -> tuple[Any, ...]:
            return (atom.predicate, *(table.value(a) for a in atom.args))

        real = [a for a in engine.store.levels if not a.predicate.startswith("@")]
        if self.best is None:
            return Solution(
                None,
                math.inf,
                Certificate(tuple(fact(a) for a in real), ()),
                status,
                dict(self.stats),
                streams,
                diagnose(
                    engine,
                    self.problem.domain,
                    self.goal,
                    status,
                    max_time=self.options.max_time,
                    overruns=self.runner.overruns,
                    complexity=self.stats["complexity"],
                ),
            )
        cost, actions, needed = self.best
        plan = [
            Action(original_name(name), tuple(table.value(a) for a in args))
            for name, args in actions
        ]
        certificate = Certificate(
            tuple(fact(a) for a in real),
            tuple(fact(a) for a in sorted(needed, key=str) if not a.predicate.startswith("@")),
        )
        return Solution(plan, cost, certificate, Status.SOLVED, dict(self.stats), streams)


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
