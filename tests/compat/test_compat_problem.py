"""PDDLStream's leniency about stream maps, and its stream options."""

from __future__ import annotations

import logging

import pytest
from compat_domains import DOMAIN, EXO_DOMAIN, EXO_STREAMS, GOAL, INIT, STREAMS, stream_map

from sdar_tamp.compat.pddlstream import (
    DEBUG,
    SHARED_DEBUG,
    FunctionInfo,
    PartialInputs,
    PDDLProblem,
    SharedDebugValue,
    StreamInfo,
    UniqueOptValue,
    WildOutput,
    from_fn,
    never_defer,
    solve,
)
from sdar_tamp.compat.pddlstream.check import check_solution
from sdar_tamp.language.errors import StreamMapError
from solvers.solution import Action, Solution


def test_undeclared_stream_map_entries_are_dropped_with_a_log_line(
    caplog: pytest.LogCaptureFixture,
) -> None:
    mapping = {**stream_map(), "duration": lambda *a: 1.0}
    with caplog.at_level(logging.INFO, logger="sdar_tamp.compat"):
        problem = PDDLProblem(DOMAIN, {}, STREAMS, mapping, INIT, GOAL)
    assert "duration" not in problem.stream_functions
    assert any(
        "'duration'" in r.getMessage() and "ignored" in r.getMessage() for r in caplog.records
    )
    solution = solve(problem, algorithm="adaptive", max_time=30, verbose=False)
    assert solution.plan is not None and check_solution(problem, solution) is None


def test_total_cost_init_fact_is_accepted() -> None:
    init = [*INIT, ("=", ("total-cost",), 0)]
    problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map(), init, GOAL)
    assert all(fact[0] != "=" for fact in problem.init)


def test_missing_function_callable_raises_only_when_called() -> None:
    mapping = {k: v for k, v in stream_map().items() if k != "lift"}
    problem = PDDLProblem(DOMAIN, {}, STREAMS, mapping, INIT, GOAL)
    with pytest.raises(StreamMapError, match="lift"):
        problem.stream_functions["lift"]("cup")


def test_bad_stream_map_values_are_errors() -> None:
    with pytest.raises(StreamMapError, match="'debug' or 'shared_debug'"):
        PDDLProblem(DOMAIN, {}, STREAMS, "everything", INIT, GOAL)
    with pytest.raises(StreamMapError, match="mapping"):
        PDDLProblem(DOMAIN, {}, STREAMS, [1, 2], INIT, GOAL)


@pytest.mark.parametrize("mode", [DEBUG, SHARED_DEBUG])
def test_debug_stream_maps_plan_with_stand_in_values(mode: str) -> None:
    problem = PDDLProblem(DOMAIN, {}, STREAMS, mode, INIT, GOAL)
    solution = solve(problem, algorithm="focused", max_time=30, verbose=False)
    assert solution.plan is not None
    place = solution.plan[-1]
    assert place.name == "place"
    if mode == SHARED_DEBUG:
        assert place.args[1] == SharedDebugValue("sample-pose", "?p")
    assert check_solution(problem, solution) is None


def test_stream_info_accepts_pddlstream_keywords() -> None:
    info = StreamInfo(p_success=0, eager=True, defer_fn=never_defer, eager_skeleton=True)
    assert info.p_success == 0 and info.defer_fn is None and info.eager
    assert StreamInfo(opt_gen_fn=PartialInputs(unique=False)).opt_gen_fn == "shared"
    assert StreamInfo(opt_gen_fn=PartialInputs(unique=True)).opt_gen_fn == "unique"
    assert StreamInfo(p_success=0.5, overhead=2, estimate=True).p_success is None
    with pytest.raises(ValueError, match="p_success"):
        StreamInfo(p_success=1.5)
    with pytest.raises(TypeError, match="opt_gen_fn"):
        StreamInfo(opt_gen_fn=3)


def test_function_info_opt_fn_sees_pddlstream_optimistic_values() -> None:
    seen: list[object] = []

    def opt_lift(block: object) -> float:
        seen.append(block)
        return 1.0

    assert FunctionInfo().eager and not FunctionInfo(eager=False).eager
    from solvers.stream_planning.opt_values import OptimisticValue

    info = FunctionInfo(opt_fn=opt_lift)
    assert info.opt_fn is not None
    assert info.opt_fn(OptimisticValue("#o1", "sample-pose")) == 1.0
    assert isinstance(seen[0], UniqueOptValue) and seen[0].output == "#o1"


def test_stream_info_opt_gen_fn_sees_values_and_pddlstream_optimistic_values() -> None:
    from solvers.stream_planning.opt_values import OptimisticValue

    seen: list[object] = []

    def guess(*inputs: object) -> tuple[int]:
        seen.extend(inputs)
        return (3,)

    opt_gen_fn = StreamInfo(opt_gen_fn=from_fn(guess)).opt_gen_fn
    assert callable(opt_gen_fn)
    assert list(opt_gen_fn(2, OptimisticValue("#o1", "sample-pose"))) == [[(3,)]]
    assert seen[0] == 2
    assert isinstance(seen[1], UniqueOptValue) and seen[1].output == "#o1"


def test_wild_output_unpacks_as_values_and_facts() -> None:
    values, facts = WildOutput(values=[(1,)], facts=[("safe", 1)])
    assert values == [(1,)] and facts == [("safe", 1)]
    with pytest.raises(NotImplementedError):
        WildOutput(actions=[("a",)])


def test_exogenous_stream_runs_once_its_fluent_domain_fact_holds() -> None:
    calls: list[str] = []

    def read(item: str) -> tuple[int]:
        calls.append(item)
        return (7,)

    problem = PDDLProblem(
        EXO_DOMAIN, {}, EXO_STREAMS, {"read": from_fn(read)}, [("item", "box")], ("have", "box")
    )
    solution = solve(problem, algorithm="adaptive", max_time=30, verbose=False)
    assert solution.plan == [Action("look", ("box",)), Action("take", ("box", 7))]
    assert calls == ["box"]
    assert check_solution(problem, solution) is None


def test_check_solution_rejects_a_plan_that_misses_the_goal() -> None:
    problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map(), INIT, GOAL)
    solution = solve(problem, algorithm="binding", max_time=30, verbose=False)
    assert solution.plan is not None and check_solution(problem, solution) is None
    truncated = Solution(solution.plan[:1], solution.cost, solution.certificate)
    assert "goal" in (check_solution(problem, truncated) or "")
    assert check_solution(problem, Solution(None)) == "no plan"


def test_values_of_undeclared_functions_are_ignored_with_a_log_line(
    caplog: pytest.LogCaptureFixture,
) -> None:
    init = [*INIT, ("=", ("Speed",), 3.0), ("=", ("lift", "cup"), 2.0)]
    with caplog.at_level(logging.INFO, logger="sdar_tamp.compat"):
        problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map(), init, GOAL)
    assert ("=", ("lift", "cup"), 2.0) in problem.init
    assert all(f[0] != "=" or f[1][0] != "Speed" for f in problem.init)
    assert any("'speed' is not declared" in r.getMessage() for r in caplog.records)
