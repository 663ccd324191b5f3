"""The state every stream algorithm shares: externals, known (real) facts, stream instances.

Real facts have complexity levels: init facts are level 0; a result of an instance whose domain
facts reach level ``d`` and that was called ``k`` times before has level ``d + k + 1``, or
``d + k`` for a test (a stream without outputs: its first answer makes nothing new).
``:rule`` facts are added at once. ``:function`` and ``:predicate`` instances (and negated tests,
which become predicates) are *deferred* when the engine is made with ``defer=True`` (the
optimistic algorithms): an instance whose domain holds is only recorded (:attr:`Engine.deferred`),
the optimistic world gives it its optimistic value, and :meth:`Engine.evaluate` calls it for real
when a candidate plan uses it (:mod:`.deferred`). Those are evaluated at once instead: with
``eager=True`` in their ``StreamInfo``/``FunctionInfo``, every one without ``defer`` (incremental
plans on real facts only), and predicates the domain uses negated (a plan relies on their
absence, which no plan check can name).

A ``:fluents`` stream has one instance per input tuple and fluent state. The instance made when
its domain first holds sees the initial state's facts of its fluent predicates; the algorithms
ask for more (:meth:`Engine.fluent_instance`) with the state of the plan step that uses the
output. What such an instance certifies holds in that state only: those facts are kept in the
store (streams on the outputs are instantiated) but are *hidden* from planning
(:meth:`Engine.planning_facts`); a plan may use them only at a step whose state has exactly the
instance's fluent facts (:meth:`Engine.certified_in`).

Every user call goes through the engine's :class:`CallRunner` (the solve's deadline); the
initial facts, which may call user code, are added by :meth:`Engine.start`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import Atom, FunctionTerm, IncreaseCost
from sdar_tamp.language.numeric import numeric_terms
from sdar_tamp.language.objects import ObjectTable
from sdar_tamp.language.options import FunctionInfo, StreamInfo, unsupported_options
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.language.stream_model import Rule, StreamFunction, StreamPredicate
from sdar_tamp.language.traversal import iter_effects
from sdar_tamp.logs import get_logger
from solvers.stream_planning.calls import CallRunner
from solvers.stream_planning.externals import (
    FunctionExternal,
    StreamExternal,
    StreamInstance,
    debug_gen_fn,
)
from solvers.stream_planning.facts import FactStore, Instantiator, Query
from solvers.stream_planning.negation import split_negated

LOG = get_logger(__name__)
# Options every solver acts on; any other option set to a non-default value is logged as
# not implemented (simultaneous, defer_fn, ...). p_success, overhead and effort act through
# solve(effort_weight=...). The stream algorithms also act on negate (see negation.py).
SUPPORTED_STREAM_OPTIONS = {"opt_gen_fn", "eager", "p_success", "overhead", "effort"}
#: Calls of eager stream instances one engine makes at most (a generator feeding its own
#: inputs would otherwise never stop).
EAGER_BUDGET = 10_000
SUPPORTED_FUNCTION_OPTIONS = {"opt_fn", "eager"}
RULE_PREFIX = "@rule"


def function_guard(name: str) -> str:
    """The predicate that says a function's value is known for some arguments."""
    return f"@fn:{name}"


@dataclass(frozen=True)
class InstanceState:
    """A pending stream instance and the level of its domain facts."""

    instance: StreamInstance
    domain_level: int

    @property
    def next_level(self) -> int:
        return self.domain_level + self.instance.calls + first_call_level(self.instance.external)


def first_call_level(external: StreamExternal) -> int:
    """What a stream's first call adds to the level of its domain facts: 1 for a stream with
    outputs, 0 for a test (it makes no new object; as in PDDLStream, a test does not make its
    facts more complex). Each further call adds 1."""
    return 1 if external.declaration.outputs else 0


