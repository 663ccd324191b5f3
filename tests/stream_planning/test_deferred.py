"""Deferred tests and functions: evaluated for the candidate plan's instances only (or all at
once with ``eager=True``), on domains whose combinations explode."""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from typing import Any

import pytest

from domains.nav_manip_2d.samplers import make_problem, stream_info
from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.generators import from_test
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.problem import PDDLProblem
from solvers.solve import solve
from solvers.stream_planning.context import SolveContext
from solvers.stream_planning.externals import StreamError
from solvers.stream_planning.options import StreamOptions

# A row of slots; a robot carries object ``a`` from the start to a slot on the shelf, where the
# obstacles stand. A slot is free when it is at least 1 apart from every obstacle at the shelf;
# handling costs depend on four arguments.
DOMAIN = """
(define (domain slots)
  (:requirements :strips :equality :negative-preconditions :derived-predicates
                 :existential-preconditions :action-costs)
  (:predicates (Obj ?o) (Slot ?p) (Shelf ?p) (AtPose ?o ?p) (Holding ?o) (HandEmpty)
               (CFree ?o ?p ?o2 ?p2) (Unsafe ?o ?p) (Done ?o))
  (:functions (total-cost) (Handling ?o ?p ?o2 ?p2))
  (:derived (Unsafe ?o ?p)
    (exists (?o2 ?p2) (and (Obj ?o) (Slot ?p) (Obj ?o2) (Slot ?p2) (AtPose ?o2 ?p2)
                           (not (= ?o ?o2)) (not (CFree ?o ?p ?o2 ?p2)))))
  (:action pick :parameters (?o ?p)
    :precondition (and (Obj ?o) (AtPose ?o ?p) (HandEmpty))
    :effect (and (Holding ?o) (not (AtPose ?o ?p)) (not (HandEmpty)) (increase (total-cost) 1)))
  (:action place :parameters (?o ?p ?o2 ?p2)
    :precondition (and (Holding ?o) (Shelf ?p) (AtPose ?o2 ?p2) (not (= ?o ?o2))
                       (not (Unsafe ?o ?p)))
    :effect (and (AtPose ?o ?p) (Done ?o) (HandEmpty) (not (Holding ?o))
                 (increase (total-cost) (Handling ?o ?p ?o2 ?p2)))))
"""
STREAMS = """
(define (stream slots)
  (:stream test-cfree :inputs (?o ?p ?o2 ?p2)
    :domain (and (Obj ?o) (Slot ?p) (Obj ?o2) (Slot ?p2))
    :certified (CFree ?o ?p ?o2 ?p2))
  (:function (Handling ?o ?p ?o2 ?p2) (and (Obj ?o) (Slot ?p) (Obj ?o2) (Slot ?p2))))
"""
OBSTACLES = {"b": 10, "c": 14}  # obstacle -> its slot
SLOTS = 20  # slots 0..19; the shelf is slots 8..19


def slots_problem(
    calls: list[tuple[Any, ...]], costs: list[tuple[Any, ...]], cost_fn: Callable[..., float]
) -> PDDLProblem:
    def cfree(o: str, p: int, o2: str, p2: int) -> bool:
        calls.append((o, p, o2, p2))
        return o == o2 or abs(p - p2) >= 2

    def handling(*args: Any) -> float:
        costs.append(args)
        return cost_fn(*args)

    init: list[tuple[Any, ...]] = [("HandEmpty",), ("Obj", "a"), ("AtPose", "a", 0)]
    init += [("Slot", p) for p in range(SLOTS)]
    init += [("Shelf", p) for p in range(8, SLOTS)]
    for obstacle, slot in OBSTACLES.items():
        init += [("Obj", obstacle), ("AtPose", obstacle, slot)]
    return PDDLProblem(
        DOMAIN,
        {},
        STREAMS,
        {"test-cfree": from_test(cfree), "handling": handling},
        init,
        ("Done", "a"),
    )


def combinations() -> int:
    """Input tuples whose domain holds, for the test and for the cost (the same domain)."""
    return (len(OBSTACLES) + 1) ** 2 * SLOTS**2


def check_plan(plan: list[Any]) -> None:
    place = [a for a in plan if a.name == "place"]
    assert len(place) == 1
    slot = place[0].args[1]
    assert 8 <= slot < SLOTS
    assert all(abs(slot - p) >= 2 for p in OBSTACLES.values())


