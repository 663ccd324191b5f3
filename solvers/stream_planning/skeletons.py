"""Skeletons: an optimistic plan with the stream plan that would make it real, and how a
skeleton is bound to real stream outputs step by step (placeholders replaced by the outputs of
earlier calls, failed steps retried upstream)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.substitution import ground_atom
from solvers.stream_planning.context import PlanSteps, SolveContext
from solvers.stream_planning.engine import InstanceState
from solvers.stream_planning.fluents import Fluents
from solvers.stream_planning.optimistic import OptResult, is_placeholder


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


class SkeletonBinder:
    """Binds skeletons to real stream outputs in one solve.

    ``disable_failures``: a generator call that produced nothing disables its instance until
    the level rises (focused, binding); without it (adaptive) the instance stays callable for
    the skeleton's later visits. A failed fluent call always blocks its facts.
    """

    def __init__(self, context: SolveContext, disable_failures: bool) -> None:
        self.context = context
        self.disable_failures = disable_failures

    def sample_first_layer(self, skeleton: Skeleton) -> None:
        """Call once each instance of the stream plan whose inputs are all real, and evaluate
        its deferred predicates on real inputs (focused)."""
        for index, result in enumerate(skeleton.stream_plan):
            if any(is_placeholder(n) for n in result.inputs):
                continue
            if result.kind == "predicate":
                self.context.evaluate_deferred(result.external, result.inputs)
                continue
            if result.kind != "stream":
                continue
            state = self.instance(skeleton, index, result.inputs, {})
            if state is None:
                continue
            self.context.check_time()
            if not self.context.sample(state):
                self.context.failed(state)
                self.context.sweep_test(state, disable=True)

    def instance(
        self, skeleton: Skeleton, index: int, inputs: tuple[str, ...], bindings: Mapping[str, str]
    ) -> InstanceState | None:
        """The real instance for stream step ``index`` on ``inputs``: for a fluent stream, the
        one seeing that step's fluent facts. None when it does not exist (yet)."""
        name = skeleton.stream_plan[index].external
        if index not in skeleton.fluents:
            return self.context.engine.instance(name, inputs)
        fluents = tuple(
            sorted(
                (ground_atom(a, bindings) for a in skeleton.fluents[index]),
                key=str,
            )
        )
        if any(is_placeholder(n) for a in fluents for n in a.args):
            return None
        return self.context.engine.fluent_instance(name, inputs, fluents)

    def bind(self, skeleton: Skeleton) -> bool | None:
        """Bind a skeleton's stream plan. True: solved; False: retry later; None: dead.

        A placeholder stands for a *new* output of its instance (outputs already produced are
        real objects the planner can use directly), so each stream step samples afresh unless
        this skeleton already holds an output for it.
        """
        bindings: dict[str, str] = {}
        store = self.context.engine.store
        for index, result in enumerate(skeleton.stream_plan):
            inputs = tuple(bindings.get(n, n) for n in result.inputs)
            if any(is_placeholder(n) for n in inputs):
                return None
            if result.kind == "predicate":
                self.context.evaluate_deferred(result.external, inputs)
                if Atom(result.external, inputs) not in store:
                    return self._upstream_retry(skeleton, index)
                continue
            if result.kind in ("rule", "function"):
                continue
            self.context.check_time()
            state = self.instance(skeleton, index, inputs, bindings)
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
        valid, check = self.context.real_check(actions, trusted)
        if valid:
            return True if self.context.record(actions, check) else None
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
            self.context.sample(state)
        if len(results) == before:
            if fluent or self.disable_failures:
                self.context.failed(state)
            if not fluent:
                self.context.sweep_test(state, self.disable_failures)
            return None
        skeleton.used[index] = len(results)
        return results[-1].outputs

    def _upstream_retry(self, skeleton: Skeleton, index: int) -> bool | None:
        """Step ``index`` cannot succeed with the outputs chosen before it: resample those
        that can give others (False), unless none can (None: dead).

        A step that cannot give other outputs (a single-call stream, an exhausted generator)
        keeps what it gave this skeleton: called again it would produce nothing, and its
        output stays valid as long as its inputs do (:meth:`bind` drops it when a
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