class Engine:
    """Real facts and stream instances of one solve (call :meth:`start` before using it)."""

    def __init__(
        self,
        problem: PDDLProblem,
        stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
        runner: CallRunner | None = None,
        defer: bool = False,
        negated: frozenset[str] = frozenset(),
    ) -> None:
        self.problem = problem
        self.defer = defer
        self.negated = negated  # predicates the domain uses negated: never deferred
        # (function or predicate, inputs) -> level: instances whose domain holds, not evaluated
        self.deferred: dict[tuple[str, tuple[str, ...]], int] = {}
        self.refuted: set[Atom] = set()  # deferred predicate instances evaluated false
        self.runner = runner if runner is not None else CallRunner()
        self.table: ObjectTable = problem.objects.copy()
        self._eager: list[InstanceState] = []  # eager instances not called yet
        self._draining = False
        self.eager_calls = 0
        streams_bound, functions = bind_externals(
            problem, stream_info, SUPPORTED_STREAM_OPTIONS | {"negate"}
        )
        debug = isinstance(problem.stream_map, str)
        self.streams, negated_tests = split_negated(streams_bound, functions, debug)
        functions.update(negated_tests)
        used = cost_functions(problem.domain)
        # a :function no action's cost mentions cannot change a plan: it is never evaluated
        self.functions = {
            name: f for name, f in functions.items() if f.is_predicate or name in used
        }
        streams = problem.streams
        self.rules = {f"{RULE_PREFIX}{i}": rule for i, rule in enumerate(streams.rules)}
        # predicates some external needs in its domain: never deferred (what follows from
        # them must follow in the optimistic world too)
        self._needed = frozenset(
            a.predicate
            for declaration in (
                *(s.declaration for s in self.streams.values()),
                *(f.declaration for f in self.functions.values()),
                *self.rules.values(),
            )
            for a in declaration.domain
        )
        self._evaluated_at_once = negated | self._needed
        self.store = FactStore()
        self.numeric: dict[tuple[str, tuple[str, ...]], float] = dict(problem.facts.numeric)
        self.instances: dict[tuple[str, tuple[str, ...]], InstanceState] = {}
        # the keys of ``instances`` in creation order (a consumer keeps its own cursor)
        self.instance_keys: list[tuple[str, tuple[str, ...]]] = []
        # fluent instances for states other than the initial one, and the calls made on all
        # instances of a (fluent stream, inputs) pair: the pair's complexity counts them all
        self.variants: dict[tuple[str, tuple[str, ...], tuple[Atom, ...]], InstanceState] = {}
        self.fluent_calls: dict[tuple[str, tuple[str, ...]], int] = {}
        # facts only fluent instances certified, and the (stream, fluent facts) of each source
        self.hidden: set[Atom] = set()
        self.fluent_sources: dict[Atom, set[tuple[str, frozenset[Atom]]]] = {}
        queries = [
            Query(s.name, s.declaration.inputs, s.declaration.domain) for s in self.streams.values()
        ]
        queries += [
            Query(f.name, f.declaration.inputs, f.declaration.domain)
            for f in self.functions.values()
        ]
        queries += [Query(name, rule.parameters, rule.domain) for name, rule in self.rules.items()]
        self.instantiator = Instantiator(queries, self.store)
        for atom in sorted(problem.facts.init, key=str):
            self.store.add(atom, 0)
        for key in self.numeric:
            self.store.add(Atom(function_guard(key[0]), key[1]), 0)

    def start(self) -> None:
        """Instantiate what the initial facts allow: evaluates functions and predicates and
        calls eager streams (user code: may raise :class:`CallTimeout`)."""
        self.add_facts(self._instantiate(self.instantiator.initial()), 0)

    # --- adding facts ---------------------------------------------------------------------

    def add_facts(self, atoms: Iterable[Atom], level: int, hidden: bool = False) -> list[Atom]:
        """Add real facts and everything that follows at once (instances, rules, functions,
        and one call of every new instance of an ``eager`` stream). ``hidden``: ``atoms``
        hold in one fluent state only (a fact known otherwise too is not hidden)."""
        new: list[Atom] = []
        given = list(atoms)
        for atom in given:
            if not hidden:
                self.hidden.discard(atom)
            elif atom not in self.store:
                self.hidden.add(atom)
        pending = given
        while pending:
            atom = pending.pop()
            if self.store.add(atom, level):
                new.append(atom)
                pending.extend(self._instantiate(self.instantiator.new_fact(atom)))
        if not self._draining:
            self._draining = True
            try:
                while self._eager and self.eager_calls < EAGER_BUDGET:
                    self.eager_calls += 1
                    self.sample(self._eager.pop(0))
            finally:
                self._draining = False
        return new

    def _instantiate(self, found: Iterable[tuple[Query, tuple[str, ...], int]]) -> list[Atom]:
        derived: list[Atom] = []
        for query, inputs, level in found:
            if query.name in self.streams:
                stream = self.streams[query.name]
                instance = StreamInstance(stream, inputs, self._fluents(stream))
                state = InstanceState(instance, level)
                self.instances[(query.name, inputs)] = state
                self.instance_keys.append((query.name, inputs))
                if stream.info.eager:
                    self._eager.append(state)
            elif query.name in self.functions:
                external = self.functions[query.name]
                if self.defers(external):
                    self.deferred[(query.name, inputs)] = level
                else:
                    derived.extend(self._value(external, inputs))
            else:
                rule: Rule = self.rules[query.name]
                mapping = dict(zip(rule.parameters, inputs, strict=True))
                derived.extend(
                    Atom(a.predicate, tuple(mapping.get(t, t) for t in a.args))
                    for a in rule.certified
                )
        return derived  # rules and predicates take the level of the fact that completed them

    def defers(self, external: FunctionExternal) -> bool:
        """Is a function or predicate evaluated only when a plan uses it?"""
        if not self.defer or external.info.eager:
            return False
        return not (external.is_predicate and external.name in self._evaluated_at_once)

    def _value(self, external: FunctionExternal, inputs: tuple[str, ...]) -> list[Atom]:
        """Evaluate a function or predicate instance: the facts its value makes known."""
        value = external.evaluate(inputs, self.table, self.runner)
        if external.is_predicate:
            return [Atom(external.name, inputs)] if value else []
        self.numeric[(external.name, inputs)] = float(value)
        return [Atom(function_guard(external.name), inputs)]

    def evaluate(self, name: str, inputs: tuple[str, ...]) -> bool:
        """Evaluate a deferred instance for real (its facts join the store); False when it is
        not deferred (unknown, or evaluated before). User code: may raise
        :class:`CallTimeout`."""
        level = self.deferred.pop((name, inputs), None)
        if level is None:
            return False
        external = self.functions[name]
        self.add_facts(self._value(external, inputs), level)
        if external.is_predicate and Atom(name, inputs) not in self.store:
            self.refuted.add(Atom(name, inputs))
        return True

    def _fluents(self, external: StreamExternal) -> tuple[Atom, ...]:
        """The initial state's facts of a stream's ``:fluents`` (what its first instance sees)."""
        wanted = set(external.declaration.fluents)
        if not wanted:
            return ()
        return tuple(sorted((a for a in self.problem.facts.init if a.predicate in wanted), key=str))

    # --- sampling -------------------------------------------------------------------------

    def sample(self, state: InstanceState) -> bool:
        """Call one instance once; True when it produced an output (or, for a test, passed)."""
        instance = state.instance
        level = state.next_level
        if instance.external.declaration.fluents:
            key = (instance.external.name, instance.inputs)
            calls = self.fluent_calls.get(key, 0)
            level = state.domain_level + calls + first_call_level(instance.external)
            self.fluent_calls[key] = self.fluent_calls.get(key, 0) + 1
        results, wild = instance.next(self.table, self.runner)
        facts = [atom for result in results for atom in result.certified]
        if instance.external.declaration.fluents:
            source = (instance.external.name, frozenset(instance.fluents))
            for atom in facts:
                self.fluent_sources.setdefault(atom, set()).add(source)
            self.add_facts(facts, level, hidden=True)
            self.add_facts(wild, level)
        else:
            self.add_facts([*facts, *wild], level)
        return bool(results)

    def planning_facts(self) -> dict[Atom, int]:
        """The real facts a plan may use in any state (all but the hidden ones)."""
        if not self.hidden:
            return self.store.levels
        return {a: level for a, level in self.store.levels.items() if a not in self.hidden}

    def certified_in(self, atom: Atom, state: Iterable[Atom]) -> bool:
        """Does ``atom`` hold in ``state``: known in every state, or certified by a fluent
        instance that saw exactly ``state``'s facts of its fluent predicates?"""
        if atom not in self.hidden:
            return atom in self.store
        facts = frozenset(state)
        for stream, fluents in self.fluent_sources.get(atom, ()):
            wanted = set(self.streams[stream].declaration.fluents)
            if fluents == frozenset(a for a in facts if a.predicate in wanted):
                return True
        return False

    def instance(self, name: str, inputs: tuple[str, ...]) -> InstanceState | None:
        return self.instances.get((name, inputs))

    def fluent_instance(
        self, name: str, inputs: tuple[str, ...], fluents: tuple[Atom, ...]
    ) -> InstanceState | None:
        """The instance of a fluent stream on ``inputs`` that sees ``fluents`` (real facts of
        its fluent predicates, sorted); None when its domain does not hold."""
        base = self.instances.get((name, inputs))
        if base is None or base.instance.fluents == fluents:
            return base
        key = (name, inputs, fluents)
        state = self.variants.get(key)
        if state is None:
            instance = StreamInstance(base.instance.external, inputs, fluents)
            state = self.variants[key] = InstanceState(instance, base.domain_level)
        return state

    def calls(self, state: InstanceState) -> int:
        """Calls that count for an instance's complexity: for a fluent stream, those made in
        every state."""
        instance = state.instance
        if not instance.external.declaration.fluents:
            return instance.calls
        return self.fluent_calls.get((instance.external.name, instance.inputs), 0)

    def disable(self, state: InstanceState) -> None:
        """Disable an instance until the complexity level rises (a fluent instance's failure
        is recorded as a block instead: :mod:`.blocking`)."""
        state.instance.disabled = True