@pytest.mark.parametrize("algorithm", ["focused", "binding", "adaptive"])
def test_deferred_test_and_cost_are_called_for_the_plan_only(algorithm: str) -> None:
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []
    problem = slots_problem(calls, costs, lambda *_a: 1.0)
    info = {"test-cfree": StreamInfo(eager=False, negate=True)}
    solution = solve(problem, algorithm=algorithm, stream_info=info, max_time=60, verbose=False)
    assert solution.solved
    check_plan(solution.plan or [])
    # every combination is an instance; a few are called: those of the plans tried and, when
    # one fails, a batch of its siblings (about as many as the real facts known)
    assert len(calls) <= combinations() // 10
    assert len(costs) <= 4
    assert len(set(calls)) == len(calls)  # each instance at most once (cached)
    # the test was asked about the chosen slot against each obstacle
    slot = next(a.args[1] for a in solution.plan or [] if a.name == "place")
    asked = {(o2, p2) for o, p, o2, p2 in calls if p == slot}
    assert asked == set(OBSTACLES.items())
    assert solution.streams["test-cfree"].calls == len(calls)
    assert solution.streams["handling"].calls == len(costs)


def test_the_optimistic_world_holds_no_deferred_instance() -> None:
    """Deferred tests and costs add nothing per instance to the optimistic world: the search's
    domain assumes them; a refuted instance adds one fact, which blocks it in the next search."""
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []
    problem = slots_problem(calls, costs, lambda *_a: 1.0)
    context = SolveContext(problem, StreamOptions(), {"test-cfree": StreamInfo(negate=True)})
    engine = context.engine
    engine.start()
    assert len(engine.deferred) == 2 * combinations()  # recorded, not called
    world = context.builder.build(0)
    assert set(world.facts) == set(engine.store.levels)
    key = next(k for k in engine.deferred if k[0] == "handling")
    assert key in world.numeric and world.numeric[key] == 1.0  # its optimistic value
    assert not costs
    # `a` on slot 10 collides with `b` on slot 10: evaluated, it is refuted
    name = engine.table.name
    inputs = (name("a"), name(10), name("b"), name(10))
    assert engine.evaluate("cfree", inputs)
    assert calls == [("a", 10, "b", 10)]
    assert engine.refuted == {Atom("cfree", inputs)}
    world = context.builder.build(0)
    assert set(world.facts) - set(engine.store.levels) == {Atom("@refuted:cfree", inputs)}
    # the search's domain reads (CFree ...) as its domain facts and "not refuted"
    unsafe = next(a for a in context.domain.axioms if a.predicate == "unsafe")
    assert "@refuted:cfree" in str(unsafe.body) and "(cfree " not in str(unsafe.body)


def test_a_predicate_a_stream_domain_needs_is_not_deferred() -> None:
    """What follows from a predicate (a stream on its facts) must follow optimistically too:
    such a predicate is evaluated as soon as its domain holds."""
    streams = STREAMS.replace(
        "(:function (Handling",
        "(:stream mark :inputs (?o ?p ?o2 ?p2) :domain (CFree ?o ?p ?o2 ?p2) "
        ":outputs (?m) :certified (Obj ?m))\n  (:function (Handling",
    )
    problem = slots_problem([], [], lambda *_a: 1.0)
    assert isinstance(problem.stream_map, dict)
    problem = PDDLProblem(
        problem.domain_pddl,
        {},
        streams,
        {**problem.stream_map, "mark": lambda *_a: iter(())},
        problem.init,
        problem.goal,
    )
    context = SolveContext(problem, StreamOptions(), {"test-cfree": StreamInfo(negate=True)})
    assert not context.assumed.predicates and set(context.assumed.functions) == {"handling"}


def test_eager_evaluates_every_combination() -> None:
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []
    problem = slots_problem(calls, costs, lambda *_a: 1.0)
    info: dict[str, StreamInfo | FunctionInfo] = {
        "test-cfree": StreamInfo(eager=True, negate=True),
        "handling": FunctionInfo(eager=True),
    }
    solution = solve(problem, algorithm="adaptive", stream_info=info, verbose=False)
    assert solution.solved
    check_plan(solution.plan or [])
    assert len(calls) == len(costs) == combinations()


def test_incremental_evaluates_every_combination() -> None:
    """Incremental plans on real facts only: nothing is deferred there."""
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []
    problem = slots_problem(calls, costs, lambda *_a: 1.0)
    info = {"test-cfree": StreamInfo(negate=True)}
    solution = solve(problem, algorithm="incremental", stream_info=info, verbose=False)
    assert solution.solved
    assert len(calls) == len(costs) == combinations()


