"""The optimistic world: real facts plus what every stream instance *could* certify.

Each instance whose next result stays within the complexity limit contributes placeholder
outputs (``#o<k>``). By default a placeholder belongs to its instance (``unique``); with
``StreamInfo(opt_gen_fn="shared")`` every instance of a stream shares one placeholder per output.
A plan whose stream plan takes one shared placeholder from two instances (or feeds one back to
the instance that made it) is ambiguous: :meth:`OptimisticBuilder.refine` then gives every
instance of that stream placeholders of its own for the rest of the solve and the solver plans
again before sampling, as PDDLStream refines its shared optimistic values; a shared
placeholder one instance of the plan makes is bound to that instance's output directly.
(Refining only the plan's instances left the stream's other instances sharing: the next plan
took two of those, and continuous_tamp spent half of its rounds refining, one pair a round.)

With a callable ``StreamInfo(opt_gen_fn=gen_fn)`` (a stream with outputs; tests keep their
default) an instance's optimistic outputs come from ``gen_fn`` called like the sampler on the
instance's input values: its first batch of output tuples gives one set of placeholders per
tuple, each placeholder standing for the value ``gen_fn`` produced (an empty batch: the instance
adds nothing to the optimistic world). That value is what later optimistic calls see in place
of the placeholder, so optimistic values chain through streams. ``gen_fn`` is called once per
instance and solve.

Functions on placeholders and deferred ones (:mod:`.deferred`) take their optimistic value
(``FunctionInfo.opt_fn``, default 1, called with the values of real inputs, the optimistic value
of placeholders that have one, an :class:`~.opt_values.OptimisticValue` for the others);
predicates on placeholders and deferred ones are true unless the domain uses them negated.
Deferred ones add no fact to the world: the search's domain assumes them (:mod:`.assumed`),
and their values are read when the search asks for them.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable

from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.generators import SINGLE_CALL
from sdar_tamp.language.substitution import ground_atom
from solvers.stream_planning.assumed import Assumed, OptimisticCosts, refuted_fact
from solvers.stream_planning.engine import Engine, first_call_level, function_guard
from solvers.stream_planning.externals import FunctionExternal, StreamExternal
from solvers.stream_planning.facts import FactStore, Instantiator, Query
from solvers.stream_planning.opt_results import (
    PLACEHOLDER,
    OptimisticWorld,
    OptResult,
    is_placeholder,
)
from solvers.stream_planning.placeholder_values import PlaceholderValues

__all__ = [
    "PLACEHOLDER",
    "OptResult",
    "OptimisticBuilder",
    "OptimisticWorld",
    "is_placeholder",
]


class OptimisticBuilder:
    """Builds optimistic worlds for one engine (placeholders keep their names across builds)."""

    def __init__(
        self,
        engine: Engine,
        negated: frozenset[str],
        assumed: Assumed | None = None,
        pruned: frozenset[str] = frozenset(),
    ) -> None:
        self.engine = engine
        self.negated = negated
        self.pruned = pruned  # streams never assumed: only their real results count
        self.assumed = assumed if assumed is not None else Assumed({}, {})
        self.names = PlaceholderValues(engine)  # placeholders and the values behind them
        self._shared: set[str] = set()  # placeholders shared by the instances of a stream
        self.refined: set[str] = set()  # streams whose instances have placeholders of their own
        self._later: set[str] = set()  # placeholders of later calls (see _further)
        # (external, inputs, outputs) -> its (domain, certified) facts: every build meets the
        # same instances and placeholders again (their names persist across builds)
        self._atoms: dict[
            tuple[str, tuple[str, ...], tuple[str, ...]], tuple[tuple[Atom, ...], tuple[Atom, ...]]
        ] = {}

    def placeholder(self, key: tuple[object, ...]) -> str:
        return self.names.placeholder(key)

    def build(
        self,
        limit: int,
        lazy: bool = False,
        further: bool = False,
        check_time: Callable[[], None] | None = None,
    ) -> OptimisticWorld:
        """The optimistic world at complexity ``limit``. With ``lazy`` (incremental), only
        fluent streams (called in the state of the step that uses them) and streams on
        placeholders add optimistic results; the others are called for real beforehand.
        With ``further``, instances also offer the outputs of later calls (:meth:`_further`);
        without, ``more_calls`` only says whether some instance could. ``check_time`` is
        called every so often (it raises when the solve's time is up: a world can grow large)."""
        engine = self.engine
        facts = engine.planning_facts()
        if engine.hidden:
            store = FactStore()
            for atom, level in facts.items():
                store.add(atom, level)
        else:  # every real fact: a copy of the engine's store (the same orders)
            store = engine.store.copy()
        numeric = OptimisticCosts(
            engine.numeric, frozenset(self.assumed.functions), self.names.deferred
        )
        world = OptimisticWorld(dict(facts), {}, numeric)
        for atom in engine.refuted:
            world.facts[refuted_fact(atom)] = 0
        assumed = self.assumed.names()
        queries = [
            Query(s.name, s.declaration.inputs, s.declaration.domain)
            for s in engine.streams.values()
        ]
        queries += [
            Query(f.name, f.declaration.inputs, f.declaration.domain)
            for f in engine.functions.values()
            # a negated predicate adds nothing here: real values come from the engine and
            # placeholders are optimistically false; deferred ones are assumed by the domain
            if not (f.is_predicate and f.name in self.negated) and f.name not in assumed
        ]
        queries += [Query(n, r.parameters, r.domain) for n, r in engine.rules.items()]
        instantiator = Instantiator(queries, store)
        # functions on real facts alone: the engine evaluated them or holds them deferred
        functions = {q.name: q for q in queries if q.name in engine.functions}
        # Instances and results are taken lowest level first (a level is never below the
        # levels it rests on), so every fact enters at the lowest level any instance gives it:
        # a shared placeholder made by instances on facts of several levels, and every
        # instance on it, takes the lowest (in the order found, one on a late sample could
        # fix it above the limit and leave out all that rests on it).
        queue: list[tuple[int, int, OptResult | tuple[str, tuple[str, ...]]]] = []
        order = itertools.count()

        def push(level: int, item: OptResult | tuple[str, tuple[str, ...]]) -> None:
            heapq.heappush(queue, (level, -next(order), item))  # (the latest first on ties)

        for query, inputs, level in instantiator.initial(skip=functions):
            push(level, (query.name, inputs))
        steps = 0
        while queue:
            steps += 1
            if check_time is not None and steps % 256 == 0:
                check_time()
            level, _, item = heapq.heappop(queue)
            if isinstance(item, OptResult):
                for atom in item.certified:
                    if store.add(atom, item.level):
                        world.facts[atom] = item.level
                        world.provenance[atom] = item
                        for query, inputs, found in instantiator.new_fact(atom):
                            push(found, (query.name, inputs))
                continue
            name, inputs = item
            results = self._results(name, inputs, level, limit, world, lazy)
            more = self._further(results, limit, world, further)
            for result in results:  # what rests on a later call's output is "later" too
                if any(n in self._later for n in result.inputs):
                    self._later.update(result.outputs)
            for result in [*results, *more]:
                push(result.level, result)
        world.placeholders = sorted(
            {n for atom in world.provenance for n in atom.args if is_placeholder(n)}
        )
        return world

    def _results(
        self,
        name: str,
        inputs: tuple[str, ...],
        level: int,
        limit: int,
        world: OptimisticWorld,
        lazy: bool,
    ) -> list[OptResult]:
        engine = self.engine
        real = not any(is_placeholder(n) for n in inputs)
        if name in engine.streams:
            external = engine.streams[name]
            if lazy and real and not external.declaration.fluents:
                return []
            if name in self.pruned:
                return []  # p_success=0: only its real (eager) results count
            state = engine.instance(name, inputs) if real else None
            next_level = level + first_call_level(external)
            if state is not None:
                # a fluent instance exhausted in one state may still produce in another
                if state.instance.exhausted and not external.declaration.fluents:
                    return []
                if state.instance.disabled:
                    world.complete = False
                    return []
                next_level = level + engine.calls(state) + first_call_level(external)
            if next_level > limit:
                self._left_out(inputs, world)
                world.next_level = min(world.next_level, next_level)
                return []
            generator = external.info.opt_gen_fn
            if callable(generator) and external.declaration.outputs:
                batches = self.names.generated(external, inputs, generator)
            else:
                shared = generator == "shared" and name not in self.refined
                outputs = tuple(
                    self.placeholder((name, i) if shared else (name, inputs, i))
                    for i in range(len(external.declaration.outputs))
                )
                if shared:
                    self._shared.update(outputs)
                batches = [outputs]
            return [
                OptResult(
                    name,
                    inputs,
                    outputs,
                    *self._stream_atoms(external, inputs, outputs),
                    next_level,
                    "stream",
                )
                for outputs in batches
            ]
        if name in engine.functions:
            function = engine.functions[name]
            if not real:
                return self._function(function, inputs, level, world)
            return []  # evaluated for real by the engine
        key = (name, inputs, ())
        atoms = self._atoms.get(key)
        if atoms is None:
            rule = engine.rules[name]
            mapping = dict(zip(rule.parameters, inputs, strict=True))
            atoms = self._atoms[key] = (
                tuple(ground_atom(a, mapping) for a in rule.domain),
                tuple(ground_atom(a, mapping) for a in rule.certified),
            )
        domain, certified = atoms
        if real and all(a in engine.store for a in domain):
            return []  # rules on real facts were applied by the engine
        return [OptResult(name, inputs, (), domain, certified, level, "rule")]

    def _stream_atoms(
        self, external: StreamExternal, inputs: tuple[str, ...], outputs: tuple[str, ...]
    ) -> tuple[tuple[Atom, ...], tuple[Atom, ...]]:
        """The domain and certified facts of a stream on ``inputs`` giving ``outputs``."""
        key = (external.name, inputs, outputs)
        atoms = self._atoms.get(key)
        if atoms is None:
            atoms = self._atoms[key] = (
                external.domain(inputs),
                external.certified(inputs, outputs),
            )
        return atoms

    def refine(self, stream_plan: list[OptResult]) -> bool:
        """Give every instance of the streams behind the ambiguous shared placeholders of
        ``stream_plan`` placeholders of its own in later builds; False when there is none (the
        plan binds as it is).

        A shared placeholder is ambiguous when two results of the plan make it (the plan takes
        the outputs of two instances for one value) or when a result takes its own output as
        an input. One that a single result of the plan makes stands for that result's output
        alone (every fact of the plan on it rests on that result): binding gives it one value,
        so the plan needs no new search.
        """
        results = [r for r in stream_plan if r.kind == "stream"]
        producers: dict[str, set[tuple[str, tuple[str, ...]]]] = {}
        for result in results:
            for name in result.outputs:
                if name in self._shared:
                    producers.setdefault(name, set()).add((result.external, result.inputs))
        ambiguous = {n for n, made in producers.items() if len(made) > 1}
        ambiguous.update(n for r in results for n in r.outputs if n in r.inputs)
        found = {r.external for r in results if any(n in ambiguous for n in r.outputs)}
        new = found - self.refined
        self.refined.update(new)
        return bool(new)

    def _left_out(self, inputs: tuple[str, ...], world: OptimisticWorld) -> None:
        """An instance was left out for the limit. On an output of a later call it stands
        for one on the first call's output (:meth:`_further`), so it counts as those calls."""
        if any(n in self._later for n in inputs):
            world.more_calls = True
        else:
            world.complete = False

    def _further(
        self, results: list[OptResult], limit: int, world: OptimisticWorld, wanted: bool
    ) -> list[OptResult]:
        """New outputs of later calls of the instances behind ``results``.

        A placeholder stands for the next new output of its instance; a plan may need more
        than one (two distinct values of a stream without inputs, say). The instance's ``k``-th
        later call gives outputs of level ``level + k``, offered while that is within ``limit``
        (the level incremental reaches by calling the instance ``k`` more times). Not for tests,
        single-answer adapters (``from_fn``), fluent streams or placeholder inputs.
        """
        further: list[OptResult] = []
        for result in results:
            if result.kind != "stream" or not result.outputs:
                continue
            external = self.engine.streams[result.external]
            if (
                external.declaration.fluents
                or getattr(external.gen_fn, SINGLE_CALL, False)
                or callable(external.info.opt_gen_fn)
                or any(is_placeholder(n) for n in result.inputs)
            ):
                continue
            if not wanted:
                world.more_calls = True
                world.next_level = min(world.next_level, result.level + 1)
                world.further_level = min(world.further_level, result.level + 1)
                continue
            shared = external.info.opt_gen_fn == "shared"
            k = 1
            while True:
                level = result.level + k
                if level > limit:
                    world.more_calls = True
                    world.next_level = min(world.next_level, level)
                    break
                base: tuple[object, ...] = (
                    (result.external,) if shared else (result.external, result.inputs)
                )
                outputs = tuple(self.placeholder((*base, i, k)) for i in range(len(result.outputs)))
                self._later.update(outputs)
                _, certified = self._stream_atoms(external, result.inputs, outputs)
                further.append(
                    OptResult(
                        result.external,
                        result.inputs,
                        outputs,
                        result.domain,
                        certified,
                        level,
                        "stream",
                    )
                )
                k += 1
        return further

    def _function(
        self,
        function: FunctionExternal,
        inputs: tuple[str, ...],
        level: int,
        world: OptimisticWorld,
    ) -> list[OptResult]:
        if function.is_predicate and function.name in self.negated:
            return []  # optimistically false: a negated use must not be blocked by a guess
        key = (function.name, inputs, ())
        atoms = self._atoms.get(key)
        if atoms is None:
            atoms = self._atoms[key] = (function.domain(inputs), ())
        domain = atoms[0]
        if function.is_predicate:
            return [
                OptResult(
                    function.name,
                    inputs,
                    (),
                    domain,
                    (Atom(function.name, inputs),),
                    level,
                    "predicate",
                )
            ]
        world.numeric[(function.name, inputs)] = self.names.function_value(function, inputs)
        return [
            OptResult(
                function.name,
                inputs,
                (),
                domain,
                (Atom(function_guard(function.name), inputs),),
                level,
                "function",
            )
        ]