def cost_functions(domain: Domain) -> frozenset[str]:
    """Names of the functions that appear in some action's cost increase, numeric conditions
    or numeric effects."""
    return frozenset(
        e.amount.name
        for action in domain.actions
        for e in iter_effects(action.effect)
        if isinstance(e, IncreaseCost) and isinstance(e.amount, FunctionTerm)
    ) | frozenset(t.name for action in domain.actions for t in numeric_terms(action))


def bind_externals(
    problem: PDDLProblem,
    stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
    supported: set[str] = SUPPORTED_STREAM_OPTIONS,
) -> tuple[dict[str, StreamExternal], dict[str, FunctionExternal]]:
    """The problem's streams and functions bound to their callables (or the debug ones);
    stream options outside ``supported`` are logged as not implemented."""
    info = {k.lower(): v for k, v in (stream_info or {}).items()}
    _warn_unsupported(info, supported)
    debug = isinstance(problem.stream_map, str)
    functions = problem.stream_functions
    streams = problem.streams
    bound = {
        s.name: StreamExternal(
            s,
            debug_gen_fn(s) if debug else functions[s.name],
            _as_stream_info(info.get(s.name)),
        )
        for s in streams.streams
    }
    externals: dict[str, FunctionExternal] = {}
    declarations: list[StreamFunction | StreamPredicate] = [
        *streams.functions,
        *streams.predicates,
    ]
    for decl in declarations:
        fn: Callable[..., Any]
        if not debug:
            fn = functions[decl.name]
        elif isinstance(decl, StreamFunction):
            fn = _debug_cost
        else:
            fn = _debug_predicate
        externals[decl.name] = FunctionExternal(decl, fn, info.get(decl.name) or FunctionInfo())
    return bound, externals


def _debug_cost(*_inputs: Any) -> float:
    return 1.0


def _debug_predicate(*_inputs: Any) -> bool:
    return False


def _as_stream_info(info: StreamInfo | FunctionInfo | None) -> StreamInfo:
    return info if isinstance(info, StreamInfo) else StreamInfo()


def _warn_unsupported(
    info: Mapping[str, StreamInfo | FunctionInfo], stream_options: set[str]
) -> None:
    for name, options in info.items():
        supported = (
            stream_options if isinstance(options, StreamInfo) else SUPPORTED_FUNCTION_OPTIONS
        )
        for option in unsupported_options(options, supported):
            LOG.warning(
                "stream_info[%r].%s is accepted but not implemented; it has no effect", name, option
            )