def test_a_failed_deferred_test_is_planned_around() -> None:
    """The first slot the planner tries next to an obstacle fails its test; the solve goes on
    to a free one, never asking the same instance twice."""
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []
    problem = slots_problem(calls, costs, lambda *_a: 1.0)
    info = {"test-cfree": StreamInfo(negate=True)}
    solution = solve(problem, algorithm="adaptive", stream_info=info, verbose=False)
    assert solution.solved
    check_plan(solution.plan or [])
    failed = [c for c in calls if abs(c[1] - c[3]) < 2 and c[0] != c[2]]
    slot = next(a.args[1] for a in solution.plan or [] if a.name == "place")
    assert all(c[1] != slot for c in failed)
    assert len(set(calls)) == len(calls)


def test_a_cost_dearer_than_assumed_makes_the_search_look_for_a_cheaper_plan() -> None:
    """Handling costs 1 + distance to the nearest obstacle: the first plan's real cost is
    above its optimistic one, so the solve searches again with the values known and ends with
    a plan no dearer than the first."""
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []

    def handling(o: str, p: int, o2: str, p2: int) -> float:
        return 1.0 + abs(p - p2)

    problem = slots_problem(calls, costs, handling)
    info = {"test-cfree": StreamInfo(negate=True)}
    solution = solve(problem, algorithm="focused", stream_info=info, verbose=False)
    assert solution.solved
    check_plan(solution.plan or [])
    place = next(a for a in solution.plan or [] if a.name == "place")
    first = costs[0]
    assert solution.cost <= 1.0 + (1.0 + abs(first[1] - first[3]))
    assert solution.cost == 1.0 + handling(*place.args)
    assert len(costs) < combinations()


def test_a_deferred_function_that_raises_names_itself() -> None:
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []

    def broken(*_args: Any) -> float:
        raise ValueError("no reach")

    problem = slots_problem(calls, costs, broken)
    with pytest.raises(StreamError, match=r"function 'handling' on inputs \('a', .*no reach"):
        solve(problem, algorithm="adaptive", verbose=False)


def test_a_deferred_function_with_a_negative_value_is_refused() -> None:
    calls: list[tuple[Any, ...]] = []
    costs: list[tuple[Any, ...]] = []
    problem = slots_problem(calls, costs, lambda *_a: -1.0)
    with pytest.raises(StreamError, match="non-negative"):
        solve(problem, algorithm="binding", verbose=False)


class _StoppedClock:
    """The ``time`` module as the solve's context reads it, its clock stopped when made: the
    bounds the solver measures in seconds (sweeps, drains, the queue's share) never apply, so
    the counts follow from the seed whatever the machine's load (the deadline of the calls,
    read on the real clock, stays ``max_time`` from then)."""

    def __init__(self) -> None:
        self.now = time.perf_counter()

    def perf_counter(self) -> float:
        return self.now


