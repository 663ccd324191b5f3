"""``solve`` with PDDLStream's keywords and planner names, the ``solve_*`` entry points,
``solve_from_pddl`` and constraint satisfaction."""

from __future__ import annotations

import logging
import math

import pytest
from compat_domains import DOMAIN, GOAL, INIT, STREAMS, stream_map

from sdar_tamp.compat.pddlstream import (
    WILD,
    PDDLProblem,
    PlanConstraints,
    SatisfactionProblem,
    constraint_satisfaction,
    from_gen_fn,
    from_test,
    solve,
    solve_adaptive,
    solve_focused,
    solve_from_pddl,
    solve_incremental,
    solve_pddlstream_satisfaction,
)
from sdar_tamp.compat.pddlstream.check import check_solution
from sdar_tamp.errors import ParameterError
from solvers.solve import PLANNER_ALIASES, parse_planner


def _problem() -> PDDLProblem:
    return PDDLProblem(DOMAIN, {}, STREAMS, stream_map(), INIT, GOAL)


def test_pddlstream_keywords_are_accepted_and_noted(caplog: pytest.LogCaptureFixture) -> None:
    problem = _problem()
    with caplog.at_level(logging.INFO, logger="sdar_tamp.compat"):
        solution = solve(
            problem,
            algorithm="adaptive",
            debug=True,
            replan_actions={"pick"},
            visualize=True,
            hierarchy=[],
            max_memory=1e9,
            reorder=False,
            max_failures=0,
            max_effort=10,
            planner="ff-eager",
            max_planner_time=10,
            max_time=30,
            verbose=False,
        )
    assert solution.plan is not None and check_solution(problem, solution) is None
    noted = " ".join(r.getMessage() for r in caplog.records)
    for name in ("debug", "replan_actions", "visualize", "max_memory", "reorder"):
        assert f"solve({name}=" in noted
    assert "hierarchy" not in noted  # an empty hierarchy is the default: nothing to note


def test_unknown_keyword_names_itself() -> None:
    with pytest.raises(ParameterError, match="max_tme"):
        solve(_problem(), max_tme=3)


def test_unknown_algorithm_lists_the_valid_ones() -> None:
    with pytest.raises(ParameterError, match="incremental, focused, binding, adaptive"):
        solve(_problem(), algorithm="fast")


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("dijkstra", ("astar", "blind", 1.0)),
        ("max-astar", ("astar", "max", 1.0)),
        ("lmcut-astar", ("astar", "max", 1.0)),
        ("ff-astar", ("astar", "ff", 1.0)),
        ("ff-eager", ("gbfs", "ff", 1.0)),
        ("ff-lazy", ("gbfs", "ff", 1.0)),
        ("add-random-lazy", ("gbfs", "add", 1.0)),
        ("goal-lazy", ("gbfs", "ff", 1.0)),
        ("ff-eager-pref", ("gbfs", "ff", 1.0)),
        ("ff-wastar3", ("lazy-wastar", "ff", 3.0)),
        ("lazy-wastar-ff", ("lazy-wastar", "ff", 2.0)),
        ("ff-astar2", ("wastar", "ff", 2.0)),
        ("wastar-ff", ("wastar", "ff", 2.0)),
        ("gbfs-add", ("gbfs", "add", 2.0)),
        ("lazy-gbfs", ("lazy-gbfs", "ff", 2.0)),
        ("lazy-gbfs-ff-lmcount", ("lazy-gbfs", "ff-lmcount", 2.0)),
        ("gbfs-ff-lmcount", ("gbfs", "ff-lmcount", 2.0)),
    ],
)
def test_planner_names_map_to_the_classical_planner(
    name: str, expected: tuple[str, str, float]
) -> None:
    assert parse_planner(name) == expected


def test_unknown_planner_lists_the_valid_names() -> None:
    with pytest.raises(ParameterError) as error:
        parse_planner("cerberus")
    message = str(error.value)
    assert "'cerberus'" in message and "max-astar" in message and "wastar-ff" in message
    assert len(PLANNER_ALIASES) >= 12
    with pytest.raises(ParameterError, match="planner"):
        solve(_problem(), planner="lama")


@pytest.mark.parametrize(
    "planner", ["max-astar", "ff-astar", "dijkstra", "ff-wastar2", "lazy-gbfs-ff-lmcount"]
)
def test_solve_entry_points_find_valid_plans(planner: str) -> None:
    problem = _problem()
    for solution in (
        solve_incremental(problem, planner=planner, max_time=30, unit_costs=True, debug=False),
        solve_focused(problem, planner=planner, max_time=30),
        solve_adaptive(problem, planner=planner, max_time=30, verbose=False),
    ):
        assert solution.plan is not None
        assert check_solution(problem, solution) is None


def test_max_cost_and_pddlstream_wildcard_skeletons() -> None:
    problem = _problem()
    skeleton = [("pick", ["cup", WILD]), ("place", ["cup", "*"])]
    constraints = PlanConstraints(skeletons=[skeleton], exact=True, groups={}, hint=False)
    solution = solve(problem, constraints=constraints, max_time=30, verbose=False)
    assert [a.name for a in solution.plan or []] == ["pick", "place"]
    from sdar_tamp.compat.pddlstream.algorithms.common import SOLUTIONS

    assert [(s.plan, s.cost) for s in SOLUTIONS] == [(solution.plan, solution.cost)]
    assert SOLUTIONS[0].time >= 0
    bounded = solve(problem, max_cost=1.0, max_time=1, verbose=False)  # lifting costs 2
    assert bounded.plan is None and math.isinf(bounded.cost)
    assert SOLUTIONS == []  # the last call's plans: none


