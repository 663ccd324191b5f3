"""The four algorithms as policies of one search loop (:mod:`.solver`).

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
  higher level, costs at least as much). The balance is counted in visits and calls, so a
  seeded run with fast samplers is reproducible; between levels it also stops, as
  PDDLStream's does, once the solve's sampling time reaches ``search_sample_ratio`` times its
  search time (slow samplers: a motion planner, inverse kinematics).

A stream plan with fluent streams is bound (as in binding) even by focused and incremental.
The policy is chosen once, from ``StreamOptions.algorithm`` (:func:`policy_for`).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from typing import Protocol

from solvers.stream_planning.context import DRAIN_SECONDS, SolveContext
from solvers.stream_planning.engine import InstanceState
from solvers.stream_planning.skeletons import Skeleton, SkeletonBinder


class AlgorithmPolicy(Protocol):
    """What one algorithm does at the points where the algorithms differ."""

    @property
    def lazy(self) -> bool:
        """True when the real instances are all called up to the level before planning, so
        that only fluent streams stay optimistic (incremental)."""
        ...

    @property
    def waiting(self) -> bool:
        """True while skeletons wait to be worked on (no plan then proves nothing)."""
        ...

    def prepare(self, level: int) -> None:
        """Before the world of a search at complexity ``level`` is built."""
        ...

    def take(self, skeleton: Skeleton) -> bool:
        """Work on the skeleton of a new optimistic plan; True when solved."""
        ...

    def no_new_plan(self, searched: int) -> bool:
        """A search over ``searched`` facts found no new plan; True when solved."""
        ...


class BindingPolicy:
    """Bind each stream plan once, placeholders to the outputs of earlier calls."""

    lazy = False
    waiting = False

    def __init__(self, context: SolveContext) -> None:
        self.binder = SkeletonBinder(context, disable_failures=True)

    def prepare(self, level: int) -> None:
        pass

    def take(self, skeleton: Skeleton) -> bool:
        return self.binder.bind(skeleton) is True

    def no_new_plan(self, searched: int) -> bool:
        return False


class FocusedPolicy(BindingPolicy):
    """Call the first layer of each stream plan (bind it when it has fluent streams)."""

    def take(self, skeleton: Skeleton) -> bool:
        if not skeleton.fluents:
            self.binder.sample_first_layer(skeleton)
            return False
        return self.binder.bind(skeleton) is True


class IncrementalPolicy(BindingPolicy):
    """Call every instance (but fluent ones) up to the level before each search; the plans
    that still need streams (fluent ones) are bound as in binding."""

    lazy = True

    def __init__(self, context: SolveContext) -> None:
        super().__init__(context)
        self.context = context
        # the instances (but fluent ones) that may still be called, and how many of the
        # engine's instances (in creation order) have been looked at for it
        self._callable: dict[tuple[str, tuple[str, ...]], InstanceState] = {}
        self._seen_instances = 0

    def prepare(self, level: int) -> None:
        """Call every instance (but fluent ones) until all exceed ``level``.

        Each pass calls, in the order of their keys, the instances known when it began that
        are within ``level``, once each; passes repeat until none is. Only instances that may
        still produce are looked at (:attr:`_callable`: exhausted ones drop out for good)."""
        engine = self.context.engine
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
                    self.context.check_time()
                    self.context.sample(state)
                    progress = True
                    if state.instance.exhausted:
                        del callable_[key]


class AdaptivePolicy:
    """Queue the skeletons and revisit them, balancing their stream calls against search."""

    lazy = False

    def __init__(self, context: SolveContext) -> None:
        self.context = context
        self.binder = SkeletonBinder(context, disable_failures=False)
        self.queue: list[Skeleton] = []

    @property
    def waiting(self) -> bool:
        return bool(self.queue)

    def prepare(self, level: int) -> None:
        pass

    def take(self, skeleton: Skeleton) -> bool:
        heapq.heappush(self.queue, skeleton)
        return self._process_queue()

    def no_new_plan(self, searched: int) -> bool:
        return bool(self.queue) and self._process_queue(searched)

    def _process_queue(self, searched: int = 0) -> bool:
        """Work on queued skeletons; True when solved.

        Each skeleton gets about ``search_sample_ratio`` visits. After a search over
        ``searched`` facts that found no new plan, the queue may go on until its stream calls
        reach ``search_sample_ratio * searched``: the next search (at a higher level, over a
        larger world) costs at least as much as this one did, so sampling gets a share that
        grows with the search's (counted, so a seeded run with fast samplers is
        reproducible). A visit counts at least one call.

        Between levels the work also stops (after one visit at least) once the solve's
        sampling time reaches ``search_sample_ratio`` times its search time, or after
        :data:`~.context.DRAIN_SECONDS` when it already has: PDDLStream gives its skeletons,
        between levels, the time that balance leaves. Samplers that take a fraction of a
        second a call would otherwise make thousands of facts no plan asked for (each visit
        of a failing skeleton samples afresh), slowing every later search.
        """
        context = self.context
        ratio = context.options.search_sample_ratio
        budget = max(ratio * len(self.queue), ratio * searched, 1.0)  # inf: until solved
        stats = context.stats
        start = stats.sample_time
        # [s] of sampling this work may take (the balance's share, or the least)
        seconds = math.inf
        if searched and math.isfinite(ratio):
            seconds = max(ratio * stats.search_time - start, DRAIN_SECONDS)
        spent = 0
        while spent < budget and self.queue:
            if spent and stats.sample_time - start >= seconds:
                break
            context.check_time()
            skeleton = heapq.heappop(self.queue)
            before = context.calls
            outcome = self.binder.bind(skeleton)
            spent += max(1, context.calls - before)
            if outcome is True:
                return True
            if outcome is False:  # still possible: requeue behind the others
                skeleton.attempts += 1
                skeleton.priority = (skeleton.attempts, skeleton.priority[1], context.next_order())
                heapq.heappush(self.queue, skeleton)
        return False


#: The algorithms by name, each the policy class that runs it.
POLICIES: dict[str, Callable[[SolveContext], AlgorithmPolicy]] = {
    "incremental": IncrementalPolicy,
    "focused": FocusedPolicy,
    "binding": BindingPolicy,
    "adaptive": AdaptivePolicy,
}
ALGORITHMS = tuple(POLICIES)


def policy_for(context: SolveContext) -> AlgorithmPolicy:
    """The policy of the algorithm ``context.options.algorithm`` names."""
    return POLICIES[context.options.algorithm](context)