@pytest.mark.parametrize("mode", ["negate", "auto"])
def test_navigation_and_manipulation_calls_follow_the_plan(
    mode: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The 2-D house: a path stream, a placement stream, a 4-argument collision test
    (``negate=True``, or negated automatically as in PDDLStream's namo) and a 4-argument cost.
    Deferred, the test and the costs are called a few times; eager, on every combination."""
    from solvers.stream_planning import context as context_module

    monkeypatch.setattr(context_module, "time", _StoppedClock())
    deferred = solve(
        make_problem(seed=1, clutter=2),
        algorithm="adaptive",
        stream_info=stream_info(mode),
        search_sample_ratio=0.5,
        max_time=120,
        verbose=False,
    )
    assert deferred.solved
    test = deferred.streams["test-collision-free"].calls
    cost = deferred.streams["handlingcost"].calls
    eager = solve(
        make_problem(seed=1, clutter=2),
        algorithm="adaptive",
        stream_info=stream_info("eager"),
        search_sample_ratio=0.5,
        max_time=120,
        verbose=False,
    )
    assert eager.solved
    assert test * 100 < eager.streams["test-collision-free"].calls
    assert cost * 10 < eager.streams["handlingcost"].calls
    assert math.isfinite(deferred.cost)


def test_stream_info_modes_are_checked() -> None:
    with pytest.raises(ValueError, match="mode must be one of"):
        stream_info("lazy")


def test_combinations_grow_as_the_product() -> None:
    """The count the assertions above compare with is the product of the domain's facts."""
    objects = ["a", *OBSTACLES]
    found = sum(1 for _ in itertools.product(objects, range(SLOTS), objects, range(SLOTS)))
    assert found == combinations()


def test_endless_placements_are_drawn_from_the_seed() -> None:
    from domains.nav_manip_2d.samplers import House

    first = list(itertools.islice(House(3).sample_place("shelf", "m"), 5))
    again = list(itertools.islice(House(3).sample_place("shelf", "m"), 5))
    assert first == again
    assert len({p for (p,) in first}) == 5


def test_the_plan_check_view_assumes_what_the_search_assumes() -> None:
    """The view a candidate plan is simulated on holds an assumed atom exactly when its domain
    holds and it is not refuted; its known atoms are not offered as the only candidates."""
    problem = slots_problem([], [], lambda *_a: 1.0)
    context = SolveContext(problem, StreamOptions(), {"test-cfree": StreamInfo(negate=True)})
    engine = context.engine
    engine.start()
    name = engine.table.name
    free = (name("a"), name(10), name("b"), name(14))
    clash = (name("a"), name(10), name("b"), name(10))
    assert engine.evaluate("cfree", free) and engine.evaluate("cfree", clash)
    view = context.assumed.view(engine.refuted)(frozenset(engine.store.levels))
    untried = (name("a"), name(12), name("c"), name(18))
    assert Atom("cfree", free) in view and Atom("cfree", untried) in view
    assert Atom("cfree", clash) not in view  # refuted
    assert Atom("cfree", (name("a"), "nowhere", name("b"), name(10))) not in view  # no domain
    assert view.args_of("cfree") == () and view.args_of("obj")


def test_a_sweep_of_siblings_stops_after_the_time_of_a_search(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A failed deferred test has its siblings evaluated in a batch, but only for about as
    long as a plan search takes: an expensive test (here each call takes 1 s of a clock the
    solver reads, the searches none of it) gets far fewer sibling calls than a cheap one."""

    from solvers.stream_planning import context as context_module

    def run(seconds_per_call: float) -> list[tuple[Any, ...]]:
        calls: list[tuple[Any, ...]] = []
        offset = [0.0]

        class Clock:
            @staticmethod
            def perf_counter() -> float:
                return time.perf_counter() + offset[0]

        def cfree(o: str, p: int, o2: str, p2: int) -> bool:
            calls.append((o, p, o2, p2))
            offset[0] += seconds_per_call
            return o == o2 or abs(p - p2) >= 2

        monkeypatch.setattr(context_module, "time", Clock)
        init: list[tuple[Any, ...]] = [("HandEmpty",), ("Obj", "a"), ("AtPose", "a", 0)]
        init += [("Slot", p) for p in range(SLOTS)]
        init += [("Shelf", p) for p in range(8, SLOTS)]
        for obstacle, slot in OBSTACLES.items():
            init += [("Obj", obstacle), ("AtPose", obstacle, slot)]
        streams = {"test-cfree": from_test(cfree), "handling": lambda *_a: 1.0}
        problem = PDDLProblem(DOMAIN, {}, STREAMS, streams, init, ("Done", "a"))
        info = {"test-cfree": StreamInfo(negate=True)}
        solution = solve(problem, algorithm="adaptive", stream_info=info, verbose=False)
        assert solution.solved
        check_plan(solution.plan or [])
        return calls

    cheap, expensive = run(0.0), run(1.0)
    assert len(expensive) < len(cheap)
    assert len(cheap) > 2 * len(OBSTACLES)  # the cheap test's sweeps called siblings


def test_a_sweep_budget_leaves_out_the_facts_of_deferred_predicates(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each sweep evaluates at most ``search_sample_ratio`` times the known facts other than
    the deferred predicates' own (which the sweeps add: counted, each sweep's budget would grow
    with the one before)."""
    sweeps: list[tuple[int, int, int]] = []
    original = SolveContext.sweep_deferred

    def recording(self: SolveContext, name: str, inputs: tuple[str, ...]) -> int:
        store = self.engine.store
        known = store.count_except(self.engine.functions)
        calls = original(self, name, inputs)
        sweeps.append((calls, known, len(store)))  # the store after the sweep
        return calls

    monkeypatch.setattr(SolveContext, "sweep_deferred", recording)
    calls: list[tuple[Any, ...]] = []
    problem = slots_problem(calls, [], lambda *_a: 1.0)
    info = {"test-cfree": StreamInfo(negate=True)}
    solution = solve(problem, algorithm="adaptive", stream_info=info, verbose=False)
    assert solution.solved and sweeps
    assert all(made <= known for made, known, _ in sweeps)
    # the sweeps' true results joined the store; a budget counting them would have grown
    assert all(known < after for _, known, after in sweeps)