def test_solve_from_pddl_returns_plan_and_cost() -> None:
    domain = """(define (domain d) (:requirements :strips)
      (:predicates (at ?x) (link ?x ?y))
      (:action go :parameters (?x ?y) :precondition (and (at ?x) (link ?x ?y))
         :effect (and (at ?y) (not (at ?x)))))"""
    problem = """(define (problem p) (:domain d) (:objects a b c)
      (:init (at a) (link a b) (link b c)) (:goal (at c)))"""
    plan, cost = solve_from_pddl(domain, problem, planner="dijkstra", debug=True)
    assert plan is not None and [(a.name, a.args) for a in plan] == [
        ("go", ("a", "b")),
        ("go", ("b", "c")),
    ]
    assert cost == 2.0
    unsolvable = problem.replace("(link b c)", "")
    assert solve_from_pddl(domain, unsolvable) == (None, math.inf)
    with pytest.raises(TypeError, match="bogus"):
        solve_from_pddl(domain, problem, bogus=1)


SATISFY_STREAMS = """(define (stream numbers)
  (:stream positive :outputs (?x) :certified (and (Positive ?x) (Integer ?x)))
  (:stream test-large :inputs (?x) :domain (Integer ?x) :certified (Large ?x))
  (:function (Size ?x) (Integer ?x)))"""


def _satisfaction() -> SatisfactionProblem:
    stream_map = {
        "positive": from_gen_fn(lambda: ((x,) for x in range(1, 10))),
        "test-large": from_test(lambda x: x >= 4),
        "size": lambda x: float(x),
    }
    terms = [("Positive", "?a"), ("Large", "?a"), ("minimize", ("Size", "?a"))]
    return SatisfactionProblem(SATISFY_STREAMS, stream_map, [], terms)


def test_constraint_satisfaction_binds_the_free_parameters() -> None:
    solution = constraint_satisfaction(_satisfaction(), max_time=30, verbose=False)
    assert solution.bindings is not None and solution.bindings["?a"] >= 4
    assert solution.cost == pytest.approx(float(solution.bindings["?a"]))
    retired = solve_pddlstream_satisfaction(
        _satisfaction(), algorithm="incremental", max_time=30, verbose=False
    )
    assert retired.bindings is not None and retired.bindings["?a"] >= 4


def test_unsatisfiable_terms_give_no_bindings() -> None:
    problem = _satisfaction()._replace(terms=[("Positive", "?a"), ("Large", "?a")])
    stream_map = dict(problem.stream_map)  # type: ignore[arg-type]
    stream_map["test-large"] = from_test(lambda x: False)
    solution = constraint_satisfaction(
        problem._replace(stream_map=stream_map), max_time=3, verbose=False
    )
    assert solution.bindings is None


def test_streams_without_stream_info_get_pddlstream_shared_default(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from sdar_tamp.compat.pddlstream.algorithms import meta
    from sdar_tamp.compat.pddlstream.language.stream import PartialInputs, StreamInfo

    seen: dict[str, object] = {}

    def capture(problem: object, **options: object) -> object:
        seen.update(options["stream_info"])  # type: ignore[call-overload]
        return "captured"

    monkeypatch.setattr(meta, "core_solve", capture)
    problem = _problem()
    unique = StreamInfo(opt_gen_fn=PartialInputs(unique=True))
    first, *others = [s.name for s in problem.streams.streams]
    assert others  # the shared test problem declares several streams
    assert meta.solve(problem, stream_info={first: unique}) == "captured"
    assert seen[first] is unique  # given: kept
    assert all(seen[name].opt_gen_fn == "shared" for name in others)  # type: ignore[attr-defined]
    assert StreamInfo().opt_gen_fn == "shared"


def _captured_info(monkeypatch: pytest.MonkeyPatch, **keywords: object) -> dict[str, object]:
    from sdar_tamp.compat.pddlstream.algorithms import meta

    seen: dict[str, object] = {}

    def capture(problem: object, **options: object) -> object:
        seen.update(options["stream_info"])  # type: ignore[call-overload]
        return "captured"

    monkeypatch.setattr(meta, "core_solve", capture)
    assert meta.solve(_problem(), **keywords) == "captured"  # type: ignore[arg-type,comparison-overlap]
    return seen


def test_defer_fn_without_replan_actions_changes_nothing_as_in_pddlstream(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    from sdar_tamp.compat.pddlstream.language.external import defer_shared
    from sdar_tamp.compat.pddlstream.language.stream import PartialInputs, StreamInfo

    given = StreamInfo(opt_gen_fn=PartialInputs(unique=True), defer_fn=defer_shared)
    with caplog.at_level(logging.INFO, logger="sdar_tamp.compat"):
        seen = _captured_info(monkeypatch, stream_info={"sample-pose": given})
    passed = seen["sample-pose"]
    assert passed.defer_fn is None  # type: ignore[attr-defined]
    assert passed.opt_gen_fn == "unique"  # type: ignore[attr-defined]  # the rest kept
    assert given.defer_fn is defer_shared  # the program's own object is not changed
    assert "defer_fn" not in caplog.text


def test_defer_fn_with_replan_actions_is_noted(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    from sdar_tamp.compat.pddlstream.language.external import defer_unique
    from sdar_tamp.compat.pddlstream.language.function import FunctionInfo
    from sdar_tamp.compat.pddlstream.language.stream import StreamInfo

    info = {"sample-pose": StreamInfo(defer_fn=defer_unique), "lift": FunctionInfo()}
    with caplog.at_level(logging.INFO, logger="sdar_tamp.compat"):
        seen = _captured_info(monkeypatch, stream_info=info, replan_actions={"pick"})
    assert all(item.defer_fn is None for item in seen.values())  # type: ignore[attr-defined]
    assert seen["lift"] is info["lift"]
    assert "defer_fn of sample-pose with replan_actions=['pick']" in caplog.text
